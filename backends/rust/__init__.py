"""The Rust target: a no_std controller library and one std binary per CPU.

`RustBackend.files()` lays the design out as a cargo crate:

    Cargo.toml            one [[bin]] per CPU, overflow checks on in every profile
    src/lib.rs            #![no_std], #![forbid(unsafe_code)]; the `Externs` trait
    src/num.rs            the numeric rules (copied from runtime/num.rs)
    src/types.rs          types, constants, Global Memory, command/status buffers
    src/functions.rs      the pure functions
    src/ctrl_<C>.rs       one controller (Appendix A): struct, new(), step(), a fn per plan
    src/externs_impl.rs   yours: the extern functions (written only when missing)
    src/io.rs             yours, deployment builds: the plant I/O hooks
    src/bin/<cpu>.rs      the Main Program: tables for the host runtime, HostDesign, main()
    host/                 the design-independent Main Program (copied from runtime/host/)

Expressions and statements come from `target.RustTarget`, laid out as rustfmt
would (`fmt.py`); the Main Program's tables from `tables.py`.  See
docs/backends.md.
"""

from __future__ import annotations

import os

from importlib import resources

from rcsc.semantics import model as m
from rcsc.outputs.backend import OutFile, RuleStep, ordered_types, StateTest, built_controllers, expr_key, keeps_gm_stamps, plan_layout, register, schedule_of, tests_state
from rcsc.backends.rust.fmt import Array, Atom, Bin, Call, Node, Struct, arm, assign, expr_stmt, field_decl, fn_head, if_open, let, pad, tail, Unary
from rcsc.backends.rust.target import RustTarget
from rcsc.sim.simulate import zero_value
from rcsc.semantics.types import I32, ArrayType, EnumType, RecordType, Type

def _innermost(t: Type) -> Type:
    """The element type of an array of arrays of ..., else `t`."""
    while isinstance(t, ArrayType):
        t = t.elem
    return t


LIB_ALLOWS = [
    # The design's names are kept as written (controllers, verbs, states, Global Memory).
    "non_camel_case_types",
    "non_snake_case",
    "non_upper_case_globals",
    "clippy::upper_case_acronyms",
    # A binding named like a variant of its type (`fn f(x: Axis)` with `enum
    # Axis { x, y }`, or the helpers' `|x|` over an array of it) is an error
    # by default: in a pattern, an unqualified name that is a variant in scope
    # matches the variant instead of binding.  The generated code names every
    # variant by its type (`Axis::x`) and never imports variants, so such a
    # name always binds, and the design may name its members as it likes.
    "bindings_with_variant_name",
]
# Expressions keep the structure the design gives them; a rewrite that a lint
# suggests could change what they compute (a negated comparison is not the same
# for NaN, `x == x` is a NaN test) or hide the design's text in the code.  Each
# of these fires on tests/rust_stress/stress.rcs (WORKER's post block).
EXPR_ALLOWS = [
    "clippy::nonminimal_bool",
    "clippy::neg_cmp_op_on_partial_ord",
    "clippy::assign_op_pattern",
    "clippy::collapsible_if",
    "clippy::approx_constant",
    "clippy::eq_op",
    "clippy::if_same_then_else",
    "clippy::needless_bool",
    "clippy::manual_clamp",
    # Comparisons that a type's range decides (`u >= 0` with u: u32, `x <
    # i32::MIN`), conditions that repeat (`if a {} else if a {}`) or contradict
    # themselves (`x < 1 and x > 2`), `x * -1`, `x += x * 2.0`, `x < NAN`, `if c { b = true; } else { b = false; }`, `x < y or x == y`,
    # `min(max(x, 5), 3)`, `a = b; b = a;` are legal in a design and mean what they say.
    "unused_comparisons",
    "clippy::absurd_extreme_comparisons",
    "clippy::overly_complex_bool_expr",
    "clippy::ifs_same_cond",
    "clippy::neg_multiply",
    "clippy::redundant_comparisons",
    "clippy::impossible_comparisons",
    "clippy::misrefactored_assign_op",
    "invalid_nan_comparisons",
    "clippy::needless_bool_assign",
    "clippy::double_comparisons",
    "clippy::min_max",
    "clippy::almost_swapped",
]


