"""The Main Program of one CPU: its description of the design for the host runtime.

The host (runtime/host/) is design-independent: it reads scenarios, writes
the trace and times the schedule through the tables below (`DesignDesc`)
and the `HostDesign` implementation, which moves `host::Value`s in and out
of the buffers.  Everything here is computed in Python and laid out by
templates/main.rs.j2.
"""

from __future__ import annotations

import re

from rcsc.semantics import model as m
from rcsc.outputs.backend import array_types, cpu_gm, cpu_ticks, keeps_gm_stamps, ordered_types
from rcsc.outputs.events import interface_hash
from rcsc.backends.rust.fmt import Array, Atom, Call, Cast, Node, Struct, Unary, arm, assign, field_decl, fn_head, let, pad, tail
from rcsc.backends.rust.target import RustTarget, rust_string
from rcsc.semantics.types import BOOL, DURATION, I32, U32, ArrayType, EnumType, FloatType, IntType, RecordType, Type

_BUILTIN = {"bool": "host::BOOL", "i32": "host::I32", "i64": "host::I64", "u32": "host::U32", "f64": "host::F64", "duration": "host::DURATION"}
_VALUE = {"bool": "Bool", "i32": "I32", "i64": "I64", "u32": "U32", "f64": "F64", "duration": "Duration"}
_ZERO = {"bool": "false", "i32": "0", "i64": "0", "u32": "0", "f64": "0.0", "duration": "0"}


def _s(text: str) -> Atom:
    return Atom(rust_string(text))


