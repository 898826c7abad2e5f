"""Which files a command over several PATHs works on (`rcsc check PATH...`, `rcsc fmt PATH...`).

A PATH is a file, a folder (searched recursively for `*.rcs`, skipping hidden
folders and virtual environments) or a glob pattern (`examples/**/*.rcs`,
expanded here so that it also works where no shell expands it, as in CI
configuration).  A file's role comes from its header, read without parsing:
`design NAME` starts a design, `module NAME` is a module that designs import.

A module is checked in the context of the designs that import it: they are
the only place where its names are resolved the way they are used.  Designs
can only import files inside their own folder, so the designs that may import
a module all sit in the module's folder or in one of its ancestors; those are
the only folders searched for them (`candidate_designs`).
"""

from __future__ import annotations

import glob
import os
import stat
from dataclasses import dataclass

from rcsc.front.source import skip_trivia

SUFFIX = ".rcs"
# Folders a recursive search never enters: tool caches and environments.
_SKIPPED_DIRS = frozenset({"node_modules", "__pycache__", "build", "dist", "target"})
_GLOB_CHARS = frozenset("*?[")


@dataclass
class Expanded:
    files: list[str]
    problems: list[str]


def expand(paths: list[str]) -> Expanded:
    """The files named by `paths`, each once, in a stable order (given order,
    folders and globs sorted).  A path that matches nothing is a problem, but
    the rest are still used; a plain file name that does not exist is kept so
    that reading it reports the error the same way as for a single file."""
    files: list[str] = []
    problems: list[str] = []
    seen: set[str] = set()

    def add(path: str) -> None:
        key = os.path.realpath(path)
        if key not in seen:
            seen.add(key)
            files.append(path)

    for path in paths:
        if os.path.isdir(path):
            found = _walk(path)
            if not found:
                problems.append(f"{path}: no `{SUFFIX}` files in this folder")
            for f in found:
                add(f)
        elif not os.path.lexists(path) and any(c in path for c in _GLOB_CHARS):
            matches = sorted(m for m in glob.glob(path, recursive=True) if os.path.isfile(m))
            if not matches:
                problems.append(f"{path}: no file matches this pattern")
            for m in matches:
                add(m)
        else:
            add(path)
    return Expanded(files, problems)


def _walk(folder: str) -> list[str]:
    out: list[str] = []
    for root, dirs, names in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in _SKIPPED_DIRS and not _is_venv(os.path.join(root, d)))
        out.extend(os.path.join(root, n) for n in sorted(names) if n.endswith(SUFFIX) and not n.startswith("."))
    return out


def _is_venv(path: str) -> bool:
    return os.path.isfile(os.path.join(path, "pyvenv.cfg"))


def header_kind(path: str) -> str | None:
    """`design`, `module`, or None (unreadable, or another first word), from
    the first word after comments and blanks; reads at most 64 KiB, and only
    from a regular file (opening a FIFO would wait for a writer forever; the
    front end then refuses such a file with a proper message)."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        with open(path, "rb") as f:
            head = f.read(65536)
    except OSError:
        return None
    return header_kind_text(head.decode("utf-8", "replace"))


def header_kind_text(text: str) -> str | None:
    """`design`, `module` or None, from the first word of `text`."""
    text = text.lstrip("\ufeff")
    i = skip_trivia(text, 0)
    for kind in ("design", "module"):
        if text.startswith(kind, i) and (len(text) == i + len(kind) or not (text[i + len(kind)].isalnum() or text[i + len(kind)] == "_")):
            return kind
    return None


def candidate_designs(module_path: str, stop_at: str | None = None) -> list[str]:
    """Design files that could import `module_path`: those in its folder and
    in each ancestor folder (not below them), nearest first, up to `stop_at`
    (default: the current folder when the module is inside it, else only the
    module's own folder)."""
    folder = os.path.dirname(os.path.abspath(module_path))
    stop = os.path.abspath(stop_at or os.getcwd())
    inside = os.path.commonpath([folder, stop]) == stop
    out: list[str] = []
    while True:
        try:
            names = sorted(os.listdir(folder))
        except OSError:
            names = []
        for n in names:
            p = os.path.join(folder, n)
            if n.endswith(SUFFIX) and os.path.isfile(p) and header_kind(p) == "design":
                out.append(p)
        if not inside or folder == stop or os.path.dirname(folder) == folder:
            break
        folder = os.path.dirname(folder)
    return out
