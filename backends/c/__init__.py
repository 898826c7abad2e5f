"""The C target: C99 controllers (Appendix A) and a POSIX Main Program (Appendix B).

`CBackend.files()` lays the design out as files; the text of expressions and
statements comes from `target.CTarget`, the Main Program's tables from
`tables.py`, and the design-independent runtime (rcs_num.h, rcs_runtime.h/.c)
is copied from runtime/.  See docs/backends.md.
"""

from __future__ import annotations

from rcsc import model as m
from rcsc.backend import (
    OutFile,
    RuleStep,
    initial_value,
    ordered_types,
    StateTest,
    expr_key,
    plan_layout,
    tests_state,
    built_controllers,
    register,
    schedule_of,
)
from rcsc.backends.c.tables import main_tables
from rcsc.backends.c.target import CTarget, _strip_parens
from rcsc.simulate import zero_value
from rcsc.types import I32, EnumType, RecordType

RUNTIME_FILES = ("rcs_num.h", "rcs_runtime.h", "rcs_runtime.c")


@register
class CBackend(CTarget):
    entry_files = ("Makefile", "CMakeLists.txt")

    def files(self) -> list[OutFile]:
        d, p = self.design, self.p
        ctrls = built_controllers(d, self.options)
        files = [OutFile(name, self.runtime_file(name)) for name in RUNTIME_FILES]
        files.append(OutFile(f"{p}.h", self.render("design.h.j2", **self.design_header(ctrls))))
        files.append(OutFile(f"{p}.c", self.render("design.c.j2", **self.design_source(ctrls))))
        externs = [f for f in d.functions.values() if f.extern]
        files.append(OutFile(f"{p}_externs.h", self.render("externs.h.j2", p=p, protos=[self.prototype(f) + ";" for f in externs])))
        if externs:
            files.append(OutFile(f"{p}_externs.c", self.render("externs_stub.c.j2", p=p, fns=[self.extern_stub(f) for f in externs]), user=True))
        for c in ctrls:
            ctx = self.controller(c)
            files.append(OutFile(f"{p}_{c.name}.h", self.render("ctrl.h.j2", **ctx)))
            files.append(OutFile(f"{p}_{c.name}.c", self.render("ctrl.c.j2", **ctx)))
        deploy = self.options.exclude_simulators
        if deploy:
            files.append(OutFile(f"{p}_io.h", self.render("io.h.j2", p=p)))
            files.append(OutFile(f"{p}_io.c", self.render("io_stub.c.j2", p=p), user=True))
        binaries = []
        for cpu in d.cpus.values():
            tables = main_tables(self, cpu, schedule_of(d, cpu, self.options), ctrls)
            files.append(OutFile(f"main_{cpu.name}.c", self.render("main.c.j2", p=p, cpu=cpu.name, deploy=deploy, ctrls=[c.name for c in ctrls], **tables)))
            binaries.append({"name": f"{p}_{cpu.name}", "main": f"main_{cpu.name}.c"})
        sources = [f"{p}.c"] + [f"{p}_{c.name}.c" for c in ctrls] + ([f"{p}_externs.c"] if externs else []) + ([f"{p}_io.c"] if deploy else []) + ["rcs_runtime.c"]
        build = {"p": p, "sources": sources, "binaries": binaries}
        files.append(OutFile("Makefile", self.render("Makefile.j2", **build)))
        files.append(OutFile("CMakeLists.txt", self.render("CMakeLists.txt.j2", **build)))
        return files

    # ---- the design header -------------------------------------------------------------

    def design_header(self, ctrls: list[m.Controller]) -> dict:
        d, p = self.design, self.p
        types = []
        for t in ordered_types(d):
            if isinstance(t, EnumType):
                types.append({"kind": "enum", "name": self.ctype(t), "members": [self.member(t, x) for x in t.members]})
            else:
                assert isinstance(t, RecordType)
                types.append({"kind": "record", "name": self.ctype(t), "fields": [f"{self.ctype(ft)} {self.ident(n)};" for n, ft in t.fields]})
        consts = [{"name": f"{p}_{k.name}", "value": self.literal(k.value, k.type), "where": self.where_text(k.span)} for k in d.consts.values()]
        gm = [f"{self.ctype(v.type)} {self.ident(v.name)};" for v in d.gm.values()]
        buffers = []
        for c in ctrls:
            info = self.infos[c.name]
            verbs = []
            for i, (vname, v) in enumerate(c.verbs.items(), 1):
                verbs.append({"macro": f"{p}_{c.name}_VERB_{vname}", "number": i, "member": self.ident(vname),
                              "args_type": f"{p}_{c.name}_{vname}_args",
                              "params": [f"{self.ctype(q.type)} {self.ident(q.name)};" for q in v.params]})
            buffers.append({
                "name": c.name, "member": self.ident(c.name),
                "verbs": verbs, "with_args": [v for v in verbs if v["params"]],
                "statuses": [{"macro": f"{p}_{c.name}_STATUS_{s}", "number": n} for s, n in c.statuses.items()],
                "cmd_type": f"{p}_{c.name}_cmd", "status_type": f"{p}_{c.name}_status", "args_type": f"{p}_{c.name}_args",
                "fields_type": f"{p}_{c.name}_fields",
                "fields": [f"{self.ctype(v.type)} {self.ident(v.name)};" for v in c.status_fields.values()],
                "n_rules": len(info.rules),
            })
        fns = [f for f in d.functions.values() if not f.extern]
        return {
            "p": p, "design": d.name,
            "periods": [{"macro": self.period_macro(c.name), "ns": c.heartbeat_ns} for c in d.cpus.values()],
            "types": types, "consts": consts, "gm": gm, "buffers": buffers,
            "protos": [f"static inline {self.prototype(f)};" for f in fns],
            "fns": [self.function(f) for f in fns],
        }

    def prototype(self, f: m.Function) -> str:
        params = ", ".join(f"{self.ctype(q.type)} {self.ident(q.name)}" for q in f.params) or "void"
        return f"{self.ctype(f.ret)} {self.p}_{f.name}({params})"

    def function(self, f: m.Function) -> dict:
        assert f.body is not None
        used = {e.name for e in m.walk_expr(f.body) if isinstance(e, m.Ref) and e.kind == "arg"}
        return {
            "proto": f"static inline {self.prototype(f)}",
            "where": self.where_text(f.span),
            "unused": [self.ident(q.name) for q in f.params if q.name not in used],
            "body": self.expr(f.body),
        }

    def extern_stub(self, f: m.Function) -> dict:
        return {"proto": self.prototype(f), "where": self.where_text(f.span), "params": [self.ident(q.name) for q in f.params],
                "zero": self.literal(zero_value(f.ret), f.ret)}

    def design_source(self, ctrls: list[m.Controller]) -> dict:
        d = self.design
        gm = [f"b->gm.{self.ident(n)} = {self.init_value(v)};" for n, v in d.gm.items()]
        inits = []
        for c in ctrls:
            member = self.ident(c.name)
            lines = [f"b->{member}_cmd.head.serial = 0u;", f"b->{member}_cmd.head.verb = 0;"]
            lines += [f"b->{member}_status.head.{k} = {v};" for k, v in _HEAD_INIT]
            lines += [f"b->{member}_status.f.{self.ident(n)} = {self.init_value(v)};" for n, v in c.status_fields.items()]
            inits.append(lines)
        return {"p": self.p, "gm": gm, "ctrls": inits}

    def init_value(self, v: m.Var) -> str:
        return self.literal(initial_value(v), v.type)

    # ---- one controller -----------------------------------------------------------------

    def controller(self, c: m.Controller) -> dict:
        p = self.p
        info = self.infos[c.name]
        self.info, self.verb = info, None
        member = self.ident(c.name)
        subs = [self.ident(s) for s in info.subs]
        locals_ = [f"{self.ctype(v.type)} {self.ident(v.name)};" for v in c.locals.values()]
        init = [f"self->loc.{self.ident(n)} = {self.init_value(v)};" for n, v in c.locals.items()]
        for s in subs:
            init += [f"self->sent.{s} = 0u;", f"self->send.{s} = false;"]
        plans = [self.plan(c, plan) for plan in c.plans.values()]
        self.verb = None
        ctx = {
            "p": p, "name": c.name, "type": self.ctrl_type(c.name), "member": member,
            "own": f"buf->{member}_status", "cmd": f"buf->{member}_cmd",
            "kind": "simulator" if c.simulator else "controller", "level": c.level, "where": self.where_text(c.span),
            "budget_ns": c.budget_ns,
            "subs": subs, "locals": locals_, "init": init,
            "states": [{"name": _state_enum(s), "number": i} for i, s in enumerate(info.states)],
            "rules": [{"name": f"RULE_{plan.verb}_{r.label}", "number": info.rule_number[(plan.verb, r.index)]} for plan in c.plans.values() for r in plan.rules],
            "plans": plans,
            "pre": self.stmts(c.pre, 1), "post": self.stmts(c.post, 1),
        }
        self.info = None
        return ctx

    def plan(self, c: m.Controller, plan: m.Plan) -> dict:
        self.verb = plan.verb
        layout = plan_layout(plan, self.impure)
        return {
            "fn": f"{c.name}_plan_{plan.verb}",
            "verb": plan.verb,
            "where": self.where_text(plan.span),
            "continuous": plan.continuous,
            "needs_state": tests_state(layout),
            "body": self.layout(layout),
        }

    def layout(self, items: list) -> list[str]:
        out: list[str] = []
        for item in items:
            if isinstance(item, RuleStep):
                out += self.rule(item.conds, item.rule)
                continue
            out.append(f"if ({_strip_parens(self.cond_part(item.test))}) {{")
            saved = dict(self.cse)
            for name, call in item.hoist:
                out.append(f"    const {self.ctype(call.type)} {name} = {self.expr(call)};")
                self.cse[expr_key(call)] = name
            out += ["    " + x for x in self.layout(item.items)]
            self.cse = saved
            out.append("}")
        return out

    def cond_part(self, part) -> str:
        if isinstance(part, StateTest):
            return "state == ST_NEW" if part.kind == "new" else f"state == {_state_enum(part.name or '')}"
        return self.expr(part)

    def rule(self, conj: list, r: m.Rule) -> list[str]:
        plan_verb = self.verb
        own = self.own()
        parts = [self.cond_part(t) for t in conj]
        if len(parts) > 1:
            parts = [f"({t})" if isinstance(c, StateTest) else t for t, c in zip(parts, conj)]
        cond = _strip_parens(parts[0]) if len(parts) == 1 else " && ".join(parts)
        saved, self.cse = self.cse, {}  # jobs run after the condition: no stale values
        reports = any(isinstance(s, m.Report) for s in r.jobs)
        body = [] if r.next.kind in ("done", "error") or reports else [f"{own}.head.status = RCS_EXEC;"]
        body.append(f"{own}.head.rule = RULE_{plan_verb}_{r.label};")
        body += self.stmts(r.jobs, 0)
        self.cse = saved
        nxt = r.next
        if nxt.kind == "named":
            target = _state_enum(nxt.name or "")
            enter = [f"{own}.head.state = {target};", "self->entry_cycle = cycle;"]
            if r.state.kind == "named" and r.state.name == nxt.name:
                pass  # a self-loop keeps the time in state running
            elif r.state.kind == "any":
                body.append(f"if ({own}.head.state != {target}) {{")
                body += ["    " + x for x in enter]
                body.append("}")
            else:
                body += enter
        elif nxt.kind == "done":
            body += [f"{own}.head.status = RCS_DONE;", f"{own}.head.state = ST_DONE;", "self->plan = 0;"]
        elif nxt.kind == "error":
            body += [f"{own}.head.status = RCS_ERROR;", f"{own}.head.error_code = {self.literal(nxt.code, I32)};",
                     f"{own}.head.state = ST_ERROR;", "self->plan = 0;"]
        guard_text = "otherwise" if r.guard is None else self.comment(r.guard_span.text)
        head = f"if ({cond}) {{" if cond else "{"
        return [f"/* {r.label} ({self.where_text(r.span)}): {guard_text} | {r.state} -> {self.comment(r.next.span.text)} */", head] + ["    " + x for x in body] + ["    return;", "}"]


_HEAD_INIT = [
    ("echo_serial", "0u"),
    ("status", "RCS_UNINITIALIZED"),
    ("verb", "0"),
    ("state", "0"),
    ("rule", "0"),
    ("error_code", "0"),
    ("stamp", "0u"),
]

def _state_enum(name: str) -> str:
    """File-local enumerator of a state: fixed states ST_*, named states S_<name>."""
    return {"": "ST_NONE", "new": "ST_NEW", "done": "ST_DONE", "error": "ST_ERROR"}.get(name, f"S_{name}")
