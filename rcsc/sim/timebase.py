"""Several CPUs on one time base: releases, deadlines and the buffers that cross (`System`).

Every CPU's heartbeat divides or is divided by every other's, so all release
instants lie on a grid of base ticks (the shortest heartbeat).  Cycle k of a
CPU with heartbeat P is released at (k-1)*P and has its deadline at k*P.
`System.tick` advances the time base by one base tick: every CPU released at
that instant runs one cycle (a `rcsc.sim.simulate.Simulator` per CPU does the
stepping, so each CPU follows the single-CPU rules inside).

A buffer written on one CPU and read on another (`Design.crossings`) travels
like this: the writer's CPU publishes it at the end of each of its cycles,
visible from that cycle's deadline, stamped with the deadline of the cycle
in which it was last written; a reader's CPU refreshes its copy at each of
its releases with the newest value published at a deadline at or before the
release.  Where a deadline and a release coincide, publication comes first.

Outside events (a scenario's commands, inputs and faults) happen at an
instant and are seen by each CPU at its first release at or after it.
A single-CPU design is the case of one CPU whose base tick is its heartbeat.
"""

from __future__ import annotations

from collections.abc import Callable

from dataclasses import dataclass

from rcsc.semantics import model as m
from rcsc.sim.simulate import CommandBuffer, Simulator, StatusBuffer, clone_status, clone


@dataclass
class Event:
    """Something from outside at `instant`: kind input | command | stop | freeze."""

    instant: int
    kind: str
    name: str  # GM variable, top controller, CPU or controller
    value: object = None  # the input's value, or (verb, args) of a command


@dataclass
class _Publication:
    visible: int  # the deadline from which readers see it
    kind: str  # gm | cmd | status
    name: str
    value: object
    stamp: int


class System:
    """Runs every CPU of a design on the common time base."""

    def __init__(self, design: m.Design, externs: dict | Callable[[], dict] | None = None) -> None:
        """`externs`: the extern functions' implementations by name (see
        `run_scenario`), or a function that makes them for one CPU, called
        once per CPU: each CPU's Main Program has its own, so an extern that
        keeps state keeps it per CPU."""
        self.design = design
        self.base_ns = design.base_tick_ns
        self.cpus = {name: Simulator(design, externs() if callable(externs) else externs, cpu) for name, cpu in design.cpus.items()}
        self.tick_count = 0
        self.stopped: set[str] = set()
        self._events: dict[str, list[Event]] = {name: [] for name in design.cpus}
        self._inbox: dict[str, list[_Publication]] = {name: [] for name in design.cpus}
        self._outputs: dict[str, list[m.Crossing]] = {name: [] for name in design.cpus}
        for x in design.crossings:
            self._outputs[x.writer_cpu].append(x)
        self._env: dict[str, object] = {n: clone(v.init) for n, v in design.gm.items() if v.from_env}
        # The CPU whose copy of a GM variable an observer reads: its writer's.
        self._writer_cpu: dict[str, str] = {}
        for c in design.controllers.values():
            for use in c.writes:
                if c.cpu:
                    self._writer_cpu.setdefault(use.name, c.cpu)
        self.ran: list[tuple[str, int]] = []  # (cpu, cycle) of the cycles the last tick ran

    @property
    def now(self) -> int:
        """The instant of the current base tick (tick N is at (N-1) * base)."""
        return (self.tick_count - 1) * self.base_ns

    # ---- outside world ---------------------------------------------------------

    def post(self, event: Event) -> None:
        """Queue an outside event for the CPUs that see it (call before the tick of its instant runs)."""
        if event.kind == "input":
            self._env[event.name] = clone(event.value)
            targets = list(self.cpus)
        elif event.kind == "command":
            targets = [self.design.controllers[event.name].cpu or ""]
        elif event.kind == "stop":
            targets = [event.name]
        else:
            targets = [self.design.controllers[event.name].cpu or ""]
        for t in targets:
            self._events[t].append(event)

    # ---- the time base ---------------------------------------------------------

    def tick(self) -> int:
        """Advance one base tick: each CPU released at this instant runs a cycle."""
        self.tick_count += 1
        now = self.now
        self.ran = []
        for name, sim in self.cpus.items():
            if now % sim.period_ns or name in self.stopped:
                continue
            self._deliver(name, sim, now)
            self._apply_events(name, sim, now)
            if name in self.stopped:
                continue
            sim.begin_cycle()
            sim.run_cycle()
            self._publish(name, sim)
            self.ran.append((name, sim.cycle))
        return self.tick_count

    def _deliver(self, name: str, sim: Simulator, now: int) -> None:
        """Refresh this CPU's copies with everything published at deadlines up to `now`."""
        inbox = self._inbox[name]
        keep = []
        for p in inbox:
            if p.visible > now:
                keep.append(p)
            elif p.kind == "gm":
                sim.gm[p.name] = clone(p.value)
                sim.gm_stamp[p.name] = p.stamp
            elif p.kind == "status":
                st = clone_status(p.value)  # type: ignore[arg-type]
                st.stamp = p.stamp
                sim.statuses[p.name] = st
            else:
                cmd: CommandBuffer = p.value  # type: ignore[assignment]
                sim.commands[p.name] = CommandBuffer(cmd.serial, cmd.verb, clone(cmd.args))
        self._inbox[name] = keep

    def _apply_events(self, name: str, sim: Simulator, now: int) -> None:
        events = self._events[name]
        while events and events[0].instant <= now:
            ev = events.pop(0)
            if ev.kind == "input":
                sim.set_input(ev.name, ev.value, stamp=ev.instant)
            elif ev.kind == "command":
                verb, args = ev.value  # type: ignore[misc]
                sim.operator_command(ev.name, verb, args)
            elif ev.kind == "stop":
                self.stopped.add(name)
            else:
                sim.frozen.add(ev.name)

    def _publish(self, name: str, sim: Simulator) -> None:
        """Queue this cycle's crossing outputs for their readers, visible at the deadline."""
        deadline = sim.now + sim.period_ns
        for x in self._outputs[name]:
            if x.kind == "gm":
                if sim.gm_stamp[x.name] != sim.now:
                    continue  # not written in this cycle: the readers' copy and stamp stand
                pub = _Publication(deadline, "gm", x.name, clone(sim.gm[x.name]), deadline)
            elif x.kind == "status":
                st = sim.statuses[x.name]
                if st.stamp != sim.now:
                    continue
                pub = _Publication(deadline, "status", x.name, clone_status(st), deadline)
            else:
                cmd = sim.commands[x.name]
                pub = _Publication(deadline, "cmd", x.name, CommandBuffer(cmd.serial, cmd.verb, clone(cmd.args)), deadline)
            for reader in x.reader_cpus:
                if reader not in self.stopped:  # a stopped CPU never reads again
                    self._inbox[reader].append(pub)

    # ---- observation -----------------------------------------------------------

    def observed_gm(self) -> dict:
        """Each GM variable as its writer last wrote it (inputs: the latest input)."""
        out = {}
        first = next(iter(self.cpus.values()))
        for n in self.design.gm:
            if n in self._env:
                out[n] = self._env[n]
            else:
                w = self._writer_cpu.get(n)
                out[n] = self.cpus[w].gm[n] if w is not None else first.gm[n]
        return out

    def observed_status(self, ctrl: str) -> StatusBuffer:
        """A controller's status buffer as it last wrote it (on its own CPU)."""
        cpu = self.design.controllers[ctrl].cpu or next(iter(self.cpus))
        return self.cpus[cpu].statuses[ctrl]
