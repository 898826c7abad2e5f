"""Resolved event files: a checked scenario as the compiled Main Programs read it (`event_text`).

`rcsc events` compiles a scenario (docs/scenarios.md) against a design into a
small line-based file of numbers and ids (docs/events.md): every name is
resolved to its index in the Main Program's tables, every value (computed
ones included) is evaluated here and written as the bit pattern of its
type.  The C and Rust runtimes read only this format, so the scenario
grammar and its checks live in one place (rcsc/front/scenario.py).

The file starts with the design's interface hash (`interface_hash`): a digest
of everything the ids and bit patterns depend on (CPUs, Global Memory,
controllers, verbs, parameters and their types).  The Main Program carries the
same hash in its tables and refuses a file made for another design.
"""

from __future__ import annotations

import hashlib
import struct

from rcsc.front.scenario import Scenario
from rcsc.semantics import model as m
from rcsc.semantics.types import ArrayType, BoolType, DurationType, EnumType, FloatType, IntType, RecordType, Type

MAGIC = "rcsc-events"
VERSION = 1


def _type_text(t: Type) -> str:
    if isinstance(t, EnumType):
        return f"enum {t.name}{{{','.join(t.members)}}}"
    if isinstance(t, RecordType):
        return f"record {t.name}{{{','.join(f'{n}:{_type_text(ft)}' for n, ft in t.fields)}}}"
    if isinstance(t, ArrayType):
        return f"array [{_type_text(t.elem)}; {t.size}]"
    return t.name


def interface_text(design: m.Design, ctrls: list[m.Controller]) -> str:
    """What the ids and bit patterns of an event file depend on, one item a line."""
    lines = [f"design {design.name}"]
    lines += [f"cpu {c}" for c in design.cpus]
    lines += [f"gm {n} {_type_text(v.type)} {'env' if v.from_env else 'ctrl'}" for n, v in design.gm.items()]
    for c in ctrls:
        lines.append(f"ctrl {c.name} {'top' if design.supervisor_of(c.name) is None else 'sub'}")
        for vn, v in c.verbs.items():
            lines.append(f"verb {vn}")
            lines += [f"param {p.name} {_type_text(p.type)}" for p in v.params]
    return "\n".join(lines) + "\n"


def interface_hash(design: m.Design, ctrls: list[m.Controller]) -> str:
    """16 hex digits: the first 64 bits of the SHA-256 of `interface_text`."""
    return hashlib.sha256(interface_text(design, ctrls).encode("utf-8")).hexdigest()[:16]


def leaves(value, t: Type) -> list[str]:
    """A value as its scalar leaves (records flattened in field order, arrays in index order), each
    the hex bit pattern of its type: bool 0/1, integers in two's complement
    of their width, f64 its IEEE-754 bits, duration i64 nanoseconds, enum the
    member's index."""
    if isinstance(t, RecordType):
        return [x for n, ft in t.fields for x in leaves(value[n], ft)]
    if isinstance(t, ArrayType):
        return [x for v in value for x in leaves(v, t.elem)]
    if isinstance(t, BoolType):
        bits = 1 if value else 0
    elif isinstance(t, IntType):
        bits = int(value) & ((1 << t.bits) - 1)
    elif isinstance(t, DurationType):
        bits = int(value) & ((1 << 64) - 1)
    elif isinstance(t, FloatType):
        bits = struct.unpack("<Q", struct.pack("<d", float(value)))[0]
    elif isinstance(t, EnumType):
        bits = t.members.index(str(value))
    else:  # pragma: no cover - the checker admits no other type
        raise TypeError(f"no event encoding for {t}")
    return [format(bits, "x")]


def event_text(design: m.Design, sc: Scenario, ctrls: list[m.Controller]) -> str:
    """The event file of a checked scenario for a build with controllers `ctrls`."""
    gm_ids = {n: i for i, n in enumerate(design.gm)}
    ctrl_ids = {c.name: i for i, c in enumerate(ctrls)}
    cpu_ids = {n: i for i, n in enumerate(design.cpus)}
    out = [f"{MAGIC} {VERSION} {design.name} {interface_hash(design, ctrls)}", f"cycles {sc.cycles}"]
    records = 0
    for inp in sorted(sc.inputs, key=lambda x: x.cycle):
        vals = leaves(inp.value, design.gm[inp.var].type)
        out.append(" ".join(["input", str(inp.cycle), str(gm_ids[inp.var]), str(len(vals)), *vals]))
        records += 1
    for cmd in sorted(sc.commands, key=lambda x: x.cycle):
        c = design.controllers[cmd.ctrl]
        if cmd.ctrl not in ctrl_ids:
            continue  # a simulator left out of a deployment build: nobody to command
        verb = c.verbs[cmd.verb]
        vals = [x for p in verb.params for x in leaves(cmd.args[p.name], p.type)]
        out.append(" ".join(["command", str(cmd.cycle), str(ctrl_ids[cmd.ctrl]), str(list(c.verbs).index(cmd.verb)), str(len(vals)), *vals]))
        records += 1
    for f in sorted(sc.faults, key=lambda x: x.cycle):
        if f.kind == "stop":
            out.append(f"stop {f.cycle} {cpu_ids[f.name]}")
        elif f.name in ctrl_ids:
            out.append(f"freeze {f.cycle} {ctrl_ids[f.name]}")
        else:
            continue
        records += 1
    out.append(f"end {records}")
    return "\n".join(out) + "\n"
