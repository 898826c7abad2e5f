"""The Main Program's description of its design: the tables of rcs_runtime.h.

The runtime is design-independent: it reads scenarios, writes the trace and
times the schedule through these tables (types, Global Memory, constants,
controllers).  Everything here is data, computed in Python and laid out by
templates/main.c.j2.
"""

from __future__ import annotations

from rcsc import model as m
from rcsc.backend import ordered_types
from rcsc.types import BOOL, DURATION, EnumType, FloatType, IntType, RecordType, Type

from rcsc.backends.c.target import CTarget, c_string

_BUILTIN = {"bool": "rcs_type_bool", "i32": "rcs_type_i32", "i64": "rcs_type_i64", "u32": "rcs_type_u32", "f64": "rcs_type_f64"}


def type_ref(t: Type) -> str:
    """The address of a type's descriptor."""
    if t == BOOL or isinstance(t, (IntType, FloatType)):
        return "&" + _BUILTIN[t.name]
    if t == DURATION:
        return "&rcs_type_duration"
    return f"&type_{t.name}"


def _fields(tg: CTarget, struct: str, items: list[tuple[str, Type]]) -> list[str]:
    return [f"{{{c_string(n)}, offsetof({struct}, {tg.ident(n)}), {type_ref(t)}}}," for n, t in items]


def main_tables(tg: CTarget, cpu: m.Cpu, schedule: list[m.Controller], ctrls: list[m.Controller]) -> dict:
    d, p = tg.design, tg.p
    types = []
    for t in ordered_types(d):
        if isinstance(t, EnumType):
            types.append({
                "arrays": [f"static const char *const members_{t.name}[] = {{{', '.join(c_string(x) for x in t.members)}}};"],
                "decl": f"static const rcs_type type_{t.name} = {{RCS_T_ENUM, {c_string(t.name)}, members_{t.name}, {len(t.members)}u, NULL, 0u}};",
            })
        else:
            assert isinstance(t, RecordType)
            rows = _fields(tg, tg.ctype(t), list(t.fields))
            # A record without fields has no field table (C has no empty array).
            types.append({
                "arrays": [f"static const rcs_field fields_{t.name}[] = {{"] + ["    " + r for r in rows] + ["};"] if rows else [],
                "decl": f"static const rcs_type type_{t.name} = {{RCS_T_RECORD, {c_string(t.name)}, NULL, 0u, {f'fields_{t.name}' if rows else 'NULL'}, {len(t.fields)}u}};",
            })
    type_list = [f"&type_{t.name}," for t in ordered_types(d)]

    consts = []
    for k in d.consts.values():
        consts.append({
            "decl": f"static const {tg.ctype(k.type)} const_{k.name} = {tg.literal(k.value, k.type, braces=True)};",
            "row": f"{{{c_string(k.name)}, {type_ref(k.type)}, &const_{k.name}}},",
        })

    gm_rows = _fields(tg, f"{p}_gm", [(n, v.type) for n, v in d.gm.items()])
    gm_env = ", ".join("1u" if v.from_env else "0u" for v in d.gm.values())

    index = {c.name: i for i, c in enumerate(ctrls)}
    ctrl_tables = []
    for c in ctrls:
        info = tg.infos[c.name]
        member = tg.ident(c.name)
        arrays: list[str] = []
        verb_rows = []
        for vname, v in c.verbs.items():
            if v.params:
                args_type = f"{p}_{c.name}_{vname}_args"
                arrays.append(f"static const rcs_field params_{c.name}_{vname}[] = {{")
                arrays += ["    " + r for r in _fields(tg, args_type, [(q.name, q.type) for q in v.params])]
                arrays.append("};")
                verb_rows.append(f"{{{c_string(vname)}, params_{c.name}_{vname}, {len(v.params)}u}},")
            else:
                verb_rows.append(f"{{{c_string(vname)}, NULL, 0u}},")
        if verb_rows:
            arrays.append(f"static const rcs_verb verbs_{c.name}[] = {{")
            arrays += ["    " + r for r in verb_rows]
            arrays.append("};")
        if c.status_fields:
            arrays.append(f"static const rcs_field status_fields_{c.name}[] = {{")
            arrays += ["    " + r for r in _fields(tg, f"{p}_{c.name}_fields", [(n, v.type) for n, v in c.status_fields.items()])]
            arrays.append("};")
        arrays.append(f"static const char *const states_{c.name}[] = {{{', '.join(c_string(s) for s in info.states)}}};")
        arrays.append(f"static const char *const rules_{c.name}[] = {{{', '.join(c_string(r) for r in info.rules)}}};")
        if c.statuses:
            arrays.append(f"static const rcs_status_name statuses_{c.name}[] = {{{', '.join(f'{{{c_string(s)}, {n}}}' for s, n in c.statuses.items())}}};")
        top = d.supervisor_of(c.name) is None
        has_args = any(v.params for v in c.verbs.values())
        row = [
            c_string(c.name),
            "1" if top else "0",
            "1" if c.simulator else "0",
            f"INT64_C({c.budget_ns})",
            f"step_{c.name}",
            f"&buf.{member}_cmd.head",
            f"&buf.{member}_cmd.args" if has_args else "NULL",
            f"sizeof buf.{member}_cmd.args" if has_args else "0u",
            f"verbs_{c.name}" if verb_rows else "NULL",
            f"{len(verb_rows)}u",
            f"&buf.{member}_status.head",
            f"&buf.{member}_status.f" if c.status_fields else "NULL",
            f"status_fields_{c.name}" if c.status_fields else "NULL",
            f"{len(c.status_fields)}u",
            f"states_{c.name}",
            f"{len(info.states)}u",
            f"rules_{c.name}",
            f"{len(info.rules)}u",
            f"statuses_{c.name}" if c.statuses else "NULL",
            f"{len(c.statuses)}u",
        ]
        ctrl_tables.append({
            "name": c.name, "member": member, "type": tg.ctrl_type(c.name), "arrays": arrays,
            "row": "{" + ", ".join(row) + "},",
        })
    return {
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