class _Main:
    def __init__(self, tg: RustTarget) -> None:
        self.tg = tg
        self.helpers: dict[str, list[str]] = {}  # name -> lines, the value conversions used

    # ---- type descriptors -----------------------------------------------------------------

    def type_ref(self, t: Type) -> Atom:
        if t == BOOL or t == DURATION or isinstance(t, (IntType, FloatType)):
            return Atom("&" + _BUILTIN[t.name], 11)
        if isinstance(t, ArrayType):
            return Atom(f"&{self.array_desc(t)}", 11)
        return Atom(f"&{self.tg.n.type_desc(t.name)}", 11)

    def array_desc(self, t: ArrayType) -> str:
        return self.tg.n.join("T", self.tg.n.array_key(t))

    def field_desc(self, name: str, t: Type) -> Call:
        return Call("field_desc", [_s(name), self.type_ref(t)])

    def fields(self, items: list[tuple[str, Type]]) -> Unary:
        return Unary("&", Array([self.field_desc(n, t) for n, t in items]))

    # ---- values: host::Value <-> the design's types ----------------------------------------

    def to_value(self, expr: str, t: Type) -> Node:
        """The `Value` of a Rust expression of type `t`."""
        if isinstance(t, EnumType):
            return Call("Value::Enum", [Cast.make(Atom(expr), "usize")])
        if isinstance(t, RecordType):
            self.record_value(t)
            return Call(self.tg.n.helper(t.name, "value"), [Atom(expr)])
        if isinstance(t, ArrayType):
            self.array_value(t)
            return Call(self.tg.n.helper(self.tg.n.array_key(t), "value", builtin=True), [Atom(expr)])
        return Call(f"Value::{_VALUE[t.name]}", [Atom(expr)])

    def array_value(self, t: ArrayType) -> None:
        """`<ARRAY>__value`: an array as a `Value::Record` of its elements (the host prints it as `[...]`)."""
        name = self.tg.n.helper(self.tg.n.array_key(t), "value", builtin=True)
        if name in self.helpers:
            return
        self.helpers[name] = []
        elem = self.to_value("*x", t.elem).flat()
        self.helpers[name] = [f"fn {name}(a: {self.tg.rtype(t)}) -> Value {{",
                              f"    Value::Record(a.0.iter().map(|x| {elem}).collect())", "}"]

    def from_value(self, arg: Node, t: Type) -> Node:
        """The design's value of an `Option<&Value>` expression."""
        if isinstance(t, ArrayType):
            name = self.tg.n.helper(self.tg.n.array_key(t), "of", builtin=True)
        else:
            name = self.tg.n.helper(t.name, "of", builtin=not isinstance(t, (EnumType, RecordType)))
        if name not in self.helpers:
            self.helpers[name] = []  # reserve (records refer to themselves through fields)
            self.helpers[name] = self._from_value_fn(t)
        return Call(name, [arg])

    def _from_value_fn(self, t: Type) -> list[str]:
        tg = self.tg
        if isinstance(t, ArrayType):
            name = tg.n.helper(tg.n.array_key(t), "of", builtin=True)
            elem = self.from_value(Atom("f.get(k)"), t.elem).flat()
            return [f"fn {name}(v: Option<&Value>) -> {tg.rtype(t)} {{", "    let f: &[Value] = match v {",
                    "        Some(Value::Record(f)) => f,", "        _ => &[],", "    };", "    let mut a = num::Arr::default();",
                    "    for (k, x) in a.0.iter_mut().enumerate() {", f"        *x = {elem};", "    }", "    a", "}"]
        if isinstance(t, EnumType):
            rt = tg.rtype(t)
            of = tg.n.helper(t.name, "of")
            if len(t.members) <= 1:
                return fn_head(0, "", of, ["_v: Option<&Value>"], rt) + tail(Atom(f"{rt}::{tg.ident(t.members[0])}"), 1) + ["}"]
            lines = fn_head(0, "", of, ["v: Option<&Value>"], rt) + ["    match v {"]
            for i, x in enumerate(t.members[1:], 1):
                lines += arm(f"Some(Value::Enum({i}))", Atom(f"{rt}::{tg.ident(x)}"), 2)
            lines += arm("_", Atom(f"{rt}::{tg.ident(t.members[0])}"), 2) + ["    }", "}"]
            return lines
        if isinstance(t, RecordType):
            rt = tg.rtype(t)
            if not t.fields:  # a record without fields: nothing to read
                return fn_head(0, "", tg.n.helper(t.name, "of"), ["_v: Option<&Value>"], rt) + tail(Struct(rt, []), 1) + ["}"]
            lines = fn_head(0, "", tg.n.helper(t.name, "of"), ["v: Option<&Value>"], rt) + ["    let f: &[Value] = match v {",
                     "        Some(Value::Record(f)) => f,", "        _ => &[],", "    };"]
            fields = []
            for i, (n, ft) in enumerate(t.fields):
                get = "f.first()" if i == 0 else f"f.get({i})"
                fields.append((tg.ident(n), self.from_value(Atom(get), ft)))
            lines += tail(Struct(rt, fields), 1)
            lines.append("}")
            return lines
        v = _VALUE[t.name]
        rt = tg.rtype(t)
        return [f"fn {tg.n.helper(t.name, 'of', builtin=True)}(v: Option<&Value>) -> {rt} {{", "    match v {", f"        Some(Value::{v}(x)) => *x,",
                f"        _ => {_ZERO[t.name]},", "    }", "}"]  # short: the built-in types

    def record_value(self, t: RecordType) -> None:
        name = self.tg.n.helper(t.name, "value")
        if name in self.helpers:
            return
        self.helpers[name] = []
        tg = self.tg
        items = [self.to_value(f"r.{tg.ident(n)}", ft) for n, ft in t.fields]
        body = tail(Call("Value::Record", [Call("Vec::from", [Array(items)]) if items else Call("Vec::new")]), 1)
        self.helpers[name] = fn_head(0, "", name, [f"{'r' if items else '_r'}: {tg.rtype(t)}"], "Value") + body + ["}"]


