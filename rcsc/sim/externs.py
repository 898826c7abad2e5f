"""Extern functions for the simulator, written in Python (`rcsc sim --externs FILE.py`).

The simulator has no model of the hand-written target code behind an
`extern fn`: without help, a call returns the zero value of its type, as the
generated stubs do.  A design whose externs matter (a `hypot`, an `atan2`, a
lookup table) can be simulated with a Python file that stands in for them:

* a function named like each extern, taking and returning simulator values
  (an `int` for the integer types and `duration`, in nanoseconds; a `float`;
  a `bool`; an enum member's name as a `str`; a record as a `dict` of its
  fields; an array as a `list`), or
* a function `externs()` returning a `dict` of them by name, called once per
  CPU: each CPU's Main Program has its own externs, so an extern that keeps
  state (a counter, a filter) keeps it per CPU.

The file is loaded as a Python module (it is your code: it runs with your
rights).  What goes wrong is a finding, never a traceback: the file cannot be
read or raises while it loads (E0830); an extern has no implementation
(W0830: it returns zero values, as before); a call raises or returns a value
that is not of the extern's type (E0831, which stops the run: the trace after
it would not be the design's).
"""

from __future__ import annotations

import difflib
import traceback
import types
from collections.abc import Callable

from rcsc.diagnostics import Diagnostics
from rcsc.front.source import SourceFile, Span
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


def load(path: str, design: m.Design, diags: Diagnostics) -> Callable[[], dict] | None:
    """The externs of `path` for `design` as a function making one set per CPU
    (`rcsc.sim.runner.run_scenario`); None after E0830."""
    try:
        with open(path, "rb") as f:
            raw = f.read()
        text = raw.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        diags.add("E0830", None, f"cannot read the externs file {path}: {getattr(exc, 'strerror', None) or exc}")
        return None
    source = SourceFile(path, text)
    module = types.ModuleType("rcsc_sim_externs")
    module.__file__ = path
    try:
        code = compile(text, path, "exec")
        exec(code, module.__dict__)  # noqa: S102 - the user's own file, named on the command line
    except SyntaxError as exc:
        d = diags.add("E0830", _line_span(source, exc.lineno or 1, exc.offset), f"the externs file does not load: {exc.msg}", "here")
        d.with_help(f"the file is Python: fix it, and check it with `python {path}`")
        return None
    except Exception as exc:  # the user's code may raise anything while it loads
        line = _line_in(exc, path)
        d = diags.add("E0830", _line_span(source, line or 1, None), f"the externs file does not load: it raised {_describe(exc)}", "raised here")
        d.with_help(f"the file is Python: fix it, and check it with `python {path}`")
        return None

    externs = [f for f in design.functions.values() if f.extern]
    factory = module.__dict__.get("externs")
    if callable(factory):
        try:
            first = factory()
        except Exception as exc:
            diags.add("E0830", _line_span(source, _line_in(exc, path) or 1, None),
                      f"`externs()` raised {_describe(exc)}", "raised here")
            return None
        if not isinstance(first, dict):
            diags.add("E0830", None, f"`externs()` in {path} returned a {type(first).__name__}, not a dict of functions by name")
            return None
        _check_names(first, externs, path, diags, from_dict=True)
        made = [first]

        def make() -> dict:
            # The set made to check the names serves the first CPU.
            impl = made.pop() if made else factory()
            return _wrap(impl if isinstance(impl, dict) else {}, externs, path)

        return make
    found = {f.name: module.__dict__[f.name] for f in externs if callable(module.__dict__.get(f.name))}
    _check_names(module.__dict__, externs, path, diags, from_dict=False)
    return lambda: _wrap(found, externs, path)


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


def _wrap(impl: dict, externs: list[m.Function], path: str) -> dict:
    out = {}
    for f in externs:
        fn = impl.get(f.name)
        if callable(fn):
            out[f.name] = _checked_call(f, fn, path)
    return out


def _checked_call(f: m.Function, fn: Callable, path: str) -> Callable:
    def call(*args):
        try:
            value = fn(*(clone(a) for a in args))
        except Exception as exc:
            raise ExternFailed(f, f"it raised {_describe(exc)}", _where(exc, path)) from None
        try:
            return conform(value, f.ret)
        except TypeError as exc:
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
            return float(value)
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


def _line_in(exc: BaseException, path: str) -> int | None:
    """The line of the externs file where `exc` was raised (its innermost frame there)."""
    line = None
    for frame in traceback.extract_tb(exc.__traceback__):
        if frame.filename == path:
            line = frame.lineno
    return line


def _where(exc: BaseException, path: str) -> str:
    line = _line_in(exc, path)
    return f"raised at {path}:{line}" if line else ""


def _line_span(source: SourceFile, line: int, col: int | None) -> Span:
    """A span of one character at (line, col), or of the line's first non-blank character."""
    lines = source.text.splitlines(keepends=True)
    line = max(1, min(line, len(lines) or 1))
    start = sum(len(x) for x in lines[: line - 1])
    text = lines[line - 1] if lines else ""
    if col is not None and col >= 1:
        offset = min(col - 1, max(len(text.rstrip("\r\n")) - 1, 0))
    else:
        offset = len(text) - len(text.lstrip())
    at = min(start + offset, len(source.text))
    return Span(source, at, min(at + 1, len(source.text)))
