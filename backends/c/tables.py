"""The Main Program's description of its design: the tables of rcs_runtime.h.

The runtime is design-independent: it reads scenarios, writes the trace and
times the schedule through these tables (types, Global Memory, constants,
controllers).  Everything here is data, computed in Python and laid out by
templates/main.c.j2.
"""

from __future__ import annotations

import re

from rcsc.semantics import model as m
from rcsc.outputs.backend import cpu_gm, cpu_ticks, keeps_gm_stamps, ordered_types, types_with_arrays
from rcsc.outputs.events import interface_hash
from rcsc.semantics.types import BOOL, DURATION, ArrayType, EnumType, FloatType, IntType, RecordType, Type

from rcsc.backends.c.target import CTarget, c_string

_BUILTIN = {"bool": "rcs_type_bool", "i32": "rcs_type_i32", "i64": "rcs_type_i64", "u32": "rcs_type_u32", "f64": "rcs_type_f64"}


def type_ref(tg: CTarget, t: Type) -> str:
    """The address of a type's descriptor."""
    if t == BOOL or isinstance(t, (IntType, FloatType)):
        return "&" + _BUILTIN[t.name]
    if t == DURATION:
        return "&rcs_type_duration"
    if isinstance(t, ArrayType):
        return "&" + tg.n.local("type", tg.n.array_type(t))
    return "&" + tg.n.local("type", t.name)


def _fields(tg: CTarget, struct: str, items: list[tuple[str, Type]]) -> list[str]:
    return [f"{{{c_string(n)}, offsetof({struct}, {tg.ident(n)}), {type_ref(tg, t)}}}," for n, t in items]


