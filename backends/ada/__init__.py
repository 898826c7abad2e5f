"""The Ada target: Ada 2012 controllers (Appendix A) for GNAT, with the C target's Main Program runtime.

`AdaBackend.files()` lays the design out as GNAT library units: a types
package (the buffers, laid out as the C runtime reads them), the pure
functions, the extern functions (a user body), one package per controller,
and the Main Program per CPU (several CPUs: and the C target's launcher).
The Main Program is an Ada procedure that hands the design's tables to
the C target's design-independent runtime (rcs_runtime.c: options,
heartbeat, event reader, trace, timing table, console) through `pragma Import`, so the three targets read one event-file
format with one reader and print floats in the trace with one formatter.
The tables themselves, and the C declaration of the buffers they point
into, are rendered by the C target (`rcsc.backends.c`).  See docs/backends.md.
"""

from __future__ import annotations

import math
import os
import re
import sys

from rcsc.semantics import model as m
from rcsc.backends.ada.naming import AdaNames
from rcsc.backends.c import LAUNCHER_FILES, RUNTIME_FILES as C_RUNTIME_FILES, CBackend
from rcsc.backends.c.tables import main_tables
from rcsc.outputs.backend import (
    BuildOptions, CtrlInfo, OutFile, RuleStep, StateTest, Target, base_cpu, built_controllers, calls_impure, cpu_ticks,
    expr_key, initial_value, keeps_gm_stamps, lower_controller, ordered_types, plan_layout, register, schedule_of,
    tests_state, types_with_arrays,
)
from rcsc.semantics.types import BOOL, DURATION, I32, I64, U32, ArrayType, EnumType, FloatType, IntType, RecordType, Type
from rcsc.sim.simulate import zero_value

ADA_TYPE = {"bool": "Boolean", "i32": "Integer_32", "i64": "Integer_64", "u32": "Unsigned_32", "f64": "F64", "duration": "Integer_64"}
SUFFIX = {"i32": "I32", "i64": "I64", "u32": "U32", "duration": "I64", "f64": "F64"}
ARITH = {"+": "Add", "-": "Sub", "*": "Mul", "/": "Div", "%": "Rem"}
COMPARE = {"==": "=", "!=": "/=", "<": "<", "<=": "<=", ">": ">", ">=": ">="}
PROJECT = "rcs_build.gpr"
LAUNCH_PROJECT = "rcs_launch.gpr"  # several CPUs only: the launcher
BUF = "rcs_ada_buf"  # the buffers, one C object (the runtime's namespace: rcs_)


def ada_comment(text: str) -> str:
    """Design text made safe on one `--` comment line: white space runs become
    one space and any other character that is not printable ASCII becomes `?`."""
    text = "".join(ch if " " <= ch <= "~" else (" " if ch.isspace() else "?") for ch in text)
    return re.sub(r" +", " ", text).strip()


def design_names(d: m.Design) -> list[str]:
    """Every name the design declares, of any kind (for AdaNames: names equal but for case)."""
    out = [d.name] + list(d.consts) + list(d.functions) + list(d.gm) + list(d.controllers) + list(d.cpus)
    for t in ordered_types(d):
        out.append(t.name)
        out += list(t.members) if isinstance(t, EnumType) else [n for n, _ in t.fields]  # type: ignore[attr-defined]
    for f in d.functions.values():
        out += [q.name for q in f.params]
    for c in d.controllers.values():
        out += list(c.verbs) + list(c.statuses) + list(c.status_fields) + list(c.locals)
        for v in c.verbs.values():
            out += [q.name for q in v.params]
        for p in c.plans.values():
            out += list(p.states) + [r.label for r in p.rules]
    return out


