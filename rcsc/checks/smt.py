"""Guards as SMT terms: the encoding of typed IR expressions into z3.

The guard analysis (`rcsc.checks.guards`) asks z3 questions about the
conditions of a plan's rules: can this condition be true, can these two be
true together, can all of them be false.  This module turns one condition
(an `rcsc.semantics.model.Expr` of type bool) into a z3 term over the *inputs* the
controller can see when it decides, and turns a z3 model back into values of
those inputs (a witness).

Inputs and their domains
------------------------
Each input is one z3 variable (two for an f64) with the constraints of its
type and of its declared range (`f64 in 0.0..30.0`, `i32 in 0..3`: a
declared range is taken as an assumption on the value):

| input | z3 term |
|---|---|
| Global Memory `x`, local `x`, status field `x`, `cmd.x` | by type (below); a record is one variable per field |
| `SUB.done` / `.error` / `.executing` / `.AT_GOAL` | one view variable per subordinate over {none, executing, done, error, <extra statuses>} |
| `SUB.error_code`, `SUB.FIELD` | by type |
| `SUB.age`, `in_state` | duration, >= 0 and a whole number of the controller's heartbeats |
| `cycle` | i64, >= 1 (independent of `in_state` and the ages: an over-approximation) |

The subordinate's view mirrors `rcsc.sim.simulate._StepEnv.sub_view`: `none` is
"nothing sent yet", `executing` "sent, no final status for it yet"; `SUB.done`
is view == done, `SUB.error` view == error, `SUB.AT_GOAL` view == AT_GOAL and
`SUB.executing` view in {executing, <extra statuses>}.  So `TB.done and
TB.error` is impossible and `TB.AT_GOAL` excludes `TB.done`, as in the
simulator.

Types
-----
- bool: z3 Bool.  Enums and views: an integer holding the member's index,
  constrained to the members.  Both exact.
- i32, i64, u32 and durations (i64 nanoseconds): z3 integers constrained to
  the type's range, with the language's wrapping made explicit, so the
  encoding is exact: `+ - neg abs` wrap with one conditional
  (`x > MAX ? x - 2^n : ...`, exact because the operands are in range),
  products with a constant and conversions wrap with `mod 2^n`, integer
  division by a constant truncates toward zero (`/ 0` and `% 0` give 0,
  `MIN / -1` wraps), u32 compares as the unsigned number it is.  A product or
  quotient of two integer variables goes through bit-vectors (`int2bv`, the
  bit-vector operation, `bv2int`): exact too, only slower.  Why not
  bit-vectors throughout: a typical guard (`in_state >= 2 s and count < 3`,
  comparisons with constants, mixed with f64) is linear arithmetic, which z3
  decides about ten times faster over integers than bit-blasted, and
  conversions to and from f64 stay linear (`to_real`) instead of going
  through `bv2int`.
- f64: a real number plus a NaN flag.  NaN is exact: every comparison with
  NaN is false except `!=`, NaN propagates through arithmetic, `i32(NaN)` is
  0; so a guard pair `x > 0.0` / `x <= 0.0` does *not* cover a NaN sensor
  value, as on the machine.  What is approximate is arithmetic: `+ - * /` are
  computed exactly over the reals, without IEEE rounding, overflow to
  infinity or signed zeros, and an input is never +-infinity.  (z3's exact
  Float64 theory was measured at 0.7 to 9 s for one query of the size of
  `approx_eq` or `within_pct`, far too slow for a checker run on every edit.)
  Comparisons of inputs and constants are exact: every double is a rational.
  Findings whose conditions do f64 arithmetic say so in a note, and every
  witness is rounded to doubles and replayed with the reference evaluator:
  one that does not show the claim after rounding is marked approximate.
- A product or quotient of two f64 variables is an uninterpreted function (it
  is non-linear); so is a call of an `extern` function (its code is not in the
  design).  Both make a result approximate and the findings say so.  An
  uninterpreted function over-approximates: a condition proved impossible
  stays impossible whatever the real function does.

Pure functions are inlined (their body is one expression).  Expressions that
already have a type error are refused (`Unsupported`); the analysis then
skips the plan.
"""

from __future__ import annotations

import contextlib
import os
import math
from dataclasses import dataclass
from fractions import Fraction

import z3

from rcsc.semantics import model as m
from rcsc.semantics.types import BOOL, DURATION, I64, ArrayType, EnumType, ErrorType, FloatType, IntType, RecordType, Type

VIEW_BASE = ("none", "executing", "done", "error")

# Reasons a result is approximate (shown in findings).
APPROX_ARITH = "f64 arithmetic is computed over the reals (no rounding, overflow or infinities)"
APPROX_NONLINEAR = "a product or quotient of two f64 variables is treated as an unknown function"
APPROX_SQRT = "`sqrt` is treated as an unknown non-negative function"
APPROX_INFINITE = "an infinite f64 constant is treated as an unknown value"


def approx_extern(name: str) -> str:
    return f"`{name}` is an extern function: its results are treated as unknown"


class Unsupported(Exception):
    """The expression cannot be encoded."""


class HasTypeError(Unsupported):
    """The expression holds a type error (already reported by sema)."""


