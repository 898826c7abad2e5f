"""Timing checks (paper sections 3.8.6 and 3.9).

Every controller runs on exactly one CPU; per CPU the sum of the budgets of
its controllers plus its overhead fits in the heartbeat; durations used by a
controller are whole multiples of its CPU's heartbeat (else they round up);
CPUs that exchange data have harmonic periods.  `budget_table` is the table
that `rcsc budget` and the notes print.
"""

from __future__ import annotations

from rcsc import model as m
from rcsc.diagnostics import Diagnostics
from rcsc.model import Design
from rcsc.types import DURATION


def fmt_ns(ns: int) -> str:
    """A duration in the largest unit that is at least 1, exact (3 decimals reach the next unit)."""
    sign = "-" if ns < 0 else ""
    ns = abs(ns)
    for unit, scale in (("s", 1_000_000_000), ("ms", 1_000_000), ("us", 1_000)):
        if ns >= scale and ns % (scale // 1000) == 0:
            text = f"{ns / scale:.3f}".rstrip("0").rstrip(".") if ns % scale else str(ns // scale)
            return f"{sign}{text} {unit}"
    return f"{sign}{ns} ns"


def budget_table(design: Design, cpu: m.Cpu) -> list[tuple[str, int]]:
    return [(u.name, design.controllers[u.name].budget_ns) for u in cpu.schedule]


def format_budget_table(design: Design) -> str:
    """The timing table of every CPU: each controller's budget and its share of the heartbeat."""
    out = []
    for cpu in design.cpus.values():
        hb = cpu.heartbeat_ns
        out.append(f"cpu {cpu.name}: heartbeat {fmt_ns(hb)}")
        rows = [(n, str(design.controllers[n].level) + (" sim" if design.controllers[n].simulator else ""), b) for n, b in budget_table(design, cpu)]
        if cpu.overhead_ns:
            rows.append(("(overhead)", "", cpu.overhead_ns))
        total = sum(b for _, _, b in rows)
        width = max([len(r[0]) for r in rows] + [len("controller"), len("total")])
        out.append(f"  {'controller':<{width}}  {'level':<6} {'budget':>9} {'share':>7}")
        for name, level, b in rows + [("total", "", total)]:
            share = f"{100.0 * b / hb:6.1f}%" if hb > 0 else "      -"
            out.append(f"  {name:<{width}}  {level:<6} {fmt_ns(b):>9} {share}")
        slack = hb - total
        out.append(f"  {'slack' if slack >= 0 else 'OVERRUN':<{width}}  {'':<6} {fmt_ns(abs(slack)):>9}")
        out.append("")
    return "\n".join(out)


def check(design: Design, diags: Diagnostics) -> None:
    if design.controllers and not design.cpus:
        diags.add("E0605", design.span, f"design `{design.name}` has no `cpu`", "no cpu").with_help(
            "add `cpu main { heartbeat 30 ms  schedule A, B, C }`"
        )
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
    for c in design.controllers.values():
        if c.name not in placed:
            diags.add("E0603", c.name_span, f"controller `{c.name}` is not in any CPU schedule", "never runs").with_help(
                f"add `{c.name}` to a `schedule`"
            )

    for cpu in design.cpus.values():
        if cpu.heartbeat_ns <= 0:
            continue
        table = budget_table(design, cpu)
        total = sum(b for _, b in table) + cpu.overhead_ns
        if total > cpu.heartbeat_ns:
            diag = diags.add(
                "E0600",
                cpu.heartbeat_span or cpu.name_span,
                f"cpu `{cpu.name}` needs {fmt_ns(total)} per cycle but its heartbeat is {fmt_ns(cpu.heartbeat_ns)}",
                "heartbeat too short",
            )
            rows = ", ".join(f"{n} {fmt_ns(b)}" for n, b in table)
            diag.with_note(f"budgets: {rows}" + (f", overhead {fmt_ns(cpu.overhead_ns)}" if cpu.overhead_ns else ""))

    for c in design.controllers.values():
        if c.cpu is None:
            continue
        period = design.cpus[c.cpu].heartbeat_ns
        if period <= 0:
            continue
        for span, ns in _durations(c):
            if ns % period:
                cycles = -(-ns // period)
                diags.add("W0601", span, f"{fmt_ns(ns)} is not a whole number of {fmt_ns(period)} cycles", f"rounds up to {cycles} cycles").with_help(
                    f"write `{fmt_ns(cycles * period)}` to say what happens"
                )

    _check_harmonic(design, diags)


def _durations(c: m.Controller):
    exprs = []
    for stmts in [c.pre, c.post] + [r.jobs for p in c.plans.values() for r in p.rules]:
        for s in m.walk_stmts(stmts):
            exprs.extend(m.stmt_exprs(s))
    for p in c.plans.values():
        exprs.extend(r.guard for r in p.rules if r.guard is not None)
    seen = set()
    for e in exprs:
        for x in m.walk_expr(e):
            if isinstance(x, m.Const) and x.type == DURATION and isinstance(x.value, int) and x.value > 0:
                key = (x.span.start, x.span.end)
                if key not in seen:
                    seen.add(key)
                    yield x.span, x.value


def _check_harmonic(design: Design, diags: Diagnostics) -> None:
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
