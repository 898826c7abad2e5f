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

from importlib import resources

from rcsc import model as m
from rcsc.backend import CtrlInfo, OutFile, built_controllers, register, schedule_of, where
from rcsc.backends.rust.fmt import Atom, Bin, Call, Struct, arm, assign, field_decl, fn_head, if_open, pad, tail
from rcsc.backends.rust.target import RustTarget, rust_comment
from rcsc.types import I32, EnumType, RecordType, Type

LIB_ALLOWS = [
    # The design's names are kept as written (controllers, verbs, states, Global Memory).
    "non_camel_case_types",
    "non_snake_case",
    "non_upper_case_globals",
    "clippy::upper_case_acronyms",
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
]


def ordered_types(design: m.Design) -> list[Type]:
    """Enums, then records with every record after the records it contains."""
    out: list[Type] = list(design.enums.values())
    done: set[str] = set()

    def visit(t: RecordType) -> None:
        if t.name in done:
            return
        done.add(t.name)
        for _, ft in t.fields:
            if isinstance(ft, RecordType):
                visit(ft)
        out.append(t)

    for t in design.records.values():
        visit(t)  # type: ignore[arg-type]
    return out


@register
class RustBackend(RustTarget):
    def files(self) -> list[OutFile]:
        from rcsc.backends.rust.tables import main_program

        d = self.design
        ctrls = built_controllers(d, self.options)
        deploy = self.options.exclude_simulators
        externs = [f for f in d.functions.values() if f.extern]
        pure = [f for f in d.functions.values() if not f.extern]
        files: list[OutFile] = []
        ctrl_files = [OutFile(f"src/{self.module(c)}.rs", self.render("ctrl.rs.j2", **self.controller(c))) for c in ctrls]
        files.append(OutFile("Cargo.toml", self.render("Cargo.toml.j2", crate=self.crate, design=d.name, cpus=[c.name for c in d.cpus.values()])))
        modules = ["num", "types"] + (["functions"] if pure else []) + [self.module(c) for c in ctrls] + (["externs_impl"] if externs else [])
        files.append(OutFile("src/lib.rs", self.render("lib.rs.j2", **self.lib(sorted(modules, key=_mod_key), externs))))
        files.append(OutFile("src/num.rs", self.runtime_text("num.rs")))
        files.append(OutFile("src/types.rs", self.render("types.rs.j2", **self.types_module(ctrls))))
        if pure:
            files.append(OutFile("src/functions.rs", self.render("functions.rs.j2", **self.functions_module(pure))))
        files += ctrl_files
        for cpu in d.cpus.values():
            files.append(OutFile(f"src/bin/{cpu.name}.rs", self.render("main.rs.j2", **main_program(self, cpu, schedule_of(d, cpu, self.options), ctrls))))
        if externs:
            files.append(OutFile("src/externs_impl.rs", self.render("externs_impl.rs.j2", **self.externs_stub(externs)), user=True))
        if deploy:
            files.append(OutFile("src/io.rs", self.render("io.rs.j2", crate=self.crate), user=True))
        for name in self.host_files():
            files.append(OutFile(f"host/{name}", self.runtime_text(f"host/{name}")))
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
        return f"ctrl_{c.name}"

    # ---- lib.rs ----------------------------------------------------------------------------

    def lib(self, modules: list[str], externs: list[m.Function]) -> dict:
        methods = []
        for f in externs:
            self.begin()
            params = ["&self"] + [f"{self.param(q.name)}: {self.lib_type(q.type)}" for q in f.params]
            methods.append({
                "doc": f"{where(f.span)}, budget {_duration(f.budget_ns)}.",
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

    def lib_type(self, t: Type) -> str:
        return f"types::{self.rtype(t)}" if isinstance(t, (EnumType, RecordType)) else self.rtype(t)

    def externs_stub(self, externs: list[m.Function]) -> dict:
        fns = []
        uses_types = False
        for f in externs:
            params = ["&self"] + [f"_{self.param(q.name)}: {self.rtype(q.type)}" for q in f.params]
            uses_types |= any(isinstance(t, (EnumType, RecordType)) for t in [f.ret] + [q.type for q in f.params])
            fns.append({
                "where": f"{where(f.span)}, budget {_duration(f.budget_ns)}",
                "head": fn_head(1, "", self.ident(f.name), params, self.rtype(f.ret)),
                "zero": tail(self.literal(self.zero(f.ret), f.ret), 2),
            })
        return {"design": self.design.name, "fns": fns, "uses_types": uses_types}

    # ---- types.rs --------------------------------------------------------------------------

    def types_module(self, ctrls: list[m.Controller]) -> dict:
        d = self.design
        types = []
        for t in ordered_types(d):
            if isinstance(t, EnumType):
                types.append({"kind": "enum", "name": self.tname(t.name), "where": _where_type(t), "members": [self.ident(x) for x in t.members]})
            else:
                assert isinstance(t, RecordType)
                types.append({"kind": "record", "name": self.tname(t.name), "where": _where_type(t),
                              "fields": [x for n, ft in t.fields for x in field_decl(f"pub {self.ident(n)}: {self.rtype(ft)}", 1)]})
        consts = [{"where": where(k.span), "lines": assign(f"pub const {self.vname(k.name)}: {self.rtype(k.type)}", "=", self.literal(k.value, k.type), 0)}
                  for k in d.consts.values()]
        gm_fields = [x for n, v in d.gm.items() for x in field_decl(f"pub {self.ident(n)}: {self.rtype(v.type)}", 1)]
        gm_init = assign("pub const INIT: Gm", "=", Struct("Gm", [(self.ident(n), self.init_value(v)) for n, v in d.gm.items()]), 1)
        buffers = []
        for c in ctrls:
            info = self.infos[c.name]
            verbs = []
            for i, (vname, v) in enumerate(c.verbs.items(), 1):
                verbs.append({"const": f"{c.name}_VERB_{vname}", "number": i, "member": self.ident(vname),
                              "args_type": f"{c.name}_{vname}_args",
                              "params": [x for q in v.params for x in field_decl(f"pub {self.ident(q.name)}: {self.rtype(q.type)}", 1)]})
            fields_type = f"{c.name}_fields"
            status_init = [("head", Atom("StatusHead::INIT"))]
            if c.status_fields:
                status_init.append(("f", Struct(fields_type, [(self.ident(n), self.init_value(v)) for n, v in c.status_fields.items()])))
            buffers.append({
                "name": c.name, "member": self.ident(c.name), "where": where(c.span),
                "kind": "simulator" if c.simulator else "controller",
                "verbs": verbs, "with_args": [v for v in verbs if v["params"]],
                "statuses": [{"const": f"{c.name}_STATUS_{s}", "number": n} for s, n in c.statuses.items()],
                "cmd_type": f"{c.name}_cmd", "status_type": f"{c.name}_status", "args_type": f"{c.name}_args",
                "fields_type": fields_type,
                "fields": [x for n, v in c.status_fields.items() for x in field_decl(f"pub {self.ident(n)}: {self.rtype(v.type)}", 1)],
                "arg_members": [x for v in verbs if v["params"] for x in field_decl(f"pub {v['member']}: {v['args_type']}", 1)],
                "status_init": assign(f"pub const INIT: {c.name}_status", "=", Struct(f"{c.name}_status", status_init), 1),
                "n_rules": len(info.rules),
                "buffer_decls": field_decl(f"pub {c.name}_cmd: {c.name}_cmd", 1) + field_decl(f"pub {c.name}_status: {c.name}_status", 1),
            })
        buf_new = tail(Struct("Buffers", [("gm", Atom("Gm::INIT"))] + [
            x for c in ctrls for x in ((f"{c.name}_cmd", Call("Default::default")), (f"{c.name}_status", Atom(f"{c.name}_status::INIT")))
        ]), 2)
        return {
            "design": d.name,
            "periods": [{"const": self.period_const(c.name), "ns": c.heartbeat_ns, "cpu": c.name} for c in d.cpus.values()],
            "types": types, "consts": consts, "gm_fields": gm_fields, "gm_init": gm_init,
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
            if any(isinstance(t, (EnumType, RecordType)) for t in [f.ret] + [q.type for q in f.params]):
                self.uses.add("types")
            out.append({
                "where": where(f.span),
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
        subs = [{"name": s, "member": self.ident(s), "status_type": f"{s}_status", "cmd_type": f"{s}_cmd",
                 "status_decl": field_decl(f"pub {self.ident(s)}: {s}_status", 1), "cmd_decl": field_decl(f"pub {self.ident(s)}: {s}_cmd", 1)} for s in info.subs]
        gm = [{"decl": field_decl(f"pub {self.ident(n)}: {self.rtype(self.design.gm[n].type)}", 1), "member": self.ident(n)} for n in info.gm_uses]
        writes = [self.ident(u.name) for u in c.writes]
        locals_ = [x for v in c.locals.values() for x in field_decl(f"pub {self.ident(v.name)}: {self.rtype(v.type)}", 1)]
        init: list[tuple[str, object]] = [("cmd", Call("Default::default")), ("status", Atom(f"{c.name}_status::INIT"))]
        if subs:
            init.append(("sub", Struct("Subs", [(s["member"], Atom(f"{s['status_type']}::INIT")) for s in subs])))
            init += [("sent", Call("Default::default")), ("out", Call("Default::default")), ("send", Call("Default::default"))]
        if gm:
            init.append(("gm", Call("Default::default")))
        if c.locals:
            init.append(("loc", Struct("Locals", [(self.ident(n), self.init_value(v)) for n, v in c.locals.items()])))
        init += [("plan", Atom("0")), ("idle", Atom("true")), ("entry_cycle", Atom("0")), ("steps", Atom("0"))]
        new_body = tail(Struct(me, init), 2)  # type: ignore[arg-type]

        pre = self.stmts(c.pre, 2)
        post = self.stmts(c.post, 2)
        plans = [self.plan(c, plan) for plan in c.plans.values()]
        step_ext = "ext" in self.uses
        self.step_uses_ext[c.name] = step_ext
        decide = []
        for p in plans:
            args = ", ".join((["ext"] if p["ext"] else []) + (["cycle"] if p["cycle"] else []))
            decide += arm(f"{c.name}_VERB_{p['verb']}", Atom(f"self.{p['fn']}({args})"), 4)
        params = ["&mut self", "buf: &mut Buffers"] + (["ext: &impl Externs"] if step_ext else []) + ["cycle: u64"]
        self.verb = None
        ctx = {
            "name": c.name, "type": me,
            "kind": "simulator" if c.simulator else "controller", "level": c.level, "where": where(c.span),
            "budget_ns": c.budget_ns,
            "cmd_type": f"{c.name}_cmd", "status_type": f"{c.name}_status",
            "member": self.ident(c.name),
            "subs": subs, "gm": gm, "writes": writes, "locals": locals_,
            "new_body": new_body,
            "states": [{"name": self.state_const(s), "number": i} for i, s in enumerate(info.states)],
            "rules": [{"name": self.rule_const(plan.verb, r.label), "number": info.rule_number[(plan.verb, r.index)]} for plan in c.plans.values() for r in plan.rules],
            "plans": plans, "decide": decide,
            "pre": pre, "post": post,
            "step_head": fn_head(1, "pub ", "step", params, None),
            "imports": self.imports(self.uses),
        }
        self.info = None
        return ctx

    def plan(self, c: m.Controller, plan: m.Plan) -> dict:
        info = self.infos[c.name]
        self.verb = plan.verb
        outer_uses = self.uses
        self.uses = set()
        guarded = [r for r in plan.rules if not r.otherwise]
        fallbacks = [r for r in plan.rules if r.otherwise and r.state.kind != "any"]
        rules = []
        for r in guarded + fallbacks:
            rule = self.rule(info, plan, r)
            rules.append(rule)
            if not rule["cond"]:
                break  # the rules after one that always fires can never fire
        body: list[str] = []
        needs_state = any(r["tests_state"] for r in rules)
        if needs_state:
            body.append(f"{pad(2)}let state = self.status.head.state;")
        for i, rule in enumerate(rules):
            last = i == len(rules) - 1
            body += [f"{pad(2)}// {rule['comment']}"]
            if rule["cond"] is None:
                body += rule["body"]
            else:
                body += if_open(rule["cond"], 2)
                body += rule["body"]
                if not last:
                    body.append(f"{pad(3)}return;")
                body.append(f"{pad(2)}}}")
        uses = self.uses
        self.uses = outer_uses | uses
        params = ["&mut self"] + (["ext: &impl Externs"] if "ext" in uses else []) + (["cycle: u64"] if "cycle" in uses else [])
        return {
            "fn": f"plan_{plan.verb}",
            "verb": plan.verb,
            "doc": f"plan {plan.verb}{' (continuous)' if plan.continuous else ''}, {where(plan.span)}: the first rule whose state and",
            "head": fn_head(1, "", f"plan_{plan.verb}", params, None),
            "body": body,
            "ext": "ext" in uses,
            "cycle": "cycle" in uses,
        }

    def rule(self, info: CtrlInfo, plan: m.Plan, r: m.Rule) -> dict:
        tests: list = []
        tests_state = False
        if r.state.kind == "new":
            tests.append(Bin.make("==", Atom("state"), Atom("Self::ST_NEW")))
            tests_state = True
        elif r.state.kind == "named":
            tests.append(Bin.make("==", Atom("state"), Atom(f"Self::{self.state_const(r.state.name or '')}")))
            tests_state = True
        if r.guard is not None and not (isinstance(r.guard, m.Const) and r.guard.value is True):
            tests.append(self.expr(r.guard))
        cond = None
        for t in tests:
            cond = t if cond is None else Bin.make("&&", cond, t)
        guard_text = "otherwise" if r.guard is None else rust_comment(r.guard_span.text)
        ind = 3 if cond is not None else 2
        body = assign("self.status.head.status", "=", Atom("num::EXEC"), ind)
        body += assign("self.status.head.rule", "=", Atom(f"Self::{self.rule_const(plan.verb, r.label)}"), ind)
        body += self.stmts(r.jobs, ind)
        nxt = r.next
        if nxt.kind == "named":
            target = f"Self::{self.state_const(nxt.name or '')}"
            if r.state.kind == "named" and r.state.name == nxt.name:
                pass  # a self-loop keeps the time in state running
            elif r.state.kind == "any":
                self.uses.add("cycle")
                body += if_open(Bin.make("!=", Atom("self.status.head.state"), Atom(target)), ind)
                body += assign("self.status.head.state", "=", Atom(target), ind + 1)
                body += assign("self.entry_cycle", "=", Atom("cycle"), ind + 1)
                body.append(f"{pad(ind)}}}")
            else:
                self.uses.add("cycle")
                body += assign("self.status.head.state", "=", Atom(target), ind)
                body += assign("self.entry_cycle", "=", Atom("cycle"), ind)
        elif nxt.kind == "done":
            body += assign("self.status.head.status", "=", Atom("num::DONE"), ind)
            body += assign("self.status.head.state", "=", Atom("Self::ST_DONE"), ind)
            body += assign("self.idle", "=", Atom("true"), ind)
        elif nxt.kind == "error":
            body += assign("self.status.head.status", "=", Atom("num::ERROR"), ind)
            body += assign("self.status.head.error_code", "=", self.literal(nxt.code, I32), ind)
            body += assign("self.status.head.state", "=", Atom("Self::ST_ERROR"), ind)
            body += assign("self.idle", "=", Atom("true"), ind)
        return {
            "comment": f"{r.label} ({where(r.span)}): {guard_text} | {r.state} -> {nxt}",
            "cond": cond,
            "tests_state": tests_state,
            "body": body,
        }


def _mod_key(name: str) -> tuple:
    return (name.lower(), name)


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


def _where_type(t: Type) -> str:
    span = getattr(t, "span", None)
    return where(span) if span is not None else t.name

