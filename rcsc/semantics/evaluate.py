"""Evaluation of typed expressions under the language's numeric rules.

One evaluator serves the constant folder (where every reference is an error:
`NotConstant`) and the reference simulator (which supplies an `Env` that reads
variables, the subordinates' status and the time in state).
"""

from __future__ import annotations

import math
import operator

from rcsc.semantics import model as m
from rcsc.semantics import numeric
from rcsc.semantics.types import BOOL, DURATION, F64, I64, ArrayType, EnumType, FloatType, IntType, RecordType, Type


class NotConstant(Exception):
    """The expression reads something that is only known at run time."""

    def __init__(self, expr: m.Expr) -> None:
        super().__init__("not constant")
        self.expr = expr


class Env:
    """What an expression can read.  The base class knows nothing (constant folding)."""

    def ref(self, e: m.Ref):
        raise NotConstant(e)

    def in_state(self, e: m.InState):
        raise NotConstant(e)

    def sub_view(self, e: m.SubView):
        raise NotConstant(e)

    def cycle(self, e: m.Cycle):
        raise NotConstant(e)

    def age(self, e: m.Age):
        raise NotConstant(e)

    def call_extern(self, e: m.Call, args: list):
        raise NotConstant(e)

    def function(self, name: str) -> m.Function:
        raise NotConstant(None)  # type: ignore[arg-type]

    def other(self, e: m.Expr):
        """A node that only this environment understands (e.g. a scenario's observation)."""
        raise NotConstant(e)


CONST_ENV = Env()


def convert(value, source: Type, target: Type):
    """Explicit conversion `target(value)` between numeric types."""
    if isinstance(target, FloatType):
        return float(value)
    assert isinstance(target, IntType)
    if isinstance(source, FloatType):
        return numeric.float_to_int(value, target)
    return numeric.wrap(int(value), target)


def zero_value(t: Type):
    """The zero value of type `t`: false, 0, 0.0, the first enum member, a
    record or array of zeros.  An out-of-range array read gives it."""
    if t == BOOL:
        return False
    if isinstance(t, FloatType):
        return 0.0
    if isinstance(t, IntType) or t == DURATION:
        return 0
    if isinstance(t, EnumType):
        return t.members[0] if t.members else ""
    if isinstance(t, RecordType):
        return {name: zero_value(ft) for name, ft in t.fields}
    if isinstance(t, ArrayType):
        return [zero_value(t.elem) for _ in range(t.size)]
    return 0


def _min(a, b, t: Type):
    # f64: NaN if either is NaN, -0.0 below 0.0 (the scalar built-in's rule).
    if t == F64:
        return numeric.f64_min(a, b)
    return a if a <= b else b


def _max(a, b, t: Type):
    if t == F64:
        return numeric.f64_max(a, b)
    return a if a >= b else b


def _arith(op: str, a, b, t: Type):
    if isinstance(t, IntType) or t == DURATION:
        it = t if isinstance(t, IntType) else I64
        if op == "+":
            return numeric.wrap(a + b, it)
        if op == "-":
            return numeric.wrap(a - b, it)
        if op == "*":
            return numeric.wrap(a * b, it)
        if op == "/":
            return numeric.int_div(a, b, it)
        if op == "%":
            return numeric.int_rem(a, b, it)
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if op == "/":
        return numeric.float_div(a, b)
    raise ValueError(op)


def eval_expr(e: m.Expr, env: Env = CONST_ENV, fn_args: dict | None = None):
    """The value of `e`.  Raises NotConstant when `env` cannot supply a read.

    Each expression is compiled once into a Python closure (kept on the node)
    and the closure is what runs: the simulator evaluates the same guards and
    jobs every cycle, and a closure avoids re-dispatching on the node types.
    """
    return _sub(e)(env, fn_args)


def _compile(e: m.Expr):
    f = _COMPILERS.get(type(e), _c_other)(e)
    # Kept with the node it belongs to, so that a copied node (whose closure
    # would still read the original) is recompiled rather than trusted.
    e._compiled = (e, f)
    return f


def _sub(e: m.Expr):
    entry = getattr(e, "_compiled", None)
    return entry[1] if entry is not None and entry[0] is e else _compile(e)


def _c_const(e):
    value = e.value
    return lambda env, a: value


def _c_ref(e):
    if e.kind == "arg":
        name = e.name
        return lambda env, a: a[name] if a is not None else env.ref(e)
    return lambda env, a: env.ref(e)


def _c_in_state(e):
    return lambda env, a: env.in_state(e)


def _c_cycle(e):
    return lambda env, a: env.cycle(e)


def _c_sub_view(e):
    return lambda env, a: env.sub_view(e)


def _c_age(e):
    return lambda env, a: env.age(e)


def _c_field(e):
    obj, name = _sub(e.obj), e.name
    return lambda env, a: obj(env, a)[name]


def _c_index(e):
    obj, idx = _sub(e.obj), _sub(e.index)
    size = e.obj.type.size
    zero = zero_value(e.type)
    if isinstance(zero, (dict, list)):
        from copy import deepcopy

        return lambda env, a: _element(obj(env, a), idx(env, a), size, zero, deepcopy)
    return lambda env, a: _element(obj(env, a), idx(env, a), size, zero, None)


