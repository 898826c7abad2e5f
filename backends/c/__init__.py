"""The C target: C99 controllers (Appendix A) and a POSIX Main Program (Appendix B).

`CBackend.files()` lays the design out as files; the text of expressions and
statements comes from `target.CTarget`, the Main Program's tables from
`tables.py`, and the design-independent runtime (rcs_num.h, rcs_runtime.h/.c)
is copied from runtime/.  See docs/backends.md.
"""

from __future__ import annotations

import os

from rcsc.semantics import model as m
from rcsc.outputs.backend import (
    OutFile,
    RuleStep,
    initial_value,
    ordered_types,
    types_with_arrays,
    StateTest,
    expr_key,
    keeps_gm_stamps,
    plan_layout,
    tests_state,
    built_controllers,
    register,
    schedule_of,
)
from rcsc.backends.c.tables import main_tables
from rcsc.backends.c.target import INT_SUFFIX, CTarget, _strip_parens, c_comment, c_string
from rcsc.sim.simulate import zero_value
from rcsc.semantics.types import DURATION, I32, ArrayType, EnumType, FloatType, RecordType

RUNTIME_FILES = ("rcs_num.h", "rcs_runtime.h", "rcs_runtime.c", "rcs_link.h", "rcs_shm.h", "rcs_shm.c")
LAUNCHER_FILES = ("rcs_launch.h", "rcs_launch.c")  # several CPUs only
DDS_FILES = ("rcs_dds.h", "rcs_dds.c")  # several CPUs built with `--transport dds`


