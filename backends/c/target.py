"""The C target: type table, expressions and statements (`<node>_expr`, `<node>_stmt`).

Every name in the generated C comes from `naming.CNames` (`self.n`), one
method per kind of name, so that no two things of the design get one name.

Numbers follow the numeric rules (docs/language.md §5) without undefined behaviour: integer
arithmetic goes through the helpers of rcs_num.h (wrapping in the unsigned
type), f64 arithmetic is plain C (built with -ffp-contract=off).
"""

from __future__ import annotations

import math
import re

from rcsc.semantics import model as m
from rcsc.backends.c.naming import CNames
from rcsc.outputs.backend import BuildOptions, CtrlInfo, Target, base_cpu, cpu_ticks, expr_key, lower_controller
from rcsc.semantics.types import BOOL, DURATION, I64, U32, ArrayType, EnumType, FloatType, IntType, RecordType, Type

# Suffix of the rcs_num.h helper for each integer type.
INT_SUFFIX = {"i32": "i32", "i64": "i64", "u32": "u32", "duration": "i64"}
# The <stdint.h> macro family of each integer type (`INT32_C`, `INT32_MIN`).
C_INT_MACRO = {"i32": "INT32", "i64": "INT64", "u32": "UINT32"}
ARITH = {"+": "add", "-": "sub", "*": "mul", "/": "div", "%": "rem"}


def _same_suffix(t: Type) -> str:
    """The rcs_same_* identity of an operand type other than f64."""
    return "bool" if t == BOOL else "i32" if isinstance(t, EnumType) else INT_SUFFIX[t.name]


def _compares_const(e: m.Expr) -> bool:
    """A comparison of a non-f64 value with a constant (clang checks pairs of them for overlap)."""
    return (isinstance(e, m.Binary) and e.op in ("==", "!=", "<", "<=", ">", ">=")
            and not isinstance(e.left.type, (FloatType, RecordType))
            and (isinstance(e.left, m.Const) or isinstance(e.right, m.Const)))


def _is_zero(e: m.Expr) -> bool:
    return isinstance(e, m.Const) and e.value == 0


def c_comment(text: str) -> str:
    """Design text made safe inside a one-line `/* ... */` (the C target's comment
    sanitiser).  White space runs become one space, so no newline ends the line
    early; a character that is not printable ASCII, and a backslash (a line
    splice before a newline), becomes `?`; `/*` and `*/` are split (-Wcomment,
    and the comment would end early); `??` is split, so no trigraph forms (with
    -std=c99 `??/` is a backslash, and -Wtrigraphs warns)."""
    text = "".join(ch if " " <= ch <= "~" and ch != "\\" else (" " if ch.isspace() else "?") for ch in text)
    text = re.sub(r" +", " ", text).strip()
    text = re.sub(r"(?<=/)(?=\*)|(?<=\*)(?=/)", " ", text)
    return re.sub(r"(?<=\?)(?=\?)", " ", text)


def c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