def main_program(tg: RustTarget, cpu: m.Cpu, schedule: list[m.Controller], ctrls: list[m.Controller]) -> dict:
    d = tg.design
    mp = _Main(tg)
    deploy = tg.options.exclude_simulators
    index = {c.name: i for i, c in enumerate(ctrls)}

    # Type descriptors.
    statics: list[list[str]] = []
    for t in ordered_types(d):
        if isinstance(t, EnumType):
            kind = Call("Kind::Enum", [Unary("&", Array([_s(x) for x in t.members]))])
        else:
            assert isinstance(t, RecordType)
            kind = Call("Kind::Record", [mp.fields(list(t.fields))])
        statics.append(assign(f"static {tg.n.type_desc(t.name)}: TypeDesc", "=", Struct("TypeDesc", [("name", _s(t.name)), ("kind", kind)]), 0))
    described: set = set()  # the arrays the tables refer to (a local-only array has no descriptor)

    def reach(t) -> None:
        if isinstance(t, ArrayType):
            described.add(t)
            reach(t.elem)
        elif isinstance(t, RecordType):
            for _, ft in t.fields:
                reach(ft)

    for t in [k.type for k in d.consts.values()] + [v.type for v in d.gm.values()] + list(d.records.values()):
        reach(t)
    for c in ctrls:
        for v in c.status_fields.values():
            reach(v.type)
        for verb in c.verbs.values():
            for q in verb.params:
                reach(q.type)
    for t in [t for t in array_types(d) if t in described]:
        # An array: its element type and length (the host prints it as `[...]`).
        kind = Call("Kind::Array", [mp.type_ref(t.elem), Atom(str(t.size))])
        statics.append(assign(f"static {mp.array_desc(t)}: TypeDesc", "=", Struct("TypeDesc", [("name", _s(str(t))), ("kind", kind)]), 0))
    types = [Atom(f"&{tg.n.type_desc(t.name)}", 11) for t in ordered_types(d)]
    statics.append(assign(f"static TYPES: [&TypeDesc; {len(types)}]", "=", Array(types), 0))
    consts = [Call("const_desc", [_s(k.name), mp.type_ref(k.type)]) for k in d.consts.values()]
    statics.append(assign(f"static CONSTS: [ConstDesc; {len(consts)}]", "=", Array(consts), 0))
    gm = [Call("gm_desc", [_s(n), mp.type_ref(v.type), Atom("true" if v.from_env else "false")]) for n, v in d.gm.items()]
    statics.append(assign(f"static GM: [GmDesc; {len(gm)}]", "=", Array(gm), 0))

    ctrl_descs = []
    names: list[list[str]] = []
    for c in ctrls:
        info = tg.infos[c.name]
        verbs = [Call("verb_desc", [_s(vn), mp.fields([(q.name, q.type) for q in v.params])]) for vn, v in c.verbs.items()]
        ctrl_descs.append(Struct("CtrlDesc", [
            ("name", _s(c.name)),
            ("top", Atom("true" if d.supervisor_of(c.name) is None else "false")),
            ("simulator", Atom("true" if c.simulator else "false")),
            ("budget_ns", Atom(str(c.budget_ns))),
            ("verbs", Unary("&", Array(verbs))),
            ("fields", mp.fields([(n, v.type) for n, v in c.status_fields.items()])),
            ("extra_statuses", Unary("&", Array([Atom(f"({rust_string(s)}, {n})") for s, n in c.statuses.items()]))),
            ("divider", Atom(str(c.divider))),
        ]))
        names.append(assign(f"static {tg.n.ctrl_part(c.name, 'STATES')}: [&str; {len(info.states)}]", "=", Array([_s(s) for s in info.states]), 0))
        names.append(assign(f"static {tg.n.ctrl_part(c.name, 'RULES')}: [&str; {len(info.rules)}]", "=", Array([_s(r) for r in info.rules]), 0))
    statics.append(assign(f"static CTRLS: [CtrlDesc; {len(ctrl_descs)}]", "=", Array(ctrl_descs), 0))
    design = Struct("DesignDesc", [
        ("design", _s(d.name)), ("cpu", _s(cpu.name)), ("period_ns", Atom(tg.period_const(cpu.name))),
        ("gm", Atom("&GM", 11)), ("consts", Atom("&CONSTS", 11)), ("types", Atom("&TYPES", 11)), ("ctrls", Atom("&CTRLS", 11)),
        ("schedule", Unary("&", Array([Atom(str(index[c.name])) for c in schedule]))),
        ("multi", Atom("Some(&MULTI)" if len(d.cpus) > 1 else "None")),
        ("events_hash", _s(interface_hash(d, ctrls))),
    ])
    if len(d.cpus) > 1:
        statics += _multi_statics(tg, cpu, ctrls)
    statics.append(assign("static DESIGN: DesignDesc", "=", design, 0))

    # HostDesign.
    constant = []
    for i, k in enumerate(d.consts.values()):
        constant += arm(str(i), mp.to_value(tg.vname(k.name), k.type), 3)
    step = []
    for c in ctrls:
        if c not in schedule:
            continue
        args = [Unary("&mut ", Atom(f"self.{_member(tg, c)}")), Unary("&mut ", Atom("self.buf"))]
        if tg.step_uses_ext.get(c.name):
            args.append(Unary("&", Atom("self.ext")))
        args.append(Atom("cycle"))
        step += arm(str(index[c.name]), Call(f"{tg.tname(c.name)}::step", args), 3)
    command = []
    for c in ctrls:
        if not c.verbs or d.supervisor_of(c.name) is not None:
            continue  # operator commands go to the top of the hierarchy only
        lines = [f"{pad(3)}{index[c.name]} => {{", f"{pad(4)}let c = &mut self.buf.{tg.n.buffer_member(c.name, 'cmd')};",
                 f"{pad(4)}c.head.serial = num::next_serial(c.head.serial);", f"{pad(4)}match verb {{"]
        for j, (vn, v) in enumerate(c.verbs.items()):
            sets = assign("c.head.verb", "=", Atom(tg.n.verb(c.name, vn)), 6)
            for k, q in enumerate(v.params):
                get = "args.first()" if k == 0 else f"args.get({k})"
                sets += assign(f"c.args.{tg.ident(vn)}.{tg.ident(q.name)}", "=", mp.from_value(Atom(get), q.type), 6)
            if len(sets) == 1:
                lines += arm(str(j), Atom(sets[0].strip().rstrip(";")), 5)
            else:
                lines += [f"{pad(5)}{j} => {{"] + sets + [f"{pad(5)}}}"]
        lines += [f"{pad(5)}_ => {{}}", f"{pad(4)}}}", f"{pad(3)}}}"]
        command += lines
    inputs = []
    gm_values = []
    for i, (n, v) in enumerate(d.gm.items()):
        inputs += [f"{pad(3)}{i} => {{"] + assign(f"self.buf.gm.{tg.ident(n)}", "=", mp.from_value(Call("Some", [Atom("value")]), v.type), 4) + [f"{pad(3)}}}"]
        gm_values += arm(str(i), mp.to_value(f"self.buf.gm.{tg.ident(n)}", v.type), 3)
    status = []
    views = []
    for c in ctrls:
        status += arm(str(index[c.name]), Call(tg.n.status_view(c.name), [Unary("&", Atom(f"self.buf.{tg.n.buffer_member(c.name, 'status')}"))]), 3)
        fields = [mp.to_value(f"s.f.{tg.ident(n)}", v.type) for n, v in c.status_fields.items()]
        view = Struct("StatusView", [
            ("echo", Atom("s.head.echo_serial")),
            ("status", Atom("s.head.status")),
            ("verb", Atom("index(s.head.verb)")),
            ("state", Call("name", [Unary("&", Atom(tg.n.ctrl_part(c.name, "STATES"))), Atom("s.head.state")])),
            ("rule", Call("name", [Unary("&", Atom(tg.n.ctrl_part(c.name, "RULES"))), Atom("s.head.rule")])),
            ("error_code", Atom("s.head.error_code")),
            ("fields", Call("Vec::from", [Array(fields)]) if fields else Atom("Vec::new()")),
        ])
        views.append(fn_head(0, "", tg.n.status_view(c.name), [f"s: &{tg.n.ctrl_part(c.name, 'status')}"], "StatusView") + tail(view, 1) + ["}"])

    methods = _stamp_and_crossing_methods(mp, tg, ctrls)
    methods += _perf_methods(tg, ctrls, index)

    # The controllers this CPU steps (the others' buffers are still here: copies).
    members = [{"name": _member(tg, c), "type": tg.tname(c.name), "module": tg.module(c)} for c in ctrls if c in schedule]
    for mb in members:
        mb["decl"] = field_decl(f"{mb['name']}: {mb['type']}", 1)
    ext_type = "ExternsImpl" if any(f.extern for f in d.functions.values()) else "NoExterns"
    # Only the controllers this CPU steps call externs through `self.ext`.
    uses_ext = any(tg.step_uses_ext.get(c.name) for c in ctrls if c in schedule)
    ext_init = "ExternsImpl::default()" if ext_type == "ExternsImpl" else "NoExterns"
    init = [("buf", Atom("Buffers::new()"))] + ([("ext", Atom(ext_init))] if uses_ext else []) + [(mb["name"], Atom(f"{mb['type']}::new()")) for mb in members]
    if deploy:
        init.append(("io", Atom("io::Io::default()")))
    main_body = assign("let mut main", "=", Struct("Main", init), 1)
    main_body += tail(Call("std::process::exit", [Call("host::run", [Unary("&mut ", Atom("main"))])]), 1)
    # The descriptor constructors the tables use, and the imports of what the
    # generated text uses (the template's own text uses the first four).
    text = "\n".join(x for group in (statics, views, [command], methods, list(mp.helpers.values())) for lines in group for x in lines)
    ctors = []
    for fn, ty, params, fields in (
        ("field_desc", "FieldDesc", "name: &'static str, ty: &'static TypeDesc", "name, ty"),
        ("const_desc", "ConstDesc", "name: &'static str, ty: &'static TypeDesc", "name, ty"),
        ("gm_desc", "GmDesc", "name: &'static str, ty: &'static TypeDesc, from_env: bool", "name, ty, from_env"),
        ("verb_desc", "VerbDesc", "name: &'static str, params: &'static [FieldDesc]", "name, params"),
    ):
        if re.search(rf"\b{fn}\(", text):
            ctors.append(fn_head(0, "const ", fn, params.split(", "), ty) + [f"    {ty} {{ {fields} }}", "}"])
    text += "\n".join(x for c in ctors for x in c)
    host_uses = ["DesignDesc", "HostDesign", "StatusView", "Value"]
    host_uses += [x for x in ("ConstDesc", "CrossingDesc", "CtrlDesc", "FieldDesc", "GmDesc", "Kind", "MultiDesc", "TypeDesc", "VerbDesc") if re.search(rf"\b{x}\b", text)]
    crate = tg.crate
    uses = [f"use host::{x};" for x in host_uses]
    uses += [f"use {crate}::{mb['module']}::{mb['type']};" for mb in members]
    if "num::" in text:
        uses.append(f"use {crate}::num;")
    uses.append(f"use {crate}::types::*;")
    if uses_ext:
        uses.append(f"use {crate}::{'externs_impl::ExternsImpl' if ext_type == 'ExternsImpl' else 'NoExterns'};")
    from rcsc.backends.rust import _rustfmt_use_order

    return {
        "design": d.name, "cpu": cpu.name, "deploy": deploy,
        "uses": _rustfmt_use_order(uses),
        "statics": statics, "names": names, "ctors": ctors,
        "members": members, "ext_type": ext_type if uses_ext else None,
        "constant": constant, "step": step, "command": command, "command_args": any("args." in x for x in command), "inputs": inputs, "gm_values": gm_values, "status": status,
        "views": views,
        "methods": methods,
        "helpers": [mp.helpers[k] for k in sorted(mp.helpers) if mp.helpers[k]],
        "main_body": main_body,
    }