def _element(values, i, size, zero, copy):
    """Element i of an array, or the element type's zero out of range."""
    if 0 <= i < size:
        return values[i]
    return copy(zero) if copy is not None else zero


def _c_array(e):
    items = [_sub(x) for x in e.items]
    return lambda env, a: [f(env, a) for f in items]


def _c_unary(e):
    v = _sub(e.operand)
    if e.op == "not":
        return lambda env, a: not v(env, a)
    if isinstance(e.type, IntType) or e.type == DURATION:
        t = e.type if isinstance(e.type, IntType) else I64
        return lambda env, a: numeric.wrap(-v(env, a), t)
    return lambda env, a: -v(env, a)


_COMPARE = {"==": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge}


def _c_binary(e):
    op, lf, rf = e.op, _sub(e.left), _sub(e.right)
    if op == "and":
        return lambda env, a: bool(lf(env, a)) and bool(rf(env, a))
    if op == "or":
        return lambda env, a: bool(lf(env, a)) or bool(rf(env, a))
    if e.type == BOOL:
        cmp = _COMPARE[op]
        return lambda env, a: cmp(lf(env, a), rf(env, a))
    t = e.type
    if isinstance(t, IntType) or t == DURATION:
        it = t if isinstance(t, IntType) else I64
        wrap = numeric.wrap
        if op == "+":
            return lambda env, a: wrap(lf(env, a) + rf(env, a), it)
        if op == "-":
            return lambda env, a: wrap(lf(env, a) - rf(env, a), it)
        if op == "*":
            return lambda env, a: wrap(lf(env, a) * rf(env, a), it)
        if op == "/":
            return lambda env, a: numeric.int_div(lf(env, a), rf(env, a), it)
        if op == "%":
            return lambda env, a: numeric.int_rem(lf(env, a), rf(env, a), it)
    if op == "+":
        return lambda env, a: lf(env, a) + rf(env, a)
    if op == "-":
        return lambda env, a: lf(env, a) - rf(env, a)
    if op == "*":
        return lambda env, a: lf(env, a) * rf(env, a)
    if op == "/":
        return lambda env, a: numeric.float_div(lf(env, a), rf(env, a))
    raise ValueError(op)


def _c_if(e):
    c, t, f = _sub(e.cond), _sub(e.then), _sub(e.else_)
    return lambda env, a: t(env, a) if c(env, a) else f(env, a)


def _c_call(e):
    argfs = [_sub(x) for x in e.args]
    if e.kind == "fn":
        name = e.func

        def call_fn(env, a):
            values = [g(env, a) for g in argfs]
            fn = env.function(name)
            return _sub(fn.body)(env, {p.name: v for p, v in zip(fn.params, values)})

        return call_fn
    return lambda env, a: _call(e, [g(env, a) for g in argfs], env)


def _c_other(e):
    return lambda env, a: env.other(e)


_COMPILERS = {
    m.Const: _c_const,
    m.Ref: _c_ref,
    m.InState: _c_in_state,
    m.SubView: _c_sub_view,
    m.Cycle: _c_cycle,
    m.Age: _c_age,
    m.Field: _c_field,
    m.Unary: _c_unary,
    m.Binary: _c_binary,
    m.IfExpr: _c_if,
    m.Call: _c_call,
    m.Index: _c_index,
    m.ArrayLit: _c_array,
}


_MATH = {
    "sqrt": numeric.f64_sqrt,
    "floor": numeric.f64_floor,
    "ceil": numeric.f64_ceil,
    "trunc": numeric.f64_trunc,
    "round_even": numeric.f64_round_even,
    "copysign": numeric.f64_copysign,
}


def _call(e: m.Call, args: list, env: Env):
    if e.kind == "convert":
        return convert(args[0], e.args[0].type, e.type)
    if e.kind == "record":
        fields = [name for name, _ in e.type.fields]  # type: ignore[attr-defined]
        return dict(zip(fields, args))
    if e.kind == "builtin":
        if e.func == "abs":
            v = args[0]
            if isinstance(e.type, IntType) or e.type == DURATION:
                return numeric.wrap(abs(v), e.type if isinstance(e.type, IntType) else I64)
            return math.fabs(v)
        if e.func == "seconds":
            return args[0] / 1e9
        if e.func == "min":
            return _min(args[0], args[1], e.type)
        if e.func == "max":
            return _max(args[0], args[1], e.type)
        math_fn = _MATH.get(e.func)
        if math_fn is not None:
            return math_fn(*args)
        if e.func in ("sum", "min_of", "max_of"):
            # From the first element to the last, one operation at a time
            # (the order the generated loops use: f64 sums are not associative).
            values = args[0]
            acc = values[0]
            for v in values[1:]:
                if e.func == "sum":
                    acc = _arith("+", acc, v, e.type)
                elif e.func == "min_of":
                    acc = _min(acc, v, e.type)
                else:
                    acc = _max(acc, v, e.type)
            return acc
        raise ValueError(e.func)
    if e.kind == "extern":
        return env.call_extern(e, args)
    fn = env.function(e.func)
    assert fn.body is not None
    return eval_expr(fn.body, env, {p.name: v for p, v in zip(fn.params, args)})
