"""The Rust target: type table, expressions and statements (`<node>_expr`, `<node>_stmt`).

Expressions are built as trees (`rcsc.backends.rust.fmt`), which lay
themselves out as rustfmt does; `<node>_stmt` methods return the lines of a
statement.

Every name in the generated Rust comes from `naming.RustNames` (`self.n`),
one method per kind of name; the design's names are kept where they can be,
so the library allows the naming lints.  Design-wide items live in `types`
(types, constants, Global Memory, buffers) and `functions` (pure
functions); a controller's states and rules are associated constants of its
struct (`Self::S_S1`, `Self::RULE_AHEAD_E0`).

Numbers follow the numeric rules (docs/language.md §5) with no panic even under
`overflow-checks = true`: integer arithmetic is `wrapping_*` (as
`i32::wrapping_add(a, b)`) or a helper of `num` (division, remainder,
abs), f64 arithmetic is plain Rust, conversions are `as` (which saturates
float to int, gives 0 for NaN and wraps int to int, the language's rules).
"""

from __future__ import annotations

import math
import re

from rcsc.semantics import model as m
from rcsc.backends.rust.naming import RustNames
from rcsc.outputs.backend import BuildOptions, CtrlInfo, Target, base_cpu, cpu_ticks, expr_key, initial_value, lower_controller
from rcsc.backends.rust.fmt import (
    P_POSTFIX,
    P_UNARY,
    Array,
    Atom,
    Bin,
    Call,
    Cast,
    FieldOf,
    If,
    Node,
    Paren,
    Struct,
    Unary,
    assign,
    expr_stmt,
    if_open,
    let,
    pad,
)
from rcsc.semantics.types import BOOL, DURATION, I64, U32, ArrayType, EnumType, FloatType, IntType, RecordType, Type

INT_NAME = {"i32": "i32", "i64": "i64", "u32": "u32", "duration": "i64"}
WRAPPING = {"+": "wrapping_add", "-": "wrapping_sub", "*": "wrapping_mul"}
NUM_DIV = {"/": "div", "%": "rem"}
RUST_BIN = {"and": "&&", "or": "||"}


def rust_comment(text: str) -> str:
    """Design text made safe on one `//` or `///` comment line (the Rust target's
    comment sanitiser).  White space runs become one space (no newline ends the
    line early, no bare CR, which rustc refuses in doc comments, no tab,
    clippy::tabs_in_doc_comments); a character that is not printable ASCII
    becomes `?` (rustc refuses bidirectional controls); `/*` and `*/` are split
    (Rust block comments nest); a backquote becomes `'` (in a doc comment it
    would open Markdown code, a doctest)."""
    text = "".join(ch if " " <= ch <= "~" else (" " if ch.isspace() else "?") for ch in text)
    text = re.sub(r" +", " ", text).strip().replace("`", "'")
    return re.sub(r"(?<=/)(?=\*)|(?<=\*)(?=/)", " ", text)


