"""Traces: what a run looked like, cycle by cycle, in JSON lines, CSV and VCD.

The JSON-lines trace is the canonical format: the C and Rust Main Programs
write the same bytes for the same design and scenario, so it is fixed here
(see docs/scenarios.md).  One line per cycle:

    {"cycle":1,"gm":{...},"ctrl":{"PR":{"echo":1,"status":"EXEC","verb":"AHEAD",
     "state":"S1","rule":"E0","error_code":0,"fields":{...}},...}}

No spaces; Global Memory and controllers in declaration order; record fields
in declaration order.  Numbers: integers in decimal; f64 as C's `%.17g`
(exact, round-trips), with NaN and infinities as the strings "nan", "inf" and
"-inf" (JSON has no such numbers); durations as integer nanoseconds; enum
values, states, statuses and rule labels as strings.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rcsc.semantics import model as m
from rcsc.sim.simulate import Simulator

if TYPE_CHECKING:
    from rcsc.sim.timebase import System
from rcsc.semantics.types import BOOL, DURATION, ArrayType, EnumType, FloatType, IntType, RecordType, Type


@dataclass
class CtrlSnapshot:
    echo: int
    status: str
    verb: str
    state: str
    rule: str
    error_code: int
    fields: dict


@dataclass
class Snapshot:
    cycle: int
    gm: dict
    ctrl: dict  # name -> CtrlSnapshot


def snapshot(sim: Simulator) -> Snapshot:
    ctrls = {name: _ctrl_snapshot(sim, name, sim.statuses[name]) for name in sim.design.controllers}
    return Snapshot(sim.cycle, dict(sim.gm), ctrls)


def fmt_float(x: float) -> str:
    if math.isnan(x):
        return '"nan"'
    if math.isinf(x):
        return '"inf"' if x > 0 else '"-inf"'
    return format(x, ".17g")


def _json_str(s: str) -> str:
    out = ['"']
    for ch in s:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def json_value(value, t: Type) -> str:
    """One value as the canonical trace writes it (type-directed, not repr-directed)."""
    if t == BOOL:
        return "true" if value else "false"
    if isinstance(t, FloatType):
        return fmt_float(float(value))
    if isinstance(t, IntType) or t == DURATION:
        return str(int(value))
    if isinstance(t, EnumType):
        return _json_str(str(value))
    if isinstance(t, RecordType):
        return "{" + ",".join(f"{_json_str(n)}:{json_value(value[n], ft)}" for n, ft in t.fields) + "}"
    if isinstance(t, ArrayType):
        return "[" + ",".join(json_value(v, t.elem) for v in value) + "]"
    return _json_str(str(value))


def _gm_json(design: m.Design, gm: dict, names) -> str:
    return ",".join(f"{_json_str(n)}:{json_value(gm[n], design.gm[n].type)}" for n in names)


def _ctrl_json(design: m.Design, ctrl: dict, names) -> str:
    parts = []
    for name in names:
        c = design.controllers[name]
        s = ctrl[name]
        fields = ",".join(f"{_json_str(n)}:{json_value(s.fields[n], v.type)}" for n, v in c.status_fields.items())
        parts.append(
            f"{_json_str(name)}:{{\"echo\":{s.echo},\"status\":{_json_str(s.status)},\"verb\":{_json_str(s.verb)},"
            f"\"state\":{_json_str(s.state)},\"rule\":{_json_str(s.rule)},\"error_code\":{s.error_code},\"fields\":{{{fields}}}}}"
        )
    return ",".join(parts)


def jsonl_line(design: m.Design, snap: Snapshot) -> str:
    gm = _gm_json(design, snap.gm, design.gm)
    return f"{{\"cycle\":{snap.cycle},\"gm\":{{{gm}}},\"ctrl\":{{{_ctrl_json(design, snap.ctrl, design.controllers)}}}}}"


def to_jsonl(design: m.Design, snaps: list[Snapshot]) -> str:
    return "".join(jsonl_line(design, s) + "\n" for s in snaps)


# ---- several CPUs ------------------------------------------------------------------


@dataclass
class CpuSnapshot:
    """One cycle of one CPU of a multi-CPU design: that CPU's view after the cycle."""

    cpu: str
    cycle: int
    t: int  # the cycle's release instant, in ns
    gm: dict  # the GM variables the CPU's controllers read or write (its copies)
    ctrl: dict  # the controllers placed on the CPU