def _member(tg: RustTarget, c: m.Controller) -> str:
    """The field of `Main` that holds a controller (apart from `buf`, `ext` and `io`)."""
    return tg.n.main_member(c.name)



def _multi_statics(tg: RustTarget, cpu: m.Cpu, ctrls: list[m.Controller]) -> list[list[str]]:
    """What one CPU of a multi-CPU design knows of the others: names, heartbeats in
    base ticks, the buffers that cross (writer, readers) and what its trace shows."""
    d = tg.design
    names = list(d.cpus)
    rows = [Struct("CrossingDesc", [("writer", Atom(str(names.index(x.writer_cpu)))),
                                    ("readers", Atom(str(sum(1 << names.index(r) for r in x.reader_cpus))))]) for x in d.crossings]
    gm_names = list(d.gm)
    multi = Struct("MultiDesc", [
        ("me", Atom(str(names.index(cpu.name)))),
        ("cpu_names", Unary("&", Array([_s(n) for n in names]))),
        ("ticks", Unary("&", Array([Atom(str(cpu_ticks(d, n))) for n in names]))),
        ("base_tick_ns", Atom(str(d.base_tick_ns))),
        ("crossings", Atom("&CROSSINGS", 11)),
        ("gm_here", Unary("&", Array([Atom(str(gm_names.index(n))) for n in cpu_gm(d, cpu.name)]))),
        ("ctrls_here", Unary("&", Array([Atom(str(i)) for i, c in enumerate(ctrls) if c.cpu == cpu.name]))),
    ])
    return [assign(f"static CROSSINGS: [CrossingDesc; {len(rows)}]", "=", Array(rows), 0), assign("static MULTI: MultiDesc", "=", multi, 0)]