@register
class CBackend(CTarget):
    entry_files = ("Makefile", "CMakeLists.txt")
    transports = ("shm", "dds")

    def files(self) -> list[OutFile]:
        d, n = self.design, self.n
        ctrls = built_controllers(d, self.options)
        dds = self.options.transport == "dds" and len(d.cpus) > 1
        files = [OutFile(name, self.runtime_file(name)) for name in RUNTIME_FILES + (DDS_FILES if dds else ())]
        common = self.common_names()
        files.append(OutFile(f"{n.p}.h", self.render("design.h.j2", **common, **self.design_header(ctrls))))
        files.append(OutFile(f"{n.p}.c", self.render("design.c.j2", **common, **self.design_source(ctrls))))
        externs = [f for f in d.functions.values() if f.extern]
        files.append(OutFile(f"{n.p}_externs.h", self.render("externs.h.j2", **common, protos=[self.prototype(f) + ";" for f in externs])))
        if externs:
            files.append(OutFile(f"{n.p}_externs.c", self.render("externs_stub.c.j2", **common, fns=[self.extern_stub(f) for f in externs]), user=True))
        for c in ctrls:
            ctx = self.controller(c)
            files.append(OutFile(f"{n.ctrl_stem(c.name)}.h", self.render("ctrl.h.j2", **common, **ctx)))
            files.append(OutFile(f"{n.ctrl_stem(c.name)}.c", self.render("ctrl.c.j2", **common, **ctx)))
        deploy = self.options.exclude_simulators
        if deploy:
            files.append(OutFile(f"{n.p}_io.h", self.render("io.h.j2", **common)))
            files.append(OutFile(f"{n.p}_io.c", self.render("io_stub.c.j2", **common), user=True))
        binaries = []
        for cpu in d.cpus.values():
            tables = main_tables(self, cpu, schedule_of(d, cpu, self.options), ctrls)
            main = f"{n.main_stem(cpu.name)}.c"
            files.append(OutFile(main, self.render("main.c.j2", **common, cpu=cpu.name, main_file=main, cpu_string=c_string(cpu.name), deploy=deploy, dds=dds,
                                                   ctrl_headers=[f"{n.ctrl_stem(c.name)}.h" for c in ctrls], **tables)))
            binaries.append({"name": n.binary(cpu.name), "main": main})
        sources = [f"{n.p}.c"] + [f"{n.ctrl_stem(c.name)}.c" for c in ctrls] + ([f"{n.p}_externs.c"] if externs else []) + ([f"{n.p}_io.c"] if deploy else []) + ["rcs_runtime.c", "rcs_shm.c"] + (["rcs_dds.c"] if dds else [])
        launcher = None
        if len(d.cpus) > 1:
            files += [OutFile(name, self.runtime_file(name)) for name in LAUNCHER_FILES]
            files.append(OutFile(f"run_{n.p}.c", self.render("run.c.j2", **common, cpus=", ".join(c_string(c) for c in d.cpus),
                                                             bins=", ".join(c_string(n.binary(c)) for c in d.cpus))))
            launcher = {"name": f"run_{n.p}", "main": f"run_{n.p}.c", "objects": f"run_{n.p}.o rcs_launch.o"}
        build = {"p": n.p, "lib": f"{n.p}__controllers", "sources": sources, "binaries": binaries, "launcher": launcher, "dds": dds}
        files.append(OutFile("Makefile", self.render("Makefile.j2", **build)))
        files.append(OutFile("CMakeLists.txt", self.render("CMakeLists.txt.j2", **build)))
        return files

    def build_commands(self, folder: str) -> list[tuple[list[str], dict[str, str] | None]]:
        return [(["make", "-s"], None)]

    def program(self, folder: str) -> str:
        d, n = self.design, self.n
        return os.path.join(folder, f"run_{n.p}" if len(d.cpus) > 1 else n.binary(next(iter(d.cpus))))

    def common_names(self) -> dict:
        """The design-wide names every file of the design uses."""
        n = self.n
        return {
            "p": n.p, "design": c_comment(self.design.name), "design_string": c_string(self.design.name),
            "gm_type": n.fixed("gm"), "gm_stamps_type": n.fixed("gm_stamps"), "buffers_type": n.fixed("buffers"), "buffers_init": n.fixed("buffers_init"),
            "io_read": n.fixed("io_read"), "io_write": n.fixed("io_write"),
            "guard": n.fixed("H"), "externs_guard": n.fixed("externs", "H"), "io_guard": n.fixed("io", "H"),
        }

    # ---- the design header -------------------------------------------------------------

    def design_header(self, ctrls: list[m.Controller]) -> dict:
        d = self.design
        types = []
        for t in types_with_arrays(d):
            if isinstance(t, EnumType):
                types.append({"kind": "enum", "name": self.ctype(t), "members": [self.member(t, x) for x in t.members]})
            elif isinstance(t, ArrayType):
                types.append({"kind": "record", "name": self.ctype(t), "fields": [f"{self.ctype(t.elem)} v[{t.size}];"],
                              "helpers": self.array_helpers(t)})
            else:
                assert isinstance(t, RecordType)
                types.append({"kind": "record", "name": self.ctype(t), "fields": [f"{self.ctype(ft)} {self.ident(n)};" for n, ft in t.fields],
                              "helpers": []})
        n = self.n
        consts = [{"name": n.const(k.name), "value": self.literal(k.value, k.type), "where": self.where_text(k.span)} for k in d.consts.values()]
        gm = [f"{self.ctype(v.type)} {self.ident(v.name)};" for v in d.gm.values()]
        buffers = []
        for c in ctrls:
            info = self.infos[c.name]
            verbs = []
            for i, (vname, v) in enumerate(c.verbs.items(), 1):
                verbs.append({"macro": n.verb(c.name, vname), "number": i, "member": self.ident(vname),
                              "args_type": n.verb_args(c.name, vname),
                              "params": [f"{self.ctype(q.type)} {self.ident(q.name)};" for q in v.params]})
            buffers.append({
                "name": c_comment(c.name), "cmd_member": n.buffer_member(c.name, "cmd"), "status_member": n.buffer_member(c.name, "status"),
                "verbs": verbs, "with_args": [v for v in verbs if v["params"]],
                "statuses": [{"macro": n.status(c.name, s), "number": k} for s, k in c.statuses.items()],
                "cmd_type": n.ctrl_part(c.name, "cmd"), "status_type": n.ctrl_part(c.name, "status"), "args_type": n.ctrl_part(c.name, "args"),
                "fields_type": n.ctrl_part(c.name, "fields"),
                "fields": [f"{self.ctype(v.type)} {self.ident(v.name)};" for v in c.status_fields.values()],
                "n_rules": len(info.rules),
            })
        fns = [f for f in d.functions.values() if not f.extern]
        return {
            "gm_stamps": [self.ident(v) for v in d.gm] if keeps_gm_stamps(d) else [],
            "periods": [{"macro": self.period_macro(c.name), "ns": c.heartbeat_ns} for c in d.cpus.values()],
            "types": types, "consts": consts, "gm": gm, "buffers": buffers,
            "protos": [f"static inline {self.prototype(f)};" for f in fns],
            "fns": [self.function(f) for f in fns],
        }

    def array_helpers(self, t: ArrayType) -> list[str]:
        """An array type's element read (the element type's zero outside
        0..N-1, as in the simulator) and, for numbers, `sum`, `min_of` and
        `max_of` folded from the first element to the last."""
        at, et = self.ctype(t), self.ctype(t.elem)
        zero = self.literal(zero_value(t.elem), t.elem)
        out = [f"static inline {et} {self.n.array_fn(t, 'get')}(const {at} *a, int64_t i) {{",
               f"    return i >= 0 && i < {t.size} ? a->v[i] : {zero};", "}"]
        if t.elem.is_numeric or t.elem == DURATION:
            suffix = "f64" if isinstance(t.elem, FloatType) else INT_SUFFIX[t.elem.name]
            step = {"sum": "s + a->v[k]" if suffix == "f64" else f"rcs_add_{suffix}(s, a->v[k])",
                    "min_of": f"rcs_min_{suffix}(s, a->v[k])", "max_of": f"rcs_max_{suffix}(s, a->v[k])"}
            for op, expr in step.items():
                out += [f"static inline {et} {self.n.array_fn(t, op)}(const {at} *a) {{", f"    {et} s = a->v[0];",
                        f"    for (int64_t k = 1; k < {t.size}; k++) s = {expr};", "    return s;", "}"]
        return out

    def prototype(self, f: m.Function) -> str:
        params = ", ".join(f"{self.ctype(q.type)} {self.ident(q.name)}" for q in f.params) or "void"
        return f"{self.ctype(f.ret)} {self.n.function(f.name)}({params})"

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
        if keeps_gm_stamps(d):
            gm += [f"b->gm_stamp.{self.ident(n)} = 0u;" for n in d.gm]
        inits = []
        for c in ctrls:
            cmd, status = self.n.buffer_member(c.name, "cmd"), self.n.buffer_member(c.name, "status")
            lines = [f"b->{cmd}.head.serial = 0u;", f"b->{cmd}.head.verb = 0;"]
            lines += [f"b->{status}.head.{k} = {v};" for k, v in _HEAD_INIT]
            lines += [f"b->{status}.f.{self.ident(n)} = {self.init_value(v)};" for n, v in c.status_fields.items()]
            inits.append(lines)
        return {"gm": gm, "ctrls": inits}

    def init_value(self, v: m.Var) -> str:
        return self.literal(initial_value(v), v.type)

    # ---- one controller -----------------------------------------------------------------

    def controller(self, c: m.Controller) -> dict:
        n = self.n
        info = self.infos[c.name]
        self.info, self.verb = info, None
        subs = [{"member": self.ident(s), "cmd": n.buffer_member(s, "cmd")} for s in info.subs]
        locals_ = [f"{self.ctype(v.type)} {self.ident(v.name)};" for v in c.locals.values()]
        init = [f"self->loc.{self.ident(n)} = {self.init_value(v)};" for n, v in c.locals.items()]
        for s in subs:
            init += [f"self->sent.{s['member']} = 0u;", f"self->send.{s['member']} = false;"]
        plans = [self.plan(c, plan) for plan in c.plans.values()]
        self.verb = None
        self.seq_decls.clear()
        pre, post = self.stmts(c.pre, 1), self.stmts(c.post, 1)
        pre = ["    " + d for d in self.take_temporaries(pre + post)] + pre
        ctx = {
            "name": c_comment(c.name), "doc": c_comment(c.doc), "stem": n.ctrl_stem(c.name), "type": self.ctrl_type(c.name),
            "init_fn": n.ctrl_part(c.name, "init"), "step_fn": n.ctrl_part(c.name, "step"),
            "ctrl_guard": n.ctrl_part(c.name, "H"), "budget_macro": n.ctrl_part(c.name, "BUDGET_NS"),
            "state_enum": n.ctrl_part(c.name, "state"), "rule_enum": n.ctrl_part(c.name, "rule"),
            "own": f"buf->{n.buffer_member(c.name, 'status')}", "cmd": f"buf->{n.buffer_member(c.name, 'cmd')}",
            "kind": "simulator" if c.simulator else "controller", "level": c.level, "where": self.where_text(c.span),
            "budget_ns": c.budget_ns,
            "subs": subs, "locals": locals_, "init": init,
            "states": [{"name": n.state(s), "number": i} for i, s in enumerate(info.states)],
            "rules": [{"name": n.rule(plan.verb, r.label), "number": info.rule_number[(plan.verb, r.index)]} for plan in c.plans.values() for r in plan.rules],
            "plans": plans,
            "pre": pre, "post": post,
            "tick": self.tick(),
            "gm_stamps": [self.ident(u.name) for u in c.writes] if keeps_gm_stamps(self.design) else [],
        }
        self.info = None
        return ctx

    def plan(self, c: m.Controller, plan: m.Plan) -> dict:
        self.verb = plan.verb
        layout = plan_layout(plan, self.impure)
        self.seq_decls.clear()
        body = self.layout(layout)
        return {
            "fn": self.n.plan_fn(plan.verb),
            "verb": c_comment(plan.verb),
            "verb_macro": self.n.verb(c.name, plan.verb),
            "where": self.where_text(plan.span),
            "continuous": plan.continuous,
            "needs_state": tests_state(layout),
            "body": self.take_temporaries(body) + body,
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
            return f"state == {self.n.state('new' if part.kind == 'new' else part.name or '')}"
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
        body.append(f"{own}.head.rule = {self.n.rule(plan_verb or '', r.label)};")
        body += self.stmts(r.jobs, 0)
        self.cse = saved
        nxt = r.next
        if nxt.kind == "named":
            target = self.n.state(nxt.name or "")
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
        doc = [f"/* {self.comment(r.doc)} */"] if r.doc else []
        return doc + [f"/* {r.label} ({self.where_text(r.span)}): {guard_text} | {r.state} -> {self.comment(r.next.span.text)} */", head] + ["    " + x for x in body] + ["    return;", "}"]


_HEAD_INIT = [
    ("echo_serial", "0u"),
    ("status", "RCS_UNINITIALIZED"),
    ("verb", "0"),
    ("state", "0"),
    ("rule", "0"),
    ("error_code", "0"),
    ("stamp", "0u"),
]