@dataclass
class F:
    """An f64 value: a real number and a NaN flag (the number is meaningless when NaN)."""

    r: z3.ArithRef
    nan: z3.BoolRef


class Rec:
    """A record value: its fields, made on first use (so unused fields add no inputs)."""

    def __init__(self, rtype: RecordType, make) -> None:
        self.rtype = rtype
        self._make = make
        self._fields: dict[str, object] = {}

    def __getitem__(self, name: str):
        if name not in self._fields:
            self._fields[name] = self._make(name)
        return self._fields[name]

    def values(self) -> list:
        return [self[name] for name, _ in self.rtype.fields]


class Arr:
    """An array value (bounded encoding): its elements, made on first use."""

    def __init__(self, atype: ArrayType, make) -> None:
        self.atype = atype
        self._make = make
        self._elems: dict[int, object] = {}

    def __getitem__(self, i: int):
        if i not in self._elems:
            self._elems[i] = self._make(i)
        return self._elems[i]

    def values(self) -> list:
        return [self[i] for i in range(self.atype.size)]


# The longest array indexed by a value the solver chooses: `a[k]` is encoded
# as `if k == 0 then a[0] elif ... else zero`, one case per element.
MAX_SYMBOLIC_INDEX = 64


@dataclass
class Input:
    """One input of a guard: a value the controller reads when it decides."""

    key: tuple  # identity, e.g. ("gm", "x"), ("param", "spec", "rpm"), ("view", "TB")
    name: str  # as the designer writes it: `x`, `cmd.spec.rpm`, `TB`, `TB.error_code`, `in_state`
    type: Type | None  # None for a subordinate view
    term: object  # z3 term, or F for an f64
    consts: list  # the z3 constants (for quantifying)
    constraint: z3.BoolRef  # its domain
    members: tuple[str, ...] = ()  # enum members, or the view's values

    @property
    def kind(self) -> str:
        return self.key[0]


@dataclass
class ExternCall:
    func: str
    arg_types: list[Type]
    args: list
    ret: Type
    result: object


@dataclass
class Encoding:
    """One guard: its term, the inputs it reads (in order of first use), its approximations."""

    term: z3.BoolRef
    inputs: list[tuple]
    approx: set[str]
    calls: list[ExternCall]
    f64_arith: bool = False


def wrap(x, t: IntType):
    """`x` reduced into `t`'s range, two's complement (exact for any integer term)."""
    return (x - t.min) % (1 << t.bits) + t.min


def wrap_once(x, t: IntType):
    """`x` reduced into `t`'s range when it is at most one period outside (sums, negations)."""
    span = 1 << t.bits
    return z3.If(x > t.max, x - span, z3.If(x < t.min, x + span, x))


def _bv(x, t: IntType):
    return z3.Int2BV(x, t.bits)


def _from_bv(x, t: IntType):
    return z3.BV2Int(x, is_signed=t.signed)


def int_divide(a, b, op: str, it: IntType):
    """`a / b` or `a % b` on integer type `it`, as rcsc defines them
    (`rcsc.semantics.numeric.int_div`/`int_rem`): truncation toward zero,
    0 for a zero divisor, MIN / -1 wraps to MIN and MIN % -1 is 0."""
    kb = _int_numeral(b)
    if kb is not None:
        if kb == 0:
            return z3.IntVal(0)
        # truncating division by a constant (z3's div is Euclidean)
        q = z3.If(a >= 0, a / abs(kb), -((-a) / abs(kb)))
        q = q if kb > 0 else -q
        if op == "/":
            return wrap_once(q, it)  # MIN / -1 wraps to MIN
        return a - q * kb
    # Truncating division by a variable, in integer arithmetic: z3's `div`
    # is Euclidean, so the quotient is taken of the magnitudes and given the
    # sign.  (The same question through bit-vectors, Int2BV/BV2Int, took the
    # solver about 100 times longer or ran out of its budget: it mixes two
    # theories.)
    if it.signed:
        q = z3.If(a >= 0, z3.If(b > 0, a / b, -(a / -b)), z3.If(b > 0, -(-a / b), -a / -b))
    else:
        q = a / b  # both operands are in 0..max
    r = wrap_once(q, it) if op == "/" else a - b * q
    return _ite(b == 0, z3.IntVal(0), r)


I64_T = I64  # durations are i64 nanoseconds


# z3 terms are hash-consed: `true` and `false` have one id each in a context,
# the same in every context (made first, when it is), and comparing ids is
# much cheaper than z3.is_true (several foreign calls).  They are read from
# the first context a check makes: making one at import would cost 10 ms
# of every `rcsc` command that imports the checks.
_bool_ids: tuple[int, int] | None = None


def _true_false_ids(ctx) -> tuple[int, int]:
    global _bool_ids
    if _bool_ids is None:
        _bool_ids = (z3.BoolVal(True, ctx).get_id(), z3.BoolVal(False, ctx).get_id())
    return _bool_ids