def rust_string(text: str) -> str:
    out = ['"']
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ch == "\n":
            out.append("\\n")
        elif ord(ch) < 0x20:
            out.append(f"\\u{{{ord(ch):x}}}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


class RustTarget(Target):
    name = "rust"
    comment = staticmethod(rust_comment)
    summary = "Rust crate: a no_std, unsafe-free controller library and a std Main Program per CPU"
    package = "rcsc.backends.rust"
    multi_cpu = True
    multi_rate = True

    def __init__(self, design: m.Design, options: BuildOptions | None = None) -> None:
        super().__init__(design, options)
        top_level = [*design.consts, *design.enums, *design.records, *design.functions, *design.controllers, *design.gm, *design.cpus]
        self.n = RustNames(design.name, top_level, list(design.controllers), list(design.cpus), [*design.consts, *design.functions])
        self.crate = self.n.crate
        self.infos = {name: lower_controller(c) for name, c in design.controllers.items()}
        # Context of the code being emitted.
        self.info: CtrlInfo | None = None
        self.verb: str | None = None
        # What the code emitted since the last `begin()` used: "num", "types",
        # "functions", "ext", "cycle".
        self.uses: set[str] = set()
        # Pure calls computed once for the conditions being emitted: expr_key -> local name.
        self.cse: dict[object, str] = {}

    def begin(self) -> None:
        self.uses = set()

    # ---- names and types ---------------------------------------------------------

    def ident(self, name: str) -> str:
        """A struct field, an enum variant or an extern method named by the design."""
        return self.n.member(name)

    def tname(self, name: str) -> str:
        """A design-wide type (enum, record, controller)."""
        return self.n.global_(name)

    def vname(self, name: str) -> str:
        """A design-wide value (constant, function)."""
        return self.n.global_(name)

    def param(self, name: str) -> str:
        return self.n.param(name)

    def rtype(self, t: Type) -> str:
        if t == BOOL:
            return "bool"
        if t == DURATION:
            return "i64"
        if isinstance(t, IntType):
            return t.name
        if isinstance(t, FloatType):
            return "f64"
        if isinstance(t, (EnumType, RecordType)):
            return self.tname(t.name)
        if isinstance(t, ArrayType):
            return f"num::Arr<{self.rtype(t.elem)}, {t.size}>"
        raise ValueError(f"no Rust type for {t}")

    def period_const(self, cpu: str) -> str:
        return self.n.period(cpu)

    def state_const(self, name: str) -> str:
        return self.n.state(name)

    def rule_const(self, verb: str, label: str) -> str:
        return self.n.rule(verb, label)

    # ---- values --------------------------------------------------------------------

    def literal(self, value, t: Type) -> Node:
        if t == BOOL:
            return Atom("true" if value else "false")
        if isinstance(t, IntType) or t == DURATION:
            v = int(value)
            it = I64 if t == DURATION else t
            assert isinstance(it, IntType)
            if it.signed and v == it.min:
                return Atom(f"{it.name}::MIN")
            # Suffixed: an unsuffixed literal takes its type from inference,
            # which falls back to i32 where nothing constrains it (`if c { 1 }
            # else { 3000000000 } <= 1000000000` would not compile).
            return Atom(f"{v}_{it.name}", P_UNARY if v < 0 else P_POSTFIX)
        if isinstance(t, FloatType):
            x = float(value)
            if math.isnan(x):
                return Atom("f64::NAN")
            if math.isinf(x):
                return Atom("f64::INFINITY" if x > 0 else "f64::NEG_INFINITY")
            text = repr(x)
            if "." not in text and "e" not in text:
                text += ".0"
            return Atom(f"{text}_f64", P_UNARY if text.startswith("-") else P_POSTFIX)
        if isinstance(t, EnumType):
            return Atom(f"{self.tname(t.name)}::{self.ident(str(value))}")
        if isinstance(t, RecordType):
            return Struct(self.tname(t.name), [(self.ident(n), self.literal(value[n], ft)) for n, ft in t.fields])
        if isinstance(t, ArrayType):
            return Call("num::Arr", [Array([self.literal(v, t.elem) for v in value])])
        raise ValueError(f"no Rust literal for {t}")

    def init_value(self, v: m.Var) -> Node:
        return self.literal(initial_value(v), v.type)

    # ---- expressions ---------------------------------------------------------------

    def const_expr(self, e: m.Const) -> Node:
        if e.name is not None and e.name in self.design.consts:
            self.uses.add("types")
            return Atom(self.vname(e.name))
        if isinstance(e.type, (EnumType, RecordType)):
            self.uses.add("types")
        if isinstance(e.type, ArrayType):
            self.uses.add("num")
            t = e.type.elem
            while isinstance(t, ArrayType):
                t = t.elem
            if isinstance(t, (EnumType, RecordType)):
                self.uses.add("types")
        return self.literal(e.value, e.type)

    def own(self) -> str:
        """The controller's own status buffer (it lives in the CPU's buffers)."""
        assert self.info is not None
        return f"buf.{self.n.buffer_member(self.info.c.name, 'status')}"

    def ref_expr(self, e: m.Ref) -> Node:
        name = self.ident(e.name)
        if e.kind == "gm":
            return Atom(f"buf.gm.{name}")
        if e.kind == "local":
            return Atom(f"self.loc.{name}")
        if e.kind == "status":
            return Atom(f"{self.own()}.f.{name}")
        if e.kind == "param":
            assert self.info is not None and self.verb is not None, "a command parameter outside a plan"
            return Atom(f"buf.{self.n.buffer_member(self.info.c.name, 'cmd')}.args.{self.ident(self.verb)}.{name}")
        return Atom(self.param(e.name))  # a function's parameter

    def _period(self) -> str:
        assert self.info is not None
        self.uses.add("types")
        return self.period_const(self.info.c.cpu or "")

    def tick(self) -> Node:
        """The tick at which the current cycle of the controller's CPU is released (stamps count ticks)."""
        assert self.info is not None
        n = cpu_ticks(self.design, self.info.c.cpu or "")
        if n == 1:
            return Atom("cycle")
        self.uses.add("num")
        return Call("num::tick", [Atom("cycle"), Atom(str(n))])

    def age_of(self, stamp: str) -> Node:
        """The time since the tick `stamp`, in base ticks (the shortest heartbeat)."""
        self.uses.update(("num", "cycle", "types"))
        return Call("num::cycles_ns", [self.tick(), Atom(stamp), Atom(self.period_const(base_cpu(self.design).name))])

    def age_expr(self, e: m.Age) -> Node:
        return self.age_of(f"buf.gm_stamp.{self.ident(e.name)}")

    def cycle_expr(self, e: m.Cycle) -> Node:
        assert self.info is not None
        self.uses.update(("num", "cycle"))
        return Call("num::step_number", [Atom("cycle"), Atom(str(max(1, self.info.c.divider)))])

    def instate_expr(self, e: m.InState) -> Node:
        self.uses.update(("num", "cycle"))
        return Call("num::cycles_ns", [Atom("cycle"), Atom("self.entry_cycle"), Atom(self._period())])

    def subview_expr(self, e: m.SubView) -> Node:
        assert self.info is not None
        status = f"buf.{self.n.buffer_member(e.sub, 'status')}"
        head, sent = Unary("&", Atom(f"{status}.head")), Atom(f"self.sent.{self.ident(e.sub)}")
        if e.attr in ("done", "error", "executing"):
            self.uses.add("types")
            return Call(f"sub_{e.attr}", [head, sent])
        if e.attr == "status":
            self.uses.add("types")
            return Call("sub_status", [head, sent, Atom(self.n.status(e.sub, e.value or ""))])
        if e.attr == "error_code":
            return Atom(f"{status}.head.error_code")
        if e.attr == "age":
            return self.age_of(f"{status}.head.stamp")
        if e.attr == "field":
            return Atom(f"{status}.f.{self.ident(e.value or '')}")
        raise ValueError(e.attr)

    def field_expr(self, e: m.Field) -> Node:
        obj = self.expr(e.obj)
        name = self.ident(e.name)
        if isinstance(obj, Atom) and obj.prec == P_POSTFIX:
            return Atom(f"{obj.text}.{name}")
        if obj.prec < P_POSTFIX or isinstance(obj, Struct):
            obj = Paren(obj)
        return Atom(f"{obj.flat()}.{name}") if isinstance(obj, Atom) else FieldOf(obj, name)

    def index64(self, e: m.Expr) -> Node:
        """An array index as the i64 that `num::at`/`num::slot` take."""
        v = self.expr(e)
        return v if e.type == I64 else Call("i64::from", [v])

    def index_expr(self, e: m.Index) -> Node:
        """`a[i]`: the element, or the element type's zero outside 0..N-1 (`num::at`)."""
        from rcsc.semantics.evaluate import zero_value

        self.uses.add("num")
        if isinstance(e.type, (EnumType, RecordType)):
            self.uses.add("types")
        return Call("num::at", [Unary("&", self.expr(e.obj)), self.index64(e.index), self.literal(zero_value(e.type), e.type)])

    def arraylit_expr(self, e: m.ArrayLit) -> Node:
        self.uses.add("num")
        return Call("num::Arr", [Array([self.expr(x) for x in e.items])])

    def unary_expr(self, e: m.Unary) -> Node:
        v = self.expr(e.operand)
        if e.op == "not":
            return Unary.make("!", v)
        if e.type.name in INT_NAME:
            return Call(f"{INT_NAME[e.type.name]}::wrapping_neg", [v])
        return Unary.make("-", v)

    def binary_expr(self, e: m.Binary) -> Node:
        a, b = self.expr(e.left), self.expr(e.right)
        if e.op in RUST_BIN:
            return Bin.make(RUST_BIN[e.op], a, b)
        if e.type == BOOL:
            if e.left.type == BOOL and e.op in ("==", "!=") and (_bool_const(e.left) is not None or _bool_const(e.right) is not None):
                # `x == true` is `x` (clippy::bool_comparison); both sides are evaluated either way.
                lit, other = (e.left, b) if _bool_const(e.left) is not None else (e.right, a)
                positive = (_bool_const(lit) is True) == (e.op == "==")
                return other if positive else Unary.make("!", other)
            return Bin.make(e.op, a, b)
        if e.type.name in INT_NAME:
            t = INT_NAME[e.type.name]
            if e.op in WRAPPING:
                return Call(f"{t}::{WRAPPING[e.op]}", [a, b])
            self.uses.add("num")
            return Call(f"num::{NUM_DIV[e.op]}_{t}", [a, b])
        return Bin.make(e.op, a, b)

    def ifexpr_expr(self, e: m.IfExpr) -> Node:
        return If(self.expr(e.cond), self.expr(e.then), self.expr(e.else_))

    def call_expr(self, e: m.Call) -> Node:
        if e.kind in ("fn", "extern") and expr_key(e) in self.cse:
            return Atom(self.cse[expr_key(e)])
        args = [self.expr(a) for a in e.args]
        if e.kind == "fn":
            self.uses.add("functions")
            return Call(self.vname(e.func), args)
        if e.kind == "extern":
            # `Externs::f(ext, ...)` rather than `ext.f(...)`: the same call, laid out as a
            # call (rustfmt lays method calls out as chains).
            self.uses.add("ext")
            return Call(f"Externs::{self.ident(e.func)}", [Atom("ext")] + args)
        if e.kind == "record":
            self.uses.add("types")
            assert isinstance(e.type, RecordType)
            return Struct(self.tname(e.type.name), [(self.ident(n), a) for (n, _), a in zip(e.type.fields, args)])
        if e.kind == "convert":
            return self._convert(args[0], e.args[0].type, e.type)
        if e.func == "seconds":
            return Bin.make("/", Cast.make(args[0], "f64"), Atom("1e9"))
        is_float = isinstance(e.type, FloatType)
        if e.func in ("sum", "min_of", "max_of"):
            self.uses.add("num")
            if e.func == "sum" or is_float:
                return Call(f"num::{e.func}_{'f64' if is_float else INT_NAME[e.type.name]}", [Unary("&", args[0])])
            return Call(f"num::{e.func}", [Unary("&", args[0])])
        if e.func == "abs":
            if e.type == U32:
                return args[0]  # |x| of an unsigned value is x (and needs no `num`)
            self.uses.add("num")
            if is_float:
                return Call("num::fabs", args)
            return Call(f"num::abs_{INT_NAME[e.type.name]}", args)
        if is_float:
            self.uses.add("num")
            return Call(f"num::{e.func}_f64", args)
        return Call(f"core::cmp::{e.func}", args)

    def _convert(self, v: Node, src: Type, dst: Type) -> Node:
        s, d = self.rtype(src), self.rtype(dst)
        if s == d:
            return v
        return Cast.make(v, d)

    # ---- statements ----------------------------------------------------------------

    def lvalue(self, lv: m.LValue) -> str:
        base = {"gm": "buf.gm", "local": "self.loc", "status": f"{self.own()}.f"}[lv.kind]
        return ".".join([base, self.ident(lv.name)] + [self.ident(p) for p in lv.path])

    def assign_stmt(self, s: m.Assign, indent: int) -> list[str]:
        target = self.lvalue(s.target)
        value = self.expr(s.value)
        if s.target.index is not None:
            # `a[i] = v`: the value, then the index (the simulator's order); a
            # write outside 0..N-1 is ignored (`num::slot` gives None).
            self.uses.add("num")
            t = s.target.type
            if s.op == "=":
                store = assign("*rcs_e", "=", Atom("rcs_x"), indent + 2)
            elif t.name in INT_NAME:
                store = assign("*rcs_e", "=", Call(f"{INT_NAME[t.name]}::{WRAPPING[s.op[0]]}", [Atom("*rcs_e"), Atom("rcs_x")]), indent + 2)
            else:
                store = assign("*rcs_e", s.op, Atom("rcs_x"), indent + 2)
            return ([f"{pad(indent)}{{"] + let("rcs_x", value, indent + 1) + let("rcs_i", self.index64(s.target.index), indent + 1)
                    + [f"{pad(indent + 1)}if let Some(rcs_e) = num::slot(&mut {target}, rcs_i) {{"] + store
                    + [f"{pad(indent + 1)}}}", f"{pad(indent)}}}"])
        if s.op == "=" and isinstance(value, Atom) and value.text == target:
            # `x = x;` is legal in a design and does nothing; written in Rust
            # it is a dead_code warning and a clippy::self_assignment error.
            return [f"{pad(indent)}// {target} = {target}: no effect"]
        if s.op == "=":
            return assign(target, "=", value, indent)
        op = s.op[0]
        t = s.target.type
        if t.name in INT_NAME:
            return assign(target, "=", Call(f"{INT_NAME[t.name]}::{WRAPPING[op]}", [Atom(target), value]), indent)
        return assign(target, s.op, value, indent)

    def callstmt_stmt(self, s: m.CallStmt, indent: int) -> list[str]:
        e = self.expr(s.call)
        if s.call.kind in ("fn", "extern"):
            return expr_stmt(e, indent)
        # A built-in or a conversion has no effect; it is evaluated all the same.
        return let("_", e, indent)

    def command_stmt(self, s: m.Command, indent: int) -> list[str]:
        sub = self.ident(s.sub)
        verb = self.design.controllers[s.sub].verbs[s.verb]
        self.uses.add("types")
        # Written in place: nothing else runs during this step, and the serial
        # that makes the command new is set at the write phase.
        cmd = self.n.buffer_member(s.sub, "cmd")
        out = assign(f"buf.{cmd}.head.verb", "=", Atom(self.n.verb(s.sub, s.verb)), indent)
        for p, a in zip(verb.params, s.args):
            out += assign(f"buf.{cmd}.args.{self.ident(s.verb)}.{self.ident(p.name)}", "=", self.expr(a), indent)
        out += assign(f"self.send.{sub}", "=", Atom("true"), indent)
        return out

    def report_stmt(self, s: m.Report, indent: int) -> list[str]:
        assert self.info is not None
        self.uses.add("types")
        return assign(f"{self.own()}.head.status", "=", Atom(self.n.status(self.info.c.name, s.status)), indent)

    def if_stmt(self, s: m.If, indent: int) -> list[str]:
        out: list[str] = []
        branches = list(s.branches)
        else_body = s.else_body
        # `else { if ... }` with nothing else in the else block is an `else if` chain.
        while len(else_body) == 1 and isinstance(else_body[0], m.If):
            branches += else_body[0].branches
            else_body = else_body[0].else_body
        for i, (cond, body) in enumerate(branches):
            out += if_open(self.expr(cond), indent, "if" if i == 0 else "} else if")
            out += self.stmts(body, indent + 1)
        if else_body:
            out.append(f"{pad(indent)}}} else {{")
            out += self.stmts(else_body, indent + 1)
        out.append(f"{pad(indent)}}}")
        return out


def _bool_const(e: m.Expr):
    if isinstance(e, m.Const) and e.type == BOOL and e.name is None:
        return bool(e.value)
    return None
