"""Evaluation of typed expressions under the language's numeric rules.

One evaluator serves the constant folder (where every reference is an error:
`NotConstant`) and the reference simulator (which supplies an `Env` that reads
variables, the subordinates' status and the time in state).
"""

from __future__ import annotations

import math

from rcsc import model as m
from rcsc import numeric
from rcsc.types import BOOL, DURATION, F64, I64, FloatType, IntType, Type


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


def _compare(op: str, a, b) -> bool:
    if op == "==":
        return a == b
    if op == "!=":
        return a != b
    if op == "<":
        return a < b
    if op == "<=":
        return a <= b
    if op == ">":
        return a > b
    if op == ">=":
        return a >= b
    raise ValueError(op)


def eval_expr(e: m.Expr, env: Env = CONST_ENV, fn_args: dict | None = None):
    """The value of `e`.  Raises NotConstant when `env` cannot supply a read."""
    # Dispatch on the node's exact type: this is the simulator's inner loop.
    return _EVAL.get(type(e), _e_other)(e, env, fn_args)


def _e_const(e, env, fn_args):
    return e.value


def _e_ref(e, env, fn_args):
    if e.kind == "arg" and fn_args is not None:
        return fn_args[e.name]
    return env.ref(e)


def _e_in_state(e, env, fn_args):
    return env.in_state(e)


def _e_sub_view(e, env, fn_args):
    return env.sub_view(e)


def _e_field(e, env, fn_args):
    return eval_expr(e.obj, env, fn_args)[e.name]


def _e_unary(e, env, fn_args):
    v = eval_expr(e.operand, env, fn_args)
    if e.op == "not":
        return not v
    if isinstance(e.type, IntType):
        return numeric.wrap(-v, e.type)
    if e.type == DURATION:
        return numeric.wrap(-v, I64)
    return -v


def _e_binary(e, env, fn_args):
    op = e.op
    if op == "and":
        return bool(eval_expr(e.left, env, fn_args)) and bool(eval_expr(e.right, env, fn_args))
    if op == "or":
        return bool(eval_expr(e.left, env, fn_args)) or bool(eval_expr(e.right, env, fn_args))
    a = eval_expr(e.left, env, fn_args)
    b = eval_expr(e.right, env, fn_args)
    if e.type == BOOL:
        return _compare(op, a, b)
    return _arith(op, a, b, e.type)


def _e_if(e, env, fn_args):
    if eval_expr(e.cond, env, fn_args):
        return eval_expr(e.then, env, fn_args)
    return eval_expr(e.else_, env, fn_args)


def _e_call(e, env, fn_args):
    return _call(e, [eval_expr(a, env, fn_args) for a in e.args], env)


def _e_other(e, env, fn_args):
    return env.other(e)


_EVAL = {
    m.Const: _e_const,
    m.Ref: _e_ref,
    m.InState: _e_in_state,
    m.SubView: _e_sub_view,
    m.Field: _e_field,
    m.Unary: _e_unary,
    m.Binary: _e_binary,
    m.IfExpr: _e_if,
    m.Call: _e_call,
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
            if isinstance(e.type, IntType):
                return numeric.wrap(abs(v), e.type)
            return math.fabs(v)
        if e.func == "seconds":
            return args[0] / 1e9
        if e.func == "min":
            a, b = args
            if e.type == F64 and (math.isnan(a) or math.isnan(b)):
                return math.nan
            return a if a <= b else b
        if e.func == "max":
            a, b = args
            if e.type == F64 and (math.isnan(a) or math.isnan(b)):
                return math.nan
            return a if a >= b else b
        raise ValueError(e.func)
    if e.kind == "extern":
        return env.call_extern(e, args)
    fn = env.function(e.func)
    assert fn.body is not None
    return eval_expr(fn.body, env, {p.name: v for p, v in zip(fn.params, args)})