def cpu_gm_names(design: m.Design, cpu: str) -> list[str]:
    """The GM variables that the controllers of `cpu` read or write, in declaration order."""
    used = {u.name for c in design.controllers.values() if c.cpu == cpu for u in c.reads + c.writes}
    return [n for n in design.gm if n in used]


def _ctrl_snapshot(sim: Simulator, name: str, st) -> CtrlSnapshot:
    return CtrlSnapshot(st.echo_serial, sim.status_name(name, st.status), st.verb, st.state, st.rule, st.error_code, dict(st.fields))


def cpu_snapshot(system: "System", cpu: str) -> CpuSnapshot:
    sim = system.cpus[cpu]
    d = system.design
    gm = {n: sim.gm[n] for n in cpu_gm_names(d, cpu)}
    ctrl = {n: _ctrl_snapshot(sim, n, sim.statuses[n]) for n, c in d.controllers.items() if c.cpu == cpu}
    return CpuSnapshot(cpu, sim.cycle, sim.now, gm, ctrl)


def observed_snapshot(system: "System") -> Snapshot:
    """The observer's view of a multi-CPU design at the current tick (see `rcsc.sim.runner`)."""
    first = next(iter(system.cpus.values()))
    ctrls = {n: _ctrl_snapshot(first, n, system.observed_status(n)) for n in system.design.controllers}
    return Snapshot(system.tick_count, system.observed_gm(), ctrls)


def cpu_jsonl_line(design: m.Design, snap: CpuSnapshot) -> str:
    gm = _gm_json(design, snap.gm, snap.gm)
    return (
        f"{{\"cpu\":{_json_str(snap.cpu)},\"cycle\":{snap.cycle},\"t\":{snap.t},"
        f"\"gm\":{{{gm}}},\"ctrl\":{{{_ctrl_json(design, snap.ctrl, snap.ctrl)}}}}}"
    )


def cycles_to_jsonl(design: m.Design, snaps: list[CpuSnapshot]) -> str:
    """The multi-CPU trace: one line per CPU cycle, by release instant, then CPU declaration order."""
    order = {name: i for i, name in enumerate(design.cpus)}
    ordered = sorted(snaps, key=lambda s: (s.t, order[s.cpu]))
    return "".join(cpu_jsonl_line(design, s) + "\n" for s in ordered)


def jsonl_chunks(design: m.Design, records: Iterable[Snapshot | CpuSnapshot]) -> Iterator[str]:
    """The JSON-lines trace as the run makes it, from its records in run
    order (`rcsc.sim.runner.Tick.ran`: a CPU's cycles in time order, the
    CPUs of one instant in declaration order, as `cycles_to_jsonl` sorts)."""
    for rec in records:
        if isinstance(rec, CpuSnapshot):
            yield cpu_jsonl_line(design, rec) + "\n"
        else:
            yield jsonl_line(design, rec) + "\n"


def run_to_jsonl(design: m.Design, run) -> str:
    """The JSON-lines trace of a scenario run (a `rcsc.sim.runner` result), as
    `rcsc sim` writes it and the compiled Main Programs must: per cycle on one
    CPU (up to a `stop`), per CPU cycle with several."""
    if len(design.cpus) > 1:
        return cycles_to_jsonl(design, run.cpu_cycles)
    return to_jsonl(design, run.trace_snapshots)


# ---- flat columns: CSV and VCD ---------------------------------------------------


def _flatten(prefix: str, value, t: Type):
    if isinstance(t, RecordType):
        for n, ft in t.fields:
            yield from _flatten(f"{prefix}.{n}", value[n], ft)
    elif isinstance(t, ArrayType):
        for i, v in enumerate(value):
            yield from _flatten(f"{prefix}[{i}]", v, t.elem)
    else:
        yield prefix, value, t


def columns(design: m.Design, snap: Snapshot) -> list[tuple[str, object, Type | str]]:
    """(name, value, type) of every scalar in a snapshot, in a fixed order."""
    out: list[tuple[str, object, Type | str]] = []
    for n, v in design.gm.items():
        out.extend(_flatten(n, snap.gm[n], v.type))
    for name, c in design.controllers.items():
        s = snap.ctrl[name]
        out.append((f"{name}.echo", s.echo, "u32"))
        out.append((f"{name}.status", s.status, "str"))
        out.append((f"{name}.verb", s.verb, "str"))
        out.append((f"{name}.state", s.state, "str"))
        out.append((f"{name}.rule", s.rule, "str"))
        out.append((f"{name}.error_code", s.error_code, "i32"))
        for n, v in c.status_fields.items():
            out.extend(_flatten(f"{name}.{n}", s.fields[n], v.type))
    return out


