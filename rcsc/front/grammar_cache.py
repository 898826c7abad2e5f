"""Where lark keeps a built parser between runs (`lark_cache`).

Building the LALR tables of the design grammar takes about 60 ms, a large
part of a small check; lark can save the built parser and load it in a few
milliseconds.  The file lives in the user's own cache folder
(`$XDG_CACHE_HOME/rcsc`, else `~/.cache/rcsc`), never in a shared temporary
folder: lark loads it with pickle, so a file another user could plant there
would run their code.  The name holds lark's version and a hash of the
grammar text, and lark itself rebuilds when the hash in the file differs.
Any problem with the folder means no cache, never an error.
"""

from __future__ import annotations

import hashlib
import os
import stat


def cache_folder() -> str | None:
    """The user's rcsc cache folder (created private), or None when unusable."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    if not os.path.isabs(base):
        return None
    folder = os.path.join(base, "rcsc")
    try:
        os.makedirs(folder, mode=0o700, exist_ok=True)
        st = os.lstat(folder)
    except OSError:
        return None
    # Our own real folder, writable by nobody else.
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid() or st.st_mode & 0o022:
        return None
    return folder


def lark_cache(name: str, grammar: str) -> str | bool:
    """The `cache=` argument for `Lark(grammar, ...)`: a file path, or False."""
    if os.environ.get("RCSC_NO_GRAMMAR_CACHE"):
        return False
    folder = cache_folder()
    if folder is None:
        return False
    import lark

    digest = hashlib.sha256(grammar.encode("utf-8")).hexdigest()[:16]
    path = os.path.join(folder, f"{name}-lark{lark.__version__}-{digest}.cache")
    if os.path.lexists(path):
        try:
            st = os.lstat(path)
        except OSError:
            return False
        if not stat.S_ISREG(st.st_mode) or st.st_uid != os.getuid():
            return False
    return path