def main_tables(tg: CTarget, cpu: m.Cpu, schedule: list[m.Controller], ctrls: list[m.Controller], buf: str = "buf") -> dict:
    """The tables of one CPU's Main Program; `buf` names the buffers object they point into
    (another target's Main Program may own it under another name)."""
    d, n = tg.design, tg.n
    types = []
    for t in types_with_arrays(d):
        if isinstance(t, ArrayType):
            # An array: one row per element (name "", offset of v[i]), so the
            # runtime walks it as it walks a record and prints it as `[...]`.
            at = tg.ctype(t)
            fields = n.local("fields", at)
            rows = [f"{{\"\", offsetof({at}, v) + {i}u * sizeof(((const {at} *)0)->v[0]), {type_ref(tg, t.elem)}}}," for i in range(t.size)]
            types.append({
                "arrays": [f"static const rcs_field {fields}[] = {{"] + ["    " + r for r in rows] + ["};"],
                "decl": f"static const rcs_type {type_ref(tg, t)[1:]} = {{RCS_T_ARRAY, {c_string(str(t))}, NULL, 0u, {fields}, {t.size}u}};",
            })
            continue
        desc = n.local("type", t.name)
        if isinstance(t, EnumType):
            members = n.local("members", t.name)
            types.append({
                "arrays": [f"static const char *const {members}[] = {{{', '.join(c_string(x) for x in t.members)}}};"],
                "decl": f"static const rcs_type {desc} = {{RCS_T_ENUM, {c_string(t.name)}, {members}, {len(t.members)}u, NULL, 0u}};",
            })
        else:
            assert isinstance(t, RecordType)
            rows = _fields(tg, tg.ctype(t), list(t.fields))
            fields = n.local("fields", t.name)
            # A record without fields has no field table (C has no empty array).
            types.append({
                "arrays": [f"static const rcs_field {fields}[] = {{"] + ["    " + r for r in rows] + ["};"] if rows else [],
                "decl": f"static const rcs_type {desc} = {{RCS_T_RECORD, {c_string(t.name)}, NULL, 0u, {fields if rows else 'NULL'}, {len(t.fields)}u}};",
            })
    type_list = [f"&{n.local('type', t.name)}," for t in ordered_types(d)]

    consts = []
    for k in d.consts.values():
        name = n.local("const", k.name)
        consts.append({
            "decl": f"static const {tg.ctype(k.type)} {name} = {tg.literal(k.value, k.type, braces=True)};",
            "row": f"{{{c_string(k.name)}, {type_ref(tg, k.type)}, &{name}}},",
        })

    gm_rows = _fields(tg, n.fixed("gm"), [(x, v.type) for x, v in d.gm.items()])
    gm_env = ", ".join("1u" if v.from_env else "0u" for v in d.gm.values())

    index = {c.name: i for i, c in enumerate(ctrls)}
    ctrl_tables = []
    for c in ctrls:
        info = tg.infos[c.name]
        cmd, status = n.buffer_member(c.name, "cmd"), n.buffer_member(c.name, "status")
        verbs, status_fields = n.local("verbs", c.name), n.local("status_fields", c.name)
        states, rules, statuses = n.local("states", c.name), n.local("rules", c.name), n.local("statuses", c.name)
        arrays: list[str] = []
        verb_rows = []
        for vname, v in c.verbs.items():
            if v.params:
                params = n.local("params", c.name, vname)
                arrays.append(f"static const rcs_field {params}[] = {{")
                arrays += ["    " + r for r in _fields(tg, n.verb_args(c.name, vname), [(q.name, q.type) for q in v.params])]
                arrays.append("};")
                verb_rows.append(f"{{{c_string(vname)}, {params}, {len(v.params)}u}},")
            else:
                verb_rows.append(f"{{{c_string(vname)}, NULL, 0u}},")
        if verb_rows:
            arrays.append(f"static const rcs_verb {verbs}[] = {{")
            arrays += ["    " + r for r in verb_rows]
            arrays.append("};")
        if c.status_fields:
            arrays.append(f"static const rcs_field {status_fields}[] = {{")
            arrays += ["    " + r for r in _fields(tg, n.ctrl_part(c.name, "fields"), [(x, v.type) for x, v in c.status_fields.items()])]
            arrays.append("};")
        arrays.append(f"static const char *const {states}[] = {{{', '.join(c_string(s) for s in info.states)}}};")
        arrays.append(f"static const char *const {rules}[] = {{{', '.join(c_string(r) for r in info.rules)}}};")
        if c.statuses:
            arrays.append(f"static const rcs_status_name {statuses}[] = {{{', '.join(f'{{{c_string(s)}, {k}}}' for s, k in c.statuses.items())}}};")
        top = d.supervisor_of(c.name) is None
        has_args = any(v.params for v in c.verbs.values())
        row = [
            c_string(c.name),
            "1" if top else "0",
            "1" if c.simulator else "0",
            f"INT64_C({c.budget_ns})",
            n.local("step", c.name),
            f"&{buf}.{cmd}.head",
            f"&{buf}.{cmd}.args" if has_args else "NULL",
            f"sizeof {buf}.{cmd}.args" if has_args else "0u",
            verbs if verb_rows else "NULL",
            f"{len(verb_rows)}u",
            f"&{buf}.{status}.head",
            f"&{buf}.{status}.f" if c.status_fields else "NULL",
            status_fields if c.status_fields else "NULL",
            f"{len(c.status_fields)}u",
            states,
            f"{len(info.states)}u",
            rules,
            f"{len(info.rules)}u",
            statuses if c.statuses else "NULL",
            f"{len(c.statuses)}u",
            f"{c.divider}u",
        ]
        ctrl_tables.append({
            "type": tg.ctrl_type(c.name), "instance": n.local("ctrl", c.name), "step": n.local("step", c.name),
            "init_fn": n.ctrl_part(c.name, "init"), "step_fn": n.ctrl_part(c.name, "step"), "arrays": arrays,
            "row": "{" + ", ".join(row) + "},",
        })
    gm_stamps = [f"offsetof({tg.n.fixed('buffers')}, gm_stamp.{tg.ident(n)})," for n in d.gm] if keeps_gm_stamps(d) else []
    out = {
        "events_hash": c_string(interface_hash(d, ctrls)),
        "multi": multi_tables(tg, cpu, ctrls, buf) if len(d.cpus) > 1 else None,
        "gm_stamps": gm_stamps,
        "period": tg.period_macro(cpu.name),
        "types": types,
        "type_list": type_list,
        "consts": consts,
        "gm_rows": gm_rows,
        "gm_env": gm_env,
        "ctrl_tables": ctrl_tables,
        "schedule": ", ".join(f"{index[c.name]}u" for c in schedule),
        "n_schedule": len(schedule),
    }
    # An array type that only a local, a parameter of a function or an
    # expression has is in no row: its descriptor would be an unused static
    # (-Wunused-const-variable).  Drop those, the ones only they use included.
    arrays = {t["decl"].split(" = ")[0].split()[-1]: t for t in types if "RCS_T_ARRAY" in t["decl"]}
    while True:
        rest = repr({k: v for k, v in out.items() if k != "types"}) + repr([t for t in types if t["decl"] not in {a["decl"] for a in arrays.values()}])
        rest += repr([a["arrays"] for a in arrays.values()])
        unused = [name for name in arrays if not re.search(rf"&{name}\b", rest)]
        if not unused:
            break
        for name in unused:
            types.remove(arrays.pop(name))
    return out


