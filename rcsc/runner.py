"""Running a scenario against a design: the simulator plus expectations (`run_scenario`).

The scenario's commands and inputs for cycle N are applied at the start of
cycle N, before any controller steps; expectations are evaluated on the state
at the end of a cycle (after every controller of the schedule has written).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rcsc import model as m
from rcsc.evaluate import Env, eval_expr
from rcsc.scenario import Expectation, Observed, Scenario
from rcsc.simulate import Simulator
from rcsc.trace import Snapshot, json_value, snapshot
from rcsc.types import Type


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
    snapshots: list[Snapshot]
    results: list[ExpectResult]

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


def drive(sim: Simulator, sc: Scenario):
    """Run `sc`'s cycles on `sim`, yielding after each cycle (inputs and commands applied first)."""
    commands = list(sc.commands)
    inputs = list(sc.inputs)
    for _ in range(sc.cycles):
        cycle = sim.begin_cycle()
        while inputs and inputs[0].cycle == cycle:
            inp = inputs.pop(0)
            sim.set_input(inp.var, inp.value)
        while commands and commands[0].cycle == cycle:
            cmd = commands.pop(0)
            sim.operator_command(cmd.ctrl, cmd.verb, cmd.args)
        sim.run_cycle()
        yield cycle


def run_scenario(design: m.Design, sc: Scenario, externs: dict | None = None) -> RunResult:
    sim = Simulator(design, externs)
    snaps = [snapshot(sim) for _ in drive(sim, sc)]
    results = [evaluate_expectation(design, x, snaps) for x in sc.expects]
    return RunResult(sc, snaps, results)
