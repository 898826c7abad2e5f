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

from collections.abc import Callable, Iterator

from dataclasses import dataclass, field, replace

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


class Expectations:
    """A scenario's expectations, decided as the run goes (`see` each view in
    tick order, then `results`), so that a run keeps no history: a soak
    scenario of millions of ticks takes as little memory as a short one.

    A view may stand for a span of ticks (`first`..`last`) in which nothing
    ran (every CPU stopped): each tick of the span sees the same values.
    """

    def __init__(self, design: m.Design, expects: list[Expectation]) -> None:
        self.design = design
        self.expects = expects
        self._decided: dict[int, ExpectResult] = {}
        self._open = list(range(len(expects)))  # not decided yet
        self._last: tuple[Snapshot, int] | None = None

    def see(self, snap: Snapshot, last: int | None = None) -> None:
        """Observe `snap` at its tick (`snap.cycle`) and, with `last`, at every tick up to `last`."""
        first = snap.cycle
        last = first if last is None else last
        still = []
        for i in self._open:
            x = self.expects[i]
            result = self._decide(x, snap, first, last)
            if result is None:
                still.append(i)
            else:
                self._decided[i] = result
        self._open = still
        self._last = (snap, last)

    def _decide(self, x: Expectation, snap: Snapshot, first: int, last: int) -> ExpectResult | None:
        if x.kind == "at":
            if first <= x.lo <= last:
                return ExpectResult(x, _holds(self.design, snap, x.cond), x.lo, _values(self.design, snap, x.cond))
            return None
        if x.kind == "within":
            if last < x.lo or first > x.hi:
                return None
            if _holds(self.design, snap, x.cond):
                return ExpectResult(x, True, max(first, x.lo), _values(self.design, snap, x.cond))
            if x.hi <= last:
                return ExpectResult(x, False, x.hi, _values(self.design, snap, x.cond))
            return None
        if x.kind == "always" and not _holds(self.design, snap, x.cond):
            return ExpectResult(x, False, first, _values(self.design, snap, x.cond))
        return None  # `final`, and `always` while it holds: decided at the end

    def results(self) -> list[ExpectResult]:
        """Every expectation's result, in the scenario's order (after the last view)."""
        if self._last is None:
            raise ValueError("no tick was observed")
        snap, last = self._last
        out = []
        for i, x in enumerate(self.expects):
            r = self._decided.get(i)
            if r is None:
                if x.kind == "final":
                    r = ExpectResult(x, _holds(self.design, snap, x.cond), last, _values(self.design, snap, x.cond))
                elif x.kind == "always":
                    r = ExpectResult(x, True, last, [])
                else:
                    raise ValueError(f"the run ended at tick {last}, before the expectation's ticks")
            out.append(r)
        return out


def evaluate_expectations(design: m.Design, expects: list[Expectation], snaps: list[Snapshot]) -> list[ExpectResult]:
    """The expectations' results over one view per tick (`snaps`, in tick order)."""
    ex = Expectations(design, expects)
    for snap in snaps:
        ex.see(snap)
    return ex.results()


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


def drive(system: System, sc: Scenario) -> Iterator[tuple[int, int]]:
    """Run `sc`'s ticks on `system`, yielding (first, last) after each tick ran
    (its events posted first).

    Once every CPU has stopped nothing can change but the scenario's inputs,
    so the ticks up to the next one with an event are not stepped one by
    one: `last` is then the last tick of that quiet span, whose ticks all
    look like `first` (an hour-long scenario after a total stop costs one
    step, not a million)."""
    by_tick: dict[int, list] = {}
    for tick in sorted({x.cycle for x in [*sc.inputs, *sc.commands, *sc.faults]}):
        by_tick[tick] = list(events_at(sc, tick, (tick - 1) * system.base_ns))
    ahead = sorted(by_tick)
    k = 0
    tick = 1
    while tick <= sc.cycles:
        for ev in by_tick.get(tick, ()):
            system.post(ev)
        system.tick()
        while k < len(ahead) and ahead[k] <= tick:
            k += 1
        last = tick
        if len(system.stopped) == len(system.cpus):
            last = min(ahead[k] - 1 if k < len(ahead) else sc.cycles, sc.cycles)
        yield tick, last
        system.tick_count = last  # the quiet ticks: nothing to step
        tick = last + 1


