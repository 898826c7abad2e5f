"""The abstract syntax tree: what the engineer wrote, with a span on every node.

The tree mirrors the text closely (no name resolution, no types); `rcsc.semantics.sema`
turns it into the checked design model of `rcsc.semantics.model`.  Nodes have slots
(no per-instance dictionary): a large design has millions of them.
"""

from __future__ import annotations

from dataclasses import field

from rcsc.front.fields import Fields, node
from rcsc.front.source import Span


class _Slots(Fields):
    """The root of the node classes: a slot for the nesting depth the parser
    records on expressions and statements (see `rcsc.front.parse.MAX_NESTING`)."""

    __slots__ = ("depth",)


@node
class Node(_Slots):
    span: Span


@node
class DocComment(Node):
    """The `///` lines before an item (rcsc.front.doccomment), without the slashes."""

    text: str


@node
class Ident(Node):
    """A name together with the span of just that name."""

    name: str


# ---- expressions -------------------------------------------------------------


@node
class Expr(Node):
    pass


@node
class IntLit(Expr):
    value: int


@node
class FloatLit(Expr):
    value: float


@node
class BoolLit(Expr):
    value: bool


@node
class DurationLit(Expr):
    nanos: int
    text: str


@node
class Name(Expr):
    name: str


@node
class Attr(Expr):
    obj: Expr
    attr: Ident


@node
class Arg(Node):
    name: Ident | None
    value: Expr


@node
class Call(Expr):
    func: Ident
    args: list[Arg]


@node
class Index(Expr):
    """`obj[index]`: an element of a fixed-size array."""

    obj: Expr
    index: Expr


@node
class ArrayLit(Expr):
    """`[a, b, c]`."""

    items: list[Expr]


@node
class ArrayRepeat(Expr):
    """`[value; count]`: `count` copies of `value`."""

    value: Expr
    count: Expr


@node
class Unary(Expr):
    op: str  # "-" or "not"
    operand: Expr


@node
class Binary(Expr):
    op: str  # + - * / % == != < <= > >= and or
    left: Expr
    right: Expr
    op_span: Span


@node
class IfExpr(Expr):
    cond: Expr
    then: Expr
    else_: Expr


# ---- statements and jobs -------------------------------------------------------


@node
class Stmt(Node):
    pass


@node
class Assign(Stmt):
    target: list[Ident]  # a.b.c
    op: str  # = += -= *=
    value: Expr
    index: Expr | None = None  # `a.b[i] = v`: the element of the array `a.b`


@node
class CallStmt(Stmt):
    call: Call


@node
class Command(Stmt):
    sub: Ident
    verb: Ident
    args: list[Arg]


@node
class Report(Stmt):
    status: Ident


@node
class If(Stmt):
    branches: list[tuple[Expr, list[Stmt]]]
    else_body: list[Stmt] | None


# ---- declarations --------------------------------------------------------------


@node
class TypeRef(Node):
    name: Ident  # `[T; N]`: the span of the whole type, name "[]"
    lo: Expr | None = None
    hi: Expr | None = None
    elem: "TypeRef | None" = None  # `[T; N]`: T
    size: Expr | None = None  # `[T; N]`: N


@node
class Param(Node):
    name: Ident
    type: TypeRef
    doc: DocComment | None = None


@node
class Import(Node):
    target: str  # "std.math" or a relative path
    is_file: bool


@node
class Const(Node):
    name: Ident
    type: TypeRef
    value: Expr
    doc: DocComment | None = None


@node
class Enum(Node):
    name: Ident
    members: list[Ident]
    doc: DocComment | None = None


@node
class Record(Node):
    name: Ident
    fields: list[Param]
    doc: DocComment | None = None


@node
class GmVar(Node):
    name: Ident
    type: TypeRef
    init: Expr | None
    from_env: bool
    to_env: bool = False  # `to env`: an output the environment reads (an actuator)
    doc: DocComment | None = None


@node
class Function(Node):
    name: Ident
    params: list[Param]
    ret: TypeRef
    body: Expr
    doc: DocComment | None = None


@node
class Extern(Node):
    name: Ident
    params: list[Param]
    ret: TypeRef
    budget: DurationLit
    doc: DocComment | None = None


@node
class Verb(Node):
    name: Ident
    params: list[Param]
    doc: DocComment | None = None


