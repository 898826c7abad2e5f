"""Global Memory ownership checks (paper section 3.8.5).

Every GM variable has exactly one writer (a controller's `writes`, or `from
env`), an initial value (checked in sema, where the declaration is read), and
is read by someone (a controller's `reads`, or `to env` for an output the
plant reads); nothing is read that nobody writes.
"""

from __future__ import annotations

import re

from rcsc.diagnostics import Diagnostics
from rcsc.semantics.model import Design, Var
from rcsc.front.source import Span

# `gm`, then blanks and comments, then the name.
_GM_HEAD = re.compile(r"gm(?:\s|//[^\n]*|/\*.*?\*/)*", re.S)


def _name_span(var: Var) -> Span:
    """The span of the variable's name in its `gm NAME: ...` declaration."""
    head = _GM_HEAD.match(var.span.text)
    if head is None or not var.span.text.startswith(var.name, head.end()):
        return var.span
    start = var.span.start + head.end()
    return Span(var.span.file, start, start + len(var.name))


def check(design: Design, diags: Diagnostics) -> None:
    writers: dict[str, list] = {name: [] for name in design.gm}
    readers: dict[str, list] = {name: [] for name in design.gm}
    for c in design.controllers.values():
        for use in c.writes:
            if use.name in writers:
                writers[use.name].append((c, use))
        for use in c.reads:
            if use.name in readers:
                readers[use.name].append((c, use))

    # An instance of a controller type that could not be made (reported) may
    # be the writer or the reader a variable lacks: nothing is said of those.
    unmade = any(c.placeholder for c in design.controllers.values())
    for name, var in design.gm.items():
        ws = writers[name]
        if var.from_env and ws:
            c, use = ws[0]
            diag = diags.add("E0400", use.span, f"`{name}` is written by the environment and by `{c.name}`", "second writer")
            diag.with_label(var.span, "declared `from env`")
        for c, use in ws[1:]:
            first_c, first_use = ws[0]
            diag = diags.add("E0400", use.span, f"`{name}` is already written by `{first_c.name}`", "second writer")
            diag.with_label(first_use.span, f"first writer `{first_c.name}`").with_note(
                "every Global Memory variable has exactly one writer"
            )
        if unmade:
            continue
        if not ws and not var.from_env:
            if readers[name]:
                c, use = readers[name][0]
                diag = diags.add("E0401", use.span, f"`{name}` is read by `{c.name}` but nothing writes it", "never written")
                diag.with_label(var.span, "declared here")
                diag.with_help(f"add `writes {name}` to the controller that produces it, or declare it `from env`")
            else:
                diags.add("W0403", _name_span(var), f"Global Memory variable `{name}` is never read or written", "unused")
        elif not readers[name] and not var.to_env:
            diags.add("W0403", _name_span(var), f"Global Memory variable `{name}` is never read", "never read").with_help(
                f"add `reads {name}` to the controller that uses it, declare it `to env` if it goes to the plant, or remove it"
            )