def _csv_text(value, t) -> str:
    if isinstance(t, Type):
        text = json_value(value, t)
        return text[1:-1] if text.startswith('"') else text
    return str(value)


def to_csv(design: m.Design, snaps: list[Snapshot]) -> str:
    return "".join(csv_chunks(design, ((snap, snap.cycle) for snap in snaps)))


def csv_chunks(design: m.Design, views: Iterable[tuple[Snapshot, int]]) -> Iterator[str]:
    """The CSV trace as it is made: a header, then a row per tick.  `views`
    are (view, last tick) pairs, a view standing for each tick from its own
    up to `last` (`rcsc.sim.runner.Tick`)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    header = False
    for snap, last in views:
        cols = columns(design, snap)
        if not header:
            w.writerow(["cycle"] + [c[0] for c in cols])
            header = True
        row = [_csv_text(v, t) for _, v, t in cols]
        for k in range(snap.cycle, last + 1):
            w.writerow([k] + row)
            if k % 1024 == 0:  # a long quiet span comes out in pieces, not as one string
                yield buf.getvalue()
                buf.seek(0)
                buf.truncate()
        yield buf.getvalue()
        buf.seek(0)
        buf.truncate()


def _vcd_id(i: int) -> str:
    chars = [chr(c) for c in range(33, 127)]
    out = ""
    i += 1
    while i:
        i, r = divmod(i - 1, len(chars))
        out = chars[r] + out
    return out


def _vcd_kind(t) -> tuple[str, int]:
    if t == BOOL:
        return "wire", 1
    if isinstance(t, IntType):
        return "integer", t.bits
    if t == DURATION:
        return "integer", 64
    if t in ("u32", "i32"):
        return "integer", 32
    if isinstance(t, FloatType):
        return "real", 64
    return "string", 1


def _vcd_value(value, t, ident: str) -> str:
    kind, bits = _vcd_kind(t)
    if kind == "wire":
        return f"{1 if value else 0}{ident}"
    if kind == "integer":
        v = int(value) & ((1 << bits) - 1)
        return f"b{v:b} {ident}"
    if kind == "real":
        x = float(value)
        return f"r{format(x, '.17g') if math.isfinite(x) else ('nan' if math.isnan(x) else ('inf' if x > 0 else '-inf'))} {ident}"
    text = str(value).replace(" ", "_") or "-"
    return f"s{text} {ident}"


def to_vcd(design: m.Design, snaps: list[Snapshot], period_ns: int) -> str:
    """A VCD file (GTKWave): one scope per controller and one for Global Memory."""
    return "".join(vcd_chunks(design, ((snap, snap.cycle) for snap in snaps), period_ns))


def vcd_chunks(design: m.Design, views: Iterable[tuple[Snapshot, int]], period_ns: int) -> Iterator[str]:
    """`to_vcd` as it is made, from (view, last tick) pairs as `csv_chunks`
    takes them (the ticks after a view's own change nothing, so they add
    nothing to a VCD)."""
    head = ["$comment generated by rcsc - do not edit $end", "$timescale 1 ns $end"]
    ids: dict[str, str] = {}
    last_text: dict[str, str] = {}
    started = False
    for s, _ in views:
        cols = columns(design, s)
        lines: list[str] = []
        if not started:
            started = True
            lines.extend(head)
            ids = {name: _vcd_id(i) for i, (name, _, _) in enumerate(cols)}
            scopes: dict[str, list[tuple[str, str, object]]] = {}
            for name, _, t in cols:
                top, _, rest = name.partition(".")
                scope, var = ("gm", name) if top in design.gm else (top, rest)
                scopes.setdefault(scope, []).append((var, ids[name], t))
            lines.append(f"$scope module {design.name} $end")
            for scope, vars_ in scopes.items():
                lines.append(f"$scope module {scope} $end")
                for var, ident, t in vars_:
                    kind, bits = _vcd_kind(t)
                    lines.append(f"$var {kind} {bits} {ident} {var.replace('.', '_')} $end")
                lines.append("$upscope $end")
            lines.append("$upscope $end")
            lines.append("$enddefinitions $end")
        changes = []
        for name, value, t in cols:
            text = _vcd_value(value, t, ids[name])
            if last_text.get(name) != text:
                last_text[name] = text
                changes.append(text)
        if changes:
            lines.append(f"#{s.cycle * period_ns}")
            lines.extend(changes)
        yield "".join(line + "\n" for line in lines)
    if not started:
        yield "".join(line + "\n" for line in head + ["$enddefinitions $end"])