class CTarget(Target):
    name = "c"
    comment = staticmethod(c_comment)
    summary = "C99 controllers (freestanding) and a POSIX Main Program per CPU"
    package = "rcsc.backends.c"
    multi_cpu = True
    multi_rate = True

    def __init__(self, design: m.Design, options: BuildOptions | None = None) -> None:
        super().__init__(design, options)
        self.n = CNames(design.name, list(design.controllers), list(design.cpus))
        self.p = self.n.p
        # Context of the code being emitted: the controller and the verb whose plan it is.
        self.info: CtrlInfo | None = None
        self.verb: str | None = None
        self.infos = {name: lower_controller(c) for name, c in design.controllers.items()}
        # Pure calls computed once for the conditions being emitted: expr_key -> local name.
        self.cse: dict[object, str] = {}
        # The declarations of the temporaries that order extern calls
        # (`temporary`), for the top of the function being emitted.
        self.seq_decls: list[str] = []

    # ---- order of evaluation -----------------------------------------------------

    # C leaves the order of operands and arguments to the compiler, and gcc
    # takes arguments right to left: the comma operator orders the operands
    # that call externs (`Target.expr`).
    fixes_operand_order = True

    def temporary(self, e: m.Expr, n: int) -> tuple[str, str]:
        name = f"rcs_seq_{n}"
        self.seq_decls.append(f"{self.ctype(e.type)} {name};")
        return name, f"{name} = {self.expr(e)}"

    def sequenced(self, parts: list[str], body: str) -> str:
        return f"({', '.join(parts)}, {body})"

    def take_temporaries(self, lines: list[str]) -> list[str]:
        """The declarations of the temporaries made since the last call that
        `lines` use (for the top of their function).  An expression emitted
        twice, once to be thrown away (`binary_expr`'s opaque constants, the
        argument of `sum`), made temporaries nobody reads: C would warn of
        them."""
        decls, self.seq_decls = self.seq_decls, []
        used = set(re.findall(r"\brcs_seq_\d+\b", "\n".join(lines)))
        return [d for d in decls if d.rsplit(" ", 1)[1].rstrip(";") in used]

    # ---- names and types ---------------------------------------------------------

    def ident(self, name: str) -> str:
        """A struct member or parameter named by the design."""
        return self.n.member(name)

    def ctype(self, t: Type) -> str:
        if t == BOOL:
            return "bool"
        if t == DURATION:
            return "int64_t"
        if isinstance(t, IntType):
            return {"i32": "int32_t", "i64": "int64_t", "u32": "uint32_t"}[t.name]
        if isinstance(t, FloatType):
            return "double"
        if isinstance(t, (EnumType, RecordType)):
            return self.n.type(t.name)
        if isinstance(t, ArrayType):
            return self.n.array_type(t)
        raise ValueError(f"no C type for {t}")

    def member(self, t: EnumType, name: str) -> str:
        return self.n.enum_member(t.name, name)

    def ctrl_type(self, c: str) -> str:
        return self.n.ctrl_type(c)

    def period_macro(self, cpu: str) -> str:
        return self.n.period(cpu)

    # ---- values --------------------------------------------------------------------

    def literal(self, value, t: Type, braces: bool = False) -> str:
        """A constant value of type `t`.  `braces`: as a static initializer (records as `{...}`)."""
        if t == BOOL:
            return "true" if value else "false"
        if isinstance(t, IntType) or t == DURATION:
            # Each integer literal is written with the macro of its exact type
            # (<stdint.h>): a bare `3000000000` would be whatever type holds it
            # on the platform.  The most negative value has no literal.
            it = I64 if t == DURATION else t
            assert isinstance(it, IntType)
            v = int(value)
            if it.signed and v == it.min:
                return f"{C_INT_MACRO[it.name]}_MIN"
            return f"{C_INT_MACRO[it.name]}_C({v})" if v >= 0 else f"(-{C_INT_MACRO[it.name]}_C({-v}))"
        if isinstance(t, FloatType):
            x = float(value)
            if math.isnan(x):
                return "RCS_NAN"
            if math.isinf(x):
                return "RCS_INF" if x > 0 else "(-RCS_INF)"
            text = repr(abs(x))
            if "." not in text and "e" not in text:
                text += ".0"
            return f"(-{text})" if math.copysign(1.0, x) < 0 else text
        if isinstance(t, EnumType):
            return self.member(t, str(value))
        if isinstance(t, RecordType):
            # A record without fields holds one unused member (C has no empty struct).
            inner = ", ".join(self.literal(value[n], ft, braces) for n, ft in t.fields) or "0"
            return "{" + inner + "}" if braces else f"(({self.ctype(t)}){{{inner}}})"
        if isinstance(t, ArrayType):
            # The struct of one member `v` (the elements), so `{{...}}`.
            inner = ", ".join(self.literal(v, t.elem, True) for v in value)
            return "{{" + inner + "}}" if braces else f"(({self.ctype(t)}){{{{{inner}}}}})"
        raise ValueError(f"no C literal for {t}")

    # ---- expressions ---------------------------------------------------------------

    def const_expr(self, e: m.Const) -> str:
        if e.name is not None and e.name in self.design.consts:
            return self.n.const(e.name)
        return self.literal(e.value, e.type)

    def own(self) -> str:
        """The controller's own status buffer (it lives in the CPU's buffers)."""
        assert self.info is not None
        return f"buf->{self.n.buffer_member(self.info.c.name, 'status')}"

    def ref_expr(self, e: m.Ref) -> str:
        name = self.ident(e.name)
        if e.kind == "gm":
            return f"buf->gm.{name}"
        if e.kind == "local":
            return f"self->loc.{name}"
        if e.kind == "status":
            return f"{self.own()}.f.{name}"
        if e.kind == "param":
            assert self.info is not None and self.verb is not None, "a command parameter outside a plan"
            return f"buf->{self.n.buffer_member(self.info.c.name, 'cmd')}.args.{self.ident(self.verb)}.{name}"
        return name  # a function's parameter

    def tick(self) -> str:
        """The tick at which the current cycle of the controller's CPU is released (stamps count ticks)."""
        assert self.info is not None
        n = cpu_ticks(self.design, self.info.c.cpu or "")
        return "cycle" if n == 1 else f"rcs_tick(cycle, {n}u)"

    def age_of(self, stamp: str) -> str:
        """The time since the tick `stamp`, in base ticks (the shortest heartbeat)."""
        return f"rcs_cycles_ns({self.tick()}, {stamp}, {self.period_macro(base_cpu(self.design).name)})"

    def age_expr(self, e: m.Age) -> str:
        return self.age_of(f"buf->gm_stamp.{self.ident(e.name)}")

    def cycle_expr(self, e: m.Cycle) -> str:
        assert self.info is not None
        return f"rcs_step_number(cycle, {max(1, self.info.c.divider)}u)"

    def instate_expr(self, e: m.InState) -> str:
        assert self.info is not None
        return f"rcs_cycles_ns(cycle, self->entry_cycle, {self.period_macro(self.info.c.cpu or '')})"

    def subview_expr(self, e: m.SubView) -> str:
        assert self.info is not None
        sub = self.ident(e.sub)
        status = f"buf->{self.n.buffer_member(e.sub, 'status')}"
        head, sent = f"&{status}.head", f"self->sent.{sub}"
        if e.attr in ("done", "error", "executing"):
            return f"rcs_sub_{e.attr}({head}, {sent})"
        if e.attr == "status":
            return f"rcs_sub_status({head}, {sent}, {self.n.status(e.sub, e.value or '')})"
        if e.attr == "error_code":
            return f"{status}.head.error_code"
        if e.attr == "age":
            return self.age_of(f"{status}.head.stamp")
        if e.attr == "field":
            return f"{status}.f.{self.ident(e.value or '')}"
        raise ValueError(e.attr)

    def field_expr(self, e: m.Field) -> str:
        obj = self.expr(e.obj)
        if not isinstance(e.obj, (m.Ref, m.Field, m.SubView)):
            obj = f"({obj})"
        return f"{obj}.{self.ident(e.name)}"

    def array_ptr(self, e: m.Expr) -> str:
        """A pointer to the array value of `e`: its address when it is stored
        somewhere (a variable, a field, a constant's compound literal), else a
        one-element compound literal that holds a copy (C99 6.5.2.5)."""
        text = self.expr(e)
        x = e
        while isinstance(x, m.Field):
            x = x.obj
        if isinstance(x, (m.Ref, m.Const)) or (isinstance(x, m.SubView) and x.attr == "field"):
            return f"&{text}" if isinstance(x, m.Const) or isinstance(e, m.Ref) else f"&({text})"
        return f"({self.ctype(e.type)}[1]){{{text}}}"

    def index_expr(self, e: m.Index) -> str:
        """`a[i]`: the element, or the element type's zero when i is outside 0..N-1 (rcs_ARRAY_..._get)."""
        return f"{self.n.array_fn(e.obj.type, 'get')}({self.array_ptr(e.obj)}, {self.expr(e.index)})"

    def arraylit_expr(self, e: m.ArrayLit) -> str:
        return f"(({self.ctype(e.type)}){{{{{', '.join(self.expr(x) for x in e.items)}}}}})"

    def unary_expr(self, e: m.Unary) -> str:
        v = self.expr(e.operand)
        if e.op == "not":
            return f"(!{v})"
        if e.type.name in INT_SUFFIX:
            return f"rcs_neg_{INT_SUFFIX[e.type.name]}({v})"
        return f"(-{v})"

    def binary_expr(self, e: m.Binary, opaque_consts: bool = False) -> str:
        a, b = self.expr(e.left), self.expr(e.right)
        if e.op in ("and", "or"):
            if _compares_const(e.left) and _compares_const(e.right):
                # `x > 3 and x < 2` is legal in a design but a clang
                # -Wtautological-overlap-compare error in C: the constant of
                # the second comparison goes through the identity.
                b = self.binary_expr(e.right, opaque_consts=True)  # type: ignore[arg-type]
            return f"({a} {'&&' if e.op == 'and' else '||'} {b})"
        if e.type == BOOL:
            if a == b and not isinstance(e.left.type, FloatType):
                # `x == x` is legal in a design but a -Wtautological-compare error in C.
                b = f"rcs_same_{_same_suffix(e.left.type)}({b})"
            elif opaque_consts:
                a = f"rcs_same_{_same_suffix(e.left.type)}({a})" if isinstance(e.left, m.Const) else a
                b = f"rcs_same_{_same_suffix(e.right.type)}({b})" if isinstance(e.right, m.Const) else b
            elif e.left.type == U32 and e.op in ("<", "<=", ">", ">="):
                # `u >= 0` is legal in a design but a -Wtype-limits error in C.
                a = f"rcs_same_u32({a})" if _is_zero(e.left) else a
                b = f"rcs_same_u32({b})" if _is_zero(e.right) else b
            return f"({a} {e.op} {b})"
        if e.type.name in INT_SUFFIX:
            return f"rcs_{ARITH[e.op]}_{INT_SUFFIX[e.type.name]}({a}, {b})"
        return f"({a} {e.op} {b})"

    def ifexpr_expr(self, e: m.IfExpr) -> str:
        return f"({self.expr(e.cond)} ? {self.expr(e.then)} : {self.expr(e.else_)})"

    def call_expr(self, e: m.Call) -> str:
        args = [self.expr(a) for a in e.args]
        if e.kind in ("fn", "extern"):
            name = self.cse.get(expr_key(e))
            return name if name is not None else f"{self.n.function(e.func)}({', '.join(args)})"
        if e.kind == "record":
            return f"(({self.ctype(e.type)}){{{', '.join(args) or '0'}}})"
        if e.kind == "convert":
            return self._convert(args[0], e.args[0].type, e.type)
        if e.func == "seconds":
            return f"((double){args[0]} / 1e9)"
        if e.func in ("sum", "min_of", "max_of"):
            return f"{self.n.array_fn(e.args[0].type, e.func)}({self.array_ptr(e.args[0])})"
        suffix = "f64" if isinstance(e.type, FloatType) else INT_SUFFIX[e.type.name]
        if e.func == "abs":
            return f"rcs_fabs({args[0]})" if suffix == "f64" else f"rcs_abs_{suffix}({args[0]})"
        return f"rcs_{e.func}_{suffix}({', '.join(args)})"

    def _convert(self, v: str, src: Type, dst: Type) -> str:
        s = "i64" if src == DURATION else src.name
        d = dst.name
        if s == d:
            return v
        if d == "f64":
            return f"((double){v})"
        if s == "f64":
            return f"rcs_f64_to_{d}({v})"
        return f"rcs_{s}_to_{d}({v})"

    # ---- statements ----------------------------------------------------------------

    def lvalue(self, lv: m.LValue) -> str:
        base = {"gm": "buf->gm", "local": "self->loc", "status": f"{self.own()}.f"}[lv.kind]
        return ".".join([base, self.ident(lv.name)] + [self.ident(p) for p in lv.path])

    def assign_stmt(self, s: m.Assign, indent: int) -> list[str]:
        pad = "    " * indent
        target = self.lvalue(s.target)
        value = self.expr(s.value)
        if s.target.index is not None:
            # `a[i] = v`: the value, then the index (the simulator's order);
            # a write outside 0..N-1 is ignored.
            t = s.target.type
            size = self.design_array_size(s.target)
            element = f"{target}.v[rcs_i]"
            if s.op == "=":
                store = f"{element} = rcs_x;"
            elif t.name in INT_SUFFIX:
                store = f"{element} = rcs_{ARITH[s.op[0]]}_{INT_SUFFIX[t.name]}({element}, rcs_x);"
            else:
                store = f"{element} = {element} {s.op[0]} rcs_x;"
            return [f"{pad}{{", f"{pad}    const {self.ctype(t)} rcs_x = {value};",
                    f"{pad}    const int64_t rcs_i = (int64_t){self.expr(s.target.index)};",
                    f"{pad}    if (rcs_i >= 0 && rcs_i < {size}) {store}", f"{pad}}}"]
        if s.op == "=":
            return [f"{pad}{target} = {value};"]
        op = s.op[0]
        t = s.target.type
        if t.name in INT_SUFFIX:
            return [f"{pad}{target} = rcs_{ARITH[op]}_{INT_SUFFIX[t.name]}({target}, {value});"]
        return [f"{pad}{target} = {target} {op} {value};"]

    def design_array_size(self, lv: m.LValue) -> int:
        """The length of the array that `lv` (an indexed assignment) writes an element of."""
        c = self.info.c if self.info is not None else None
        assert c is not None
        t = {"gm": lambda: self.design.gm[lv.name].type, "local": lambda: c.locals[lv.name].type,
             "status": lambda: c.status_fields[lv.name].type}[lv.kind]()
        for part in lv.path:
            t = t.field_type(part)  # type: ignore[attr-defined]
        assert isinstance(t, ArrayType)
        return t.size

    def callstmt_stmt(self, s: m.CallStmt, indent: int) -> list[str]:
        return ["    " * indent + f"(void){self.expr(s.call)};"]

    def command_stmt(self, s: m.Command, indent: int) -> list[str]:
        pad = "    " * indent
        sub = self.ident(s.sub)
        verb = self.design.controllers[s.sub].verbs[s.verb]
        # Written in place: nothing else runs during this step, and the serial
        # that makes the command new is set at the write phase.
        cmd = self.n.buffer_member(s.sub, "cmd")
        out = [f"{pad}buf->{cmd}.head.verb = {self.n.verb(s.sub, s.verb)};"]
        for p, a in zip(verb.params, s.args):
            out.append(f"{pad}buf->{cmd}.args.{self.ident(s.verb)}.{self.ident(p.name)} = {self.expr(a)};")
        out.append(f"{pad}self->send.{sub} = true;")
        return out

    def report_stmt(self, s: m.Report, indent: int) -> list[str]:
        assert self.info is not None
        return ["    " * indent + f"{self.own()}.head.status = {self.n.status(self.info.c.name, s.status)};"]

    def if_stmt(self, s: m.If, indent: int) -> list[str]:
        pad = "    " * indent
        out = []
        for i, (cond, body) in enumerate(s.branches):
            head = "if" if i == 0 else "} else if"
            out.append(f"{pad}{head} ({_strip_parens(self.expr(cond))}) {{")
            out.extend(self.stmts(body, indent + 1))
        if s.else_body:
            out.append(f"{pad}}} else {{")
            out.extend(self.stmts(s.else_body, indent + 1))
        out.append(f"{pad}}}")
        return out


def _strip_parens(text: str) -> str:
    """`(a && b)` -> `a && b` when the outer parentheses enclose the whole text."""
    if not (text.startswith("(") and text.endswith(")")):
        return text
    depth = 0
    for i, ch in enumerate(text):
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
            if depth == 0 and i != len(text) - 1:
                return text
    return text[1:-1]