def multi_tables(tg: CTarget, cpu: m.Cpu, ctrls: list[m.Controller], buf: str = "buf") -> dict:
    """What one CPU of a multi-CPU design knows of the others: names, heartbeats
    in base ticks, the buffers that cross (writer, readers, where they are in
    the buffers struct and where their stamp is), and what its trace shows."""
    d, n = tg.design, tg.n
    buffers = n.fixed("buffers")
    names = list(d.cpus)
    kept = keeps_gm_stamps(d)
    rows = []
    for x in d.crossings:
        readers = sum(1 << names.index(r) for r in x.reader_cpus)
        if x.kind == "gm":
            member, stamp = f"gm.{tg.ident(x.name)}", f"offsetof({buffers}, gm_stamp.{tg.ident(x.name)})" if kept else "RCS_NO_STAMP"
        elif x.kind == "cmd":
            member, stamp = n.buffer_member(x.name, "cmd"), "RCS_NO_STAMP"
        else:
            member = n.buffer_member(x.name, "status")
            stamp = f"offsetof({buffers}, {member}.head.stamp)"
        rows.append(f"{{{names.index(x.writer_cpu)}u, UINT64_C({hex(readers)}), offsetof({buffers}, {member}), sizeof {buf}.{member}, {stamp}}}, /* {x.kind} {tg.comment(x.name)} */")
    gm_names = list(d.gm)
    # No crossing buffer, no encoding table (an empty initializer is not C).
    wire = wire_tables(tg) if tg.options.transport == "dds" and d.crossings else None
    return {
        "wire": wire,
        "names": ", ".join(c_string(n) for n in names),
        "ticks": ", ".join(f"{cpu_ticks(d, n)}u" for n in names),
        "crossings": rows,
        "gm_here": ", ".join(f"{gm_names.index(n)}u" for n in cpu_gm(d, cpu.name)),
        "ctrls_here": ", ".join(f"{i}u" for i, c in enumerate(ctrls) if c.cpu == cpu.name),
        "row": [
            f"{names.index(cpu.name)}u",
            f"{len(names)}u",
            "cpu_names",
            "cpu_ticks",
            f"INT64_C({d.base_tick_ns})",
            "crossings" if rows else "NULL",
            f"{len(rows)}u",
            "gm_here" if cpu_gm(d, cpu.name) else "NULL",
            f"{len(cpu_gm(d, cpu.name))}u",
            "ctrls_here" if any(c.cpu == cpu.name for c in ctrls) else "NULL",
            f"{sum(1 for c in ctrls if c.cpu == cpu.name)}u",
            "&rcs_dds_transport" if tg.options.transport == "dds" else "&rcs_shm_transport",
            "wire" if wire else "NULL",
        ],
    }