def observe(system: System) -> Snapshot:
    """What an expectation at the current tick sees: each buffer as its writer last wrote it."""
    if len(system.cpus) == 1:
        snap = snapshot(next(iter(system.cpus.values())))
        snap.cycle = system.tick_count  # differs only after a `stop`: the tick, not the last cycle run
        return snap
    return observed_snapshot(system)


@dataclass
class Tick:
    """One step of a run: what expectations see at ticks `view.cycle`..`last`
    (one tick, or a quiet span after every CPU stopped), and the trace's
    records of the cycles that ran at the first of them (`Snapshot`s on one
    CPU, `CpuSnapshot`s with several)."""

    view: Snapshot
    last: int
    ran: list


class ScenarioRun:
    """A scenario run as a stream of `Tick`s (`ticks()`), its expectations
    decided on the way (`results` once the ticks are through).  Nothing is
    kept behind the current tick, so `rcsc sim` and `rcsc test` run
    scenarios of any length in constant memory; `run_scenario` keeps it all.

    `externs` implements the design's extern functions (name -> Python
    callable taking and returning simulator values); an extern without one
    returns its type's zero value, as the targets' stubs do.  With several
    CPUs, pass a function that makes the dictionary: it is called once per
    CPU, so that an extern that keeps state keeps it per CPU, as in the
    compiled programs (one process per CPU).  `step_log` gets a line per
    controller step (`Simulator.step_log`): a list, or anything with `append`."""

    def __init__(self, design: m.Design, sc: Scenario, externs: dict | Callable[[], dict] | None = None,
                 step_log=None) -> None:
        self.design = design
        self.scenario = sc
        self.system = System(design, externs)
        if step_log is not None:
            for sim in self.system.cpus.values():
                sim.step_log = step_log
        self.multi = len(self.system.cpus) > 1
        self._expectations = Expectations(design, sc.expects)
        self.results: list[ExpectResult] | None = None

    def ticks(self) -> Iterator[Tick]:
        system = self.system
        for _, last in drive(system, self.scenario):
            view = observe(system)
            if self.multi:
                ran: list = [cpu_snapshot(system, cpu) for cpu, _ in system.ran]
            else:
                ran = [view] if system.ran else []
            self._expectations.see(view, last)
            yield Tick(view, last, ran)
        self.results = self._expectations.results()

    def run(self) -> RunResult:
        """Run to the end keeping nothing but the expectations' results."""
        for _ in self.ticks():
            pass
        assert self.results is not None
        return RunResult(self.scenario, [], self.results, multi_cpu=self.multi)


def run_scenario(design: m.Design, sc: Scenario, externs: dict | Callable[[], dict] | None = None,
                 step_log: list[str] | None = None) -> RunResult:
    """Runs `sc` and keeps every tick's view and every cycle's trace record
    (see `ScenarioRun` for the arguments; the differential tester and the
    tests compare them)."""
    run = ScenarioRun(design, sc, externs, step_log)
    snaps: list[Snapshot] = []
    cycles: list[CpuSnapshot] = []
    ran: list[Snapshot] = []
    for t in run.ticks():
        snaps.extend(spread(t.view, t.last))
        if run.multi:
            cycles.extend(t.ran)
        else:
            ran.extend(t.ran)
    assert run.results is not None
    return RunResult(sc, snaps, run.results, cycles, ran, run.multi)


def spread(view: Snapshot, last: int) -> Iterator[Snapshot]:
    """One view per tick of `view.cycle`..`last` (they share their values)."""
    yield view
    for k in range(view.cycle + 1, last + 1):
        yield replace(view, cycle=k)
