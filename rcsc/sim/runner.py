"""Running a scenario against a design: the simulator plus expectations (`run_scenario`).

A scenario counts base ticks (the shortest heartbeat; on a single-CPU design
its cycles).  The scenario's inputs, commands and faults of tick N happen at
instant (N-1) * base tick and are seen by each CPU at its first release at or
after it; expectations of tick N are evaluated after every CPU released at
that instant has run its cycle, on each buffer as its writer last wrote it
(every controller's own status buffer, each Global Memory variable on its
writer's CPU, inputs as the scenario last set them).
"""

from __future__ import annotations

from collections.abc import Callable

from dataclasses import dataclass, field

from rcsc.semantics import model as m
from rcsc.semantics.evaluate import Env, eval_expr
from rcsc.front.scenario import Expectation, Observed, Scenario
from rcsc.sim.timebase import Event, System
from rcsc.sim.trace import CpuSnapshot, Snapshot, cpu_snapshot, json_value, observed_snapshot, snapshot
from rcsc.semantics.types import Type


class ObserverEnv(Env):
    """Reads an end-of-cycle snapshot, the way a scenario's expectations see the design."""

    def __init__(self, design: m.Design, snap: Snapshot) -> None:
        self.design = design
        self.snap = snap

    def ref(self, e: m.Ref):
        return self.snap.gm[e.name]

    def function(self, name: str) -> m.Function:
        return self.design.functions[name]

    def other(self, e: m.Expr):
        if not isinstance(e, Observed):
            return super().other(e)
        s = self.snap.ctrl[e.ctrl]
        a = e.attr
        if a in ("status", "state", "rule", "verb"):
            return getattr(s, a) == e.value
        if a == "done":
            return s.status == "DONE"
        if a == "error":
            return s.status == "ERROR"
        if a == "executing":
            return s.status not in ("DONE", "ERROR", "UNINITIALIZED")
        if a == "extra":
            return s.status == e.value
        if a == "error_code":
            return s.error_code
        if a == "echo":
            return s.echo
        if a == "field":
            return s.fields[e.value]
        raise KeyError(a)


@dataclass
class ExpectResult:
    expect: Expectation
    passed: bool
    cycle: int  # where it was decided (the failing cycle, or the cycle that satisfied it)
    values: list[tuple[str, str]] = field(default_factory=list)  # what the condition read there


@dataclass
class RunResult:
    scenario: Scenario
    snapshots: list[Snapshot]  # one per tick: what expectations see
    results: list[ExpectResult]
    cpu_cycles: list[CpuSnapshot] = field(default_factory=list)  # multi-CPU designs: one per CPU cycle run
    trace_snapshots: list[Snapshot] = field(default_factory=list)  # single-CPU designs: the cycles that ran
    multi_cpu: bool = False  # several CPUs: snapshots are per base tick

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.results)


def _leaves(e: m.Expr):
    if isinstance(e, (m.Ref, Observed)):
        yield e
        return
    for attr in ("obj", "operand", "left", "right", "cond", "then", "else_"):
        sub = getattr(e, attr, None)
        if isinstance(sub, m.Expr):
            yield from _leaves(sub)
    for a in getattr(e, "args", []) or []:
        yield from _leaves(a)


def _show(design: m.Design, snap: Snapshot, leaf: m.Expr) -> tuple[str, str]:
    if isinstance(leaf, m.Ref):
        return leaf.name, json_value(snap.gm[leaf.name], leaf.type)
    assert isinstance(leaf, Observed)
    s = snap.ctrl[leaf.ctrl]
    if leaf.attr in ("status", "done", "error", "executing", "extra"):
        return f"{leaf.ctrl}.status", s.status
    if leaf.attr in ("state", "rule", "verb"):
        return f"{leaf.ctrl}.{leaf.attr}", getattr(s, leaf.attr)
    if leaf.attr == "field":
        t: Type = design.controllers[leaf.ctrl].status_fields[leaf.value or ""].type
        return f"{leaf.ctrl}.{leaf.value}", json_value(s.fields[leaf.value], t)
    return f"{leaf.ctrl}.{leaf.attr}", str(s.error_code if leaf.attr == "error_code" else s.echo)