@contextlib.contextmanager
def own_context():
    """Make the z3 terms of one plan's analysis in a context of their own.

    The solvers run under a resource limit, and what a question costs
    depends on the context's history: terms made for earlier questions
    shift the numbering of new ones, so the order in which z3 meets them,
    so the work it does.  In a shared context, a question near the limit
    could then be decided in one run and given up on in another (W0518
    instead of a finding) depending on which plans were analysed before
    it: a check without the cache, one with it (which skips the stored
    plans), an incremental re-check and the language server could disagree.
    Each plan's analysis in a new context sees the same history whatever
    ran before, so the same answers.  The context is made when the first
    term is (z3 makes its default context on demand), so a plan that asks
    z3 nothing costs nothing; one that does pays about a millisecond.

    On leaving, the context is let go (the caller's is the default again),
    and so freed as soon as the last term made in it is.  That must be at once: the collector of cycles
    does not run during a check (`rcsc.driver.check_path`), so a context
    held by a cycle would stay until a long-lived process collects, and
    each one holds its terms' memory.  So the encoders made inside are
    emptied when it ends (`Encoder.close`), and tests/test_memory.py counts the
    contexts left after checking every example and test case."""
    if not _allocator_tuned:
        _keep_solver_memory()
    outer = getattr(z3.z3, "_main_ctx", None)
    z3.z3._main_ctx = None
    _open_encoders.append([])
    try:
        yield
    finally:
        for enc in _open_encoders.pop():
            enc.close()
        # The context of whoever called (an enclosing `own_context`, or the
        # shared one) is the default again.
        z3.z3._main_ctx = outer


# Whether `_keep_solver_memory` ran in this process.
_allocator_tuned = False

# glibc's `mallopt` parameters (malloc.h).
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3


def _keep_solver_memory() -> None:
    """Let the C allocator keep the memory of a freed z3 context for the next one.

    Each z3 context allocates two blocks of about 8.5 MB and frees them
    when it ends.  glibc's default thresholds are adaptive: the first such
    block is mapped, and once freed, raises the mapping threshold to its size
    and the trim threshold to twice it, about 17 MB.  From then on the
    blocks come from the top of the heap, and freeing both leaves just
    more than 17 MB free there, which glibc gives back to the system; the
    next context asks for it again, and the kernel hands out zeroed pages,
    one fault per 4 KB page.  On a design of 100 controllers that was 1.3
    million page faults, 2 s of system time on top of 3.9 s of work.
    Blocks up to 32 MB (glibc's largest mapping threshold) now come from
    the heap, and up to 32 MB free at its top stays in the process.  The
    peak memory is about the same (the blocks were in use at the peak
    anyway).  Only the speed changes, never a result; elsewhere than glibc
    nothing is done."""
    global _allocator_tuned
    _allocator_tuned = True
    import ctypes

    try:
        # glibc answers this; other C libraries do not know the name.
        libc = os.confstr("CS_GNU_LIBC_VERSION") or ""
    except (ValueError, OSError):
        return
    if not libc.startswith("glibc"):
        return
    mallopt = getattr(ctypes.CDLL(None), "mallopt", None)
    if mallopt is None:
        return
    mallopt(_M_MMAP_THRESHOLD, 32 << 20)
    mallopt(_M_TRIM_THRESHOLD, 32 << 20)


# The encoders made in each `own_context` entered and not yet left, the
# innermost last: closed when it ends (whether the analysis ended normally
# or with an exception).  An encoder made outside any is not held.
_open_encoders: list[list["Encoder"]] = []


def _is_true(x) -> bool:
    return x.get_id() == (_bool_ids or _true_false_ids(x.ctx))[0]


def _is_false(x) -> bool:
    return x.get_id() == (_bool_ids or _true_false_ids(x.ctx))[1]


def _mk_bool(mk, xs):
    """`z3.And(*xs)` / `z3.Or(*xs)` of Boolean terms, without the Python API's coercions.

    The same call of z3's C API makes the same term; only the checks and
    casts of arguments that are Boolean terms already are skipped.
    """
    ctx = xs[0].ctx
    if any(type(x) is not z3.BoolRef or x.ctx is not ctx for x in xs):
        return (z3.And if mk is z3.Z3_mk_and else z3.Or)(*xs)
    arr = (z3.Ast * len(xs))()
    for i, x in enumerate(xs):
        arr[i] = x.as_ast()
    return z3.BoolRef(mk(ctx.ref(), len(xs), arr), ctx)


def neg(x):
    """`z3.Not(x)`: the same term, without the Python API's cast when `x` is a Boolean term already."""
    if type(x) is z3.BoolRef:
        return z3.BoolRef(z3.Z3_mk_not(x.ctx.ref(), x.as_ast()), x.ctx)
    return z3.Not(x)


def _or(*xs):
    xs = [x for x in xs if not _is_false(x)]
    if any(_is_true(x) for x in xs):
        return z3.BoolVal(True)
    if not xs:
        return z3.BoolVal(False)
    return xs[0] if len(xs) == 1 else _mk_bool(z3.Z3_mk_or, xs)


def _and(*xs):
    xs = [x for x in xs if not _is_true(x)]
    if any(_is_false(x) for x in xs):
        return z3.BoolVal(False)
    if not xs:
        return z3.BoolVal(True)
    return xs[0] if len(xs) == 1 else _mk_bool(z3.Z3_mk_and, xs)


