"""Name resolution and type checking of expressions and statements (AST -> typed IR).

A `Scope` says what is visible where: everywhere the design's constants,
functions and types; in a controller its locals, status fields, the Global
Memory it declares, and its subordinates; in a plan also `cmd.PARAM` and
`in_state`; in a function only its parameters.  `Checker` turns AST nodes into
`rcsc.semantics.model` nodes, reporting each problem once and returning an ERROR-typed
node so that one mistake does not cascade.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rcsc.front import ast
from rcsc.front.source import Span
from rcsc.semantics import model as m
from rcsc.diagnostics import Diagnostics
from rcsc.semantics.evaluate import Env, NotConstant, eval_expr
from rcsc.semantics.types import (
    BOOL,
    BUILTIN_TYPES,
    DURATION,
    ERROR,
    F64,
    I32,
    I64,
    EnumType,
    ErrorType,
    FloatType,
    IntType,
    RecordType,
    Type,
    ArrayType,
    array_of,
    compatible,
)

BUILTIN_FUNCS = {"abs": 1, "min": 2, "max": 2}
# The f64 math built-ins (docs/language.md, "Math built-ins"): correctly
# rounded, the same bits in the simulator, C and Rust (rcsc.semantics.numeric).
MATH_FUNCS = {"sqrt": 1, "floor": 1, "ceil": 1, "trunc": 1, "round_even": 1, "copysign": 2}
# Built-ins over a fixed-size array (one argument, the array): `len` is its
# length (an i32 constant), `sum` adds the elements from the first to the
# last, `min_of`/`max_of` fold `min`/`max` over them (NaN in, NaN out).
# Distinct names from the scalar `min(a, b)`/`max(a, b)`.
ARRAY_FUNCS = ("len", "sum", "min_of", "max_of")
# The largest array length: every element is a row of the runtime's type
# tables and a line of a literal in the generated code.
MAX_ARRAY_LENGTH = 65536
CONVERSIONS = {"i32", "i64", "u32", "f64"}
ARITH_OPS = ("+", "-", "*", "/", "%")


@dataclass


class Globals:
    """Design-wide names, filled in by rcsc.semantics.sema before bodies are checked."""

    types: dict[str, Type] = field(default_factory=dict)
    consts: dict[str, m.ConstDef] = field(default_factory=dict)
    gm: dict[str, m.Var] = field(default_factory=dict)
    functions: dict[str, m.Function] = field(default_factory=dict)
    controllers: dict[str, m.Controller] = field(default_factory=dict)
    # Lazily resolve a constant, or type-check a function's body, that is used
    # before its own declaration was processed (constants may call functions
    # and functions may read constants, in any order of declaration).
    resolve_const: object = None
    resolve_fn: object = None
    # Names already reported as undeclared where they were declared to be used
    # (an unknown subordinate, an unknown GM variable in `reads`): later uses
    # stay quiet so that one mistake gives one finding.
    poisoned: set[str] = field(default_factory=set)
    # Names of variables declared but not yet modelled while constants are
    # evaluated (all Global Memory; the locals and status fields of the
    # controller whose header is being read): a constant expression that
    # names one reads a variable (E0204), it does not name something unknown.
    variables: dict[str, str] = field(default_factory=dict)  # name -> what it is


@dataclass
class Scope:
    g: Globals
    controller: m.Controller | None = None
    verb: m.Verb | None = None  # set inside a plan
    in_plan: bool = False
    fn_params: dict[str, m.Var] | None = None
    const_only: bool = False  # constant expressions: only literals, consts, enum members
    pure: bool = False  # function bodies: no externs


class FoldEnv(Env):
    def __init__(self, g: Globals) -> None:
        self.g = g

    def function(self, name: str) -> m.Function:
        fn = self.g.functions[name]
        if fn.body is None:  # not checked yet (a call in a constant before pass 5) or being checked
            raise NotConstant(None)  # type: ignore[arg-type]
        return fn


def _literal_values(node: ast.Expr):
    """The integer literals of an untyped expression (`Checker._untyped`), with the
    sign of a `-` written on one (`-2147483648` fits in `i32`)."""
    if isinstance(node, ast.IntLit):
        yield node.value
    elif isinstance(node, ast.Unary):
        if isinstance(node.operand, ast.IntLit):
            yield -node.operand.value
        else:
            yield from _literal_values(node.operand)
    elif isinstance(node, ast.Binary):
        yield from _literal_values(node.left)
        yield from _literal_values(node.right)
    elif isinstance(node, ast.IfExpr):
        yield from _literal_values(node.then)
        yield from _literal_values(node.else_)
    elif isinstance(node, ast.Call):
        for arg in node.args:
            yield from _literal_values(arg.value)


def _known(e: m.Expr) -> bool:
    """Whether a folded operand may have a compile-time value: a constant, or
    a record-typed expression (those are never replaced by a Const)."""
    return isinstance(e, m.Const) or isinstance(e.type, RecordType)


def _may_fold(e: m.Expr) -> bool:
    """False when evaluating `e` would surely stop at an operand that is not
    constant: operands are folded first (bottom-up), so an operand still not
    a Const is not constant, and the evaluator reads it before anything
    else.  Only `and`, `or` and `if` may skip an operand, so for them just
    the operand read first counts.  This keeps folding linear: without it
    every level of `a + b + c + ...` would evaluate its whole left side."""
    if isinstance(e, m.Binary):
        if e.op in ("and", "or"):
            return _known(e.left)
        return _known(e.left) and _known(e.right)
    if isinstance(e, m.Unary):
        return _known(e.operand)
    if isinstance(e, m.Field):
        return _known(e.obj)
    if isinstance(e, m.IfExpr):
        return _known(e.cond)
    if isinstance(e, m.Call):
        return all(_known(a) for a in e.args)
    if isinstance(e, m.Index):
        return _known(e.obj) and _known(e.index)
    if isinstance(e, m.ArrayLit):
        return all(_known(a) for a in e.items)
    return True


def _copy(value):
    """A deep copy of a constant value (records are dicts, arrays lists)."""
    if isinstance(value, dict):
        return {k: _copy(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_copy(v) for v in value]
    return value


def describe(t: Type) -> str:
    return "an integer literal" if t is None else f"`{t}`"


class Checker:
    def __init__(self, scope: Scope, diags: Diagnostics) -> None:
        self.s = scope
        self.g = scope.g
        self.d = diags
        self._wrapped: dict[int, m.Const] = {}  # folded constants that wrapped (W0525 once, where it happened)

    # ---- helpers -------------------------------------------------------------

    def mismatch(self, span, expected: Type, actual: Type, what: str = "") -> None:
        if isinstance(expected, ErrorType) or isinstance(actual, ErrorType):
            return
        msg = f"mismatched types: expected `{expected}`, found `{actual}`"
        diag = self.d.add("E0200", span, msg, f"this is `{actual}`" + (f" ({what})" if what else ""))
        if expected.is_numeric and actual.is_numeric:
            diag.with_help(f"convert explicitly: `{expected}(...)`")

    def fold(self, e: m.Expr) -> m.Expr:
        """Replace a constant sub-tree by its value (numeric rules apply)."""
        if isinstance(e, m.Const) or isinstance(e.type, (ErrorType, RecordType)) or not _may_fold(e):
            return e
        try:
            value = eval_expr(e, FoldEnv(self.g))
        except NotConstant:
            return e
        except (TypeError, KeyError, ValueError, ArithmeticError, RecursionError):
            return e
        folded = m.Const(e.span, e.type, value)
        if self._certain_wrap(e, value):
            self._wrapped[id(folded)] = folded  # kept alive, so its id is not reused
        return folded

    def _certain_wrap(self, e: m.Expr, value) -> bool:
        """W0525 for integer arithmetic of constants that wraps or divides by
        zero: folded here, the value analysis never sees it, and the mistake
        is certain, not only possible (`2147483647 + 1` in a job)."""
        t = I64 if e.type == DURATION else e.type
        if not isinstance(t, IntType):
            return False
        if isinstance(e, m.Binary) and e.op in ("+", "-", "*", "/", "%"):
            if not (isinstance(e.left, m.Const) and isinstance(e.right, m.Const)):
                return False
            if id(e.left) in self._wrapped or id(e.right) in self._wrapped:
                return True  # reported where it first wrapped
            a, b = e.left.value, e.right.value
            if not (isinstance(a, int) and isinstance(b, int)):
                return False
            if e.op in ("/", "%") and b == 0:
                self.d.add("W0525", e.span, f"division by zero in constant arithmetic: `{e.span.text}` is 0 by the language's rules",
                           "divides by zero")
                return True
            exact = {"+": a + b, "-": a - b, "*": a * b}.get(e.op)
            if e.op == "/":
                exact = abs(a) // abs(b) * (1 if (a < 0) == (b < 0) else -1)
        elif isinstance(e, m.Unary) and e.op == "-" and isinstance(e.operand, m.Const) and isinstance(e.operand.value, int):
            if id(e.operand) in self._wrapped:
                return True
            exact = -e.operand.value
        elif (isinstance(e, m.Call) and e.kind == "builtin" and e.func in ("abs", "sum") and len(e.args) == 1
              and isinstance(e.args[0], m.Const)):
            # `abs(i32 MIN)` and a `sum` of constants wrap as `-` and `+` do.
            if id(e.args[0]) in self._wrapped:
                return True
            v = e.args[0].value
            if e.func == "abs" and isinstance(v, int) and not isinstance(v, bool):
                exact = abs(v)
            elif e.func == "sum" and isinstance(v, list) and v and all(isinstance(x, int) and not isinstance(x, bool) for x in v):
                exact = sum(v)
            else:
                return False
        else:
            return False
        if exact is None or exact == value:
            return False
        self.d.add("W0525", e.span, f"constant arithmetic overflows `{e.type}`: `{e.span.text}` is {exact}, which wraps to {value}",
                   "wraps around").with_help(f"use a wider type, or a value that fits {t.min}..{t.max}")
        return True

    def expect(self, node: ast.Expr, expected: Type, what: str = "") -> m.Expr:
        e = self.expr(node, expected)
        if not compatible(expected, e.type):
            self.mismatch(node.span, expected, e.type, what)
            return m.Const(node.span, ERROR, 0)
        return e

    def condition(self, node: ast.Expr) -> m.Expr:
        return self.expect(node, BOOL, "a condition must be `bool`")

    def constant(self, node: ast.Expr, expected: Type, what: str) -> m.Const | None:
        """A compile-time value of type `expected`, or None after a diagnostic."""
        saved = self.s.const_only
        self.s.const_only = True
        try:
            e = self.expect(node, expected)
        finally:
            self.s.const_only = saved
        if isinstance(e.type, ErrorType):
            return None
        e = self.fold(e)
        if not isinstance(e, m.Const):
            # Records are not folded; an array of arrays of records, or of
            # records, is evaluated whole here, as a record is.
            if not isinstance(e.type, (RecordType, ArrayType)):
                self.d.add("E0204", node.span, f"{what} must be a constant expression", "not known at compile time")
                return None
            try:
                value = eval_expr(e, FoldEnv(self.g))
            except (NotConstant, TypeError, KeyError, ValueError, ArithmeticError):
                self.d.add("E0204", node.span, f"{what} must be a constant expression", "not known at compile time")
                return None
            return m.Const(e.span, e.type, value)
        return e

    def array_length(self, node: ast.Expr, what: str) -> int | None:
        """A positive integer constant (an array's length or a repeat count), or None after a diagnostic."""
        saved = self.s.const_only
        self.s.const_only = True
        try:
            e = self.fold(self.expr(node))
        finally:
            self.s.const_only = saved
        if isinstance(e.type, ErrorType):
            return None
        if not isinstance(e, m.Const) or not isinstance(e.type, IntType):
            self.d.add("E0251", node.span, f"{what} must be an integer constant", "not an integer constant").with_help(
                "write a literal (`[f64; 16]`) or the name of an integer constant (`[f64; N]`)"
            )
            return None
        n = int(e.value)  # type: ignore[arg-type]
        if n < 1:
            self.d.add("E0250", node.span, f"{what} must be at least 1, not {n}", "empty array").with_note(
                "an array (a path, a history) holds at least one element; a plan that may have nothing to do checks a count instead"
            )
            return None
        if n > MAX_ARRAY_LENGTH:
            self.d.add("E0251", node.span, f"{what} {n} is above the limit of {MAX_ARRAY_LENGTH}", "too long")
            return None
        return n

    def _index_warning(self, index: m.Expr, t: ArrayType, span, writing: bool) -> None:
        """W0250 when an index is a constant outside 0..size-1.  (An index that
        only may be outside is W0251, asked of the solver with the rule's
        condition: `rcsc.checks.values`.)"""
        if isinstance(index, m.Const) and isinstance(index.value, int) and not isinstance(index.value, bool):
            if not (0 <= index.value < t.size):
                effect = "the write is ignored" if writing else f"the read gives the zero value of `{t.elem}`"
                self.d.add("W0250", span, f"index {index.value} is outside the array of {t.size} elements", "out of range").with_note(
                    f"valid indices are 0..{t.size - 1}; out of range {effect}"
                )

    def index_expr(self, node: ast.Expr) -> m.Expr:
        idx = self.expr(node)
        if isinstance(idx.type, ErrorType):
            return idx
        if not isinstance(idx.type, IntType):
            self.d.add("E0253", node.span, f"an array index must be an integer, not `{idx.type}`", f"`{idx.type}`").with_help(
                "convert it: `i32(x)`"
            )
            return m.Const(node.span, ERROR, 0)
        return idx

    def e_Index(self, node: ast.Index, expected: Type | None) -> m.Expr:
        obj = self.expr(node.obj)
        idx = self.index_expr(node.index)
        if isinstance(obj.type, ErrorType) or isinstance(idx.type, ErrorType):
            return m.Const(node.span, ERROR, 0)
        if not isinstance(obj.type, ArrayType):
            self.d.add("E0253", node.obj.span, f"`{obj.type}` is not an array", "cannot be indexed")
            return m.Const(node.span, ERROR, 0)
        self._index_warning(idx, obj.type, node.index.span, writing=False)
        return self.fold(m.Index(node.span, obj.type.elem, obj, idx))

    def e_ArrayLit(self, node: ast.ArrayLit, expected: Type | None) -> m.Expr:
        if not node.items:
            self.d.add("E0250", node.span, "an empty array literal", "no elements").with_note("an array holds at least one element")
            return m.Const(node.span, ERROR, 0)
        hint = expected.elem if isinstance(expected, ArrayType) else None
        items = self.together(node.items, hint)
        if any(isinstance(x.type, ErrorType) for x in items):
            return m.Const(node.span, ERROR, 0)
        elem = hint if hint is not None else items[0].type
        for item, x in zip(node.items, items):
            if not compatible(elem, x.type):
                self.mismatch(item.span, elem, x.type, "an array's elements have one type")
                return m.Const(node.span, ERROR, 0)
        if isinstance(expected, ArrayType) and len(items) != expected.size:
            self.d.add("E0252", node.span, f"array literal of {len(items)} elements where `{expected}` is expected", f"{len(items)} elements").with_help(
                f"write {expected.size} elements, or `[value; {expected.size}]`"
            )
            return m.Const(node.span, ERROR, 0)
        t = array_of(elem, len(items))
        if len(items) > MAX_ARRAY_LENGTH:
            self.d.add("E0251", node.span, f"an array literal of {len(items)} elements is above the limit of {MAX_ARRAY_LENGTH}", "too long")
            return m.Const(node.span, ERROR, 0)
        if all(isinstance(x, m.Const) for x in items):
            return m.Const(node.span, t, [x.value for x in items])
        return m.ArrayLit(node.span, t, items)

    def e_ArrayRepeat(self, node: ast.ArrayRepeat, expected: Type | None) -> m.Expr:
        hint = expected.elem if isinstance(expected, ArrayType) else None
        value = self.fold(self.expr(node.value, hint))
        if not isinstance(value, m.Const) and isinstance(value.type, (RecordType, ArrayType)):
            try:  # a record built of constants (records are not folded)
                value = m.Const(value.span, value.type, eval_expr(value, FoldEnv(self.g)))
            except (NotConstant, TypeError, KeyError, ValueError, ArithmeticError):
                pass
        n = self.array_length(node.count, "the count of `[value; count]`")
        if n is None or isinstance(value.type, ErrorType):
            return m.Const(node.span, ERROR, 0)
        if not isinstance(value, m.Const):
            self.d.add("E0251", node.value.span, "the value of `[value; count]` must be a constant expression", "not constant").with_help(
                "write the elements out (`[a, b, c]`), or fill the array in a `pre` block"
            )
            return m.Const(node.span, ERROR, 0)
        if isinstance(expected, ArrayType) and n != expected.size and compatible(expected.elem, value.type):
            self.d.add("E0252", node.span, f"array of {n} elements where `{expected}` is expected", f"{n} elements")
            return m.Const(node.span, ERROR, 0)
        return m.Const(node.span, array_of(value.type, n), [_copy(value.value) for _ in range(n)])

    def _array_call(self, node: ast.Call, name: str) -> m.Expr:
        args = self.match_args([("array", None)], node.args, node, f"`{name}`")
        if args is None or isinstance(args[0].type, ErrorType):
            return m.Const(node.span, ERROR, 0)
        t = args[0].type
        if not isinstance(t, ArrayType):
            self.d.add("E0253", node.args[0].span, f"`{name}` needs an array, not `{t}`", "not an array")
            return m.Const(node.span, ERROR, 0)
        if name == "len":
            return m.Const(node.span, I32, t.size)
        if not (t.elem.is_numeric or t.elem == DURATION):
            self.d.add("E0208", node.span, f"`{name}` is not defined for `{t}`", f"`{t.elem}` elements")
            return m.Const(node.span, ERROR, 0)
        return self.fold(m.Call(node.span, t.elem, "builtin", name, args))

    # ---- expressions -----------------------------------------------------------

    # The `e_` method of each node class, per checker class (a subclass may
    # override some): looked up once instead of by name for every node.
    _methods: dict[type, object] = {}

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        cls._methods = {}

    def expr(self, node: ast.Expr, expected: Type | None = None) -> m.Expr:
        kind = type(node)
        method = self._methods.get(kind)
        if method is None:
            method = self._methods[kind] = getattr(type(self), "e_" + kind.__name__)
        return method(self, node, expected)

    def e_IntLit(self, node: ast.IntLit, expected: Type | None) -> m.Expr:
        return self._int_value(node.value, node.span, expected)

    def _int_value(self, value: int, span, expected: Type | None) -> m.Expr:
        if isinstance(expected, FloatType):
            return m.Const(span, F64, float(value))
        t = expected if isinstance(expected, IntType) else None
        if t is None:
            t = I32 if I32.min <= value <= I32.max else I64
        if not (t.min <= value <= t.max):
            self.d.add("E0207", span, f"integer literal out of range for `{t}`", f"`{t}` holds {t.min}..{t.max}")
            return m.Const(span, ERROR, 0)
        return m.Const(span, t, value)

    def e_FloatLit(self, node: ast.FloatLit, expected: Type | None) -> m.Expr:
        return m.Const(node.span, F64, node.value)

    def e_BoolLit(self, node: ast.BoolLit, expected: Type | None) -> m.Expr:
        return m.Const(node.span, BOOL, node.value)

    def e_DurationLit(self, node: ast.DurationLit, expected: Type | None) -> m.Expr:
        if not (I64.min <= node.nanos <= I64.max):  # held as i64 nanoseconds
            self.d.add("E0207", node.span, "duration literal out of range for `duration`", f"`duration` holds at most {I64.max} ns")
            return m.Const(node.span, ERROR, 0)
        return m.Const(node.span, DURATION, node.nanos)

    def e_Name(self, node: ast.Name, expected: Type | None) -> m.Expr:
        n = node.name
        s = self.s
        if s.fn_params is not None and n in s.fn_params:
            return m.Ref(node.span, s.fn_params[n].type, "arg", n)
        c = s.controller
        if c is not None and not s.const_only:
            if n in c.locals:
                return m.Ref(node.span, c.locals[n].type, "local", n)
            if n in c.status_fields:
                return m.Ref(node.span, c.status_fields[n].type, "status", n)
            if n in self.g.gm:
                if any(u.name == n for u in c.reads) or any(u.name == n for u in c.writes):
                    return m.Ref(node.span, self.g.gm[n].type, "gm", n)
                self.d.add("E0100", node.span, f"`{n}` is not in the `reads` of `{c.name}`", "not declared as read").with_help(
                    f"add `reads {n}` to controller `{c.name}`"
                )
                return m.Const(node.span, ERROR, 0)
            if n == "in_state" and s.in_plan:
                return m.InState(node.span, DURATION)
            if n == "cycle":
                return m.Cycle(node.span, I64)
        if n in self.g.consts or (callable(self.g.resolve_const) and self.g.resolve_const(n)):
            cd = self.g.consts.get(n)
            if cd is None:
                return m.Const(node.span, ERROR, 0)
            if isinstance(expected, FloatType) and isinstance(cd.type, IntType):
                pass  # no implicit conversion of typed constants
            return m.Const(node.span, cd.type, cd.value, name=n)
        return self._unknown_name(node, n)

    def _unknown_name(self, node: ast.Node, n: str) -> m.Expr:
        if n in self.g.poisoned or isinstance(self.g.types.get(n), ErrorType):  # reported already (E0101: an enum defined twice)
            return m.Const(node.span, ERROR, 0)
        s = self.s
        if s.const_only and (n in self.g.gm or n in self.g.variables or n in self.g.controllers or n == "cmd"
                             or (s.controller and (n in s.controller.locals or n in s.controller.status_fields))):
            # The name is known: what is wrong is reading a variable (or a
            # controller's status, or the command) where a value must be known
            # before the design runs.
            if n in self.g.gm:
                what = "a Global Memory variable"
            elif n in self.g.variables:
                what = self.g.variables[n]
            elif s.controller and (n in s.controller.locals or n in s.controller.status_fields):
                what = "a variable of the controller"
            elif n == "cmd":
                what = "the running command"
            else:
                what = "a controller, whose status is known only when the design runs"
            label = "known only at run time" if n in self.g.controllers or n == "cmd" else "a variable"
            self.d.add("E0204", node.span, f"`{n}` is {what}: a constant expression cannot read it", label).with_note(
                "constants, initial values, ranges and scenario values are known before the design runs: "
                "literals, constants, enum members and arithmetic on them")
            return m.Const(node.span, ERROR, 0)
        diag = self.d.add("E0100", node.span, f"cannot find `{n}` in this scope", "not found")
        if n in self.g.types and isinstance(self.g.types[n], EnumType):
            diag.with_help(f"name a member: `{n}.{self.g.types[n].members[0] if self.g.types[n].members else 'MEMBER'}`")
        elif n in self.g.controllers:
            diag.with_help(f"read a subordinate's status with `{n}.done`, `{n}.error`, ...")
        elif n == "cmd":
            diag.with_help("read a command parameter with `cmd.NAME`")
        elif owners := [t for t in self.g.types.values() if isinstance(t, EnumType) and n in t.members]:
            # An enum member is named with its enum (one rule for every enum).
            diag.with_help("write " + " or ".join(f"`{t.name}.{n}`" for t in owners) + ": a member is named with its enum")
        elif n in ("done", "error"):
            # What a rule goes to, not something a condition can test.
            diag.with_note(f"`{n}` is a next state, written after `->`" + (" as `error(CODE)`" if n == "error" else ""))
            diag.with_help(f"test a subordinate's status with `SUB.{n}`")
        elif n == "in_state":
            diag.with_note("`in_state` is only available in the rules of a plan")
        elif n == "cycle":
            diag.with_note("`cycle` (the controller's step number) is only available in a controller's pre, post and plans")
        elif n in self.g.gm and s.fn_params is not None:
            diag.with_note("functions are pure: pass Global Memory values as arguments")
        return m.Const(node.span, ERROR, 0)

    def e_Attr(self, node: ast.Attr, expected: Type | None) -> m.Expr:
        attr = node.attr.name
        if isinstance(node.obj, ast.Name):
            base = node.obj.name
            local_shadow = self._is_variable(base)
            if not local_shadow:
                if base == "cmd" and self.s.fn_params is None:
                    return self._cmd_param(node, attr)
                t = self.g.types.get(base)
                if isinstance(t, EnumType):
                    if attr not in t.members:
                        self.d.add("E0103", node.attr.span, f"enum `{base}` has no member `{attr}`", "unknown member").with_note(
                            f"members: {', '.join(t.members)}"
                        )
                        return m.Const(node.span, ERROR, 0)
                    return m.Const(node.span, t, attr)
                if base in self.g.controllers and self.s.controller is not None and not self.s.const_only:
                    return self._sub_view(node, base, attr)
        obj = self.expr(node.obj)
        if isinstance(obj.type, ErrorType):
            return m.Const(node.span, ERROR, 0)
        if isinstance(obj.type, RecordType):
            ft = obj.type.field_type(attr)
            if ft is None:
                self.d.add("E0103", node.attr.span, f"record `{obj.type}` has no field `{attr}`", "unknown field").with_note(
                    "fields: " + ", ".join(f for f, _ in obj.type.fields)
                )
                return m.Const(node.span, ERROR, 0)
            return self.fold(m.Field(node.span, ft, obj, attr)) if isinstance(obj, m.Const) else m.Field(node.span, ft, obj, attr)
        self.d.add("E0103", node.attr.span, f"`{obj.type}` has no field `{attr}`", "no such field")
        return m.Const(node.span, ERROR, 0)

    def _is_variable(self, n: str) -> bool:
        s = self.s
        if s.fn_params is not None and n in s.fn_params:
            return True
        c = s.controller
        return c is not None and (n in c.locals or n in c.status_fields or n in self.g.gm)

    def _cmd_param(self, node: ast.Attr, attr: str) -> m.Expr:
        if not self.s.in_plan or self.s.verb is None or self.s.const_only:
            self.d.add("E0108", node.span, "`cmd` is only available in a plan", "outside a plan").with_note(
                "in `pre` and `post` the active command may be any verb; copy the parameter into a local in the plan"
            )
            return m.Const(node.span, ERROR, 0)
        p = self.s.verb.param(attr)
        if p is None:
            diag = self.d.add("E0103", node.attr.span, f"verb `{self.s.verb.name}` has no parameter `{attr}`", "unknown parameter")
            names = [q.name for q in self.s.verb.params]
            diag.with_note(f"parameters: {', '.join(names)}" if names else f"`{self.s.verb.name}` takes no parameters")
            return m.Const(node.span, ERROR, 0)
        return m.Ref(node.span, p.type, "param", attr)

    def _age(self, node: ast.Call) -> m.Expr:
        """`age(V)` of a Global Memory variable the controller uses, or `age(SUB)` of a subordinate."""
        c = self.s.controller
        if c is None or self.s.const_only or self.s.fn_params is not None:
            self.d.add("E0100", node.span, "`age` is only available in a controller", "outside a controller").with_note(
                "the age of a buffer is measured by the controller that reads it"
            )
            return m.Const(node.span, ERROR, 0)
        if len(node.args) != 1 or node.args[0].name is not None or not isinstance(node.args[0].value, ast.Name):
            self.d.add("E0201", node.span, "`age` takes one argument: a Global Memory variable or a subordinate", "one name").with_help(
                "write `age(speed)` or `age(SUB)`"
            )
            return m.Const(node.span, ERROR, 0)
        arg = node.args[0].value
        n = arg.name
        if n in self.g.controllers and n not in self.g.gm:
            view = self._sub_view(ast.Attr(node.span, arg, ast.Ident(arg.span, "age")), n, "age")
            return view
        if n in self.g.gm:
            if any(u.name == n for u in c.reads) or any(u.name == n for u in c.writes):
                return m.Age(node.span, DURATION, n)
            self.d.add("E0100", arg.span, f"`{n}` is not in the `reads` of `{c.name}`", "not declared as read").with_help(
                f"add `reads {n}` to controller `{c.name}`"
            )
            return m.Const(node.span, ERROR, 0)
        if n in self.g.poisoned:
            return m.Const(node.span, ERROR, 0)
        self.d.add("E0100", arg.span, f"`age` needs a Global Memory variable or a subordinate; `{n}` is neither", "not a buffer")
        return m.Const(node.span, ERROR, 0)

    def _not_a_subordinate(self, span, sub: str, commanding: bool) -> None:
        """E0507 for a command to, or a status read of, a controller that the
        current one does not list in `subordinates`, with the fix that fits
        where `sub` stands in the hierarchy."""
        c = self.s.controller
        assert c is not None
        if sub == c.name:
            self.d.add("E0507", span, f"`{sub}` cannot command itself", "itself").with_note(
                "commands go down the hierarchy, to the controllers in `subordinates`").with_help(
                "to go on with other work, move to another state of the plan")
            return
        diag = self.d.add("E0507", span, f"`{sub}` is not a subordinate of `{c.name}`", "not a subordinate")
        supervisor = next((o.name for o in self.g.controllers.values() if any(u.name == sub for u in o.subordinates)), None)
        if any(u.name == c.name for u in self.g.controllers[sub].subordinates):
            diag.with_note(f"`{sub}` is the supervisor of `{c.name}`: commands go down the hierarchy, status comes up")
            diag.with_help(f"`{sub}` reads `{c.name}`'s status; share other data through Global Memory")
        elif supervisor is not None:
            # Adding it would give it a second supervisor (E0300).
            diag.with_note(f"`{sub}` is a subordinate of `{supervisor}`; a controller has one supervisor")
            diag.with_help(f"command `{supervisor}`, which commands `{sub}`" if commanding
                           else f"read `{supervisor}`'s status, or share the data through Global Memory")
        elif commanding:
            diag.with_help(f"add `subordinates {sub}` to `{c.name}`")
        else:
            diag.with_help(f"add `subordinates {sub}` to `{c.name}`, or read shared data through Global Memory")

    def _sub_view(self, node: ast.Attr, sub: str, attr: str) -> m.Expr:
        c = self.s.controller
        assert c is not None
        if sub in self.g.poisoned:
            return m.Const(node.span, ERROR, 0)
        if sub == c.name:
            self.d.add("E0100", node.obj.span, "a controller cannot read its own status this way", "this controller").with_help(
                "read its status fields by their bare names"
            )
            return m.Const(node.span, ERROR, 0)
        if not any(u.name == sub for u in c.subordinates):
            self._not_a_subordinate(node.obj.span, sub, commanding=False)
            return m.Const(node.span, ERROR, 0)
        target = self.g.controllers[sub]
        fixed = {"done": BOOL, "error": BOOL, "executing": BOOL, "error_code": I32, "age": DURATION}
        if attr in fixed:
            return m.SubView(node.span, fixed[attr], sub, attr)
        if attr in target.statuses:
            return m.SubView(node.span, BOOL, sub, "status", attr)
        if attr in target.status_fields:
            return m.SubView(node.span, target.status_fields[attr].type, sub, "field", attr)
        if attr in target.verbs:
            self.d.add("E0103", node.attr.span, f"`{attr}` is a verb of `{sub}`, not a status", "a verb").with_help(
                f"command it in a job list: `{sub}.{attr}(...)`"
            )
            return m.Const(node.span, ERROR, 0)
        diag = self.d.add("E0103", node.attr.span, f"subordinate `{sub}` has no status `{attr}`", "unknown status")
        extra = list(target.statuses) + list(target.status_fields)
        diag.with_note("available: done, error, executing, error_code, age" + "".join(", " + x for x in extra))
        return m.Const(node.span, ERROR, 0)

    def e_Unary(self, node: ast.Unary, expected: Type | None) -> m.Expr:
        if node.op == "-" and isinstance(node.operand, ast.IntLit):
            return self._int_value(-node.operand.value, node.span, expected)
        if node.op == "-" and type(node.operand) is ast.FloatLit:
            # What folding `-(literal)` gives (a float literal is `f64`
            # whatever the context), without building and evaluating the
            # negation: ranges and guards are full of negative literals.
            return m.Const(node.span, F64, -node.operand.value)
        if node.op == "not":
            operand = self.expect(node.operand, BOOL, "`not` needs a `bool`")
            return self.fold(m.Unary(node.span, BOOL, "not", operand))
        operand = self.expr(node.operand, expected)
        t = operand.type
        if isinstance(t, ErrorType):
            return m.Const(node.span, ERROR, 0)
        if not (t.is_numeric or t == DURATION):
            self.d.add("E0208", node.span, f"cannot negate a value of type `{t}`", f"`{t}`")
            return m.Const(node.span, ERROR, 0)
        return self.fold(m.Unary(node.span, t, "-", operand))

    def _untyped(self, node: ast.Expr) -> bool:
        """Whether `node` is made of integer literals only (`5`, `-5`, `5 + 1`, `abs(5)`,
        `if c then 1 else 2`): such an expression has no type of its own and takes
        the one its context gives it (see `together`)."""
        if isinstance(node, ast.IntLit):
            return True
        if isinstance(node, ast.Unary):
            return node.op == "-" and self._untyped(node.operand)
        if isinstance(node, ast.Binary):
            return node.op in ARITH_OPS and self._untyped(node.left) and self._untyped(node.right)
        if isinstance(node, ast.IfExpr):
            return self._untyped(node.then) and self._untyped(node.else_)
        if isinstance(node, ast.Call):
            name = node.func.name
            return (name in BUILTIN_FUNCS and name not in self.g.functions and len(node.args) == BUILTIN_FUNCS[name]
                    and all(self._untyped(a.value) for a in node.args))
        return False

    def together(self, nodes: list[ast.Expr], hint: Type | None) -> list[m.Expr]:
        """Check operands that must have one type (the two sides of an operator, the
        branches of an `if`, the arguments of `abs`/`min`/`max`): the language's one
        rule for untyped integer literals.  The typed operands are checked first, in
        order, each expecting the type of the first; then every untyped operand is
        checked expecting that type, or `hint` (the context's type) when no operand
        is typed.  So `A > 5 + 1`, `5 + 1 < A` and `abs(5) == A` type alike."""
        untyped = [self._untyped(n) for n in nodes]
        t = hint
        if t is None and all(untyped):
            # No type anywhere: the literals' own default, i32, or i64 if one does not fit.
            t = I32 if all(I32.min <= v <= I32.max for n in nodes for v in _literal_values(n)) else I64
        out: list[m.Expr | None] = [None] * len(nodes)
        first = True
        for i, n in enumerate(nodes):
            if not untyped[i]:
                e = out[i] = self.expr(n, t)
                if first:
                    t, first = e.type, False
        for i, n in enumerate(nodes):
            if untyped[i]:
                out[i] = self.expr(n, t)
        return out  # type: ignore[return-value]

    def e_Binary(self, node: ast.Binary, expected: Type | None) -> m.Expr:
        op = node.op
        if op in ("and", "or"):
            left = self.expect(node.left, BOOL, f"`{op}` needs `bool` operands")
            right = self.expect(node.right, BOOL, f"`{op}` needs `bool` operands")
            return self.fold(m.Binary(node.span, BOOL, op, left, right))
        arith = op in ARITH_OPS
        hint = expected if arith else None
        left, right = self.together([node.left, node.right], hint)
        lt, rt = left.type, right.type
        if isinstance(lt, ErrorType) or isinstance(rt, ErrorType):
            return m.Const(node.span, ERROR, 0)
        if lt is not rt and lt != rt:
            diag = self.d.add("E0200", node.op_span, f"mismatched types: `{lt}` {op} `{rt}`", "operands of different types")
            diag.with_label(node.left.span, f"`{lt}`").with_label(node.right.span, f"`{rt}`")
            if lt.is_numeric and rt.is_numeric:
                # Name the operands as written, the conversion to f64 (which loses nothing) first.
                ways = [f"`{_shown(node.left, op, node.right, None, lt)}`", f"`{_shown(node.left, op, node.right, rt, None)}`"]
                diag.with_help("convert one side explicitly: " + " or ".join(ways[::-1] if isinstance(rt, FloatType) else ways))
            elif DURATION in (lt, rt) and (lt.is_numeric or rt.is_numeric):
                diag.with_help("a duration is written with its unit (`5 ms`, `2 s`); `seconds(d)` gives a duration as f64 seconds")
            return m.Const(node.span, ERROR, 0)
        if arith:
            ok = lt.is_numeric or (lt == DURATION and op in ("+", "-"))
            if op == "%" and isinstance(lt, FloatType):
                ok = False
            if not ok:
                self.d.add("E0208", node.op_span, f"operator `{op}` is not defined for `{lt}`", f"`{lt}` operands")
                return m.Const(node.span, ERROR, 0)
            return self.fold(m.Binary(node.span, lt, op, left, right))
        if op in ("<", "<=", ">", ">="):
            if not (lt.is_numeric or lt == DURATION):
                self.d.add("E0208", node.op_span, f"`{op}` is not defined for `{lt}`", "no ordering").with_note(
                    "enums and bools compare only with `==` and `!=`"
                )
                return m.Const(node.span, ERROR, 0)
        elif isinstance(lt, RecordType):
            self.d.add("E0208", node.op_span, f"`{op}` is not defined for records", "compare fields instead")
            return m.Const(node.span, ERROR, 0)
        elif isinstance(lt, ArrayType):
            self.d.add("E0254", node.op_span, f"`{op}` is not defined for arrays", "compare elements instead")
            return m.Const(node.span, ERROR, 0)
        return self.fold(m.Binary(node.span, BOOL, op, left, right))

    def e_IfExpr(self, node: ast.IfExpr, expected: Type | None) -> m.Expr:
        cond = self.condition(node.cond)
        then, else_ = self.together([node.then, node.else_], expected)
        if not compatible(then.type, else_.type):
            diag = self.d.add("E0200", node.else_.span, f"`if` branches differ: `{then.type}` and `{else_.type}`", f"`{else_.type}`")
            diag.with_label(node.then.span, f"`{then.type}`")
            return m.Const(node.span, ERROR, 0)
        t = then.type if not isinstance(then.type, ErrorType) else else_.type
        return self.fold(m.IfExpr(node.span, t, cond, then, else_))

    def e_Call(self, node: ast.Call, expected: Type | None) -> m.Expr:
        name = node.func.name
        if name in CONVERSIONS and not self._is_variable(name):
            target = BUILTIN_TYPES[name]
            args = self.match_args([("value", None)], node.args, node, f"conversion `{name}`")
            if args is None:
                return m.Const(node.span, ERROR, 0)
            if not (args[0].type.is_numeric or isinstance(args[0].type, ErrorType)):
                self.d.add("E0208", node.args[0].span, f"cannot convert `{args[0].type}` to `{name}`", "not a number")
                return m.Const(node.span, ERROR, 0)
            if isinstance(args[0].type, ErrorType):
                return m.Const(node.span, ERROR, 0)
            return self.fold(m.Call(node.span, target, "convert", name, args))
        if name == "seconds" and name not in self.g.functions and not self._is_variable(name):
            # Durations are whole nanoseconds; `seconds(d)` is the f64 number
            # of seconds, for integrating and rate limits (d / 1e9, IEEE).
            args = self.match_args([("duration", DURATION)], node.args, node, "`seconds`")
            if args is None:
                return m.Const(node.span, ERROR, 0)
            return self.fold(m.Call(node.span, F64, "builtin", name, args))
        if name == "age" and name not in self.g.functions and not self._is_variable(name):
            return self._age(node)
        if name in MATH_FUNCS and name not in self.g.functions and not self._is_variable(name):
            params = [("x", F64)] if MATH_FUNCS[name] == 1 else [("x", F64), ("y", F64)]
            args = self.match_args(params, node.args, node, f"`{name}`")
            if args is None or any(isinstance(a.type, ErrorType) for a in args):
                return m.Const(node.span, ERROR, 0)
            return self.fold(m.Call(node.span, F64, "builtin", name, args))
        if name in ARRAY_FUNCS and name not in self.g.functions and not self._is_variable(name):
            return self._array_call(node, name)
        if name in BUILTIN_FUNCS and name not in self.g.functions:
            count = BUILTIN_FUNCS[name]
            params = [("x", None)] if count == 1 else [("a", None), ("b", None)]
            args = self.match_args(params, node.args, node, f"`{name}`", expected)
            if args is None:
                return m.Const(node.span, ERROR, 0)
            types = {a.type for a in args}
            if any(isinstance(t, ErrorType) for t in types):
                return m.Const(node.span, ERROR, 0)
            if len(types) != 1:
                self.d.add("E0200", node.span, f"`{name}` needs arguments of one type", "different types")
                return m.Const(node.span, ERROR, 0)
            t = types.pop()
            if not (t.is_numeric or t == DURATION):
                self.d.add("E0208", node.span, f"`{name}` is not defined for `{t}`", f"`{t}`")
                return m.Const(node.span, ERROR, 0)
            return self.fold(m.Call(node.span, t, "builtin", name, args))
        t = self.g.types.get(name)
        if isinstance(t, ErrorType):  # a record defined twice (E0101): whose fields, nobody knows
            for a in node.args:
                self.expr(a.value)
            return m.Const(node.span, ERROR, 0)
        if isinstance(t, RecordType):
            args = self.match_args(list(t.fields), node.args, node, f"record `{name}`")
            if args is None:
                return m.Const(node.span, ERROR, 0)
            return m.Call(node.span, t, "record", name, args)
        fn = self.g.functions.get(name)
        if fn is None:
            if name in self.g.consts or name in self.g.gm or name in self.g.types or name in self.g.controllers:
                self.d.add("E0211", node.func.span, f"`{name}` is not a function", "not callable")
                return m.Const(node.span, ERROR, 0)
            return self._unknown_name(node.func, name)
        if fn.extern and (self.s.pure or self.s.const_only):
            where = "a pure function" if self.s.pure else "a constant expression"
            self.d.add("E0211", node.func.span, f"extern function `{name}` cannot be called in {where}", "extern call").with_note(
                "extern functions are hand-written target code; their results are not known at compile time"
            )
            return m.Const(node.span, ERROR, 0)
        args = self.match_args([(p.name, p.type) for p in fn.params], node.args, node, f"function `{name}`")
        if args is None:
            return m.Const(node.span, ERROR, 0)
        if fn.body is None and not fn.extern and callable(self.g.resolve_fn):
            self.g.resolve_fn(name)
        call = m.Call(node.span, fn.ret, "extern" if fn.extern else "fn", name, args)
        return call if fn.extern or fn.body is None else self.fold(call)

    def match_args(self, params, args: list[ast.Arg], call: ast.Node, what: str, hint: Type | None = None) -> list[m.Expr] | None:
        """Match positional then named arguments to `params` [(name, type|None)]."""
        if len(args) == len(params) and all(a.name is None for a in args):
            # The common case: every argument given, by position.
            return self._typed_args(params, list(args), hint)
        slots: list[ast.Arg | None] = [None] * len(params)
        names = [p[0] for p in params]
        ok = True
        positional_done = False
        for i, a in enumerate(args):
            if a.name is None:
                if positional_done:
                    self.d.add("E0202", a.span, "positional argument after a named one", "positional")
                    ok = False
                    continue
                if i >= len(params):
                    self.d.add("E0201", a.span, f"{what} takes {len(params)} argument{'s' if len(params) != 1 else ''}, {len(args)} given", "extra argument")
                    return None
                slots[i] = a
            else:
                positional_done = True
                if a.name.name not in names:
                    noun = "field" if what.startswith("record") else "parameter"
                    diag = self.d.add("E0202", a.name.span, f"{what} has no {noun} `{a.name.name}`", f"unknown {noun}")
                    diag.with_note(f"{noun}s: " + ", ".join(names) if names else f"{what} takes no arguments")
                    diag.guess(a.name.name, names)
                    ok = False
                    continue
                k = names.index(a.name.name)
                if slots[k] is not None:
                    noun = "field" if what.startswith("record") else "parameter"
                    self.d.add("E0202", a.name.span, f"{noun} `{a.name.name}` given twice", "given again")
                    ok = False
                    continue
                slots[k] = a
        missing = [names[i] for i, s in enumerate(slots) if s is None]
        if missing and ok:
            diag = self.d.add("E0201", call.span, f"{what} takes {len(params)} argument{'s' if len(params) != 1 else ''}, {len(params) - len(missing)} given", "missing arguments")
            diag.with_note("missing: " + ", ".join(f"`{n}`" for n in missing))
            return None
        if not ok:
            return None
        return self._typed_args(params, slots, hint)  # type: ignore[arg-type]

    def _typed_args(self, params, slots: list[ast.Arg], hint: Type | None) -> list[m.Expr]:
        """The arguments matched to `params`, in the parameters' order, checked."""
        out: dict[int, m.Expr] = {}
        free = []  # parameters of no fixed type (builtins): their arguments take one type
        for i, ((pname, ptype), a) in enumerate(zip(params, slots)):
            if ptype is None:
                free.append(i)
            else:
                out[i] = self.expect(a.value, ptype, f"argument `{pname}`")
        out.update(zip(free, self.together([slots[i].value for i in free], hint)))  # type: ignore[union-attr]
        return [out[i] for i in range(len(params))]

    # ---- statements ------------------------------------------------------------

    def stmts(self, nodes: list[ast.Stmt]) -> list[m.Stmt]:
        out = []
        for n in nodes:
            s = self.stmt(n)
            if s is not None:
                out.append(s)
        return out

    def stmt(self, node: ast.Stmt) -> m.Stmt | None:
        if isinstance(node, ast.Assign):
            return self.assign(node)
        if isinstance(node, ast.CallStmt):
            e = self.expr(node.call)
            if isinstance(e, m.Call):
                if e.kind != "extern":
                    # Only hand-written code can do something besides its value.
                    # The statement's span, which the parsers give the call too, ends with its `;`.
                    whole = node.call.span
                    call = Span(whole.file, whole.start, whole.start + len(whole.text.rstrip().removesuffix(";").rstrip()))
                    diag = self.d.add("W0213", call, f"the value of `{e.func}(...)` is not used", "value dropped").with_note(
                        "a function does nothing but compute its value")
                    first = node.call.args[0].value if node.call.args else None
                    if isinstance(first, ast.Name):
                        diag.with_help(f"to change `{first.name}`, assign the value: `{first.name} = {call.text}`")
                    else:
                        diag.with_help("assign the value to a variable, or remove the call")
                return m.CallStmt(node.span, e)
            return None
        if isinstance(node, ast.Command):
            return self.command(node)
        if isinstance(node, ast.Report):
            c = self.s.controller
            assert c is not None
            if node.status.name not in c.statuses:
                diag = self.d.add("E0107", node.status.span, f"`{c.name}` declares no status value `{node.status.name}`", "undeclared status")
                diag.guess(node.status.name, c.statuses)
                diag.with_help(f"declare it: `reports {node.status.name}`")
                return None
            return m.Report(node.span, node.status.name)
        if isinstance(node, ast.If):
            branches = [(self.condition(cond), self.stmts(body)) for cond, body in node.branches]
            return m.If(node.span, branches, self.stmts(node.else_body or []))
        raise TypeError(type(node).__name__)

    def lvalue(self, target: list[ast.Ident], index: ast.Expr | None = None) -> m.LValue | None:
        head = target[0]
        n = head.name
        c = self.s.controller
        span = head.span.to(target[-1].span)
        kind, t = None, None
        if c is not None:
            if n in c.locals:
                kind, t = "local", c.locals[n].type
            elif n in c.status_fields:
                kind, t = "status", c.status_fields[n].type
            elif n in self.g.gm:
                if any(u.name == n for u in c.writes):
                    kind, t = "gm", self.g.gm[n].type
                else:
                    diag = self.d.add("E0203", head.span, f"`{c.name}` does not write Global Memory variable `{n}`", "not in `writes`")
                    reads = any(u.name == n for u in c.reads)
                    diag.with_help(f"add `writes {n}` to `{c.name}`" + (" (it is only read now)" if reads else "")).with_note(
                        "every Global Memory variable has exactly one writer"
                    )
                    return None
        if kind is None:
            if n in self.g.consts:
                self.d.add("E0203", head.span, f"cannot assign to constant `{n}`", "a constant")
            elif n == "cmd":
                self.d.add("E0203", head.span, "cannot assign to a command parameter", "read-only").with_help("copy it into a local")
            elif n == "in_state" or n in self.g.controllers:
                self.d.add("E0203", head.span, f"cannot assign to `{n}`", "read-only")
            else:
                self._unknown_name(head, n)
            return None
        path = []
        for ident in target[1:]:
            if isinstance(t, ErrorType):
                return None  # reported where the type went wrong
            if not isinstance(t, RecordType):
                self.d.add("E0103", ident.span, f"`{t}` has no field `{ident.name}`", "no such field")
                return None
            ft = t.field_type(ident.name)
            if ft is None:
                self.d.add("E0103", ident.span, f"record `{t}` has no field `{ident.name}`", "unknown field")
                return None
            path.append(ident.name)
            t = ft
        if index is None:
            return m.LValue(span, kind, n, path, t)
        idx = self.index_expr(index)
        if isinstance(idx.type, ErrorType) or isinstance(t, ErrorType):
            return None
        if not isinstance(t, ArrayType):
            self.d.add("E0253", span, f"`{t}` is not an array", "cannot be indexed")
            return None
        self._index_warning(idx, t, index.span, writing=True)
        return m.LValue(span.to(index.span), kind, n, path, t.elem, idx)

    def assign(self, node: ast.Assign) -> m.Stmt | None:
        lv = self.lvalue(node.target, node.index)
        if lv is None:
            self.expr(node.value)  # still report problems inside the value
            return None
        value = self.expect(node.value, lv.type, f"assigned to `{'.'.join(i.name for i in node.target)}`")
        if node.op != "=":
            ok = lv.type.is_numeric or (lv.type == DURATION and node.op in ("+=", "-="))
            if isinstance(lv.type, ArrayType):
                self.d.add("E0254", node.span, f"`{node.op}` is not defined for arrays", "a whole array").with_help(
                    "assign element by element: `a[i] += x`"
                )
                return None
            if not ok and not isinstance(lv.type, ErrorType):
                self.d.add("E0208", node.span, f"`{node.op}` is not defined for `{lv.type}`", f"`{lv.type}`")
                return None
        return m.Assign(node.span, lv, node.op, value)

    def command(self, node: ast.Command) -> m.Stmt | None:
        c = self.s.controller
        assert c is not None
        sub = node.sub.name
        if sub in self.g.poisoned:
            return None
        if sub not in self.g.controllers:
            self.d.add("E0104", node.sub.span, f"no controller named `{sub}`", "unknown controller")
            return None
        if not any(u.name == sub for u in c.subordinates):
            self._not_a_subordinate(node.sub.span, sub, commanding=True)
            return None
        target = self.g.controllers[sub]
        verb = target.verbs.get(node.verb.name)
        if verb is None:
            diag = self.d.add("E0105", node.verb.span, f"`{sub}` does not accept the verb `{node.verb.name}`", "unknown verb")
            diag.with_note(f"`{sub}` accepts: " + (", ".join(target.verbs) if target.verbs else "no verbs"))
            return None
        args = self.match_args([(p.name, p.type) for p in verb.params], node.args, node, f"`{sub}.{verb.name}`")
        if args is None:
            return None
        return m.Command(node.span, sub, verb.name, args, node.sub.span)


def _shown(left: ast.Expr, op: str, right: ast.Expr, left_to: Type | None, right_to: Type | None) -> str:
    """`left op right` with one side converted (`x > f64(K)`), as a help shows it;
    `...` for an operand too long to repeat."""
    def text(e: ast.Expr, to: Type | None) -> str:
        t = e.span.text if len(e.span.text) <= 30 and "\n" not in e.span.text else "..."
        return f"{to}({t})" if to is not None else t
    return f"{text(left, left_to)} {op} {text(right, right_to)}"