@register
class AdaBackend(Target):
    name = "ada"
    summary = "Ada 2012 controllers for GNAT (SPARK mode) and a Main Program per CPU on the C runtime"
    package = "rcsc.backends.ada"
    comment = staticmethod(ada_comment)
    entry_files = (PROJECT, LAUNCH_PROJECT)
    multi_cpu = True
    multi_rate = True

    def __init__(self, design: m.Design, options: BuildOptions | None = None) -> None:
        super().__init__(design, options)
        self.n = AdaNames(design.name, design_names(design))
        self.c = CBackend(design, self.options)
        self.infos = {name: lower_controller(c) for name, c in design.controllers.items()}
        self.info: CtrlInfo | None = None
        self.verb: str | None = None
        self.cse: dict[object, str] = {}

    # ---- order of evaluation -------------------------------------------------------

    # Ada leaves the order of operands, arguments and aggregate components
    # to the compiler, and GNAT takes arguments right to left: constants of
    # a declare expression order the operands that call externs (`Target.expr`).
    fixes_operand_order = True

    def temporary(self, e: m.Expr, n: int) -> tuple[str, str]:
        name = f"Rcs_Seq_{n}"
        return name, f"{name} : constant {self.atype(e.type)} := {_strip(self.expr(e))};"

    def sequenced(self, parts: list[str], body: str) -> str:
        return f"(declare {' '.join(parts)} begin {_strip(body)})"

    def ada_version(self) -> str:
        """Ada 2022 for a design with a declare expression (a temporary was
        made: `temporary`), else Ada 2012."""
        return "2022" if self._temp_count else "2012"

    # ---- files ---------------------------------------------------------------------

    def files(self) -> list[OutFile]:
        d, n, c = self.design, self.n, self.c
        ctrls = built_controllers(d, self.options)
        files = [OutFile(name, c.runtime_file(name)) for name in C_RUNTIME_FILES]
        files += [OutFile(name, self.runtime_file(name)) for name in ("rcs_num.ads", "rcs_num.adb")]
        common = c.common_names()
        files.append(OutFile(f"{c.n.p}.h", c.render("design.h.j2", **common, **c.design_header(ctrls))))
        files.append(OutFile(f"{c.n.p}.c", c.render("design.c.j2", **common, **c.design_source(ctrls))))
        externs = [f for f in d.functions.values() if f.extern]
        files.append(OutFile(f"{c.n.p}_externs.h", c.render("externs.h.j2", **common, protos=[c.prototype(f) + ";" for f in externs])))
        ctx = self.context()
        types = self.types(ctrls)
        files.append(OutFile(n.file(ctx["types_pkg"], ".ads"), self.render("types.ads.j2", **ctx, **types)))
        if any(a["folds"] for a in types["arrays"]):
            files.append(OutFile(n.file(ctx["types_pkg"], ".adb"), self.render("types.adb.j2", **ctx, **types)))
        fns = [f for f in d.functions.values() if not f.extern]
        files.append(OutFile(n.file(ctx["functions_pkg"], ".ads"), self.render("functions.ads.j2", **ctx, fns=[self.function(f) for f in fns])))
        if fns:
            files.append(OutFile(n.file(ctx["functions_pkg"], ".adb"), self.render("functions.adb.j2", **ctx, fns=[self.function(f) for f in fns])))
        files.append(OutFile(n.file(ctx["externs_pkg"], ".ads"), self.render("externs.ads.j2", **ctx, fns=[self.function(f) for f in externs])))
        if externs:
            files.append(OutFile(n.file(ctx["externs_pkg"], ".adb"), self.render("externs.adb.j2", **ctx, fns=[self.function(f) for f in externs]), user=True))
        units = []
        for i, ctrl in enumerate(ctrls):
            cx = self.controller(ctrl, i)
            units.append(cx["pkg"])
            files.append(OutFile(n.file(cx["pkg"], ".ads"), self.render("ctrl.ads.j2", **ctx, **cx)))
            files.append(OutFile(n.file(cx["pkg"], ".adb"), self.render("ctrl.adb.j2", **ctx, **cx)))
        mains = []
        multi = len(d.cpus) > 1
        for k, cpu in enumerate(d.cpus.values()):
            # Every CPU's tables are linked into every CPU's program (gprbuild links
            # the project's C objects into each main): one run function per CPU,
            # and the buffers defined once (each process has its own).
            tables = main_tables(c, cpu, schedule_of(d, cpu, self.options), ctrls, buf=BUF)
            unit = n.main_unit(cpu.name)
            run = f"rcs_ada_run_{k}" if multi else "rcs_ada_run"
            files.append(OutFile(n.file(unit, ".adb"), self.render("main.adb.j2", **ctx, unit=unit, cpu=ada_comment(cpu.name), ctrl_pkgs=units, run=run)))
            steps = [{"step": t["step"], "symbol": f"rcs_ada_step_{i}"} for i, t in enumerate(tables["ctrl_tables"])]
            files.append(OutFile(f"rcs_tables_{k}.c" if multi else "rcs_tables.c",
                                 self.render("tables.c.j2", **common, **tables, cpu_string=_c_string(cpu.name), buf=BUF, steps=steps, run=run,
                                             defines_buf=k == 0, deploy=self.options.exclude_simulators)))
            mains.append({"file": n.file(unit, ".adb"), "binary": c.n.binary(cpu.name)})
        launcher = None
        if multi:
            # The C target's launcher, built by a C-only project of its own.
            files += [OutFile(name, c.runtime_file(name)) for name in LAUNCHER_FILES]
            files.append(OutFile(f"run_{c.n.p}.c", c.render("run.c.j2", **common, cpus=", ".join(_c_string(x) for x in d.cpus),
                                                            bins=", ".join(_c_string(c.n.binary(x)) for x in d.cpus))))
            launcher = {"name": f"run_{c.n.p}", "main": f"run_{c.n.p}.c", "sources": [f"run_{c.n.p}.c", *[x for x in LAUNCHER_FILES if x.endswith(".c")]]}
            files.append(OutFile(LAUNCH_PROJECT, self.render("launch.gpr.j2", launcher=launcher)))
        if self.options.exclude_simulators:
            files.append(OutFile(f"{c.n.p}_io.h", c.render("io.h.j2", **common)))
            files.append(OutFile(f"{c.n.p}_io.c", c.render("io_stub.c.j2", **common), user=True))
        files.append(OutFile(PROJECT, self.render("project.gpr.j2", mains=mains, launcher=launcher, ada_version=self.ada_version())))
        return files

    def build_commands(self, folder: str) -> list[tuple[list[str], dict[str, str] | None]]:
        cmds: list[tuple[list[str], dict[str, str] | None]] = [(["gprbuild", "-q", "-P", PROJECT], None)]
        if len(self.design.cpus) > 1:
            cmds.append((["gprbuild", "-q", "-P", LAUNCH_PROJECT], None))
        return cmds

    def program(self, folder: str) -> str:
        d, n = self.design, self.c.n
        return os.path.join(folder, f"run_{n.p}" if len(d.cpus) > 1 else n.binary(next(iter(d.cpus))))

    def context(self) -> dict:
        n = self.n
        return {"types_pkg": n.package("Types"), "functions_pkg": n.package("Functions"), "externs_pkg": n.package("Externs"),
                "design": ada_comment(self.design.name), "buf": BUF}

    # ---- the types package -----------------------------------------------------------

    def types(self, ctrls: list[m.Controller]) -> dict:
        d, n = self.design, self.n
        types, arrays = [], []
        for t in types_with_arrays(d):
            if isinstance(t, EnumType):
                types.append({"kind": "enum", "name": n.type(t.name), "members": [n.enum_member(t.name, x) for x in t.members]})
            elif isinstance(t, ArrayType):
                types.append({"kind": "array", "name": n.array_type(t), "last": t.size - 1, "elem": self.atype(t.elem)})
                arrays.append(self.array_helpers(t))
            else:
                assert isinstance(t, RecordType)
                types.append({"kind": "record", "name": n.type(t.name), "fields": [self.decl(x, ft) for x, ft in t.fields]})
        consts = [{"decl": f"{n.const(k.name)} : constant {self.atype(k.type)} := {self.literal(k.value, k.type)};", "where": self.where_text(k.span)}
                  for k in d.consts.values()]
        buffers = []
        for c in ctrls:
            verbs = []
            for i, (vname, v) in enumerate(c.verbs.items(), 1):
                verbs.append({"const": n.verb(c.name, vname), "number": i, "member": n.member(vname), "args_type": n.verb_args(c.name, vname),
                              "params": [self.decl(q.name, q.type) for q in v.params]})
            buffers.append({
                "name": ada_comment(c.name), "verbs": verbs, "with_args": [v for v in verbs if v["params"]],
                "statuses": [{"const": n.status(c.name, s), "number": k} for s, k in c.statuses.items()],
                "args_type": n.ctrl_part(c.name, "Args"), "cmd_type": n.ctrl_part(c.name, "Cmd_Buffer"),
                "fields_type": n.ctrl_part(c.name, "Fields"), "status_type": n.ctrl_part(c.name, "Status_Buffer"),
                "fields": [self.decl(x, v.type) for x, v in c.status_fields.items()],
                "cmd_member": n.buffer_member(c.name, "cmd"), "status_member": n.buffer_member(c.name, "status"),
            })
        return {
            "types": types, "arrays": arrays, "consts": consts, "gm": [self.decl(x, v.type) for x, v in d.gm.items()],
            "gm_stamps": [n.member(x) for x in d.gm] if keeps_gm_stamps(d) else [],
            "periods": [f"{n.period(cpu.name)} : constant Integer_64 := {cpu.heartbeat_ns};" for cpu in d.cpus.values()],
            "buffers": buffers,
        }

    def array_helpers(self, t: ArrayType) -> dict:
        """An array type's element read (the element type's zero outside
        0..N-1, as in the simulator) and, for numbers, `sum`, `min_of` and
        `max_of` folded from the first element to the last."""
        at, et = self.n.array_type(t), self.atype(t.elem)
        out = {"getter": self.n.array_fn(t, "Get"), "type": at, "elem": et, "last": t.size - 1,
               "zero": _strip(self.literal(zero_value(t.elem), t.elem)), "folds": []}
        if t.elem.is_numeric or t.elem == DURATION:
            suffix = SUFFIX[t.elem.name]
            step = {"Sum": "S + A (K)" if suffix == "F64" else f"Add_{suffix} (S, A (K))",
                    "Min_Of": f"Min_{suffix} (S, A (K))", "Max_Of": f"Max_{suffix} (S, A (K))"}
            out["folds"] = [{"fn": self.n.array_fn(t, op), "step": x} for op, x in step.items()]
        return out

    def decl(self, name: str, t: Type) -> str:
        return f"{self.n.member(name)} : {self.atype(t)};"

    def atype(self, t: Type) -> str:
        if isinstance(t, (EnumType, RecordType)):
            return self.n.type(t.name)
        if isinstance(t, ArrayType):
            return self.n.array_type(t)
        return ADA_TYPE[t.name]

    def function(self, f: m.Function) -> dict:
        params = "; ".join(f"{self.n.member(q.name)} : {self.atype(q.type)}" for q in f.params)
        spec = f"function {self.n.function(f.name)}{f' ({params})' if params else ''} return {self.atype(f.ret)}"
        used = {e.name for e in m.walk_expr(f.body) if isinstance(e, m.Ref) and e.kind == "arg"} if f.body is not None else set()
        return {"spec": spec, "where": self.where_text(f.span), "doc": ada_comment(f.doc), "name": self.n.function(f.name),
                "unused": [self.n.member(q.name) for q in f.params if q.name not in used],
                "body": self.expr(f.body) if f.body is not None else "", "zero": self.literal(zero_value(f.ret), f.ret)}

    # ---- values --------------------------------------------------------------------

    def literal(self, value, t: Type) -> str:
        """A constant of type `t`, qualified with its type (nothing is inferred)."""
        if t == BOOL:
            return "True" if value else "False"
        if isinstance(t, IntType) or t == DURATION:
            return f"{ADA_TYPE[t.name]}'({int(value)})"
        if isinstance(t, FloatType):
            x = float(value)
            if math.isnan(x):
                return "Rcs_Num.NaN"
            if math.isinf(x):
                return "Rcs_Num.Inf" if x > 0 else "(-Rcs_Num.Inf)"
            if x == 0 and math.copysign(1.0, x) < 0:
                return "Rcs_Num.Neg_F64 (F64'(0.0))"  # a static -0.0 would be exact zero
            if 0 < abs(x) < sys.float_info.min:
                num, den = abs(x).as_integer_ratio()  # den is a power of two
                return f"Rcs_Num.Scale (F64'({'-' if x < 0 else ''}{num}.0), -{den.bit_length() - 1})"
            text = repr(abs(x))
            mant, _, exp = text.partition("e")
            if "." not in mant:
                mant += ".0"
            text = mant + (f"E{exp}" if exp else "")
            return f"F64'({'-' if x < 0 else ''}{text})"
        if isinstance(t, EnumType):
            return self.n.enum_member(t.name, str(value))
        if isinstance(t, RecordType):
            inner = ", ".join(f"{self.n.member(x)} => {self.literal(value[x], ft)}" for x, ft in t.fields) or "Unused => 0"
            return f"{self.n.type(t.name)}'({inner})"
        if isinstance(t, ArrayType):
            items = [self.literal(v, t.elem) for v in value]
            if len(set(items)) == 1:
                return f"{self.n.array_type(t)}'(others => {_strip(items[0])})"
            return f"{self.n.array_type(t)}'({', '.join(f'{i} => {_strip(x)}' for i, x in enumerate(items))})"
        raise ValueError(f"no Ada literal for {t}")

    # ---- expressions ---------------------------------------------------------------

    def const_expr(self, e: m.Const) -> str:
        if e.name is not None and e.name in self.design.consts:
            return self.n.const(e.name)
        return self.literal(e.value, e.type)

    def own(self) -> str:
        assert self.info is not None
        return f"Buf.{self.n.buffer_member(self.info.c.name, 'status')}"

    def ref_expr(self, e: m.Ref) -> str:
        name = self.n.member(e.name)
        if e.kind == "gm":
            return f"Buf.Gm.{name}"
        if e.kind == "local":
            return f"Loc.{name}"
        if e.kind == "status":
            return f"{self.own()}.F.{name}"
        if e.kind == "param":
            assert self.info is not None and self.verb is not None
            return f"Buf.{self.n.buffer_member(self.info.c.name, 'cmd')}.Args.{self.n.member(self.verb)}.{name}"
        return name

    def tick(self) -> str:
        assert self.info is not None
        k = cpu_ticks(self.design, self.info.c.cpu or "")
        return "Cycle" if k == 1 else f"Rcs_Num.Tick (Cycle, {k})"

    def age_of(self, stamp: str) -> str:
        return f"Rcs_Num.Cycles_Ns ({self.tick()}, {stamp}, {self.n.period(base_cpu(self.design).name)})"

    def age_expr(self, e: m.Age) -> str:
        return self.age_of(f"Buf.Gm_Stamp.{self.n.member(e.name)}")

    def cycle_expr(self, e: m.Cycle) -> str:
        assert self.info is not None
        return f"Rcs_Num.Step_Number (Cycle, {max(1, self.info.c.divider)})"

    def instate_expr(self, e: m.InState) -> str:
        assert self.info is not None
        return f"Rcs_Num.Cycles_Ns (Cycle, Entry_Cycle, {self.n.period(self.info.c.cpu or '')})"

    def subview_expr(self, e: m.SubView) -> str:
        status = f"Buf.{self.n.buffer_member(e.sub, 'status')}"
        sent = f"Sent.{self.n.member(e.sub)}"
        if e.attr in ("done", "error", "executing"):
            return f"Rcs_Num.Sub_{e.attr.capitalize()} ({status}.Head, {sent})"
        if e.attr == "status":
            return f"Rcs_Num.Sub_Status ({status}.Head, {sent}, {self.n.status(e.sub, e.value or '')})"
        if e.attr == "error_code":
            return f"{status}.Head.Error_Code"
        if e.attr == "age":
            return self.age_of(f"{status}.Head.Stamp")
        if e.attr == "field":
            return f"{status}.F.{self.n.member(e.value or '')}"
        raise ValueError(e.attr)

    def field_expr(self, e: m.Field) -> str:
        obj = self.expr(e.obj)
        if not isinstance(e.obj, (m.Ref, m.Field, m.SubView)) or (isinstance(e.obj, m.Ref) and e.obj.kind == "arg"):
            obj = f"{self.atype(e.obj.type)}'({_strip(obj)})"  # a qualified expression is a name
        return f"{obj}.{self.n.member(e.name)}"

    def index64(self, e: m.Expr) -> str:
        """An array index as the Integer_64 the helpers take."""
        v = _strip(self.expr(e))
        return v if e.type in (I64, DURATION) else f"Rcs_Num.{SUFFIX[e.type.name]}_To_I64 ({v})"

    def index_expr(self, e: m.Index) -> str:
        """`a[i]`: the element, or the element type's zero when i is outside 0..N-1 (Get_...)."""
        return f"{self.n.array_fn(e.obj.type, 'Get')} ({_strip(self.expr(e.obj))}, {self.index64(e.index)})"

    def arraylit_expr(self, e: m.ArrayLit) -> str:
        items = ", ".join(f"{i} => {_strip(self.expr(x))}" for i, x in enumerate(e.items))
        return f"{self.atype(e.type)}'({items})"

    def unary_expr(self, e: m.Unary) -> str:
        v = self.expr(e.operand)
        if isinstance(e.operand, m.Unary) and e.operand.op == e.op:
            v = self.same(e.operand, v)  # `not not x` is legal in a design; GNAT warns of it
        if e.op == "not":
            return f"(not {v})"
        if e.type.name in ("i32", "i64", "u32", "duration"):
            return f"Rcs_Num.Neg_{SUFFIX[e.type.name]} ({_strip(v)})"
        return f"(-{v})"

    def same(self, e: m.Expr, text: str) -> str:
        """A constant operand of a comparison, through the identity: GNAT folds a
        comparison of constants and warns that it is always true or false."""
        t = e.type
        if isinstance(t, (FloatType, RecordType)):
            return f"Rcs_Num.Same_F64 ({_strip(text)})" if isinstance(t, FloatType) else text
        kind = "Bool" if t == BOOL else "I32" if isinstance(t, EnumType) else SUFFIX[t.name]
        return f"Rcs_Num.Same_{kind} ({_strip(text)})"

    def binary_expr(self, e: m.Binary) -> str:
        a, b = self.expr(e.left), self.expr(e.right)
        if e.op in ("and", "or"):
            return f"({a} {'and then' if e.op == 'and' else 'or else'} {b})"
        if e.op in COMPARE:
            if isinstance(e.left, m.Const) or isinstance(e.left.type, IntType) and e.left.type == U32:
                a = self.same(e.left, a)
            if isinstance(e.right, m.Const) or a == b:
                b = self.same(e.right, b)
            return f"({a} {COMPARE[e.op]} {b})"
        if e.type.name in ("i32", "i64", "u32", "duration"):
            return f"Rcs_Num.{ARITH[e.op]}_{SUFFIX[e.type.name]} ({_strip(a)}, {_strip(b)})"
        if e.op == "/" and isinstance(e.right, m.Const) and e.right.value == 0.0:
            # IEEE division by zero is defined (an infinity or NaN), but GNAT
            # warns of a static zero divisor ("float division by zero"), and
            # -gnatwe makes that an error: the divisor goes through the identity.
            b = self.same(e.right, b)
        return f"({a} {e.op} {b})"

    def ifexpr_expr(self, e: m.IfExpr) -> str:
        return f"(if {_strip(self.expr(e.cond))} then {_strip(self.expr(e.then))} else {_strip(self.expr(e.else_))})"

    def call_expr(self, e: m.Call) -> str:
        raw = [self.expr(a) for a in e.args]
        args = [_strip(a) for a in raw]
        if e.kind in ("fn", "extern"):
            name = self.cse.get(expr_key(e))
            return name if name is not None else self.n.function(e.func) + (f" ({', '.join(args)})" if args else "")
        if e.kind == "record":
            t = e.type
            assert isinstance(t, RecordType)
            inner = ", ".join(f"{self.n.member(x)} => {a}" for (x, _), a in zip(t.fields, args)) or "Unused => 0"
            return f"{self.n.type(t.name)}'({inner})"
        if e.kind == "convert":
            s, d = SUFFIX[e.args[0].type.name], SUFFIX[e.type.name]
            if s == d:
                # The operand stands where the conversion stood: it keeps its
                # parentheses (`-f64(-x)` would be `--x`, an Ada comment).
                return raw[0]
            return f"Rcs_Num.To_F64 ({args[0]})" if d == "F64" else f"Rcs_Num.{s}_To_{d} ({args[0]})"
        if e.func == "seconds":
            return f"(Rcs_Num.To_F64 ({args[0]}) / F64'(1.0E+09))"
        if e.func in ("sum", "min_of", "max_of"):
            op = "_".join(w.capitalize() for w in e.func.split("_"))
            return f"{self.n.array_fn(e.args[0].type, op)} ({args[0]})"
        suffix = SUFFIX[e.type.name]
        if e.func == "abs" and suffix == "F64":
            return f"(abs {self.expr(e.args[0])})"
        func = "_".join(w.capitalize() for w in e.func.split("_"))  # round_even -> Round_Even
        return f"Rcs_Num.{func}_{suffix} ({', '.join(args)})"

    # ---- statements ----------------------------------------------------------------

    def lvalue(self, lv: m.LValue) -> str:
        base = {"gm": "Buf.Gm", "local": "Loc", "status": f"{self.own()}.F"}[lv.kind]
        return ".".join([base, self.n.member(lv.name)] + [self.n.member(p) for p in lv.path])

    def assign_stmt(self, s: m.Assign, indent: int) -> list[str]:
        pad = "   " * indent
        target, value = self.lvalue(s.target), _strip(self.expr(s.value))
        if s.target.index is not None:
            # `a[i] = v`: the value, then the index (the simulator's order); a
            # write outside 0..N-1 is ignored.  Same_I64: no constant condition.
            t, elem = s.target.type, f"{target} (Rcs_I)"
            if s.op == "=":
                store = f"{elem} := Rcs_X;"
            elif t.name in ("i32", "i64", "u32", "duration"):
                store = f"{elem} := Rcs_Num.{ARITH[s.op[0]]}_{SUFFIX[t.name]} ({elem}, Rcs_X);"
            else:
                store = f"{elem} := {elem} {s.op[0]} Rcs_X;"
            return [f"{pad}declare", f"{pad}   Rcs_X : constant {self.atype(t)} := {value};",
                    f"{pad}   Rcs_I : constant Integer_64 := Rcs_Num.Same_I64 ({self.index64(s.target.index)});",
                    f"{pad}begin", f"{pad}   if Rcs_I in {target}'Range then", f"{pad}      {store}", f"{pad}   end if;", f"{pad}end;"]
        if s.op == "=":
            if value == target:  # `x = x` is legal in a design, and does nothing; GNAT warns of it
                return [f"{pad}null; --  {self.comment(target)} := itself"]
            return [f"{pad}{target} := {value};"]
        op, t = s.op[0], s.target.type
        if t.name in ("i32", "i64", "u32", "duration"):
            return [f"{pad}{target} := Rcs_Num.{ARITH[op]}_{SUFFIX[t.name]} ({target}, {value});"]
        return [f"{pad}{target} := {target} {op} ({value});"]

    def callstmt_stmt(self, s: m.CallStmt, indent: int) -> list[str]:
        pad = "   " * indent
        # Ada has no discarded results: the value goes to a constant GNAT knows is ignored.
        return [f"{pad}declare", f"{pad}   Ignore : constant {self.atype(s.call.type)} := {_strip(self.expr(s.call))};",
                f"{pad}begin", f"{pad}   null;", f"{pad}end;"]

    def command_stmt(self, s: m.Command, indent: int) -> list[str]:
        pad = "   " * indent
        verb = self.design.controllers[s.sub].verbs[s.verb]
        cmd = f"Buf.{self.n.buffer_member(s.sub, 'cmd')}"
        out = [f"{pad}{cmd}.Head.Verb := {self.n.verb(s.sub, s.verb)};"]
        if verb.params:
            # The arguments go into the verb's variant of the union, whole.  An
            # aggregate's components come in any order: those that call
            # externs are computed first, in the order of the parameters.
            first = [a for a in s.args if calls_impure(a, self.impure)][:-1]
            decls = self.bind(first)
            vals = ", ".join(f"{self.n.member(p.name)} => {_strip(self.expr(a))}" for p, a in zip(verb.params, s.args))
            self.unbind(first)
            store = f"{cmd}.Args := (Verb => {self.n.verb(s.sub, s.verb)}, {self.n.member(s.verb)} => ({vals}));"
            if decls:
                out += [f"{pad}declare"] + [f"{pad}   {d}" for d in decls] + [f"{pad}begin", f"{pad}   {store}", f"{pad}end;"]
            else:
                out.append(pad + store)
        out.append(f"{pad}Send.{self.n.member(s.sub)} := True;")
        return out

    def report_stmt(self, s: m.Report, indent: int) -> list[str]:
        assert self.info is not None
        return ["   " * indent + f"{self.own()}.Head.Status := {self.n.status(self.info.c.name, s.status)};"]

    def if_stmt(self, s: m.If, indent: int) -> list[str]:
        pad = "   " * indent
        out = []
        if len(s.branches) == 1 and not s.else_body:
            body = self.stmts(s.branches[0][1], indent)
            if all(x.lstrip().startswith("null;") for x in body) and not self._calls(s.branches[0][0], self.impure):
                # Nothing to do either way (`if c { x = x; }` is legal in a
                # design): GNAT warns that such an `if` has no effect, and
                # -gnatwe makes that an error.  The condition has no effect
                # either (it calls no extern function), so only the comments stay.
                return body
        for i, (cond, body) in enumerate(s.branches):
            out.append(f"{pad}{'if' if i == 0 else 'elsif'} {_strip(self.expr(cond))} then")
            out += self.stmts(body, indent + 1) or [pad + "   null;"]
        if s.else_body:
            out.append(f"{pad}else")
            out += self.stmts(s.else_body, indent + 1) or [pad + "   null;"]
        out.append(f"{pad}end if;")
        return out

    @staticmethod
    def _calls(e: m.Expr, functions: set[str]) -> bool:
        return any(isinstance(x, m.Call) and x.kind in ("fn", "extern") and x.func in functions for x in m.walk_expr(e))

    # ---- one controller -----------------------------------------------------------------

    def controller(self, c: m.Controller, index: int) -> dict:
        n = self.n
        info = self.infos[c.name]
        self.info, self.verb = info, None
        subs = [{"member": n.member(s), "cmd": f"Buf.{n.buffer_member(s, 'cmd')}"} for s in info.subs]
        init = [f"Loc.{n.member(x)} := {self.literal(initial_value(v), v.type)};" for x, v in c.locals.items()]
        for s in subs:
            init += [f"Sent.{s['member']} := 0;", f"Send.{s['member']} := False;"]
        seq_before = self._temp_count
        plans = [self.plan(c, plan) for plan in c.plans.values()]
        self.verb = None
        pre, post = self.stmts(c.pre, 1), self.stmts(c.post, 1)
        gm_stamps = [f"Buf.Gm_Stamp.{n.member(u.name)} := {self.tick()};" for u in c.writes] if keeps_gm_stamps(self.design) else []
        ctx = {
            "pkg": n.ctrl_package(c.name), "name": ada_comment(c.name), "doc": ada_comment(c.doc), "kind": "simulator" if c.simulator else "controller",
            "level": c.level, "where": self.where_text(c.span), "budget_ns": c.budget_ns, "symbol": f"rcs_ada_step_{index}",
            "own": self.own_of(c.name), "cmd": f"Buf.{n.buffer_member(c.name, 'cmd')}",
            "subs": subs, "locals": [self.decl(x, v.type) for x, v in c.locals.items()], "init": init,
            "states": [{"name": n.state(s), "number": i} for i, s in enumerate(info.states)],
            "rules": [{"name": n.rule(p.verb, r.label), "number": info.rule_number[(p.verb, r.index)]} for p in c.plans.values() for r in p.rules],
            "plans": plans, "pre": pre, "post": post, "tick": self.tick(), "gm_stamps": gm_stamps,
            # GNAT 12 does not count a use of a declare expression's constant
            # inside an aggregate (`(declare X : constant ... := F; begin
            # T'(A => X, B => G))`) and warns that X is not referenced: the
            # warning is turned off for those constants only, in the
            # controllers that have some.
            "sequenced": self._temp_count > seq_before,
        }
        # The step always reads Cycle (the entry cycle of a new command and the
        # status stamp), so it needs no `pragma Unreferenced (Cycle)`.
        self.info = None
        return ctx

    def own_of(self, c: str) -> str:
        return f"Buf.{self.n.buffer_member(c, 'status')}"

    def plan(self, c: m.Controller, plan: m.Plan) -> dict:
        self.verb = plan.verb
        layout = plan_layout(plan, self.impure)
        body = self.layout(layout)
        return {"fn": self.n.plan_fn(plan.verb), "verb": ada_comment(plan.verb), "doc": ada_comment(plan.doc), "verb_const": self.n.verb(c.name, plan.verb),
                "where": self.where_text(plan.span), "continuous": plan.continuous, "needs_state": tests_state(layout),
                "body": body, "uses_cycle": any(re.search(r"\bCycle\b", x) for x in body)}

    def layout(self, items: list) -> list[str]:
        out: list[str] = []
        for item in items:
            if isinstance(item, RuleStep):
                out += self.rule(item.conds, item.rule)
                continue
            out.append(f"if {_strip(self.cond_part(item.test))} then")
            saved = dict(self.cse)
            inner = []
            for name, call in item.hoist:
                inner.append(f"   {name} : constant {self.atype(call.type)} := {_strip(self.expr(call))};")
                self.cse[expr_key(call)] = name
            body = ["   " + x for x in self.layout(item.items)]
            if inner:
                out += ["   declare"] + ["   " + x for x in inner] + ["   begin"] + ["   " + x for x in body] + ["   end;"]
            else:
                out += body
            self.cse = saved
            out.append("end if;")
        return out

    def cond_part(self, part) -> str:
        if isinstance(part, StateTest):
            return f"(State = {self.n.state('new' if part.kind == 'new' else part.name or '')})"
        return self.expr(part)

    def rule(self, conj: list, r: m.Rule) -> list[str]:
        own = self.own()
        parts = [self.cond_part(t) for t in conj]
        cond = _strip(parts[0]) if len(parts) == 1 else " and then ".join(parts)
        saved, self.cse = self.cse, {}
        reports = any(isinstance(s, m.Report) for s in r.jobs)
        body = [] if r.next.kind in ("done", "error") or reports else [f"{own}.Head.Status := Rcs_Num.Exec;"]
        body.append(f"{own}.Head.Rule := {self.n.rule(self.verb or '', r.label)};")
        body += self.stmts(r.jobs, 0)
        self.cse = saved
        nxt = r.next
        if nxt.kind == "named":
            target = self.n.state(nxt.name or "")
            enter = [f"{own}.Head.State := {target};", "Entry_Cycle := Cycle;"]
            if r.state.kind == "named" and r.state.name == nxt.name:
                pass
            elif r.state.kind == "any":
                body += [f"if {own}.Head.State /= {target} then"] + ["   " + x for x in enter] + ["end if;"]
            else:
                body += enter
        elif nxt.kind == "done":
            body += [f"{own}.Head.Status := Rcs_Num.Done;", f"{own}.Head.State := St_Done;", "Plan := 0;"]
        elif nxt.kind == "error":
            body += [f"{own}.Head.Status := Rcs_Num.Error;", f"{own}.Head.Error_Code := {self.literal(nxt.code, I32)};",
                     f"{own}.Head.State := St_Error;", "Plan := 0;"]
        guard = "otherwise" if r.guard is None else self.comment(r.guard_span.text)
        head = [f"--  {self.comment(r.doc)}"] if r.doc else []
        head.append(f"--  {r.label} ({self.where_text(r.span)}): {guard} | {self.comment(str(r.state))} -> {self.comment(r.next.span.text)}")
        if not cond:
            return head + body + ["return;"]
        return head + [f"if {cond} then"] + ["   " + x for x in body] + ["   return;", "end if;"]


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _strip(text: str) -> str:
    """`(a and then b)` -> `a and then b` when the outer parentheses enclose the whole text."""
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
    # if- and declare expressions keep their parentheses (Ada requires them)
    return text if text.startswith(("(if ", "(declare ")) else text[1:-1]
