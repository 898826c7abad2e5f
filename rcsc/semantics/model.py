"""The checked design model: the IR that the checks, the simulator and every backend consume.

`rcsc.semantics.sema.ast_to_model` builds it from the AST.  Everything in it is resolved
and typed: a name in an expression is a `Ref` that says what it refers to
(Global Memory, local, status field, command parameter, constant, function
parameter), calls know their callee, command arguments are in parameter
order, constant expressions are folded to values.  Every node keeps the span
of the text it came from, so later stages can point at it.

Containers are dicts in declaration order; the order is part of the design
(rule order, schedule order) and keeps every output deterministic.
See docs/model.md for a guided tour.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union

from rcsc.front.fields import Fields, node
from rcsc.front.source import Span
from rcsc.semantics.types import Type

# Status values, numbered as in NIST rcslib; extra values are numbered after these.
UNINITIALIZED, DONE, EXEC, ERROR = -1, 1, 2, 3
FIRST_EXTRA_STATUS = 4

Value = Union[bool, int, float, str, dict, list]  # enums are member names; records dicts; arrays lists


# ---- expressions -------------------------------------------------------------


class _Compiled(Fields):
    """The root of the expression classes: a slot where `rcsc.semantics.evaluate` keeps
    an expression's compiled closure, and one where `walk_expr` keeps its walk."""

    __slots__ = ("_compiled", "_walk")


@node
class Expr(_Compiled):
    span: Span
    type: Type


@node
class Const(Expr):
    """A literal or a folded constant expression. `name` keeps a constant's name for readable code."""

    value: Value
    name: str | None = None


@node
class Ref(Expr):
    """A named value. kind: gm | local | status | param | arg (function argument)."""

    kind: str
    name: str


@node
class InState(Expr):
    """Time since the plan entered its current state (a duration)."""


@node
class Cycle(Expr):
    """`cycle`: the number of the controller's current step, counted from 1
    (an i64; with `period`, one step every `divider` cycles of its CPU)."""


@node
class Age(Expr):
    """`age(V)` of a Global Memory variable V: the reader's release instant minus
    the instant the value it read became visible (a duration).

    `age(SUB)` of a subordinate is the `SubView` with attr `age` (the same as `SUB.age`).
    """

    name: str


@node
class SubView(Expr):
    """The supervisor's view of a subordinate's status buffer.

    attr: done | error | executing | error_code | age | status (an extra status
    value, in `value`) | field (a status field, in `value`).
    """

    sub: str
    attr: str
    value: str | None = None


@node
class Field(Expr):
    obj: Expr
    name: str


@node
class Call(Expr):
    """kind: fn | extern | builtin (abs/min/max) | convert (i32/i64/u32/f64) | record."""

    kind: str
    func: str
    args: list[Expr]


@node
class Index(Expr):
    """`obj[index]`: an element of an array; out of range it is the element type's zero."""

    obj: Expr
    index: Expr


@node
class ArrayLit(Expr):
    """`[a, b, c]` with an element that is not constant (constant ones fold to a Const list)."""

    items: list[Expr]


@node
class Unary(Expr):
    op: str  # "-" or "not"
    operand: Expr


@node
class Binary(Expr):
    op: str  # + - * / % == != < <= > >= and or
    left: Expr
    right: Expr


@node
class IfExpr(Expr):
    cond: Expr
    then: Expr
    else_: Expr


# ---- statements and jobs -------------------------------------------------------


@node
class Stmt(Fields):
    span: Span


@node
class LValue(Fields):
    span: Span
    kind: str  # gm | local | status
    name: str
    path: list[str]  # record fields below the variable
    type: Type  # the type of what is assigned (the element's, with `index`)
    index: Expr | None = None  # `a[i] = v`: the element i of the array at `path` (ignored out of range)


@node
class Assign(Stmt):
    target: LValue
    op: str  # = += -= *=
    value: Expr


@node
class CallStmt(Stmt):
    call: Call


@node
class Command(Stmt):
    sub: str
    verb: str
    args: list[Expr]  # in the verb's parameter order
    sub_span: Span = None  # type: ignore[assignment]


@node
class Report(Stmt):
    status: str


