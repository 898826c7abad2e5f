"""A whole check kept between runs: `rcsc check` of an unchanged design answers from `.rcsc-cache/`.

`rcsc check` stores, next to the guard analysis (`rcsc.checks.cache`), the
findings of each design it checked (namespace "result"), under a key made
of the root file's path (as given and resolved), whether it was checked as
a module and the `RCSC_*` environment variables that tune the analysis; the
store adds the version of rcsc (`cache.code_version`).  One entry per root
file: each full check overwrites it.  The entry lists every file the check
read (the root, its imports and the standard-library modules) with the
SHA-256 of its text: a later run re-reads those files and replays the
findings only when every one is unchanged, so the answer is the one a full
check would give, byte for byte.  Anything else
(a changed import, a file that cannot be read, a corrupt entry) is a miss
and the design is checked in full.

A check that could not read an imported file (E0003) is not stored: its
result depends on a file that does not exist yet.

This module is light on purpose (no parser, no z3): a hit never loads the
front end or the solver.  Only findings are replayed, not the design
model, so only `rcsc check` uses it (`CheckResult.model` is None then).
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass

from rcsc.checks import cache
from rcsc.outputs import safeio
from rcsc.diagnostics import Diagnostic, Diagnostics, Label, Severity
from rcsc.front.source import SourceFile, Span, normalized

NAMESPACE = "result"
FORMAT = 2  # 2: each finding keeps the key that tells instances apart
# Findings that depend on something other than the texts of the files read.
_UNSTORABLE_CODES = frozenset(("E0003",))


# The last texts digested (the same objects) and their digests: a re-check
# digests its root text when it compares, and again when it stores, with
# the files it imports (two of the standard library's, often) in between.
_sha_memo: list[tuple[str, str]] = []


def _sha(text: str) -> str:
    for seen, sha in _sha_memo:
        # The same text read again (the daemon compares a file's text, then
        # reads it again to check it): comparing is a fifth of digesting.
        if seen is text or (len(seen) == len(text) and seen == text):
            return sha
    sha = hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()
    _sha_memo[:] = [(text, sha)] + _sha_memo[:3]
    return sha


def key_of(path: str, as_module: bool) -> str:
    """The key of the entry of the design `path`: one entry per root file (each check overwrites it)."""
    env = sorted((k, v) for k, v in os.environ.items()
                 if k.startswith("RCSC_") and k not in ("RCSC_NO_CACHE", "RCSC_INCREMENTAL") and not k.startswith("RCSC_DAEMON_"))
    return cache.digest(("replay", FORMAT, path, os.path.realpath(path), as_module, tuple(env)))


def _read_text(where: str) -> str | None:
    """The text of a recorded file (a real path), or None."""
    try:
        return safeio.read_input(where).decode("utf-8")
    except (OSError, ValueError, safeio.InputError):
        return None


# ---- storing -----------------------------------------------------------------------------


def _span(span: Span | None, index: dict[int, int]):
    if span is None:
        return None
    return [index[id(span.file)], span.start, span.end]


def _diag(d: Diagnostic, index: dict[int, int]) -> list:
    return [
        d.code,
        d.severity.value,
        d.message,
        _span(d.span, index),
        d.label,
        [[_span(lab.span, index), lab.message] for lab in d.labels],
        list(d.notes),
        list(d.helps),
        cache.encode(d.data),
        # What tells the findings of two instances of one block or
        # controller type apart (the same text, the same message): without
        # it a report that merges findings would keep one of them.
        "".join(str(x) for x in getattr(d, "_key", ())[4:5]),
    ]


def store(store: cache.Store, key: str, files: list[tuple[str, str, object]], diags: Diagnostics) -> None:
    """Keep the findings `diags` of a check that read `files` [(display path, where, SourceFile)]
    (`where`: the real path of the file; for a standard-library module, that
    of its resource).  Silently skipped when the findings cannot be stored."""
    if any(d.code in _UNSTORABLE_CODES for d in diags.items):
        return
    index = {id(src): i for i, (_, _, src) in enumerate(files)}
    try:
        value = {
            "files": [[display, where, _sha(src.text)] for display, where, src in files],
            "items": [_diag(d, index) for d in diags.items],
            "suppressed": [_diag(d, index) for d in diags.suppressed],
        }
    except (cache.NotStorable, KeyError):
        return  # a span into a file that is not listed, a value JSON cannot hold
    try:
        store.put(key, value)
    except (ValueError, TypeError):
        return


# ---- replaying ----------------------------------------------------------------------------


def decode(data: list, span) -> Diagnostic:
    """A stored finding (`_diag`), its spans made by `span(stored span)`."""
    code, sev, message, sp, label, labels, notes, helps, extra, instance = data
    d = Diagnostic(code, Severity(sev), message, span(sp), label)
    d.labels = [Label(span(s), msg) for s, msg in labels]
    d.notes = list(notes)
    d.helps = list(helps)
    d.data = cache.decode(extra, {})
    key = (d.code, d.message, d.span.file.path if d.span else "", d.span.start if d.span else -1)
    d._key = key + (str(instance),) if instance else key  # type: ignore[attr-defined]
    return d


def replay(store: cache.Store, key: str, root_text: str):
    """(sources [(display path, SourceFile)], diags) of a stored check whose files are all
    unchanged, or None."""
    value = store.get(key)
    if not isinstance(value, dict):
        return None
    try:
        sources: list[tuple[str, SourceFile]] = []
        for i, (display, where, sha) in enumerate(value["files"]):
            text = root_text if i == 0 else _read_text(where)
            if text is None:
                return None
            src = SourceFile(display, text)
            # SourceFile drops a byte-order mark and turns lone CRs into LFs:
            # compare what the check saw.
            if _sha(src.text) != sha:
                return None
            sources.append((where, src))
        files = [src for _, src in sources]

        def span(data):
            return None if data is None else Span(files[data[0]], int(data[1]), int(data[2]))

        def diag(data) -> Diagnostic:
            return decode(data, span)

        diags = Diagnostics()
        for data in value["items"]:
            d = diag(data)
            diags._seen.add((d.code, d.message, d.span.file.path if d.span else "", d.span.start if d.span else -1))
            diags.items.append(d)
        diags.suppressed = [diag(data) for data in value["suppressed"]]
    except (KeyError, ValueError, TypeError, IndexError):
        return None
    return sources, diags


# ---- the entry points of `rcsc check` -----------------------------------------------------


@dataclass
class ReplayedFile:
    """What `rcsc check` needs of a file of a replayed check (see `rcsc.front.loader.LoadedFile`)."""

    source: SourceFile
    tree: None = None
    module: str = ""
    is_root: bool = False
    real: str = ""


@dataclass
class Replayed:
    """A replayed check: its findings and files; no design model."""

    diags: Diagnostics
    files: list[ReplayedFile]
    model: None = None

    @property
    def ok(self) -> bool:
        return not self.diags.has_errors()


def _root_text(path: str) -> str | None:
    text = _read_text(path)
    return None if text is None else normalized(text)


def lookup(path: str, as_module: bool, folder: str, store=None) -> Replayed | None:
    """The stored check of the design `path` if nothing it read has changed,
    else None; from `folder`, or from `store` (the check daemon's)."""
    if cache.disabled_by_environment():
        return None
    text = _root_text(path)
    if text is None:
        return None  # the full check reports why
    found = replay(store if store is not None else cache.Store(folder, NAMESPACE), key_of(path, as_module), text)
    if found is None:
        return None
    sources, diags = found
    files = [ReplayedFile(src, is_root=(i == 0), real=where) for i, (where, src) in enumerate(sources)]
    return Replayed(diags, files)


def where_of(f) -> str | None:
    """Where a loaded file (`rcsc.front.loader.LoadedFile`) is read again:
    its real path, or for a standard-library module that of its resource;
    None if that is not a plain file."""
    from rcsc.front.loader import stdlib_path

    where = f.real
    if where.startswith("<stdlib>/"):
        res = stdlib_path(where[len("<stdlib>/"):])
        where = str(res) if res is not None else ""
        if not where or not os.path.isfile(where):
            return None
    return where or None


def remember(path: str, as_module: bool, folder: str | None, result, into=None) -> None:
    """Store the findings of `result` (a `rcsc.driver.CheckResult` of the
    design `path`) in `folder`, or in the store `into` (a language server's
    `cache.MemoryStore`)."""
    loaded = getattr(result, "files", None)
    if (into is None and cache.disabled_by_environment()) or not loaded or not loaded[0].is_root:
        return
    files = []
    for f in loaded:
        where = where_of(f)
        if where is None:
            return  # not a plain file: cannot be re-read cheaply
        files.append((f.source.path, where, f.source))
    store(into if into is not None else cache.Store(folder, NAMESPACE), key_of(path, as_module), files, result.diags)