def _stamp_and_crossing_methods(mp: _Main, tg: RustTarget, ctrls: list[m.Controller]) -> list[list[str]]:
    """HostDesign's `set_gm_stamp` (when the design reads ages of Global Memory)
    and, for several CPUs, `crossing` / `set_crossing`: each crossing buffer as a
    `Value` and its stamp, and back."""
    d = tg.design
    out: list[list[str]] = []
    kept = keeps_gm_stamps(d)
    gm_index = {n: i for i, n in enumerate(d.gm)}
    if kept:
        body = [f"{pad(1)}fn set_gm_stamp(&mut self, gm: usize, tick: u64) {{", f"{pad(2)}match gm {{"]
        for n, i in gm_index.items():
            body += arm(str(i), Atom(f"self.buf.gm_stamp.{tg.ident(n)} = tick"), 3)
        body += [f"{pad(3)}_ => {{}}", f"{pad(2)}}}", f"{pad(1)}}}"]
        out.append(body)
    if len(d.cpus) <= 1 or not d.crossings:
        return out  # nothing crosses between CPUs: the trait's defaults (no match on an index)
    get = [f"{pad(1)}fn crossing(&self, i: usize) -> (Value, u64) {{", f"{pad(2)}match i {{"]
    put: list[str] = []
    uses_stamp = False
    for i, x in enumerate(d.crossings):
        if x.kind == "gm":
            v = d.gm[x.name]
            member = f"self.buf.gm.{tg.ident(x.name)}"
            stamp = f"self.buf.gm_stamp.{tg.ident(x.name)}" if kept else "0"
            get += arm(str(i), Call("", [mp.to_value(member, v.type), Atom(stamp)]), 3)
            sets = assign(member, "=", mp.from_value(Call("Some", [Atom("value")]), v.type), 4)
            if kept:
                sets += assign(stamp, "=", Atom("stamp"), 4)
                uses_stamp = True
        elif x.kind == "cmd":
            _buffer_helpers(mp, tg, d.controllers[x.name], "cmd")
            cmd = f"self.buf.{tg.n.buffer_member(x.name, 'cmd')}"
            get += arm(str(i), Call("", [Call(_helper(tg, x.name, "cmd", "value"), [Unary("&", Atom(cmd))]), Atom("0")]), 3)
            sets = expr_stmt_lines(Call(_helper(tg, x.name, "cmd", "set"), [Unary("&mut ", Atom(cmd)), Atom("value")]), 4)
        else:
            _buffer_helpers(mp, tg, d.controllers[x.name], "status")
            status = f"self.buf.{tg.n.buffer_member(x.name, 'status')}"
            get += arm(str(i), Call("", [Call(_helper(tg, x.name, "status", "value"), [Unary("&", Atom(status))]), Atom(f"{status}.head.stamp")]), 3)
            sets = expr_stmt_lines(Call(_helper(tg, x.name, "status", "set"), [Unary("&mut ", Atom(status)), Atom("value")]), 4)
            sets += assign(f"{status}.head.stamp", "=", Atom("stamp"), 4)
            uses_stamp = True
        if len(sets) == 1:
            put += arm(str(i), Atom(sets[0].strip().rstrip(";")), 3)
        else:
            put += [f"{pad(3)}{i} => {{"] + sets + [f"{pad(3)}}}"]
    get += arm("_", Call("", [Atom("Value::Bool(false)"), Atom("0")]), 3) + [f"{pad(2)}}}", f"{pad(1)}}}"]
    stamp_param = "stamp" if uses_stamp else "_stamp"
    put = fn_head(1, "", "set_crossing", ["&mut self", "i: usize", "value: &Value", f"{stamp_param}: u64"], None) + [f"{pad(2)}match i {{"] + put
    put += [f"{pad(3)}_ => {{}}", f"{pad(2)}}}", f"{pad(1)}}}"]
    return out + [get, put]