@node
class VerbSet(Node):
    name: Ident
    verbs: list[Verb]
    doc: DocComment | None = None


@node
class StatePat(Node):
    kind: str  # "new", "any", "named"
    name: str | None = None


@node
class NextState(Node):
    kind: str  # "named", "done", "error", "same", "new"
    name: str | None = None
    code: Expr | None = None


@node
class Rule(Node):
    label: Ident
    guard: Expr | None  # None: the `otherwise` rule of its state
    guard_span: Span
    state: StatePat
    next: NextState
    jobs: list[Stmt]
    doc: DocComment | None = None


@node
class Plan(Node):
    name: Ident
    continuous: bool
    rules: list[Rule]
    modifiers: list[Ident] = field(default_factory=list)
    doc: DocComment | None = None


@node
class Decl(Node):
    """A named, typed member of a controller (status field or local)."""

    name: Ident
    type: TypeRef
    init: Expr
    doc: DocComment | None = None


@node
class NameList(Node):
    names: list[Ident]


@node
class Controller(Node):
    name: Ident
    simulator: bool
    level: list[tuple[int, Span]] = field(default_factory=list)
    budget: list[DurationLit] = field(default_factory=list)
    period: list[DurationLit] = field(default_factory=list)
    subordinates: list[NameList] = field(default_factory=list)
    reads: list[NameList] = field(default_factory=list)
    writes: list[NameList] = field(default_factory=list)
    verbs: list[Verb] = field(default_factory=list)
    verb_sets: list[Ident] = field(default_factory=list)
    reports: list[NameList] = field(default_factory=list)
    status_fields: list[Decl] = field(default_factory=list)
    locals: list[Decl] = field(default_factory=list)
    pre: list[tuple[Span, list[Stmt]]] = field(default_factory=list)
    post: list[tuple[Span, list[Stmt]]] = field(default_factory=list)
    plans: list[Plan] = field(default_factory=list)
    doc: DocComment | None = None
    blocks: list["BlockUse"] = field(default_factory=list)
    # Set by rcsc.front.instantiate: (parameter, argument) of a controller
    # type's value parameters, for the semantic pass to check as constants.
    param_args: list = field(default_factory=list)
    # Names the semantic pass must not report again (block instances, an
    # instance that could not be made); `placeholder`: such an instance.
    poisoned: list[str] = field(default_factory=list)
    placeholder: bool = False


# ---- controller types and function blocks (instantiated by rcsc.front.instantiate) ----


@node
class TypeParam(Node):
    """A parameter of a controller type: a compile-time constant (`max: f64`)
    or, with `type` None, a Global Memory binding (`cmd_out: gm`)."""

    name: Ident
    type: TypeRef | None


@node
class ControllerType(Node):
    """`controller type NAME(params) attrs { body }`: `body` is the template
    (a controller named after the type)."""

    name: Ident
    params: list[TypeParam]
    body: Controller
    doc: DocComment | None = None


@node
class ControllerInstance(Node):
    """`controller NAME: TYPE(args)`."""

    name: Ident
    simulator: bool
    type_name: Ident
    args: list[Arg]
    doc: DocComment | None = None


@node
class BlockUse(Node):
    """`block NAME: TYPE(args)` in a controller: one instance of a function block."""

    name: Ident
    type_name: Ident
    args: list[Arg]


@node
class BlockMember(Node):
    """`input NAME: type = init`, `state ...` or `output ...` of a block."""

    kind: str  # "input", "state", "output"
    name: Ident
    type: TypeRef
    init: Expr
    doc: DocComment | None = None


@node
class BlockType(Node):
    """`block NAME(params) { members; step { ... } }`: a function block."""

    name: Ident
    params: list[Param]
    members: list[BlockMember]
    steps: list[tuple[Span, list[Stmt]]]
    doc: DocComment | None = None


@node
class Cpu(Node):
    name: Ident
    heartbeat: list[DurationLit] = field(default_factory=list)
    overhead: list[DurationLit] = field(default_factory=list)
    schedule: list[NameList] = field(default_factory=list)
    doc: DocComment | None = None


@node
class File(Node):
    """One parsed source file: `design NAME` or `module a.b`, then items."""

    kind: str  # "design", "module" or "" (no header)
    name: Ident | None
    items: list[Node]
