"""The checked design model: the IR that the checks, the simulator and every backend consume.

`rcsc.sema.ast_to_model` builds it from the AST.  Everything in it is resolved
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

from rcsc.source import Span
from rcsc.types import Type

# Status values, numbered as in NIST rcslib; extra values are numbered after these.
UNINITIALIZED, DONE, EXEC, ERROR = -1, 1, 2, 3
FIRST_EXTRA_STATUS = 4

Value = Union[bool, int, float, str, dict]  # enums are member names; records dicts


# ---- expressions -------------------------------------------------------------


@dataclass
class Expr:
    span: Span
    type: Type


@dataclass
class Const(Expr):
    """A literal or a folded constant expression. `name` keeps a constant's name for readable code."""

    value: Value
    name: str | None = None


@dataclass
class Ref(Expr):
    """A named value. kind: gm | local | status | param | arg (function argument)."""

    kind: str
    name: str


@dataclass
class InState(Expr):
    """Time since the plan entered its current state (a duration)."""


@dataclass
class SubView(Expr):
    """The supervisor's view of a subordinate's status buffer.

    attr: done | error | executing | error_code | age | status (an extra status
    value, in `value`) | field (a status field, in `value`).
    """

    sub: str
    attr: str
    value: str | None = None


@dataclass
class Field(Expr):
    obj: Expr
    name: str


@dataclass
class Call(Expr):
    """kind: fn | extern | builtin (abs/min/max) | convert (i32/i64/u32/f64) | record."""

    kind: str
    func: str
    args: list[Expr]


@dataclass
class Unary(Expr):
    op: str  # "-" or "not"
    operand: Expr


@dataclass
class Binary(Expr):
    op: str  # + - * / % == != < <= > >= and or
    left: Expr
    right: Expr


@dataclass
class IfExpr(Expr):
    cond: Expr
    then: Expr
    else_: Expr


# ---- statements and jobs -------------------------------------------------------


@dataclass
class Stmt:
    span: Span


@dataclass
class LValue:
    span: Span
    kind: str  # gm | local | status
    name: str
    path: list[str]  # record fields below the variable
    type: Type


@dataclass
class Assign(Stmt):
    target: LValue
    op: str  # = += -= *=
    value: Expr


@dataclass
class CallStmt(Stmt):
    call: Call


@dataclass
class Command(Stmt):
    sub: str
    verb: str
    args: list[Expr]  # in the verb's parameter order
    sub_span: Span = None  # type: ignore[assignment]


@dataclass
class Report(Stmt):
    status: str


@dataclass
class If(Stmt):
    branches: list[tuple[Expr, list[Stmt]]]
    else_body: list[Stmt]


# ---- declarations --------------------------------------------------------------


@dataclass
class Range:
    lo: int | float
    hi: int | float


@dataclass
class Var:
    """A typed, initialised variable: GM variable, local, status field, parameter."""

    name: str
    type: Type
    span: Span
    init: Value | None = None
    range: Range | None = None
    from_env: bool = False  # GM only
    to_env: bool = False  # GM only: the environment reads it (an actuator output)


@dataclass
class ConstDef:
    name: str
    type: Type
    value: Value
    span: Span


@dataclass
class Function:
    name: str
    params: list[Var]
    ret: Type
    span: Span
    body: Expr | None = None  # None for externs
    extern: bool = False
    budget_ns: int = 0
    module: str = ""  # the design or module that declares it


@dataclass
class Verb:
    name: str
    params: list[Var]
    span: Span
    # Where the controller declares it: the verb itself, or its `verbs SET` line.
    use_span: Span | None = None

    def param(self, name: str) -> Var | None:
        return next((p for p in self.params if p.name == name), None)


@dataclass
class StateRef:
    """`new`, `*` (any) or a named state; as a next state also done/error/same."""

    kind: str  # new | any | named | done | error | same
    name: str | None
    span: Span
    code: int = 0  # error code for kind == error

    def __str__(self) -> str:
        return {"new": "new", "any": "*", "done": "done", "same": "*"}.get(
            self.kind, f"error({self.code})" if self.kind == "error" else str(self.name)
        )


@dataclass
class Rule:
    index: int  # position in the plan, from 0
    label: str
    span: Span
    label_span: Span
    state: StateRef
    guard: Expr | None  # None for `otherwise`
    guard_span: Span
    next: StateRef
    jobs: list[Stmt]

    @property
    def otherwise(self) -> bool:
        return self.guard is None

    @property
    def line(self) -> int:
        return self.span.line


@dataclass
class Plan:
    verb: str
    span: Span
    name_span: Span
    continuous: bool
    rules: list[Rule]
    # `plan X ordered`: the table is prioritized on purpose (first match wins
    # by design), so the guard analysis does not report overlapping rules.
    ordered: bool = False

    @property
    def states(self) -> list[str]:
        """Named states in order of first appearance."""
        seen: dict[str, None] = {}
        for r in self.rules:
            for ref in (r.state, r.next):
                if ref.kind == "named" and ref.name is not None:
                    seen.setdefault(ref.name, None)
        return list(seen)


@dataclass
class NameUse:
    name: str
    span: Span


@dataclass
class Controller:
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


@dataclass
class Cpu:
    name: str
    span: Span
    name_span: Span
    heartbeat_ns: int
    overhead_ns: int
    schedule: list[NameUse]
    heartbeat_span: Span | None = None


@dataclass
class Design:
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

    def supervisor_of(self, name: str) -> str | None:
        return self.controllers[name].supervisor


# ---- walking ---------------------------------------------------------------------


def walk_expr(e: Expr):
    """Every sub-expression of `e`, `e` first."""
    yield e
    if isinstance(e, Field):
        yield from walk_expr(e.obj)
    elif isinstance(e, Call):
        for a in e.args:
            yield from walk_expr(a)
    elif isinstance(e, Unary):
        yield from walk_expr(e.operand)
    elif isinstance(e, Binary):
        yield from walk_expr(e.left)
        yield from walk_expr(e.right)
    elif isinstance(e, IfExpr):
        yield from walk_expr(e.cond)
        yield from walk_expr(e.then)
        yield from walk_expr(e.else_)


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
    elif isinstance(s, CallStmt):
        yield s.call
    elif isinstance(s, Command):
        yield from s.args
    elif isinstance(s, If):
        for cond, _ in s.branches:
            yield cond