def _perf_methods(tg: RustTarget, ctrls: list[m.Controller], index: dict[str, int]) -> list[list[str]]:
    """HostDesign's `head`, `set_rule` and `names`: what the Main Program reads
    of each status head to keep the performance per controller and per
    (state, rule) (host/perf.rs)."""
    head = [f"{pad(1)}fn head(&self, ctrl: usize) -> (u32, i32, i32, i32) {{", f"{pad(2)}let h = match ctrl {{"]
    put = [f"{pad(1)}fn set_rule(&mut self, ctrl: usize, rule: i32) {{", f"{pad(2)}let h = match ctrl {{"]
    names = fn_head(1, "", "names", ["&self", "ctrl: usize"], "(&'static [&'static str], &'static [&'static str])")
    names.append(f"{pad(2)}match ctrl {{")
    for c in ctrls:
        status = f"self.buf.{tg.n.buffer_member(c.name, 'status')}.head"
        head += arm(str(index[c.name]), Unary("&", Atom(status)), 3)
        put += arm(str(index[c.name]), Unary("&mut ", Atom(status)), 3)
        names += arm(str(index[c.name]), Call("", [Atom(f"&{tg.n.ctrl_part(c.name, 'STATES')}"), Atom(f"&{tg.n.ctrl_part(c.name, 'RULES')}")]), 3)
    head += arm("_", Atom("return (0, 0, 0, 0)"), 3) + [f"{pad(2)}}};", f"{pad(2)}(h.echo_serial, h.verb, h.state, h.rule)", f"{pad(1)}}}"]
    put += arm("_", Atom("return"), 3) + [f"{pad(2)}}};", f"{pad(2)}h.rule = rule;", f"{pad(1)}}}"]
    names += arm("_", Atom("(&[], &[])"), 3) + [f"{pad(2)}}}", f"{pad(1)}}}"]
    return [head, put, names]


