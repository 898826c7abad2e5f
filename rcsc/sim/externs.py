"""Extern functions for the simulator, written in Python (`rcsc sim --externs FILE.py`).

The simulator has no model of the hand-written target code behind an
`extern fn`: without help, a call returns the zero value of its type, as the
generated stubs do.  A design whose externs matter (a `hypot`, an `atan2`, a
lookup table) can be simulated with a Python file that stands in for them:

* a function named like each extern, taking and returning simulator values
  (an `int` for the integer types and `duration`, in nanoseconds; a `float`;
  a `bool`; an enum member's name as a `str`; a record as a `dict` of its
  fields; an array as a `list`), or
* a function `externs()` returning a `dict` of them by name.

The file runs afresh for each CPU of each run: each CPU's Main Program has
its own externs and starts afresh, so an extern that keeps state (a counter,
a filter), at module level or in `externs()`, keeps it per CPU and per run.

The file is loaded as a Python module (it is your code: it runs with your
rights).  What goes wrong is a finding, never a traceback: the file cannot be
read or raises while it loads (E0830); an extern has no implementation
(W0830: it returns zero values, as before); a call raises or returns a value
that is not of the extern's type (E0831, which stops the run: the trace after
it would not be the design's).
"""

from __future__ import annotations

import difflib
import os
import sys
import traceback
import types
from collections.abc import Callable

from rcsc.diagnostics import Diagnostics
from rcsc.front.source import SourceFile, Span
from rcsc.outputs import safeio
from rcsc.semantics import model as m
from rcsc.semantics.types import BOOL, DURATION, ArrayType, EnumType, FloatType, IntType, RecordType, Type
from rcsc.sim.simulate import ExternCallError, clone


class ExternFailed(ExternCallError):
    """A call of a Python extern raised, or returned a value of another type (E0831)."""

    def __init__(self, func: m.Function, message: str, where: str) -> None:
        super().__init__(message)
        self.func = func
        self.message = message
        self.where = where

    def report(self, diags: Diagnostics) -> None:
        d = diags.add("E0831", name_span(self.func), f"extern `{self.func.name}` failed in the simulator: {self.message}", "this extern")
        if self.step:
            d.with_note(f"called {self.step}")
        if self.where:
            d.with_note(self.where)
        d.with_help("fix the Python function, or run without --externs (the extern then returns zero values)")


class ExternsFileFailed(ExternCallError):
    """The externs file failed when it was run again for another CPU or run (E0830)."""

    def __init__(self, path: str, message: str, where: str) -> None:
        super().__init__(message)
        self.path, self.message, self.where = path, message, where

    def report(self, diags: Diagnostics) -> None:
        d = diags.add("E0830", None, f"the externs file {self.path} failed when it ran again: {self.message}")
        if self.where:
            d.with_note(self.where)


class _NotADict(Exception):
    pass


_modules = 0


def load(path: str, design: m.Design, diags: Diagnostics) -> Callable[[], dict] | None:
    """The externs of `path` for `design` as a function making one set per CPU
    (`rcsc.sim.runner.run_scenario`); None after E0830.

    The file runs afresh for each CPU of each run, as each CPU's program
    starts afresh: state at module level is per CPU and per run too.  It
    runs once here, to report what is wrong before anything is simulated;
    that first instance serves the first CPU."""
    try:
        text = safeio.read_text(path)
    except OSError as exc:
        diags.add("E0830", None, f"cannot read the externs file {path}: {getattr(exc, 'strerror', None) or exc}")
        return None
    # Modules beside the file import as they would with `python FILE.py`.
    folder = os.path.dirname(os.path.abspath(path))
    if folder not in sys.path:
        sys.path.insert(0, folder)
    try:
        code = compile(text, path, "exec")
        impl, factory = _instantiate(code, path)
    except _NotADict as exc:
        diags.add("E0830", None, f"`externs()` in {path} returned a {exc}, not a dict of functions by name")
        return None
    except (Exception, SystemExit) as exc:  # the user's code may raise anything while it loads (even exit)
        file, line, col = _location(exc, path)
        d = diags.add("E0830", _span_in(file, text if file == path else None, line, col),
                      f"the externs file does not load: {exc.msg if isinstance(exc, SyntaxError) else 'it raised ' + _describe(exc)}",
                      "here" if isinstance(exc, SyntaxError) else "raised here")
        d.with_help(f"the file is Python: fix it, and check it with `python {path}`")
        return None
    externs = [f for f in design.functions.values() if f.extern]
    _check_names(impl, externs, path, diags, from_dict=factory)
    made = [impl]

    def make() -> dict:
        if made:
            return _wrap(made.pop(), externs)
        try:
            again, _ = _instantiate(code, path)
        except _NotADict as exc:
            raise ExternsFileFailed(path, f"`externs()` returned a {exc}, not a dict", "") from None
        except (Exception, SystemExit) as exc:
            raise ExternsFileFailed(path, f"it raised {_describe(exc)}", _where(exc)) from None
        return _wrap(again, externs)

    return make


def _instantiate(code, path: str) -> tuple[dict, bool]:
    """Run the file's code in a new module: its functions by name (or what
    its `externs()` returns), and whether they came from `externs()`."""
    global _modules
    _modules += 1
    name = f"rcsc_sim_externs_{_modules}"
    module = types.ModuleType(name)
    module.__file__ = path
    # Registered, as an imported module is: `dataclasses` and `typing` look
    # their module up by name.
    sys.modules[name] = module
    exec(code, module.__dict__)  # noqa: S102 - the user's own file, named on the command line
    factory = module.__dict__.get("externs")
    if callable(factory):
        impl = factory()
        if not isinstance(impl, dict):
            raise _NotADict(type(impl).__name__)
        return impl, True
    return {k: v for k, v in module.__dict__.items() if callable(v)}, False