@node
class If(Stmt):
    branches: list[tuple[Expr, list[Stmt]]]
    else_body: list[Stmt]


# ---- declarations --------------------------------------------------------------


@dataclass(repr=False, eq=False)
class Range(Fields):
    lo: int | float
    hi: int | float


@dataclass(repr=False, eq=False)
class Var(Fields):
    """A typed, initialised variable: GM variable, local, status field, parameter."""

    name: str
    type: Type
    span: Span
    init: Value | None = None
    range: Range | None = None
    from_env: bool = False  # GM only
    to_env: bool = False  # GM only: the environment reads it (an actuator output)
    doc: str = ""  # the `///` comment before it (rcsc.front.doccomment)


@dataclass(repr=False, eq=False)
class ConstDef(Fields):
    name: str
    type: Type
    value: Value
    span: Span
    doc: str = ""  # the `///` comment before it (rcsc.front.doccomment)


@dataclass(repr=False, eq=False)
class Function(Fields):
    name: str
    params: list[Var]
    ret: Type
    span: Span
    body: Expr | None = None  # None for externs
    extern: bool = False
    budget_ns: int = 0
    module: str = ""  # the design or module that declares it
    doc: str = ""  # the `///` comment before it (rcsc.front.doccomment)


@dataclass(repr=False, eq=False)
class Verb(Fields):
    name: str
    params: list[Var]
    span: Span
    # Where the controller declares it: the verb itself, or its `verbs SET` line.
    use_span: Span | None = None
    doc: str = ""  # the `///` comment before it (rcsc.front.doccomment)

    def param(self, name: str) -> Var | None:
        return next((p for p in self.params if p.name == name), None)


@dataclass(repr=False, eq=False)
class StateRef(Fields):
    """`new`, `*` (any) or a named state; as a next state also done/error/same."""

    kind: str  # new | any | named | done | error | same
    name: str | None
    span: Span
    code: int = 0  # error code for kind == error

    def __str__(self) -> str:
        return {"new": "new", "any": "*", "done": "done", "same": "*"}.get(
            self.kind, f"error({self.code})" if self.kind == "error" else str(self.name)
        )


@dataclass(repr=False, eq=False)
class Rule(Fields):
    index: int  # position in the plan, from 0
    label: str
    span: Span
    label_span: Span
    state: StateRef
    guard: Expr | None  # None for `otherwise`
    guard_span: Span
    next: StateRef
    jobs: list[Stmt]
    doc: str = ""  # the `///` comment before it (rcsc.front.doccomment)

    @property
    def otherwise(self) -> bool:
        return self.guard is None

    @property
    def line(self) -> int:
        return self.span.line


@dataclass(repr=False, eq=False)
class Plan(Fields):
    verb: str
    span: Span
    name_span: Span
    continuous: bool
    rules: list[Rule]
    # `plan X ordered`: the table is prioritized on purpose (first match wins
    # by design), so the guard analysis does not report overlapping rules.
    ordered: bool = False
    doc: str = ""  # the `///` comment before it (rcsc.front.doccomment)

    @property
    def states(self) -> list[str]:
        """Named states in order of first appearance."""
        seen: dict[str, None] = {}
        for r in self.rules:
            for ref in (r.state, r.next):
                if ref.kind == "named" and ref.name is not None:
                    seen.setdefault(ref.name, None)
        return list(seen)


@dataclass(repr=False, eq=False)
class NameUse(Fields):
    name: str
    span: Span


class PlansElided(Exception):
    """A check read the plans of a controller whose plans a re-check left out
    (`ElidedPlans`): the re-check cannot answer for it and checks in full."""


class ElidedPlans:
    """The plans of a controller that an incremental re-check did not parse
    again (`rcsc.checks.incremental`): its findings come from the previous
    check, and what other controllers' checks need of its plans from
    `summary` (see `rcsc.checks.incremental.controller_summary`).  Any use
    of the plans themselves raises `PlansElided`, so a check that would
    need them is never answered from a stale or empty table.  (Not a dict
    subclass: C code reads a dict's storage directly, past any override.)"""

    __slots__ = ("summary",)

    def __init__(self, summary: dict) -> None:
        self.summary = summary

    def _refuse(self, *args, **kwargs):
        raise PlansElided()

    __getitem__ = __contains__ = __iter__ = __len__ = __bool__ = __eq__ = _refuse  # type: ignore[assignment]
    get = keys = values = items = _refuse
    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return "ElidedPlans(...)"