# The wire kind of each scalar type (rcs_runtime.h, RCS_W_*).
_WIRE_KIND = {"bool": "RCS_W_BOOL", "i32": "RCS_W_I32", "u32": "RCS_W_U32", "i64": "RCS_W_I64", "f64": "RCS_W_F64", "duration": "RCS_W_I64"}


def _leaves(tg: CTarget, path: str, t) -> list[tuple[str, str]]:
    """The scalars of a value at `path` in the buffers struct, in the order of
    the canonical encoding: a record's fields one after the other, an enum as
    its member index."""
    if isinstance(t, EnumType):
        return [(path, "RCS_W_ENUM")]
    if isinstance(t, RecordType):
        return [leaf for n, ft in t.fields for leaf in _leaves(tg, f"{path}.{tg.ident(n)}", ft)]
    if isinstance(t, ArrayType):
        return [leaf for i in range(t.size) for leaf in _leaves(tg, f"{path}.v[{i}]", t.elem)]
    return [(path, _WIRE_KIND[t.name])]


def wire_tables(tg: CTarget) -> dict:
    """The canonical encoding of each crossing buffer, for the DDS transport:
    the same bytes a Rust CPU sends (little-endian scalars, an enum as its
    index in 8 bytes, records flattened; a command buffer's head then every
    verb's arguments; a status buffer's head then its fields), so C and Rust
    CPUs of one design interoperate.  A command's arguments are read back
    only for the verb the command carries (they share a union in C)."""
    d, n = tg.design, tg.n
    buffers = n.fixed("buffers")
    arrays, rows = [], []
    for i, x in enumerate(d.crossings):
        leaves: list[tuple[str, str, str]] = []  # path, kind, guard (verb number or "")
        if x.kind == "gm":
            leaves = [(p, k, "") for p, k in _leaves(tg, f"gm.{tg.ident(x.name)}", d.gm[x.name].type)]
        elif x.kind == "cmd":
            member = n.buffer_member(x.name, "cmd")
            c = d.controllers[x.name]
            leaves = [(f"{member}.head.serial", "RCS_W_U32", ""), (f"{member}.head.verb", "RCS_W_I32", "")]
            for number, (vname, v) in enumerate(c.verbs.items(), 1):
                for q in v.params:
                    leaves += [(p, k, str(number)) for p, k in _leaves(tg, f"{member}.args.{tg.ident(vname)}.{tg.ident(q.name)}", q.type)]
        else:
            member = n.buffer_member(x.name, "status")
            c = d.controllers[x.name]
            leaves = [(f"{member}.head.{h}", "RCS_W_U32" if h == "echo_serial" else "RCS_W_I32", "") for h in ("echo_serial", "status", "verb", "state", "rule", "error_code")]
            leaves += [(p, k, "") for fname, v in c.status_fields.items() for p, k in _leaves(tg, f"{member}.f.{tg.ident(fname)}", v.type)]
        name = f"wire_{i}"
        cmd_verb = f"offsetof({buffers}, {n.buffer_member(x.name, 'cmd')}.head.verb)" if x.kind == "cmd" else ""
        if leaves:
            arrays.append(f"static const rcs_leaf {name}[] = {{")
            for p, k, guard in leaves:
                g = f"{cmd_verb}, {guard}" if guard else "RCS_NO_STAMP, 0"
                arrays.append(f"    {{offsetof({buffers}, {p}), {g}, {k}}},")
            arrays.append("};")
        rows.append(f"{{{name if leaves else 'NULL'}, {len(leaves)}u}}, /* {x.kind} {tg.comment(x.name)} */")
    return {"arrays": arrays, "rows": rows}
