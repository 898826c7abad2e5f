"""The `rcsc` command's first step: `rcsc check --daemon` goes straight to the daemon.

Everything else loads the command line (`rcsc.cli`).  A call the check
daemon answers (`rcsc.daemon`) needs none of it: not importing it keeps
the command's own share of a re-check to a few hundredths of a second.
"""

from __future__ import annotations

import sys


def entry() -> None:
    """The `rcsc` command and `python -m rcsc`."""
    argv = sys.argv[1:]
    if "--daemon" in argv:
        from rcsc import daemon

        if daemon.wants_daemon(argv):
            code = daemon.client_main(argv)
            if code is not None:
                sys.exit(code)
    from rcsc.cli import entry as cli_entry

    cli_entry()