def is_elided(c: "Controller") -> bool:
    return type(c.plans) is ElidedPlans


def checked_controllers(design: "Design") -> list["Controller"]:
    """The controllers whose own plans a check family examines: all of them,
    except in an incremental re-check those whose plans were left out (their
    findings are the previous check's)."""
    return [c for c in design.controllers.values() if type(c.plans) is not ElidedPlans]


@dataclass(repr=False, eq=False)
class Controller(Fields):
    name: str
    span: Span
    name_span: Span
    simulator: bool
    level: int
    budget_ns: int
    subordinates: list[NameUse] = field(default_factory=list)
    reads: list[NameUse] = field(default_factory=list)
    writes: list[NameUse] = field(default_factory=list)
    verbs: dict[str, Verb] = field(default_factory=dict)
    statuses: dict[str, int] = field(default_factory=dict)  # extra status values -> number
    status_spans: dict[str, Span] = field(default_factory=dict)
    status_fields: dict[str, Var] = field(default_factory=dict)
    locals: dict[str, Var] = field(default_factory=dict)
    pre: list[Stmt] = field(default_factory=list)
    post: list[Stmt] = field(default_factory=list)
    plans: dict[str, Plan] = field(default_factory=dict)
    level_span: Span | None = None
    budget_span: Span | None = None
    supervisor: str | None = None  # filled in by the hierarchy check
    cpu: str | None = None  # filled in by the timing check
    # `period D` as written (0: not written), and the rate the timing check
    # derives from it: the controller steps on every `divider`-th cycle of its
    # CPU (cycles 1, 1 + divider, ...), so its period is divider * heartbeat.
    declared_period_ns: int = 0
    period_span: Span | None = None
    divider: int = 1  # filled in by the timing check
    period_ns: int = 0  # filled in by the timing check
    doc: str = ""  # the `///` comment before it (rcsc.front.doccomment)
    # An instance of a controller type that could not be made (reported):
    # its verbs, status and Global Memory are unknown, so the checks say
    # nothing about its uses.
    placeholder: bool = False


@dataclass(repr=False, eq=False)
class Crossing(Fields):
    """A buffer written on one CPU and read on others (each reader keeps its own copy).

    kind: gm (a Global Memory variable), cmd (the command buffer of controller
    `name`, written by its supervisor) or status (the status buffer of
    controller `name`, read by its supervisor).
    """

    kind: str
    name: str
    writer_cpu: str
    reader_cpus: list[str]


@dataclass(repr=False, eq=False)
class Cpu(Fields):
    name: str
    span: Span
    name_span: Span
    heartbeat_ns: int
    overhead_ns: int
    schedule: list[NameUse]
    heartbeat_span: Span | None = None
    doc: str = ""  # the `///` comment before it (rcsc.front.doccomment)


@dataclass(repr=False, eq=False)
class Design(Fields):
    name: str
    span: Span
    enums: dict[str, Type] = field(default_factory=dict)
    records: dict[str, Type] = field(default_factory=dict)
    consts: dict[str, ConstDef] = field(default_factory=dict)
    gm: dict[str, Var] = field(default_factory=dict)
    functions: dict[str, Function] = field(default_factory=dict)
    controllers: dict[str, Controller] = field(default_factory=dict)
    cpus: dict[str, Cpu] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)
    # The root is a module checked on its own (`rcsc check lib.rcs`, a file
    # nobody imports): declarations, not something that runs.
    is_module: bool = False
    # Controllers scheduled only by a CPU that is defined a second time (an
    # E0101): they are not also "never scheduled" (E0603).
    dropped_schedule: set[str] = field(default_factory=set)
    # Filled in by the timing check: GM variables in declaration order, then
    # command and status buffers in controller declaration order.
    crossings: list[Crossing] = field(default_factory=list)
    # The digest of the declarations the value analysis depends on, made by
    # it when it keeps results between runs (`rcsc.checks.values.globals_key`),
    # or brought by an incremental re-check from the last check.
    values_context: str | None = None

    @property
    def base_tick_ns(self) -> int:
        """The shortest heartbeat: the unit of scenario ticks (0 without CPUs)."""
        beats = [c.heartbeat_ns for c in self.cpus.values() if c.heartbeat_ns > 0]
        return min(beats) if beats else 0

    def supervisor_of(self, name: str) -> str | None:
        return self.controllers[name].supervisor


