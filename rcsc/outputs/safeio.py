"""Reading inputs and writing outputs safely: the file-system rules of every command.

rcsc runs in CI on files it did not write, in folders others can write to,
and is stopped with Ctrl-C.  Whatever happens, it must not follow a link it
did not make, delete or replace a file a person wrote, hang on a special
file, or leave an output folder half old and half new.  All file access of
the commands goes through this module:

* `read_input` reads a design or scenario: regular files only (a FIFO,
  a device or /dev/zero is refused at once) and at most `MAX_INPUT` bytes.
* `write_file` replaces one output file atomically: the data go to a fresh
  temporary file beside it (exclusive creation, a random name), which is
  then renamed over the target, so the target is never half written.  A
  target that is not a regular file (`-o /dev/null`, a FIFO, a link the user
  made) is written through instead, as a shell redirection would; where
  rcsc chooses the name itself (`rcsc doc`'s index.html) a link or special
  file is refused.
* `write_tree` writes a whole output folder (a build) as one transaction:
  every new file is first written into a private folder `.rcsc-txn` inside
  the output folder, a commit marker is written, and only then are the files
  renamed into place, with SIGINT and SIGTERM held back for that short
  phase.  The build's entry files (Makefile, CMakeLists.txt, Cargo.toml) are
  taken away first and put in place last, so if the process dies anyway
  (SIGKILL, power loss) in between, there is no build file and make, cmake
  or cargo refuse to build the mix; `.rcsc-txn` stays behind and the next
  `rcsc build` finishes the transaction (rolls it forward if it was
  committed, else discards it).  An I/O error while renaming rolls back to
  the old files.  So a build tool only ever sees the complete old or the
  complete new output.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import stat
import tempfile
from collections.abc import Callable, Iterable, Iterator
from typing import BinaryIO
from contextlib import contextmanager
from dataclasses import dataclass, field

# Designs of 200 controllers are ~5 MB; 64 MiB leaves room and stops
# `rcsc check /dev/stdin < /dev/zero`-style inputs long before memory runs out.
MAX_INPUT = 64 * 1024 * 1024

TXN = ".rcsc-txn"
_OWNER = "OWNER"
_OWNER_TEXT = "rcsc build transaction: rcsc removes this folder when the build is complete\n"


class InputError(OSError):
    """An input that rcsc refuses to read (not a regular file, too large)."""


# The files one command has read and the reports it has written, by device
# and inode (so a link or another spelling of the path is the same file):
# `rcsc sim d.rcs --scenario s.scn -o s.scn` must not replace the scenario
# it just read with its trace, nor `-o t.jsonl --step-log t.jsonl` write two
# reports over each other.  None outside a command (`command_files`), so a
# long-running server does not remember files between requests.
_seen: dict[tuple[int, int], tuple[str, str]] | None = None


@contextmanager
def command_files() -> Iterator[None]:
    """Remember the files read and the reports written while the block runs."""
    global _seen
    outer, _seen = _seen, {}
    try:
        yield
    finally:
        _seen = outer


def _note(what: str, st: os.stat_result, path: str) -> None:
    if _seen is not None:
        _seen.setdefault((st.st_dev, st.st_ino), (what, path))


def _note_file(what: str, path: str) -> None:
    """Remember `path` if it is a regular file (a device such as /dev/null
    may take any number of reports, and is no one's input)."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return
    if stat.S_ISREG(st.st_mode):
        _note(what, st, path)


def claim_inputs(paths: Iterable[str]) -> None:
    """Count the regular files among `paths` as inputs of this command."""
    for path in paths:
        _note_file("input", path)


def decode_text(data: bytes) -> str:
    """`data` as UTF-8 text; otherwise an InputError that says where
    (`not UTF-8 text (byte 9)`), the wording of every input."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"not UTF-8 text (byte {exc.start})") from exc


def decode_lossy(data: bytes) -> tuple[str, int | None, int]:
    """`data` as text with each byte that is not UTF-8 shown as U+FFFD, the
    text offset of the first such byte (None when all of it is UTF-8) and
    that byte's offset in `data`: what a finding that points at the byte
    needs (E0010)."""
    try:
        return data.decode("utf-8"), None, 0
    except UnicodeDecodeError as exc:
        # The bytes before the first bad one are UTF-8 by definition.
        return data.decode("utf-8", "replace"), len(data[: exc.start].decode("utf-8")), exc.start


def read_text(path: str, limit: int = MAX_INPUT) -> str:
    """`read_input` decoded as UTF-8 (`decode_text`)."""
    return decode_text(read_input(path, limit))


def _refuse_seen(path: str) -> None:
    """Refuse a report over a file this command read or already wrote."""
    if not _seen:
        return
    try:
        st = os.stat(path)
    except OSError:
        return  # nothing there (or a dangling link): nothing to lose
    seen = _seen.get((st.st_dev, st.st_ino))
    if seen is None:
        return
    what, first = seen
    same = "" if os.path.normpath(first) == os.path.normpath(path) else f" (`{first}`)"
    if what == "input":
        raise FileExistsError(f"it is an input of this command{same}; refusing to replace it with a report")
    raise FileExistsError(f"this command already wrote another report to it{same}")


def read_input(path: str, limit: int = MAX_INPUT) -> bytes:
    """The bytes of a regular file of at most `limit` bytes; InputError otherwise.

    The file is opened without blocking (a FIFO would otherwise wait for a
    writer forever) and checked with fstat on the open descriptor, so what is
    checked is what is read.
    """
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise InputError(f"`{path}` is not a regular file")
        _note("input", st, path)
        if st.st_size > limit:
            raise InputError(f"`{path}` is {st.st_size} bytes; the limit is {limit} bytes")
        chunks, size = [], 0
        # One read of the whole file (its size and one byte more, to see
        # that it ended) saves copying the chunks of a large design together.
        want = st.st_size + 1
        while True:
            chunk = os.read(fd, want)
            want = 1 << 20
            if not chunk:
                break
            size += len(chunk)
            if size > limit:  # the file grew while being read
                raise InputError(f"`{path}` is over {limit} bytes")
            chunks.append(chunk)
        return b"".join(chunks)
    finally:
        os.close(fd)


def is_regular_file(path: str) -> bool:
    """True for a regular file (links followed): what may be read as an input."""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except OSError:
        return False


def write_file(
    path: str, data: bytes, may_replace: Callable[[str], bool] | None = None, mode: int | None = None
) -> None:
    """Write `data` to `path` atomically (temporary file beside it, then rename).

    The new file gets permission bits `mode` (default: 0o666 less the umask);
    `rcsc fmt` passes the old file's, so that rewriting keeps them.

    `may_replace(path)` is asked when `path` exists as a regular file, and an
    existing link or special file is then refused.  Without `may_replace` (a
    report the user named on the command line) a link, device or FIFO is
    written through like a shell redirection, and a regular file is
    replaced atomically.
    """
    with open_atomic(path, may_replace, mode) as out:
        out.write(data)


@contextmanager
def open_atomic(
    path: str, may_replace: Callable[[str], bool] | None = None, mode: int | None = None
) -> Iterator[BinaryIO]:
    """A binary file to write `path` through, as `write_file` writes it: the
    data go to a temporary file that replaces `path` when the block ends
    normally, and is removed if it raises (the old file stays whole)."""
    directory = os.path.dirname(path) or "."
    if os.path.lexists(path):
        st = os.lstat(path)
        if may_replace is not None:
            if not stat.S_ISREG(st.st_mode):
                raise FileExistsError(f"refusing to replace `{path}`: it is not a regular file")
            if not may_replace(path):
                raise FileExistsError(f"refusing to replace `{path}`: it was not written by rcsc")
        elif not stat.S_ISREG(st.st_mode):
            # A path the user named that is not a plain file (`-o /dev/null`,
            # `-o /dev/stdout`, a FIFO, a link they made) is written through,
            # as a shell redirection would: renaming a file over it would
            # replace the device or the link itself.
            with open(path, "wb") as through:
                yield through
            return
    fd, tmp = tempfile.mkstemp(prefix=".rcsc-", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "wb") as out:
            yield out
        os.chmod(tmp, (0o666 & ~_umask()) if mode is None else mode)
        os.replace(tmp, path)
    except BaseException:
        _unlink_quietly(tmp)
        raise


def write_report(path: str, data: bytes) -> None:
    """Write a report to the file a person named (`-o`, `--step-log`,
    `--junit`), as `write_file` does, unless this command read that file or
    already wrote another report to it (`command_files`)."""
    with report_stream(path) as out:
        out.write(data)


@contextmanager
def report_stream(path: str) -> Iterator[BinaryIO]:
    """`write_report` for a report written as it is made (a long run's
    trace, which need not be whole in memory): the same refusals, the same
    atomic replacement when the block ends.  Two reports of one command to
    one file are refused even while both are being written."""
    _refuse_seen(path)
    try:
        special = not stat.S_ISREG(os.stat(path).st_mode)
    except (OSError, ValueError):
        special = False  # nothing there yet
    key = "" if special else os.path.realpath(path)  # a device takes any number of reports
    if key and key in _writing:
        first = _writing[key]
        same = "" if os.path.normpath(first) == os.path.normpath(path) else f" (`{first}`)"
        raise FileExistsError(f"this command already wrote another report to it{same}")
    if key:
        _writing[key] = path
    try:
        with open_atomic(path) as out:
            yield out
    finally:
        _writing.pop(key, None)
    _note_file("report", path)


# The reports being written at this moment, by real path (a report that is
# still a temporary file has no device and inode to compare yet).
_writing: dict[str, str] = {}


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _unlink_quietly(path: str) -> None:
    try:
        os.unlink(path)
    except FileNotFoundError:
        return


# ---- a whole output folder ------------------------------------------------------------


@dataclass
class TreeFile:
    """One file of an output folder; `user` files are written only when missing."""

    path: str  # relative, with "/"
    data: bytes
    user: bool = False
    entry: bool = False  # a build entry file: removed first, written last


@dataclass
class TreeResult:
    written: list[str] = field(default_factory=list)
    unchanged: list[str] = field(default_factory=list)
    kept: list[str] = field(default_factory=list)  # user files that already existed
    refused: list[str] = field(default_factory=list)  # "path: why" for files in the way
    recovered: str = ""  # what was done with an interrupted earlier transaction


def _check_relpath(rel: str) -> list[str]:
    parts = rel.split("/")
    if not rel or rel.startswith("/") or any(p in ("", ".", "..") for p in parts) or parts[0] == TXN:
        raise ValueError(f"bad output path {rel!r}")
    return parts


def write_tree(files: list[TreeFile], out_dir: str, is_ours: Callable[[str], bool]) -> TreeResult:
    """Write `files` under `out_dir` as one transaction (see the module docstring).

    A file already there is replaced only if `is_ours(path)` says rcsc wrote
    it; a file in the way that is not ours, a symbolic link, or a folder where
    a file goes (or a link where a folder goes) is reported in `refused`, and
    then nothing at all is written.  OSError on I/O failure, after rolling
    back.
    """
    res = TreeResult()
    os.makedirs(out_dir, exist_ok=True)
    res.recovered = recover(out_dir)

    plan: list[tuple[TreeFile, str]] = []
    for f in files:
        parts = _check_relpath(f.path)
        where = out_dir
        for d in parts[:-1]:
            where = os.path.join(where, d)
            if os.path.lexists(where) and (os.path.islink(where) or not os.path.isdir(where)):
                res.refused.append(f"{f.path}: `{d}` is not a plain folder")
                break
        else:
            path = os.path.join(out_dir, *parts)
            if not os.path.lexists(path):
                plan.append((f, path))
                continue
            st = os.lstat(path)
            if f.user and stat.S_ISLNK(st.st_mode) and is_regular_file(path):
                # A person's own file (an extern's code) kept elsewhere and
                # linked in: it is theirs, and rcsc writes it only when missing.
                res.kept.append(f.path)
            elif f.user and stat.S_ISLNK(st.st_mode):
                res.refused.append(f"{f.path}: it is a symbolic link to no file (dangling, or to a folder); "
                                   "point it at your file, or delete it for a fresh stub")
            elif not stat.S_ISREG(st.st_mode):
                res.refused.append(f"{f.path}: it is a {'symbolic link' if stat.S_ISLNK(st.st_mode) else 'special file or folder'}")
            elif f.user:
                res.kept.append(f.path)
            elif not is_ours(path):
                res.refused.append(f"{f.path}: it was not generated by rcsc")
            else:
                with open(path, "rb") as old:
                    if old.read() == f.data:
                        res.unchanged.append(f.path)
                        continue
                plan.append((f, path))
    if res.refused or not plan:
        return res
    # An unchanged entry file is rewritten too: it must be away while the
    # other files change, or a build tool would build the mix.
    for f in files:
        if f.entry and f.path in res.unchanged:
            res.unchanged.remove(f.path)
            plan.append((f, os.path.join(out_dir, *f.path.split("/"))))

    # Entry files last; _apply takes the old ones away before anything else.
    plan.sort(key=lambda fp: fp[0].entry)
    txn = os.path.join(out_dir, TXN)
    os.mkdir(txn, 0o700)  # exclusive: recover() removed any earlier one
    try:
        _write_exclusive(os.path.join(txn, _OWNER), _OWNER_TEXT.encode())
        os.mkdir(os.path.join(txn, "new"))
        os.mkdir(os.path.join(txn, "old"))
        for i, (f, _) in enumerate(plan):
            _write_exclusive(os.path.join(txn, "new", str(i)), f.data)
        entries = [[i, f.path, f.entry] for i, (f, _) in enumerate(plan)]
        _write_exclusive(os.path.join(txn, "plan.json"), json.dumps(entries).encode())
    except BaseException:
        shutil.rmtree(txn, ignore_errors=True)
        raise

    # The commit point: from here on the transaction is completed even if this
    # process is killed (the next run rolls it forward).
    held = _hold_signals()
    try:
        try:
            _write_exclusive(os.path.join(txn, "commit"), b"")
            _apply(out_dir, txn, entries)
        except BaseException:
            # An I/O error (or anything else this process lives through):
            # back to the old files.  Only a run that died rolls forward.
            _roll_back(out_dir, txn, entries)
            shutil.rmtree(txn, ignore_errors=True)
            raise
        shutil.rmtree(txn)
    finally:
        _release_signals(held)
    res.written = [f.path for f, _ in plan]
    res.written.sort(key=[f.path for f in files].index)
    return res


def _write_exclusive(path: str, data: bytes) -> None:
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    fd = os.open(path, flags, 0o666)
    with os.fdopen(fd, "wb") as out:
        out.write(data)


def _apply(out_dir: str, txn: str, entries: list) -> None:
    """Move each new file into place, keeping the file it replaces in old/.

    The old entry files go first (then no build tool accepts the folder) and
    the new entry files come last.
    """
    for i, rel, entry in sorted(entries, key=lambda e: not e[2]):
        if entry:
            _stash(out_dir, txn, i, rel)
    for i, rel, _ in entries:
        dest = os.path.join(out_dir, *rel.split("/"))
        new = os.path.join(txn, "new", str(i))
        if not os.path.lexists(new):
            continue  # already moved (a roll forward after an interruption)
        os.makedirs(os.path.dirname(dest), exist_ok=True)
        _stash(out_dir, txn, i, rel)
        os.rename(new, dest)


def _stash(out_dir: str, txn: str, i: int, rel: str) -> None:
    dest = os.path.join(out_dir, *rel.split("/"))
    old = os.path.join(txn, "old", str(i))
    new = os.path.join(txn, "new", str(i))
    if os.path.lexists(new) and os.path.lexists(dest) and not os.path.lexists(old):
        os.rename(dest, old)


def _roll_back(out_dir: str, txn: str, entries: list) -> None:
    """Undo `_apply` as far as it got: restore every replaced file, remove new ones."""
    for i, rel, _ in reversed(entries):
        dest = os.path.join(out_dir, *rel.split("/"))
        new = os.path.join(txn, "new", str(i))
        old = os.path.join(txn, "old", str(i))
        try:
            if not os.path.lexists(new) and os.path.lexists(dest):
                os.rename(dest, new)  # it was ours to move in; take it back out
            if os.path.lexists(old):
                os.rename(old, dest)
        except OSError:
            continue  # restore what can be restored; the error that caused this is reported


def recover(out_dir: str) -> str:
    """Finish a transaction an earlier run left behind; a sentence saying what was done.

    A `.rcsc-txn` folder without rcsc's OWNER file is not ours: it is left
    alone and reported as an error.
    """
    txn = os.path.join(out_dir, TXN)
    if not os.path.lexists(txn):
        return ""
    owner = os.path.join(txn, _OWNER)
    if not os.path.islink(txn) and os.path.isdir(txn) and not os.listdir(txn):
        os.rmdir(txn)  # killed right after creating it: nothing in it, nothing to lose
        return "discarded an interrupted build that had not replaced any file"
    if os.path.islink(txn) or not os.path.isdir(txn) or not os.path.isfile(owner):
        raise FileExistsError(f"`{txn}` is in the way and was not made by rcsc; move it away")
    with open(owner, "rb") as fh:
        if fh.read() != _OWNER_TEXT.encode():
            raise FileExistsError(f"`{txn}` is in the way and was not made by rcsc; move it away")
    committed = os.path.exists(os.path.join(txn, "commit"))
    if committed:
        with open(os.path.join(txn, "plan.json"), "rb") as fh:
            entries = json.loads(fh.read())
        held = _hold_signals()
        try:
            _apply(out_dir, txn, entries)
        finally:
            _release_signals(held)
    shutil.rmtree(txn)
    return "finished an interrupted build" if committed else "discarded an interrupted build that had not replaced any file"


def _hold_signals():
    if not hasattr(signal, "pthread_sigmask"):
        return None
    return signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM, signal.SIGHUP})


def _release_signals(held) -> None:
    if held is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)