def _check_names(impl: dict, externs: list[m.Function], path: str, diags: Diagnostics, from_dict: bool) -> None:
    names = {f.name for f in externs}
    candidates = [k for k, v in impl.items() if callable(v) and not k.startswith("_")]
    for f in externs:
        if callable(impl.get(f.name)):
            continue
        d = diags.add("W0830", name_span(f), f"extern `{f.name}` has no implementation in {path}: the simulator returns zero values for it",
                      "not in the externs file")
        close = difflib.get_close_matches(f.name, [c for c in candidates if c not in names], n=1)
        if close:
            d.with_help(f"the file defines `{close[0]}`: rename it `{f.name}`")
    if from_dict:
        for k in impl:
            if k not in names:
                diags.add("W0830", None, f"`externs()` in {path} returns `{k}`, which is no extern of the design")


def _wrap(impl: dict, externs: list[m.Function]) -> dict:
    out = {}
    for f in externs:
        fn = impl.get(f.name)
        if callable(fn):
            out[f.name] = _checked_call(f, fn)
    return out


def _checked_call(f: m.Function, fn: Callable) -> Callable:
    def call(*args):
        try:
            value = fn(*(clone(a) for a in args))
        except (Exception, SystemExit) as exc:
            raise ExternFailed(f, f"it raised {_describe(exc)}", _where(exc)) from None
        try:
            return conform(value, f.ret)
        except (TypeError, ValueError, OverflowError) as exc:
            raise ExternFailed(f, f"it returned {_short(value)}, {exc}", "") from None

    return call


def conform(value, t: Type):
    """`value` as the simulator holds a value of type `t`; TypeError says why it is not one."""
    if t == BOOL:
        if isinstance(value, bool):
            return value
        raise TypeError("not a `bool`")
    if isinstance(t, IntType) or t == DURATION:
        if isinstance(value, int) and not isinstance(value, bool):
            lo, hi = (t.min, t.max) if isinstance(t, IntType) else (-(2**63), 2**63 - 1)
            if lo <= value <= hi:
                return value
            raise TypeError(f"outside the range of `{t}`")
        raise TypeError(f"not an integer (`{t}`)")
    if isinstance(t, FloatType):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            try:
                return float(value)
            except OverflowError:
                raise TypeError("too large for `f64`") from None
        raise TypeError("not a number (`f64`)")
    if isinstance(t, EnumType):
        if isinstance(value, str) and value in t.members:
            return value
        raise TypeError(f"not a member of `{t.name}` (its names: {', '.join(t.members)})")
    if isinstance(t, RecordType):
        if not isinstance(value, dict) or set(value) != {n for n, _ in t.fields}:
            raise TypeError(f"not a `{t.name}` (a dict of the fields {', '.join(n for n, _ in t.fields)})")
        return {n: conform(value[n], ft) for n, ft in t.fields}
    if isinstance(t, ArrayType):
        if not isinstance(value, (list, tuple)) or len(value) != t.size:
            raise TypeError(f"not a `{t}` (a list of {t.size} elements)")
        return [conform(x, t.elem) for x in value]
    raise TypeError(f"of no type the simulator knows (`{t}`)")


def name_span(f: m.Function) -> Span:
    """The span of the extern's name in its declaration (the smallest span to point at)."""
    text = f.span.text
    at = text.find(f.name, text.find("fn") + 2)
    if at < 0:
        return f.span
    return Span(f.span.file, f.span.start + at, f.span.start + at + len(f.name))


def _describe(exc: BaseException) -> str:
    text = str(exc)
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _location(exc: BaseException, path: str) -> tuple[str, int, int | None]:
    """Where `exc` comes from: a syntax error's own place (maybe in a module
    the file imports), else the innermost frame in the externs file, else
    the innermost frame."""
    if isinstance(exc, SyntaxError) and exc.filename:
        return exc.filename, exc.lineno or 1, exc.offset
    frames = traceback.extract_tb(exc.__traceback__)
    mine = [fr for fr in frames if fr.filename == path]
    frame = mine[-1] if mine else (frames[-1] if frames else None)
    if frame is None:
        return path, 1, None
    return frame.filename, frame.lineno or 1, None


def _where(exc: BaseException) -> str:
    frames = traceback.extract_tb(exc.__traceback__)
    return f"raised at {frames[-1].filename}:{frames[-1].lineno}" if frames else ""


def _span_in(file: str, text: str | None, line: int, col: int | None) -> Span | None:
    """A span in `file` (read unless `text` is given), or None if it cannot be read."""
    if text is None:
        try:
            text = safeio.read_text(file)
        except OSError:
            return None
    return _line_span(SourceFile(file, text), line, col)


def _line_span(source: SourceFile, line: int, col: int | None) -> Span:
    """A span of one character at (line, col), or at the line's first non-blank character."""
    if col is None or col < 1:
        text = source.line_text(max(1, min(line, source.line_count)))
        col = len(text) - len(text.lstrip()) + 1
    at = source.offset(line, col)
    return Span(source, at, min(at + 1, len(source.text)))