# ---- walking ---------------------------------------------------------------------


def walk_expr(e: Expr) -> list[Expr]:
    """Every sub-expression of `e`, `e` first (pre-order, left to right).

    Iterative: nested generators would cost a step per level for every
    node, which is quadratic in long `a and b and c ...` chains.  The
    checks walk every expression several times, so this is a hot path: it
    dispatches on the exact class (no subclasses of the node classes exist)
    and returns a list.

    The list is kept in the node (`_walk`) and returned again by later
    calls: the check families walk the same conditions and jobs many times
    (about five walks per expression).  The model is not changed after
    `ast_to_model` (a node is replaced, never edited in place), and the
    kept list starts with the node itself, so a copied node (which copies
    the slot) walks afresh.  Callers must not change the list.
    """
    memo = getattr(e, "_walk", None)
    if memo is not None and memo[0] is e:
        return memo
    out: list[Expr] = []
    add = out.append
    stack = [e]
    pop, push = stack.pop, stack.append
    while stack:
        x = pop()
        add(x)
        t = type(x)
        if t in _LEAVES:
            continue
        if t is Binary:
            push(x.right)
            push(x.left)
        elif t is Field:
            push(x.obj)
        elif t is Call:
            stack.extend(reversed(x.args))
        elif t is Unary:
            push(x.operand)
        elif t is IfExpr:
            push(x.else_)
            push(x.then)
            push(x.cond)
        elif t is Index:
            push(x.index)
            push(x.obj)
        elif t is ArrayLit:
            stack.extend(reversed(x.items))
        elif isinstance(x, (Binary, Field, Call, Unary, IfExpr)):  # pragma: no cover - a subclass
            raise TypeError(f"walk_expr: subclass {t.__name__} of a node class")
    e._walk = out
    return out


_LEAVES = frozenset((Const, Ref, InState, Cycle, Age, SubView))


def expr_children(x: Expr) -> tuple[Expr, ...]:
    """The direct sub-expressions of `x`, left to right (the order `walk_expr` visits them)."""
    t = type(x)
    if t is Binary:
        return (x.left, x.right)
    if t is IfExpr:
        return (x.cond, x.then, x.else_)
    if t is Unary:
        return (x.operand,)
    if t is Field:
        return (x.obj,)
    if t is Call:
        return tuple(x.args)
    if t is Index:
        return (x.obj, x.index)
    if t is ArrayLit:
        return tuple(x.items)
    return ()


def walk_stmts(stmts: list[Stmt]):
    """Every statement of a block, nested ones included, in order."""
    for s in stmts:
        yield s
        if isinstance(s, If):
            for _, body in s.branches:
                yield from walk_stmts(body)
            yield from walk_stmts(s.else_body)


def stmt_exprs(s: Stmt):
    """The expressions directly held by one statement."""
    if isinstance(s, Assign):
        yield s.value
        if s.target.index is not None:
            yield s.target.index
    elif isinstance(s, CallStmt):
        yield s.call
    elif isinstance(s, Command):
        yield from s.args
    elif isinstance(s, If):
        for cond, _ in s.branches:
            yield cond


def controller_exprs(c: Controller) -> list[Expr]:
    """The top-level expressions of a controller: pre, post and jobs in order, then the rules' guards."""
    exprs: list[Expr] = []
    for stmts in [c.pre, c.post] + [r.jobs for p in c.plans.values() for r in p.rules]:
        for s in walk_stmts(stmts):
            exprs.extend(stmt_exprs(s))
    for p in c.plans.values():
        exprs.extend(r.guard for r in p.rules if r.guard is not None)
    return exprs