def _ite(c, a, b):
    if _is_true(c):
        return a
    if _is_false(c):
        return b
    return z3.If(c, a, b)


def _not(x):
    if _is_true(x):
        return z3.BoolVal(False)
    if _is_false(x):
        return z3.BoolVal(True)
    return neg(x)


def rational(fr: Fraction) -> z3.RatNumRef:
    return z3.RealVal(f"{fr.numerator}/{fr.denominator}")


def real_of(x: float) -> z3.RatNumRef:
    """The exact rational value of a double."""
    return rational(Fraction(x))


def _numeral(t) -> Fraction | None:
    if z3.is_rational_value(t):
        return t.as_fraction()
    return None


class Encoder:
    """Encodes the guards of one plan of one controller.

    One encoder per plan: the inputs are shared by the plan's rules, so that
    `x` in two conditions is one variable.
    """

    def __init__(self, design: m.Design, controller: m.Controller, verb: m.Verb | None, period_ns: int | None, nan_params: bool = True) -> None:
        self.design = design
        self.c = controller
        self.verb = verb
        # Whether an f64 command parameter can be NaN: only when a
        # supervisor sends the verb (operator commands cannot carry NaN).
        self.nan_params = nan_params
        self.period_ns = period_ns if period_ns and period_ns > 0 else None
        self.inputs: dict[tuple, Input] = {}
        self.side: list[z3.BoolRef] = []  # constraints of extern results
        self._ufs: dict[tuple, z3.FuncDeclRef] = {}
        self._used: dict[tuple, None] = {}
        self._approx: set[str] = set()
        self._calls: list[ExternCall] = []
        self._arith = False
        self.gm_types = {u.name: design.gm[u.name] for u in controller.reads + controller.writes if u.name in design.gm}
        if _open_encoders:
            _open_encoders[-1].append(self)

    def close(self) -> None:
        """Let go of every term once the plan is analysed.

        The records of a guard are made on demand by closures that name
        the encoder, and the encoder keeps the last guard's extern calls,
        which hold such records: a cycle.  Emptying the encoder breaks it,
        so its terms, and the plan's z3 context, are freed at once
        (`own_context`)."""
        self.inputs, self.side, self._ufs, self._calls, self._used = {}, [], {}, [], {}

    # ---- entry point ------------------------------------------------------------

    def guard(self, e: m.Expr) -> Encoding:
        self._used, self._approx, self._calls, self._arith = {}, set(), [], False
        t = self.expr(e, None)
        if not z3.is_bool(t):
            raise Unsupported("not a condition")
        return Encoding(t, list(self._used), set(self._approx), list(self._calls), self._arith)

    # ---- inputs -------------------------------------------------------------------

    def _input(self, key: tuple, name: str, t: Type | None, rng: m.Range | None = None, members: tuple[str, ...] = ()):
        inp = self.inputs.get(key)
        if inp is None:
            inp = self._make_input(key, name, t, rng, members)
            self.inputs[key] = inp
        self._used.setdefault(key, None)
        return inp.term

    def _make_input(self, key, name, t, rng, members) -> Input:
        vname = ".".join(str(k) for k in key)
        if t is None:  # a subordinate's view
            v = z3.Int(vname)
            return Input(key, name, None, v, [v], z3.And(v >= 0, v <= len(members) - 1), members)
        if t == BOOL:
            v = z3.Bool(vname)
            return Input(key, name, t, v, [v], z3.BoolVal(True))
        if isinstance(t, EnumType):
            v = z3.Int(vname)
            return Input(key, name, t, v, [v], z3.And(v >= 0, v <= len(t.members) - 1), tuple(t.members))
        if key[0] in ("in_state", "age", "gm_age"):
            # A whole number of periods (as the simulator counts them):
            # k * period with k in range, cheaper for the solver than a
            # divisibility constraint.  `in_state` counts the controller's own
            # steps; an age counts base ticks (the shortest heartbeat, which
            # divides every release instant and deadline).
            period = (self.period_ns if key[0] == "in_state" else self.design.base_tick_ns or self.period_ns) or 1
            k = z3.Int(vname + ".cycles")
            return Input(key, name, t, k * period if period != 1 else k, [k], z3.And(k >= 0, k <= I64_T.max // period))
        if isinstance(t, IntType) or t == DURATION:
            it = t if isinstance(t, IntType) else I64_T
            v = z3.Int(vname)
            lo, hi = (1, it.max) if key[0] == "cycle" else (it.min, it.max)  # steps count from 1
            if rng is not None and int(rng.lo) <= int(rng.hi):  # an empty range is E0206, not an assumption
                lo, hi = max(lo, int(rng.lo)), min(hi, int(rng.hi))
            return Input(key, name, t, v, [v], z3.And(v >= lo, v <= hi))
        if isinstance(t, FloatType):
            r, nan = z3.Real(vname), z3.Bool(vname + ".nan")
            cons = []
            if rng is not None and float(rng.lo) <= float(rng.hi):
                cons = [z3.Not(nan), r >= real_of(float(rng.lo)), r <= real_of(float(rng.hi))]
            elif key[0] == "param" and not self.nan_params:
                cons = [z3.Not(nan)]
            return Input(key, name, t, F(r, nan), [r, nan], _and(*cons))
        raise Unsupported(f"input of type {t}")

    def _var(self, key: tuple, name: str, t: Type, rng: m.Range | None = None):
        """A variable of any type: records become a Rec of field inputs."""
        if isinstance(t, RecordType):
            return Rec(t, lambda f, key=key, name=name, t=t: self._var(key + (f,), f"{name}.{f}", t.field_type(f), t.field_range(f)))  # type: ignore[arg-type]
        if isinstance(t, ArrayType):
            return Arr(t, lambda i, key=key, name=name, t=t: self._var(key + (i,), f"{name}[{i}]", t.elem))
        if isinstance(t, ErrorType):
            raise HasTypeError("error type")
        return self._input(key, name, t, rng)

    def view(self, sub: str) -> tuple[z3.ArithRef, tuple[str, ...]]:
        members = VIEW_BASE + tuple(self.design.controllers[sub].statuses)
        return self._input(("view", sub), sub, None, members=members), members

    # ---- expressions --------------------------------------------------------------

    def expr(self, e: m.Expr, args: dict | None):
        if isinstance(e.type, ErrorType):
            raise HasTypeError("type error")
        method = getattr(self, "e_" + type(e).__name__, None)
        if method is None:
            raise Unsupported(type(e).__name__)
        return method(e, args)

    def const(self, value, t: Type):
        if t == BOOL:
            return z3.BoolVal(bool(value))
        if isinstance(t, IntType) or t == DURATION:
            return z3.IntVal(int(value))
        if isinstance(t, FloatType):
            x = float(value)
            if math.isnan(x):
                return F(z3.RealVal(0), z3.BoolVal(True))
            if math.isinf(x):
                # One unknown for each sign, whatever the occurrence: `y >= -inf`
                # in one rule and `not (y >= -inf)` in another compare with the
                # same value, so they stay exclusive and cover every input
                # (fresh unknowns made both false: a false E0516).
                self._approx.add(APPROX_INFINITE)
                return F(z3.Real("inf.pos" if x > 0 else "inf.neg"), z3.BoolVal(False))
            return F(real_of(x), z3.BoolVal(False))
        if isinstance(t, EnumType):
            return z3.IntVal(t.members.index(value))
        if isinstance(t, RecordType):
            return Rec(t, lambda f: self.const(value[f], t.field_type(f)))  # type: ignore[arg-type]
        if isinstance(t, ArrayType):
            return Arr(t, lambda i: self.const(value[i], t.elem))
        raise Unsupported(f"constant of type {t}")

    def e_Const(self, e: m.Const, args):
        return self.const(e.value, e.type)

    def e_Ref(self, e: m.Ref, args):
        if e.kind == "arg":
            if args is None or e.name not in args:
                raise Unsupported("function argument outside a function")
            return args[e.name]
        if e.kind == "gm":
            var = self.gm_types.get(e.name)
            if var is None:
                raise Unsupported("unknown gm")
            return self._var(("gm", e.name), e.name, var.type, var.range)
        if e.kind == "local":
            var = self.c.locals.get(e.name)
            if var is None:
                raise Unsupported("unknown local")
            return self._var(("local", e.name), e.name, var.type, var.range)
        if e.kind == "status":
            var = self.c.status_fields.get(e.name)
            if var is None:
                raise Unsupported("unknown status field")
            return self._var(("status", e.name), e.name, var.type, var.range)
        if e.kind == "param":
            p = self.verb.param(e.name) if self.verb is not None else None
            if p is None:
                raise Unsupported("unknown parameter")
            return self._var(("param", e.name), f"cmd.{e.name}", p.type, p.range)
        raise Unsupported(f"reference kind {e.kind}")

    def e_InState(self, e: m.InState, args):
        return self._input(("in_state",), "in_state", DURATION)

    def e_Cycle(self, e: m.Cycle, args):
        return self._input(("cycle",), "cycle", I64)

    def e_Age(self, e: m.Age, args):
        return self._input(("gm_age", e.name), f"age({e.name})", DURATION)

    def e_SubView(self, e: m.SubView, args):
        sub = self.design.controllers.get(e.sub)
        if sub is None:
            raise Unsupported("unknown subordinate")
        if e.attr in ("done", "error", "executing", "status"):
            v, members = self.view(e.sub)
            if e.attr == "executing":
                idx = [members.index("executing")] + list(range(len(VIEW_BASE), len(members)))
                return _or(*[v == i for i in idx])
            name = e.value if e.attr == "status" else e.attr
            if name not in members:
                raise Unsupported("unknown status")
            return v == members.index(name)
        if e.attr == "error_code":
            return self._input(("error_code", e.sub), f"{e.sub}.error_code", e.type)
        if e.attr == "age":
            return self._input(("age", e.sub), f"{e.sub}.age", DURATION)
        if e.attr == "field":
            var = sub.status_fields.get(e.value or "")
            if var is None:
                raise Unsupported("unknown status field")
            return self._var(("subfield", e.sub, e.value), f"{e.sub}.{e.value}", var.type, var.range)
        raise Unsupported(f"view {e.attr}")

    def e_Field(self, e: m.Field, args):
        obj = self.expr(e.obj, args)
        if not isinstance(obj, Rec):
            raise Unsupported("field of a non-record")
        return obj[e.name]

    def e_Index(self, e: m.Index, args):
        """The element, or the element type's zero out of range (as every execution)."""
        from rcsc.semantics.evaluate import zero_value

        obj = self.expr(e.obj, args)
        idx = self.expr(e.index, args)
        if not isinstance(obj, Arr):
            raise Unsupported("index of a non-array")
        size = obj.atype.size
        known = _int_numeral(idx)
        if known is not None:
            return obj[known] if 0 <= known < size else self.const(zero_value(e.type), e.type)
        if size > MAX_SYMBOLIC_INDEX:
            raise Unsupported("variable index into a long array")
        out = self.const(zero_value(e.type), e.type)
        for i in reversed(range(size)):
            out = self.merge(idx == i, obj[i], out, e.type)
        return out

    def e_ArrayLit(self, e: m.ArrayLit, args):
        return Arr(e.type, lambda i: self.expr(e.items[i], args))  # type: ignore[arg-type]

    def e_Unary(self, e: m.Unary, args):
        v = self.expr(e.operand, args)
        if e.op == "not":
            return _not(v)
        if isinstance(v, F):
            self._arith = True
            return F(-v.r, v.nan)
        return wrap_once(-v, e.type if isinstance(e.type, IntType) else I64_T)

    def e_IfExpr(self, e: m.IfExpr, args):
        c = self.expr(e.cond, args)
        if _is_true(c):
            return self.expr(e.then, args)
        if _is_false(c):
            return self.expr(e.else_, args)
        return self.merge(c, self.expr(e.then, args), self.expr(e.else_, args), e.type)

    def merge(self, c, a, b, t: Type):
        if isinstance(a, F):
            return F(_ite(c, a.r, b.r), _ite(c, a.nan, b.nan))
        if isinstance(a, Rec):
            return Rec(a.rtype, lambda f: self.merge(c, a[f], b[f], a.rtype.field_type(f)))  # type: ignore[arg-type]
        if isinstance(a, Arr):
            return Arr(a.atype, lambda i: self.merge(c, a[i], b[i], a.atype.elem))
        return _ite(c, a, b)

    def e_Binary(self, e: m.Binary, args):
        op = e.op
        if op in ("and", "or"):
            a = self.expr(e.left, args)
            b = self.expr(e.right, args)
            return _and(a, b) if op == "and" else _or(a, b)
        a = self.expr(e.left, args)
        b = self.expr(e.right, args)
        operand_t = e.left.type
        if e.type == BOOL and op in ("==", "!=", "<", "<=", ">", ">="):
            return self.compare(op, a, b, operand_t)
        return self.arith(op, a, b, e.type)

    def compare(self, op: str, a, b, t: Type):
        if isinstance(a, F):
            if op == "!=":
                return _or(a.nan, b.nan, a.r != b.r)
            rel = {"==": lambda: a.r == b.r, "<": lambda: a.r < b.r, "<=": lambda: a.r <= b.r,
                   ">": lambda: a.r > b.r, ">=": lambda: a.r >= b.r}[op]()
            return _and(_not(a.nan), _not(b.nan), rel)
        if isinstance(a, Rec):
            raise Unsupported("record comparison")
        if op == "==":
            return a == b
        if op == "!=":
            return a != b
        return {"<": lambda: a < b, "<=": lambda: a <= b, ">": lambda: a > b, ">=": lambda: a >= b}[op]()

    def arith(self, op: str, a, b, t: Type):
        if isinstance(t, FloatType):
            self._arith = True
            nan = _or(a.nan, b.nan)
            if op == "+":
                return F(a.r + b.r, nan)
            if op == "-":
                return F(a.r - b.r, nan)
            if op == "*":
                if _numeral(a.r) is not None or _numeral(b.r) is not None:
                    return F(a.r * b.r, nan)
                self._approx.add(APPROX_NONLINEAR)
                return F(self._uf("f64.mul", [z3.RealSort(), z3.RealSort()], z3.RealSort())(a.r, b.r), nan)
            if op == "/":
                k = _numeral(b.r)
                if k is not None and k != 0:
                    return F(a.r * rational(1 / k), nan)
                # x / 0.0 is +-inf (or NaN for 0 / 0); x / y is non-linear.
                self._approx.add(APPROX_NONLINEAR if k is None else APPROX_INFINITE)
                q = self._uf("f64.div", [z3.RealSort(), z3.RealSort()], z3.RealSort())(a.r, b.r)
                return F(q, _or(nan, _and(a.r == 0, b.r == 0)))
            raise Unsupported(f"f64 {op}")
        if isinstance(t, IntType) or t == DURATION:
            it = t if isinstance(t, IntType) else I64_T
            if op == "+":
                return wrap_once(a + b, it)
            if op == "-":
                return wrap_once(a - b, it)
            ka, kb = _int_numeral(a), _int_numeral(b)
            if op == "*":
                if ka is not None or kb is not None:
                    return wrap(a * b, it)
                return _from_bv(_bv(a, it) * _bv(b, it), it)
            if op in ("/", "%"):
                return int_divide(a, b, op, it)
        raise Unsupported(f"{op} on {t}")

    def e_Call(self, e: m.Call, args):
        vals = [self.expr(a, args) for a in e.args]
        if e.kind == "convert":
            return self.convert(vals[0], e.args[0].type, e.type)
        if e.kind == "record":
            names = [n for n, _ in e.type.fields]  # type: ignore[attr-defined]
            by_name = dict(zip(names, vals))
            return Rec(e.type, lambda f: by_name[f])  # type: ignore[arg-type]
        if e.kind == "builtin":
            return self.builtin(e.func, vals, e.type, e.args)
        if e.kind == "fn":
            fn = self.design.functions.get(e.func)
            if fn is None or fn.body is None:
                raise Unsupported("unknown function")
            return self.expr(fn.body, {p.name: v for p, v in zip(fn.params, vals)})
        if e.kind == "extern":
            return self.extern(e, vals)
        raise Unsupported(f"call kind {e.kind}")

    def builtin(self, name: str, vals: list, t: Type, arg_exprs: list):
        if name == "seconds":
            self._arith = True
            return F(z3.ToReal(vals[0]) / 10**9, z3.BoolVal(False))
        if name == "abs":
            x = vals[0]
            if isinstance(x, F):
                return F(_ite(x.r < 0, -x.r, x.r), x.nan)
            it = t if isinstance(t, IntType) else I64_T
            return _ite(x < 0, wrap_once(-x, it), x)  # abs(MIN) wraps to MIN, as numeric.wrap does
        if name in ("min", "max"):
            a, b = vals
            if isinstance(a, F):
                cond = a.r <= b.r if name == "min" else a.r >= b.r
                return F(_ite(cond, a.r, b.r), _or(a.nan, b.nan))
            return _ite(a <= b if name == "min" else a >= b, a, b)
        if name in ("floor", "ceil", "trunc", "round_even"):
            # Exact over the reals (an input is never infinite; the sign of a
            # zero result is not modelled, and no comparison can see it).
            x = vals[0]
            r = x.r
            if name == "floor":
                k = z3.ToInt(r)
            elif name == "ceil":
                k = -z3.ToInt(-r)
            elif name == "trunc":
                k = z3.If(r >= 0, z3.ToInt(r), -z3.ToInt(-r))
            else:
                f = z3.ToInt(r)
                d = r - z3.ToReal(f)
                half = z3.RealVal("1/2")
                k = z3.If(d < half, f, z3.If(d > half, f + 1, z3.If(f % 2 == 0, f, f + 1)))
            return F(z3.ToReal(k), x.nan)
        if name == "copysign":
            x, y = vals
            self._arith = True  # a -0.0 `y` is not modelled
            mag = _ite(x.r < 0, -x.r, x.r)
            return F(_ite(_or(y.nan, y.r >= 0), mag, -mag), x.nan)
        if name == "sqrt":
            # An unknown non-negative function of x (exact square roots are
            # non-linear): what is proved impossible stays impossible.
            x = vals[0]
            self._approx.add(APPROX_SQRT)
            root = self._uf("sqrt", [z3.RealSort()], z3.RealSort())(x.r)
            self.side.append(root >= 0)
            self.side.append(z3.Implies(x.r == 0, root == 0))
            return F(root, _or(x.nan, x.r < 0))
        if name in ("sum", "min_of", "max_of"):
            arr = vals[0]
            if not isinstance(arr, Arr) or arr.atype.size > MAX_SYMBOLIC_INDEX:
                raise Unsupported(f"builtin {name} of a long array")
            acc = arr[0]
            for i in range(1, arr.atype.size):
                if name == "sum":
                    acc = self.arith("+", acc, arr[i], t)
                else:
                    acc = self.builtin(name[:3], [acc, arr[i]], t, arg_exprs)
            return acc
        raise Unsupported(f"builtin {name}")

    def convert(self, v, source: Type, target: Type):
        if isinstance(target, FloatType):
            if isinstance(source, FloatType):
                return v
            assert isinstance(source, IntType)
            if source.bits > 53:
                self._arith = True  # large i64 values round
            return F(z3.ToReal(v), z3.BoolVal(False))
        assert isinstance(target, IntType)
        if isinstance(source, FloatType):
            # Saturating, toward zero, NaN gives 0 (numeric.float_to_int).
            r = v.r
            trunc = z3.If(r >= 0, z3.ToInt(r), -z3.ToInt(-r))
            value = _ite(r >= target.max, z3.IntVal(target.max), _ite(r <= target.min, z3.IntVal(target.min), trunc))
            return _ite(v.nan, z3.IntVal(0), value)
        assert isinstance(source, IntType)
        if source.min >= target.min and source.max <= target.max:
            return v  # widening: the value is unchanged
        return wrap(v, target)

    # ---- externs ------------------------------------------------------------------

    def _uf(self, name: str, domain: list, rng) -> z3.FuncDeclRef:
        key = (name, tuple(str(s) for s in domain), str(rng))
        f = self._ufs.get(key)
        if f is None:
            f = z3.Function(name, *domain, rng)
            self._ufs[key] = f
        return f

    def extern(self, e: m.Call, vals: list):
        fn = self.design.functions.get(e.func)
        if fn is None:
            raise Unsupported("unknown extern")
        self._approx.add(approx_extern(e.func))
        flat = []
        for v in vals:
            flat.extend(flatten(v))
        domain = [x.sort() for x in flat]
        result = self._extern_leaf(e.func, e.type, (), flat, domain)
        self._calls.append(ExternCall(e.func, [p.type for p in fn.params], vals, e.type, result))
        return result

    def _extern_leaf(self, func: str, t: Type, path: tuple, flat: list, domain: list):
        """The result of an extern call, or the field `path` of it: a function of its arguments.

        A method, not a closure that calls itself: such a closure is a
        cycle, which would keep the terms (and their z3 context) alive
        after the plan's analysis (`own_context`)."""
        tag = ".".join((f"extern.{func}",) + path)
        if isinstance(t, RecordType):
            return Rec(t, lambda f: self._extern_leaf(func, t.field_type(f), path + (f,), flat, domain))  # type: ignore[arg-type]
        if isinstance(t, FloatType):
            r = self._uf(tag, domain, z3.RealSort())(*flat) if flat else z3.Real(tag)
            nan = self._uf(tag + ".nan", domain, z3.BoolSort())(*flat) if flat else z3.Bool(tag + ".nan")
            return F(r, nan)
        sort = _sort_of(t)
        term = self._uf(tag, domain, sort)(*flat) if flat else z3.Const(tag, sort)
        if isinstance(t, EnumType):
            self.side.append(z3.And(term >= 0, term <= len(t.members) - 1))
        elif isinstance(t, IntType) or t == DURATION:
            it = t if isinstance(t, IntType) else I64_T
            self.side.append(z3.And(term >= it.min, term <= it.max))
        return term


def _sort_of(t: Type):
    if t == BOOL:
        return z3.BoolSort()
    if isinstance(t, (IntType, EnumType)) or t == DURATION:
        return z3.IntSort()
    raise Unsupported(f"sort of {t}")


def _int_numeral(t) -> int | None:
    if z3.is_int_value(t):
        return t.as_long()
    return None


def flatten(v) -> list:
    """The z3 terms of a value (records field by field, f64 as number and NaN flag)."""
    if isinstance(v, F):
        return [v.r, v.nan]
    if isinstance(v, (Rec, Arr)):
        out = []
        for x in v.values():
            out.extend(flatten(x))
        return out
    return [v]


# ---- from a model back to values ------------------------------------------------------


def _rational(t) -> Fraction:
    if z3.is_rational_value(t):
        return t.as_fraction()
    if z3.is_algebraic_value(t):
        return Fraction(t.approx(30).as_fraction())
    if z3.is_int_value(t):
        return Fraction(t.as_long())
    raise ValueError(f"not a number: {t}")


def to_f64(x: Fraction) -> float:
    """The f64 nearest to a real of a model: beyond the largest finite f64 a
    real rounds to an infinity, as the f64 arithmetic of the targets does
    (`float()` of a `Fraction` rounds correctly but raises there)."""
    try:
        return float(x)
    except OverflowError:
        return math.inf if x > 0 else -math.inf


def concrete(model: z3.ModelRef, v, t: Type | None, members: tuple[str, ...] = ()):
    """The Python value (as the simulator holds it) of an encoded value in `model`."""
    if isinstance(v, F):
        if z3.is_true(model.eval(v.nan, model_completion=True)):
            return math.nan
        return to_f64(_rational(model.eval(v.r, model_completion=True)))
    if isinstance(v, Rec):
        return {name: concrete(model, v[name], ft) for name, ft in v.rtype.fields}
    val = model.eval(v, model_completion=True)
    if t == BOOL:
        return z3.is_true(val)
    n = val.as_long()
    if t is None or isinstance(t, EnumType):
        names = members or tuple(t.members)  # type: ignore[union-attr]
        return names[min(max(n, 0), len(names) - 1)]
    return n


def format_value(value, t: Type | None) -> str:
    """A value as the designer would write it."""
    from rcsc.checks.timing import fmt_ns

    if isinstance(value, bool):
        return "true" if value else "false"
    if t == DURATION:
        return fmt_ns(int(value))
    if isinstance(t, EnumType):
        return f"{t.name}.{value}"
    if isinstance(value, float):
        if math.isnan(value):
            return "NaN"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, dict) and isinstance(t, RecordType):
        inner = ", ".join(f"{n} = {format_value(value[n], ft)}" for n, ft in t.fields)
        return f"{t.name}({inner})"
    if isinstance(value, list) and isinstance(t, ArrayType):
        return "[" + ", ".join(format_value(v, t.elem) for v in value) + "]"
    return str(value)


def json_value(value, t: Type | None):
    """A value for the JSON/SARIF witness: numbers stay numbers, enums are `Enum.MEMBER`."""
    if isinstance(t, EnumType):
        return f"{t.name}.{value}"
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, dict) and isinstance(t, RecordType):
        return {n: json_value(value[n], ft) for n, ft in t.fields}
    if isinstance(value, list) and isinstance(t, ArrayType):
        return [json_value(v, t.elem) for v in value]
    return value
