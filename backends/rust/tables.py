"""The Main Program of one CPU: its description of the design for the host runtime.

The host (runtime/host/) is design-independent: it reads scenarios, writes
the trace and times the schedule through the tables below (`DesignDesc`)
and the `HostDesign` implementation, which moves `host::Value`s in and out
of the buffers.  Everything here is computed in Python and laid out by
templates/main.rs.j2.
"""

from __future__ import annotations

import re

from rcsc import model as m
from rcsc.backend import ordered_types
from rcsc.backends.rust.fmt import Array, Atom, Call, Cast, Node, Struct, Unary, arm, assign, fn_head, pad, tail
from rcsc.backends.rust.target import RustTarget, rust_string
from rcsc.types import BOOL, DURATION, EnumType, FloatType, IntType, RecordType, Type

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
        return Atom(f"&T_{t.name}", 11)

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
            return Call(f"{t.name}_value", [Atom(expr)])
        return Call(f"Value::{_VALUE[t.name]}", [Atom(expr)])

    def from_value(self, arg: Node, t: Type) -> Node:
        """The design's value of an `Option<&Value>` expression."""
        name = f"{t.name}_of"
        if name not in self.helpers:
            self.helpers[name] = []  # reserve (records refer to themselves through fields)
            self.helpers[name] = self._from_value_fn(t)
        return Call(name, [arg])

    def _from_value_fn(self, t: Type) -> list[str]:
        tg = self.tg
        if isinstance(t, EnumType):
            rt = tg.rtype(t)
            if len(t.members) <= 1:
                return fn_head(0, "", f"{t.name}_of", ["_v: Option<&Value>"], rt) + tail(Atom(f"{rt}::{tg.ident(t.members[0])}"), 1) + ["}"]
            lines = fn_head(0, "", f"{t.name}_of", ["v: Option<&Value>"], rt) + ["    match v {"]
            for i, x in enumerate(t.members[1:], 1):
                lines += arm(f"Some(Value::Enum({i}))", Atom(f"{rt}::{tg.ident(x)}"), 2)
            lines += arm("_", Atom(f"{rt}::{tg.ident(t.members[0])}"), 2) + ["    }", "}"]
            return lines
        if isinstance(t, RecordType):
            rt = tg.rtype(t)
            if not t.fields:  # a record without fields: nothing to read
                return fn_head(0, "", f"{t.name}_of", ["_v: Option<&Value>"], rt) + tail(Struct(rt, []), 1) + ["}"]
            lines = fn_head(0, "", f"{t.name}_of", ["v: Option<&Value>"], rt) + ["    let f: &[Value] = match v {",
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
        return [f"fn {t.name}_of(v: Option<&Value>) -> {rt} {{", "    match v {", f"        Some(Value::{v}(x)) => *x,",
                f"        _ => {_ZERO[t.name]},", "    }", "}"]  # short: the built-in types

    def record_value(self, t: RecordType) -> None:
        name = f"{t.name}_value"
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
        statics.append(assign(f"static T_{t.name}: TypeDesc", "=", Struct("TypeDesc", [("name", _s(t.name)), ("kind", kind)]), 0))
    types = [Atom(f"&T_{t.name}", 11) for t in ordered_types(d)]
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
        ]))
        names.append(assign(f"static {c.name}_STATES: [&str; {len(info.states)}]", "=", Array([_s(s) for s in info.states]), 0))
        names.append(assign(f"static {c.name}_RULES: [&str; {len(info.rules)}]", "=", Array([_s(r) for r in info.rules]), 0))
    statics.append(assign(f"static CTRLS: [CtrlDesc; {len(ctrl_descs)}]", "=", Array(ctrl_descs), 0))
    design = Struct("DesignDesc", [
        ("design", _s(d.name)), ("cpu", _s(cpu.name)), ("period_ns", Atom(tg.period_const(cpu.name))),
        ("gm", Atom("&GM", 11)), ("consts", Atom("&CONSTS", 11)), ("types", Atom("&TYPES", 11)), ("ctrls", Atom("&CTRLS", 11)),
        ("schedule", Unary("&", Array([Atom(str(index[c.name])) for c in schedule]))),
    ])
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
        lines = [f"{pad(3)}{index[c.name]} => {{", f"{pad(4)}let c = &mut self.buf.{c.name}_cmd;",
                 f"{pad(4)}c.head.serial = num::next_serial(c.head.serial);", f"{pad(4)}match verb {{"]
        for j, (vn, v) in enumerate(c.verbs.items()):
            sets = assign("c.head.verb", "=", Atom(f"{c.name}_VERB_{vn}"), 6)
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
        status += arm(str(index[c.name]), Call(f"status_{c.name}", [Unary("&", Atom(f"self.buf.{c.name}_status"))]), 3)
        fields = [mp.to_value(f"s.f.{tg.ident(n)}", v.type) for n, v in c.status_fields.items()]
        view = Struct("StatusView", [
            ("echo", Atom("s.head.echo_serial")),
            ("status", Atom("s.head.status")),
            ("verb", Atom("index(s.head.verb)")),
            ("state", Atom(f"name(&{c.name}_STATES, s.head.state)")),
            ("rule", Atom(f"name(&{c.name}_RULES, s.head.rule)")),
            ("error_code", Atom("s.head.error_code")),
            ("fields", Call("Vec::from", [Array(fields)]) if fields else Atom("Vec::new()")),
        ])
        views.append(fn_head(0, "", f"status_{c.name}", [f"s: &{c.name}_status"], "StatusView") + tail(view, 1) + ["}"])

    members = [{"name": _member(tg, c), "type": tg.tname(c.name), "module": tg.module(c)} for c in ctrls]
    ext_type = "ExternsImpl" if any(f.extern for f in d.functions.values()) else "NoExterns"
    uses_ext = any(tg.step_uses_ext.get(c.name) for c in ctrls)
    ext_init = "ExternsImpl::default()" if ext_type == "ExternsImpl" else "NoExterns"
    init = [("buf", Atom("Buffers::new()"))] + ([("ext", Atom(ext_init))] if uses_ext else []) + [(mb["name"], Atom(f"{mb['type']}::new()")) for mb in members]
    if deploy:
        init.append(("io", Atom("io::Io::default()")))
    main_body = assign("let mut main", "=", Struct("Main", init), 1)
    main_body += tail(Call("std::process::exit", [Call("host::run", [Unary("&mut ", Atom("main"))])]), 1)
    # The descriptor constructors the tables use, and the imports of what the
    # generated text uses (the template's own text uses the first four).
    text = "\n".join(x for group in (statics, views, [command]) for lines in group for x in lines)
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
    host_uses += [x for x in ("ConstDesc", "CtrlDesc", "FieldDesc", "GmDesc", "Kind", "TypeDesc", "VerbDesc") if re.search(rf"\b{x}\b", text)]
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
        "helpers": [mp.helpers[k] for k in sorted(mp.helpers) if mp.helpers[k]],
        "main_body": main_body,
    }


def _member(tg: RustTarget, c: m.Controller) -> str:
    """The field of `Main` that holds a controller (apart from `buf`, `ext` and `io`)."""
    name = tg.ident(c.name)
    return name + "_" if name in ("buf", "ext", "io") else name