def _values(design: m.Design, snap: Snapshot, e: m.Expr) -> list[tuple[str, str]]:
    seen: dict[str, str] = {}
    for leaf in _leaves(e):
        k, v = _show(design, snap, leaf)
        seen.setdefault(k, v)
    return list(seen.items())


def _holds(design: m.Design, snap: Snapshot, e: m.Expr) -> bool:
    return bool(eval_expr(e, ObserverEnv(design, snap)))


def evaluate_expectation(design: m.Design, x: Expectation, snaps: list[Snapshot]) -> ExpectResult:
    by_cycle = {s.cycle: s for s in snaps}
    if x.kind in ("at", "final"):
        snap = by_cycle[x.lo] if x.kind == "at" else snaps[-1]
        return ExpectResult(x, _holds(design, snap, x.cond), snap.cycle, _values(design, snap, x.cond))
    if x.kind == "within":
        for c in range(x.lo, x.hi + 1):
            if _holds(design, by_cycle[c], x.cond):
                return ExpectResult(x, True, c, _values(design, by_cycle[c], x.cond))
        return ExpectResult(x, False, x.hi, _values(design, by_cycle[x.hi], x.cond))
    for snap in snaps:  # always
        if not _holds(design, snap, x.cond):
            return ExpectResult(x, False, snap.cycle, _values(design, snap, x.cond))
    return ExpectResult(x, True, snaps[-1].cycle, [])


def events_at(sc: Scenario, tick: int, instant: int):
    """The outside events of tick `tick`: inputs, then commands, then faults (file order within each)."""
    for inp in sc.inputs:
        if inp.cycle == tick:
            yield Event(instant, "input", inp.var, inp.value)
    for cmd in sc.commands:
        if cmd.cycle == tick:
            yield Event(instant, "command", cmd.ctrl, (cmd.verb, cmd.args))
    for f in sc.faults:
        if f.cycle == tick:
            yield Event(instant, f.kind, f.name)


def drive(system: System, sc: Scenario):
    """Run `sc`'s ticks on `system`, yielding each tick after it ran (its events posted first)."""
    by_tick: dict[int, list] = {}
    for tick in range(1, sc.cycles + 1):
        by_tick[tick] = []
    for tick in sorted({x.cycle for x in [*sc.inputs, *sc.commands, *sc.faults]}):
        by_tick[tick] = list(events_at(sc, tick, (tick - 1) * system.base_ns))
    for tick in range(1, sc.cycles + 1):
        for ev in by_tick[tick]:
            system.post(ev)
        system.tick()
        yield tick


def observe(system: System) -> Snapshot:
    """What an expectation at the current tick sees: each buffer as its writer last wrote it."""
    if len(system.cpus) == 1:
        snap = snapshot(next(iter(system.cpus.values())))
        snap.cycle = system.tick_count  # differs only after a `stop`: the tick, not the last cycle run
        return snap
    return observed_snapshot(system)


def run_scenario(design: m.Design, sc: Scenario, externs: dict | Callable[[], dict] | None = None,
                 step_log: list[str] | None = None) -> RunResult:
    """Runs `sc`; with `step_log`, appends a line per step to it (Simulator.step_log).

    `externs` implements the design's extern functions (name -> Python
    callable taking and returning simulator values); an extern without one
    returns its type's zero value, as the targets' stubs do.  With several
    CPUs, pass a function that makes the dictionary: it is called once per
    CPU, so that an extern that keeps state keeps it per CPU, as in the
    compiled programs (one process per CPU)."""
    system = System(design, externs)
    if step_log is not None:
        for sim in system.cpus.values():
            sim.step_log = step_log
    snaps: list[Snapshot] = []
    cycles: list[CpuSnapshot] = []
    ran: list[Snapshot] = []
    multi = len(system.cpus) > 1
    for _ in drive(system, sc):
        snaps.append(observe(system))
        if multi:
            cycles.extend(cpu_snapshot(system, cpu) for cpu, _ in system.ran)
        elif system.ran:
            ran.append(snaps[-1])
    results = [evaluate_expectation(design, x, snaps) for x in sc.expects]
    return RunResult(sc, snaps, results, cycles, ran, multi)
