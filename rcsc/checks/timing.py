"""Timing checks (paper sections 3.8.6 and 3.9).

Every controller runs on exactly one CPU, every `divider`-th cycle of it
(`period D`, a whole multiple of the heartbeat); per CPU and per cycle the
budgets of the controllers due in that cycle plus the overhead fit in the
heartbeat (the frame rule, see `rcsc.checks.frames`); durations used by a
controller are whole multiples of its own period (else they round up); all
heartbeats are harmonic.  The check records each controller's CPU, divider
and period, and the design's crossing buffers (`Design.crossings`), for the
simulator and the backends.
"""

from __future__ import annotations

from rcsc.semantics import model as m
from rcsc.checks.frames import fmt_ns, worst_frame
from rcsc.diagnostics import Diagnostics
from rcsc.semantics.model import Design
from rcsc.semantics.types import DURATION


def budget_table(design: Design, cpu: m.Cpu) -> list[tuple[str, int]]:
    return [(u.name, design.controllers[u.name].budget_ns) for u in cpu.schedule]


def check(design: Design, diags: Diagnostics) -> None:
    if not design.cpus and not design.is_module:  # a module checked on its own runs nowhere by itself
        # A design is what runs: without a CPU there is no Main Program to
        # build and nothing for the simulator to step, even with no controller.
        diag = diags.add("E0605", design.span, f"design `{design.name}` has no `cpu`", "no cpu")
        if design.controllers:
            diag.with_help("add `cpu main { heartbeat 30 ms  schedule A, B, C }`")
        else:
            diag.with_note("a design runs as the Main Program of each CPU, which steps the controllers it schedules").with_help(
                "declare a controller, and `cpu main { heartbeat 30 ms  schedule NAME }`; "
                "declarations shared by several designs go in a `module` file that each design imports")
        return
    placed: dict[str, tuple[m.Cpu, m.NameUse]] = {}
    for cpu in design.cpus.values():
        for use in cpu.schedule:
            if use.name in placed:
                first_cpu, first_use = placed[use.name]
                diag = diags.add("E0604", use.span, f"`{use.name}` is scheduled more than once", "scheduled again")
                diag.with_label(first_use.span, f"first scheduled on `{first_cpu.name}`")
                continue
            placed[use.name] = (cpu, use)
            design.controllers[use.name].cpu = cpu.name
    # A CPU without a schedule (E0209) leaves every controller unplaced: that
    # one finding says it all.
    unscheduled_cpu = any(not cpu.schedule for cpu in design.cpus.values())
    for c in design.controllers.values():
        if c.name not in placed and not unscheduled_cpu and c.name not in design.dropped_schedule:
            diags.add("E0603", c.name_span, f"controller `{c.name}` is not in any CPU schedule", "never runs").with_help(
                f"add `{c.name}` to a `schedule`"
            )

    _check_periods(design, diags)

    for cpu in design.cpus.values():
        if cpu.heartbeat_ns <= 0:
            continue
        # The frame rule: the controllers due in each cycle fit in it.
        frame = worst_frame(design, cpu)
        total = frame.total_ns
        if total > cpu.heartbeat_ns:
            diag = diags.add(
                "E0600",
                cpu.heartbeat_span or cpu.name_span,
                f"cpu `{cpu.name}` needs {fmt_ns(total)} per cycle but its heartbeat is {fmt_ns(cpu.heartbeat_ns)}",
                "heartbeat too short",
            )
            rows = ", ".join(f"{n} {fmt_ns(b)}" for n, b in budget_table(design, cpu) if n in frame.controllers)
            diag.with_note(f"budgets: {rows}" + (f", overhead {fmt_ns(cpu.overhead_ns)}" if cpu.overhead_ns else ""))
            if any(design.controllers[n].divider > 1 for n in frame.controllers):
                diag.with_note("every controller steps in cycle 1, whatever its period: a longer period lowers the load, not the heaviest frame")

    for c in m.checked_controllers(design):
        period = c.period_ns
        if c.cpu is None or period <= 0:
            continue
        # Ages count base ticks (stamps are deadlines of any CPU), everything
        # else this controller's own steps (`in_state`, its timers).
        base = design.base_tick_ns or period
        with_age = None  # made only for a duration that is not a whole number of both units
        for span, ns in _durations(c):
            unit, steps = period, "cycles" if c.divider == 1 else "steps"
            if not ns % period and not ns % base:
                continue  # a whole number of either unit: no finding
            if with_age is None:
                with_age = _compared_with_age(c)
            if (span.start, span.end) in with_age:
                unit, steps = base, "base ticks"
            if ns % unit:
                cycles = -(-ns // unit)
                diags.add("W0601", span, f"{fmt_ns(ns)} is not a whole number of {fmt_ns(unit)} {steps}", f"rounds up to {cycles} {steps if cycles != 1 else steps[:-1]}").with_help(
                    f"write `{fmt_ns(cycles * unit)}` to say what happens"
                )

    _check_harmonic(design, diags)
    design.crossings = crossings(design)


def _check_periods(design: Design, diags: Diagnostics) -> None:
    """Each placed controller's divider and period: `period D` over its CPU's heartbeat."""
    for c in design.controllers.values():
        if c.cpu is None:
            continue
        hb = design.cpus[c.cpu].heartbeat_ns
        c.divider, c.period_ns = 1, max(hb, 0)
        if not c.declared_period_ns or hb <= 0:
            continue
        if c.declared_period_ns % hb:
            span = c.period_span or c.name_span
            diag = diags.add(
                "E0607",
                span,
                f"the period of `{c.name}` ({fmt_ns(c.declared_period_ns)}) is not a whole number of `{c.cpu}` cycles ({fmt_ns(hb)})",
                "not a multiple of the heartbeat",
            )
            lower = c.declared_period_ns // hb * hb
            options = [fmt_ns(x) for x in (lower, lower + hb) if x > 0]
            diag.with_help("write " + " or ".join(f"`period {x}`" for x in options))
            continue
        c.divider = c.declared_period_ns // hb
        c.period_ns = c.declared_period_ns


def crossings(design: Design) -> list[m.Crossing]:
    """The buffers that travel between CPUs, in the order the model documents."""
    ctrls = design.controllers
    out: list[m.Crossing] = []
    writer_cpu: dict[str, str] = {}
    reader_cpus: dict[str, set[str]] = {}  # one pass over the reads, not one per buffer
    for c in ctrls.values():
        if not c.cpu:
            continue
        for use in c.writes:
            writer_cpu.setdefault(use.name, c.cpu)
        for use in c.reads:
            reader_cpus.setdefault(use.name, set()).add(c.cpu)
    for name in design.gm:
        w = writer_cpu.get(name)
        if w is None:
            continue
        readers = reader_cpus.get(name, set()) - {w}
        if readers:
            out.append(m.Crossing("gm", name, w, _in_cpu_order(design, readers)))
    for c in ctrls.values():
        sup = ctrls.get(c.supervisor) if c.supervisor else None
        if sup is None or not sup.cpu or not c.cpu or sup.cpu == c.cpu:
            continue
        out.append(m.Crossing("cmd", c.name, sup.cpu, [c.cpu]))
        out.append(m.Crossing("status", c.name, c.cpu, [sup.cpu]))
    return out


def _in_cpu_order(design: Design, names: set[str]) -> list[str]:
    return [n for n in design.cpus if n in names]


def _is_age(e: m.Expr) -> bool:
    return isinstance(e, m.Age) or (isinstance(e, m.SubView) and e.attr == "age")


def _compared_with_age(c: m.Controller) -> set[tuple[int, int]]:
    """Spans of the duration constants that a comparison puts against an age."""
    out = set()
    for e in m.controller_exprs(c):
        for x in m.walk_expr(e):
            if isinstance(x, m.Binary) and x.op in ("<", "<=", ">", ">=", "==", "!="):
                sides = (x.left, x.right)
                if any(_is_age(y) for side in sides for y in m.walk_expr(side)):
                    out.update((y.span.start, y.span.end) for side in sides for y in m.walk_expr(side) if isinstance(y, m.Const))
    return out


def _durations(c: m.Controller):
    exprs = m.controller_exprs(c)
    seen = set()
    for e in exprs:
        for x in m.walk_expr(e):
            if isinstance(x, m.Const) and x.type == DURATION and isinstance(x.value, int) and x.value > 0:
                key = (x.span.start, x.span.end)
                if key not in seen:
                    seen.add(key)
                    yield x.span, x.value


def _check_harmonic(design: Design, diags: Diagnostics) -> None:
    """Every pair of heartbeats is harmonic: CPUs that exchange data first, then the rest.

    All CPUs share one time base whose tick is the shortest heartbeat, so even
    CPUs that exchange nothing must be harmonic for scenarios to address them.
    """
    pairs: set[tuple[str, str]] = set()
    ctrls = design.controllers
    for c in ctrls.values():
        for use in c.subordinates:
            a, b = c.cpu, ctrls[use.name].cpu
            if a and b and a != b:
                pairs.add(tuple(sorted((a, b))))  # type: ignore[arg-type]
    writer_cpu: dict[str, str] = {}
    for c in ctrls.values():
        for use in c.writes:
            if c.cpu:
                writer_cpu.setdefault(use.name, c.cpu)
    for c in ctrls.values():
        for use in c.reads:
            w = writer_cpu.get(use.name)
            if w and c.cpu and w != c.cpu:
                pairs.add(tuple(sorted((w, c.cpu))))  # type: ignore[arg-type]
    for a, b in sorted(pairs):
        pa, pb = design.cpus[a].heartbeat_ns, design.cpus[b].heartbeat_ns
        if pa <= 0 or pb <= 0:
            continue
        lo, hi = sorted((pa, pb))
        if hi % lo:
            cpu = design.cpus[b]
            diag = diags.add("E0602", cpu.heartbeat_span or cpu.name_span, f"cpus `{a}` and `{b}` exchange data but their periods are not harmonic", "not a multiple")
            diag.with_note(f"{fmt_ns(pa)} and {fmt_ns(pb)}: one must be a whole multiple of the other")
    cpus = [c for c in design.cpus.values() if c.heartbeat_ns > 0]
    reported = {name for pair in pairs for name in pair if _non_harmonic(design, *pair)}
    for i, cb in enumerate(cpus):
        if cb.name in reported:
            continue
        for ca in cpus[:i]:
            if ca.name not in reported and _non_harmonic(design, ca.name, cb.name):
                diag = diags.add("E0602", cb.heartbeat_span or cb.name_span, f"the heartbeats of cpus `{ca.name}` and `{cb.name}` are not harmonic", "not a multiple")
                diag.with_note(f"{fmt_ns(ca.heartbeat_ns)} and {fmt_ns(cb.heartbeat_ns)}: one must be a whole multiple of the other (all CPUs share one time base)")
                break


def _non_harmonic(design: Design, a: str, b: str) -> bool:
    lo, hi = sorted((design.cpus[a].heartbeat_ns, design.cpus[b].heartbeat_ns))
    return lo > 0 and hi % lo != 0