def expr_stmt_lines(e: Node, indent: int) -> list[str]:
    from rcsc.backends.rust.fmt import expr_stmt

    return expr_stmt(e, indent)


_HEAD = [("echo_serial", U32), ("status", I32), ("verb", I32), ("state", I32), ("rule", I32), ("error_code", I32)]


def _buffer_helpers(mp: _Main, tg: RustTarget, c: m.Controller, kind: str) -> None:
    """`<C>_cmd_value` / `set_<C>_cmd` or `<C>_status_value` / `set_<C>_status`:
    a command or status buffer (without its stamp) as a `Value` record and back."""
    name = _helper(tg, c.name, kind, "value")
    if name in mp.helpers:
        return
    if "record" not in mp.helpers:
        mp.helpers["record"] = fn_head(0, "", "record", ["v: Option<&Value>"], "&[Value]") + [
            "    match v {", "        Some(Value::Record(f)) => f,", "        _ => &[],", "    }", "}"]
    var = "c" if kind == "cmd" else "s"
    get = (lambda k: "f.first()" if k == 0 else f"f.get({k})")
    if kind == "cmd":
        head = [("serial", U32), ("verb", I32)]
        groups = [(f"args.{tg.ident(vn)}", [(q.name, q.type) for q in v.params]) for vn, v in c.verbs.items() if v.params]
    else:
        head = _HEAD
        groups = [("f", [(n, v.type) for n, v in c.status_fields.items()])]
    items: list[Node] = [mp.to_value(f"{var}.head.{h}", t) for h, t in head]
    sets = let("f", Call("record", [Call("Some", [Atom("v")])]), 1)
    sets += [x for k, (h, t) in enumerate(head) for x in assign(f"{var}.head.{h}", "=", mp.from_value(Atom(get(k)), t), 1)]
    for j, (path, fields) in enumerate(groups):
        values = [mp.to_value(f"{var}.{path}.{tg.ident(n)}", t) for n, t in fields]
        items.append(Call("Value::Record", [Call("Vec::from", [Array(values)])]) if values else Atom("Value::Record(Vec::new())"))
        if fields:
            a = f"a{j}"
            sets += let(a, Call("record", [Atom(get(len(head) + j))]), 1)
            sets += [x for k, (n, t) in enumerate(fields) for x in assign(f"{var}.{path}.{tg.ident(n)}", "=", mp.from_value(Atom(f"{a}.first()" if k == 0 else f"{a}.get({k})"), t), 1)]
    ty = tg.n.ctrl_part(c.name, kind)
    setter = _helper(tg, c.name, kind, "set")
    mp.helpers[name] = fn_head(0, "", name, [f"{var}: &{ty}"], "Value") + tail(Call("Value::Record", [Call("Vec::from", [Array(items)])]), 1) + ["}"]
    mp.helpers[setter] = fn_head(0, "", setter, [f"{var}: &mut {ty}", "v: &Value"], None) + sets + ["}"]


def _helper(tg: RustTarget, ctrl: str, kind: str, tag: str) -> str:
    """`<C>__cmd__value` / `<C>__cmd__set` (and for `status`): a buffer as a `Value`
    and back; `__` joins make them distinct from every design name."""
    return tg.n.join(tg.n.frag(ctrl), kind, tag)