@register
class RustBackend(RustTarget):
    entry_files = ("Cargo.toml",)
    transports = ("shm", "dds")

    def build_commands(self, folder: str) -> list[tuple[list[str], dict[str, str] | None]]:
        return [(["cargo", "build", "--offline", "--release", "--quiet"],
                 {"CARGO_TARGET_DIR": os.path.join(folder, "target"), "CARGO_TERM_COLOR": "never"})]

    def program(self, folder: str) -> str:
        d = self.design
        name = f"run_{self.crate}" if len(d.cpus) > 1 else self.n.binary(next(iter(d.cpus)))
        return os.path.join(folder, "target", "release", name)

    def files(self) -> list[OutFile]:
        from rcsc.backends.rust.tables import main_program

        d = self.design
        ctrls = built_controllers(d, self.options)
        deploy = self.options.exclude_simulators
        externs = [f for f in d.functions.values() if f.extern]
        pure = [f for f in d.functions.values() if not f.extern]
        files: list[OutFile] = []
        ctrl_files = [OutFile(f"src/{self.module(c)}.rs", self.render("ctrl.rs.j2", **self.controller(c))) for c in ctrls]
        launcher = f"run_{self.crate}" if len(d.cpus) > 1 else None
        dds = self.options.transport == "dds" and len(d.cpus) > 1
        files.append(OutFile("Cargo.toml", self.render("Cargo.toml.j2", crate=self.crate, design=d.name, launcher=launcher, dds=dds,
                                                                  bins=[{"name": self.n.binary(c.name), "path": f"src/bin/{self.n.bin_stem(c.name)}.rs"} for c in d.cpus.values()])))
        if launcher:
            launch = Call("std::process::exit", [Call("host::launch", [
                Atom(_rust_str(d.name)),
                Unary("&", Array([Atom(_rust_str(c)) for c in d.cpus])),
                Unary("&", Array([Atom(_rust_str(self.n.binary(c))) for c in d.cpus])),
            ])])
            files.append(OutFile("src/run.rs", self.render("run.rs.j2", design=self.comment(d.name), body=expr_stmt(launch, 1))))
        modules = ["num", "types"] + (["functions"] if pure else []) + [self.module(c) for c in ctrls] + (["externs_impl"] if externs else [])
        files.append(OutFile("src/lib.rs", self.render("lib.rs.j2", **self.lib(sorted(modules), externs))))
        files.append(OutFile("src/num.rs", self.runtime_text("num.rs")))
        files.append(OutFile("src/types.rs", self.render("types.rs.j2", **self.types_module(ctrls))))
        if pure:
            files.append(OutFile("src/functions.rs", self.render("functions.rs.j2", **self.functions_module(pure))))
        files += ctrl_files
        for cpu in d.cpus.values():
            files.append(OutFile(f"src/bin/{self.n.bin_stem(cpu.name)}.rs", self.render("main.rs.j2", **main_program(self, cpu, schedule_of(d, cpu, self.options), ctrls))))
        if externs:
            files.append(OutFile("src/externs_impl.rs", self.render("externs_impl.rs.j2", **self.externs_stub(externs)), user=True))
        if deploy:
            files.append(OutFile("src/io.rs", self.render("io.rs.j2", crate=self.crate), user=True))
        for name in self.host_files():
            files.append(OutFile(f"host/{name}", self.runtime_text(f"host/{name}")))
        if dds:
            files += self.dds_crate()
        return files

    def dds_crate(self) -> list[OutFile]:
        """rcs_dds/: the safe wrapper crate around the C target's DDS transport
        (its C files copied from the C runtime, compiled by the crate's build.rs)."""
        files = [OutFile(f"rcs_dds/{name}", self.runtime_text(f"rcs_dds/{name}")) for name in ("Cargo.toml", "build.rs", "src/lib.rs")]
        c_runtime = resources.files("rcsc.backends.c").joinpath("runtime")
        for name in ("rcs_dds.c", "rcs_dds.h", "rcs_link.h", "rcs_shm.h"):
            files.append(OutFile(f"rcs_dds/c/{name}", c_runtime.joinpath(name).read_text(encoding="utf-8")))
        return files

    # ---- runtime ------------------------------------------------------------------------

    @property
    def step_uses_ext(self) -> dict[str, bool]:
        """Whether a controller's `step` takes the extern functions (filled in by `controller`)."""
        if not hasattr(self, "_step_ext"):
            self._step_ext: dict[str, bool] = {}
        return self._step_ext

    def runtime_text(self, path: str) -> str:
        """A runtime file, copied unchanged (it carries the banner itself)."""
        return self.runtime_file(*path.split("/"))

    def host_files(self) -> list[str]:
        folder = resources.files(self.package).joinpath("runtime", "host")
        return sorted(p.name for p in folder.iterdir() if p.name.endswith(".rs"))

    def module(self, c: m.Controller) -> str:
        return self.n.module(c.name)

    # ---- lib.rs ----------------------------------------------------------------------------

    def lib(self, modules: list[str], externs: list[m.Function]) -> dict:
        methods = []
        for f in externs:
            self.begin()
            params = ["&self"] + [f"{self.param(q.name)}: {self.lib_type(q.type)}" for q in f.params]
            methods.append({
                "doc": f"{self.where_text(f.span)}, budget {_duration(f.budget_ns)}.",
                "head": fn_head(1, "", self.ident(f.name), params, self.lib_type(f.ret), end=";"),
            })
        return {
            "design": self.design.name,
            "allows": LIB_ALLOWS,
            "expr_allows": EXPR_ALLOWS,
            "modules": modules,
            "methods": methods,
            "externs_impl": bool(externs),
        }

    def type_where(self, t: Type) -> str:
        span = getattr(t, "span", None)
        return self.where_text(span) if span is not None else t.name

    def lib_type(self, t: Type) -> str:
        if isinstance(t, ArrayType):
            return f"num::Arr<{self.lib_type(t.elem)}, {t.size}>"
        return f"types::{self.rtype(t)}" if isinstance(t, (EnumType, RecordType)) else self.rtype(t)

    def externs_stub(self, externs: list[m.Function]) -> dict:
        fns = []
        uses_types = False
        for f in externs:
            params = ["&self"] + [f"_{self.param(q.name)}: {self.rtype(q.type)}" for q in f.params]
            uses_types |= any(isinstance(_innermost(t), (EnumType, RecordType)) for t in [f.ret] + [q.type for q in f.params])
            fns.append({
                "where": f"{self.where_text(f.span)}, budget {_duration(f.budget_ns)}",
                "head": fn_head(1, "", self.ident(f.name), params, self.rtype(f.ret)),
                "zero": tail(self.literal(zero_value(f.ret), f.ret), 2),
            })
        uses_num = any(isinstance(t, ArrayType) for f in externs for t in [f.ret] + [q.type for q in f.params])
        return {"design": self.design.name, "fns": fns, "uses_types": uses_types, "uses_num": uses_num}

    # ---- types.rs --------------------------------------------------------------------------

    def types_module(self, ctrls: list[m.Controller]) -> dict:
        d = self.design
        types = []
        for t in ordered_types(d):
            if isinstance(t, EnumType):
                types.append({"kind": "enum", "name": self.tname(t.name), "where": self.type_where(t), "members": [self.ident(x) for x in t.members]})
            else:
                assert isinstance(t, RecordType)
                types.append({"kind": "record", "name": self.tname(t.name), "where": self.type_where(t),
                              "fields": [x for n, ft in t.fields for x in field_decl(f"pub {self.ident(n)}: {self.rtype(ft)}", 1)]})
        consts = [{"where": self.where_text(k.span), "lines": assign(f"pub const {self.vname(k.name)}: {self.rtype(k.type)}", "=", self.literal(k.value, k.type), 0)}
                  for k in d.consts.values()]
        gm_fields = [x for n, v in d.gm.items() for x in field_decl(f"pub {self.ident(n)}: {self.rtype(v.type)}", 1)]
        gm_init = assign("pub const INIT: Gm", "=", Struct("Gm", [(self.ident(n), self.init_value(v)) for n, v in d.gm.items()]), 1)
        stamps = [x for n in d.gm for x in field_decl(f"pub {self.ident(n)}: u64", 1)] if keeps_gm_stamps(d) else []
        buffers = []
        for c in ctrls:
            info = self.infos[c.name]
            verbs = []
            for i, (vname, v) in enumerate(c.verbs.items(), 1):
                verbs.append({"const": self.n.verb(c.name, vname), "number": i, "member": self.ident(vname),
                              "args_type": self.n.verb_args(c.name, vname),
                              "params": [x for q in v.params for x in field_decl(f"pub {self.ident(q.name)}: {self.rtype(q.type)}", 1)]})
            fields_type = self.n.ctrl_part(c.name, "fields")
            status_type, cmd_type = self.n.ctrl_part(c.name, "status"), self.n.ctrl_part(c.name, "cmd")
            status_member, cmd_member = self.n.buffer_member(c.name, "status"), self.n.buffer_member(c.name, "cmd")
            status_init = [("head", Atom("StatusHead::INIT"))]
            if c.status_fields:
                status_init.append(("f", Struct(fields_type, [(self.ident(n), self.init_value(v)) for n, v in c.status_fields.items()])))
            buffers.append({
                "name": c.name, "where": self.where_text(c.span),
                "kind": "simulator" if c.simulator else "controller",
                "verbs": verbs, "with_args": [v for v in verbs if v["params"]],
                "statuses": [{"const": self.n.status(c.name, s), "number": k} for s, k in c.statuses.items()],
                "cmd_type": cmd_type, "status_type": status_type, "args_type": self.n.ctrl_part(c.name, "args"),
                "fields_type": fields_type,
                "fields": [x for n, v in c.status_fields.items() for x in field_decl(f"pub {self.ident(n)}: {self.rtype(v.type)}", 1)],
                "arg_members": [x for v in verbs if v["params"] for x in field_decl(f"pub {v['member']}: {v['args_type']}", 1)],
                "status_init": assign(f"pub const INIT: {status_type}", "=", Struct(status_type, status_init), 1),
                "n_rules": len(info.rules),
                "buffer_decls": field_decl(f"pub {cmd_member}: {cmd_type}", 1) + field_decl(f"pub {status_member}: {status_type}", 1),
            })
        buf_new = tail(Struct("Buffers", [("gm", Atom("Gm::INIT"))] + ([("gm_stamp", Call("Default::default"))] if stamps else []) + [
            x for c in ctrls for x in ((self.n.buffer_member(c.name, "cmd"), Call("Default::default")),
                                       (self.n.buffer_member(c.name, "status"), Atom(f"{self.n.ctrl_part(c.name, 'status')}::INIT")))
        ]), 2)
        return {
            "design": d.name,
            "periods": [{"const": self.period_const(c.name), "ns": c.heartbeat_ns, "cpu": c.name} for c in d.cpus.values()],
            "types": types, "consts": consts, "gm_fields": gm_fields, "gm_init": gm_init, "gm_stamps": stamps,
            "buffers": buffers, "buf_new": buf_new,
        }

    # ---- functions.rs ----------------------------------------------------------------------

    def functions_module(self, fns: list[m.Function]) -> dict:
        self.begin()
        out = []
        for f in fns:
            assert f.body is not None
            used = {e.name for e in m.walk_expr(f.body) if isinstance(e, m.Ref) and e.kind == "arg"}
            params = [f"{'' if q.name in used else '_'}{self.param(q.name)}: {self.rtype(q.type)}" for q in f.params]
            body = tail(self.expr(f.body), 1)
            if any(isinstance(_innermost(t), (EnumType, RecordType)) for t in [f.ret] + [q.type for q in f.params]):
                self.uses.add("types")
            if any(isinstance(t, ArrayType) for t in [f.ret] + [q.type for q in f.params]):
                self.uses.add("num")
            out.append({
                "where": self.where_text(f.span),
                "allow": len(params) > 7,
                "head": fn_head(0, "pub ", self.vname(f.name), params, self.rtype(f.ret)),
                "body": body,
            })
        uses = self.uses
        return {"design": self.design.name, "fns": out, "imports": self.imports(uses - {"functions"})}

    def imports(self, uses: set[str]) -> list[str]:
        """The `use` lines of a module, in rustfmt's order."""
        lines = []
        if "functions" in uses:
            lines.append("use crate::functions::*;")
        if "num" in uses:
            lines.append("use crate::num;")
        if "types" in uses:
            lines.append("use crate::types::*;")
        if "ext" in uses:
            lines.append("use crate::Externs;")
        return _rustfmt_use_order(lines)

    # ---- one controller ----------------------------------------------------------------------

    def controller(self, c: m.Controller) -> dict:
        info = self.infos[c.name]
        self.info, self.verb = info, None
        self.begin()
        self.uses.update(("num", "types"))
        me = self.tname(c.name)
        own, cmd = self.own(), f"buf.{self.n.buffer_member(c.name, 'cmd')}"
        subs = [{"name": s, "member": self.ident(s)} for s in info.subs]
        locals_ = [x for v in c.locals.values() for x in field_decl(f"pub {self.ident(v.name)}: {self.rtype(v.type)}", 1)]
        init: list[tuple[str, object]] = []
        if subs:
            init += [("sent", Call("Default::default")), ("send", Call("Default::default"))]
        if c.locals:
            init.append(("loc", Struct("Locals", [(self.ident(n), self.init_value(v)) for n, v in c.locals.items()])))
        init += [("plan", Atom("0")), ("entry_cycle", Atom("0")), ("steps", Atom("0"))]
        new_body = tail(Struct(me, init), 2)  # type: ignore[arg-type]

        pre = self.stmts(c.pre, 2)
        post = self.stmts(c.post, 2)
        plans = [self.plan(c, plan) for plan in c.plans.values()]
        step_ext = "ext" in self.uses
        self.step_uses_ext[c.name] = step_ext
        # New command: a new serial supersedes whatever ran before; the plan of its
        # verb runs, a verb without a plan is an error.
        head = f"{own}.head"
        new_command = if_open(Bin.make("!=", Atom(f"{cmd}.head.serial"), Atom(f"{head}.echo_serial")), 2)
        new_command += let("verb", Atom(f"{cmd}.head.verb"), 3)
        new_command += assign(f"{head}.echo_serial", "=", Atom(f"{cmd}.head.serial"), 3)
        for field, value in (("status", "num::EXEC"), ("verb", "verb"), ("state", "Self::ST_NEW"), ("rule", "0"), ("error_code", "0")):
            new_command += assign(f"{head}.{field}", "=", Atom(value), 3)
        new_command += assign("self.entry_cycle", "=", Atom("cycle"), 3)
        if plans:
            new_command.append(f"{pad(3)}self.plan = match verb {{")
            for p in plans:
                new_command += arm(p["verb_const"], Atom(p["verb_const"]), 4)
            new_command += [f"{pad(4)}_ => {{"] + assign(f"{head}.status", "=", Atom("num::ERROR"), 5) + [f"{pad(5)}0", f"{pad(4)}}}", f"{pad(3)}}};"]
        else:
            new_command.append(f"{pad(3)}// {c.name} has no plans: every command is answered with ERROR.")
            new_command += assign(f"{head}.status", "=", Atom("num::ERROR"), 3)
        new_command.append(f"{pad(2)}}}")
        # Write: the commands issued in this step become new with their serial.
        write = assign(f"{head}.stamp", "=", self.tick(), 2)
        if keeps_gm_stamps(self.design):
            for use in c.writes:
                write += assign(f"buf.gm_stamp.{self.ident(use.name)}", "=", self.tick(), 2)
        for s in subs:
            sent = f"self.sent.{s['member']}"
            write += if_open(Atom(f"self.send.{s['member']}"), 2)
            write += assign(sent, "=", Call("num::next_serial", [Atom(sent)]), 3)
            write += assign(f"buf.{self.n.buffer_member(s['name'], 'cmd')}.head.serial", "=", Atom(sent), 3)
            write.append(f"{pad(2)}}}")
        calls = [(p["verb_const"], Atom(f"self.{p['fn']}({', '.join(['buf'] + (['ext'] if p['ext'] else []) + (['cycle'] if p['cycle'] else []))})"))
                 for p in plans]
        if len(calls) == 1:  # clippy::single_match: one plan is an `if`
            decide = if_open(Bin.make("==", Atom("self.plan"), Atom(calls[0][0])), 2) + expr_stmt(calls[0][1], 3) + [f"{pad(2)}}}"]
        else:
            decide = [f"{pad(2)}match self.plan {{"] + [x for verb, call in calls for x in arm(verb, call, 3)] + [f"{pad(3)}_ => {{}}", f"{pad(2)}}}"]
        params = ["&mut self", "buf: &mut Buffers"] + (["ext: &impl Externs"] if step_ext else []) + ["cycle: u64"]
        self.verb = None
        ctx = {
            "name": c.name, "doc": self.comment(c.doc), "type": me,
            "kind": "simulator" if c.simulator else "controller", "level": c.level, "where": self.where_text(c.span),
            "budget_ns": c.budget_ns,
            "subs": subs, "locals": locals_,
            "new_body": new_body,
            "states": [{"name": self.state_const(s), "number": i} for i, s in enumerate(info.states)],
            "rules": [{"name": self.rule_const(plan.verb, r.label), "number": info.rule_number[(plan.verb, r.index)]} for plan in c.plans.values() for r in plan.rules],
            "plans": plans, "new_command": new_command, "decide": decide, "write": write,
            "read": [x for s in subs for x in assign(f"self.send.{s['member']}", "=", Atom("false"), 2)],
            "pre": pre, "post": post,
            "step_head": fn_head(1, "pub ", "step", params, None),
            "imports": self.imports(self.uses),
        }
        self.info = None
        return ctx

    def plan(self, c: m.Controller, plan: m.Plan) -> dict:
        self.verb = plan.verb
        outer_uses = self.uses
        self.uses = set()
        layout = plan_layout(plan, self.impure)
        body: list[str] = []
        if tests_state(layout):
            body += let("state", Atom(f"{self.own()}.head.state"), 2)
        body += self.layout(layout, 2, True)
        uses = self.uses
        self.uses = outer_uses | uses
        params = ["&mut self", "buf: &mut Buffers"] + (["ext: &impl Externs"] if "ext" in uses else []) + (["cycle: u64"] if "cycle" in uses else [])
        return {
            "fn": self.n.plan_fn(plan.verb),
            "verb": plan.verb,
            "verb_const": self.n.verb(c.name, plan.verb),
            "doc": f"plan {plan.verb}{' (continuous)' if plan.continuous else ''}, {self.where_text(plan.span)}: the first rule whose state and",
            "head": fn_head(1, "", self.n.plan_fn(plan.verb), params, None),
            "body": body,
            "ext": "ext" in uses,
            "cycle": "cycle" in uses,
        }

    def layout(self, items: list, indent: int, last: bool) -> list[str]:
        """The lines of a plan's rule layout; `last`: it ends the function (no `return;`
        after its final rule, clippy::needless_return)."""
        out: list[str] = []
        for n, item in enumerate(items):
            end = last and n == len(items) - 1
            if isinstance(item, RuleStep):
                out += self.rule(item.conds, item.rule, indent, end)
                continue
            out += if_open(self.cond_part(item.test), indent)
            saved = dict(self.cse)
            for name, call in item.hoist:
                out += let(name, self.expr(call), indent + 1)
                self.cse[expr_key(call)] = name
            out += self.layout(item.items, indent + 1, end)
            self.cse = saved
            out.append(f"{pad(indent)}}}")
        return out

    def cond_part(self, part) -> Node:
        if isinstance(part, StateTest):
            return Bin.make("==", Atom("state"), Atom(f"Self::{self.state_const('new' if part.kind == 'new' else part.name or '')}"))
        return self.expr(part)

    def rule(self, conds: list, r: m.Rule, indent: int, last: bool) -> list[str]:
        assert self.verb is not None
        own = self.own()
        cond = None
        for part in conds:
            t = self.cond_part(part)
            cond = t if cond is None else Bin.make("&&", cond, t)
        ind = indent + 1 if cond is not None else indent
        saved, self.cse = self.cse, {}  # jobs run after the condition: no stale values
        # EXEC unless the rule's own status (done, error, a report) overwrites it.
        reports = any(isinstance(s, m.Report) for s in r.jobs)
        body = [] if r.next.kind in ("done", "error") or reports else assign(f"{own}.head.status", "=", Atom("num::EXEC"), ind)
        body += assign(f"{own}.head.rule", "=", Atom(f"Self::{self.rule_const(self.verb, r.label)}"), ind)
        body += self.stmts(r.jobs, ind)
        self.cse = saved
        nxt = r.next
        if nxt.kind == "named":
            target = f"Self::{self.state_const(nxt.name or '')}"
            if r.state.kind == "named" and r.state.name == nxt.name:
                pass  # a self-loop keeps the time in state running
            elif r.state.kind == "any":
                self.uses.add("cycle")
                body += if_open(Bin.make("!=", Atom(f"{own}.head.state"), Atom(target)), ind)
                body += assign(f"{own}.head.state", "=", Atom(target), ind + 1)
                body += assign("self.entry_cycle", "=", Atom("cycle"), ind + 1)
                body.append(f"{pad(ind)}}}")
            else:
                self.uses.add("cycle")
                body += assign(f"{own}.head.state", "=", Atom(target), ind)
                body += assign("self.entry_cycle", "=", Atom("cycle"), ind)
        elif nxt.kind == "done":
            body += assign(f"{own}.head.status", "=", Atom("num::DONE"), ind)
            body += assign(f"{own}.head.state", "=", Atom("Self::ST_DONE"), ind)
            body += assign("self.plan", "=", Atom("0"), ind)
        elif nxt.kind == "error":
            body += assign(f"{own}.head.status", "=", Atom("num::ERROR"), ind)
            body += assign(f"{own}.head.error_code", "=", self.literal(nxt.code, I32), ind)
            body += assign(f"{own}.head.state", "=", Atom("Self::ST_ERROR"), ind)
            body += assign("self.plan", "=", Atom("0"), ind)
        if not last:
            body.append(f"{pad(ind)}return;")
        guard_text = "otherwise" if r.guard is None else self.comment(r.guard_span.text)
        comment = ([f"{pad(indent)}// {self.comment(r.doc)}"] if r.doc else []) + [
            f"{pad(indent)}// {r.label} ({self.where_text(r.span)}): {guard_text} | {r.state} -> {nxt}"]
        if cond is None:
            return comment + body
        return comment + if_open(cond, indent) + body + [f"{pad(indent)}}}"]


def _rustfmt_use_order(lines: list[str]) -> list[str]:
    """`use` lines in the order rustfmt (style edition 2015) sorts them: segment by
    segment, `self` < `super` < `crate` < names < `*`; among names snake_case <
    CamelCase < UPPER_SNAKE_CASE, then by text."""

    def segment(seg: str) -> tuple:
        if seg in ("self", "super", "crate"):
            return (("self", "super", "crate").index(seg),)
        if seg == "*":
            return (4,)
        upper_snake = all(c.isupper() or c == "_" or c.isdigit() for c in seg)
        return (3, upper_snake, seg[:1].isupper(), seg)

    return sorted(lines, key=lambda s: [segment(x) for x in s.removeprefix("use ").rstrip(";").split("::")])


def _duration(ns: int) -> str:
    if ns % 1_000_000_000 == 0:
        return f"{ns // 1_000_000_000} s"
    if ns % 1_000_000 == 0:
        return f"{ns // 1_000_000} ms"
    if ns % 1_000 == 0:
        return f"{ns // 1_000} us"
    return f"{ns} ns"


def _rust_str(text: str) -> str:
    """A Rust string literal of `text` (names are identifiers; escaped anyway)."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'
