"""Frames and rate groups of a CPU: what `rcsc budget` prints and the frame rule checks.

A controller with divider n steps in its CPU's cycles 1, 1 + n, 1 + 2n, ...
Over the hyperperiod (the least common multiple of the dividers on the CPU)
the set of controllers due in a cycle repeats; a *frame* is one such cycle,
and its worst case is the sum of the budgets of the controllers due in it
plus the CPU's overhead.  The frame rule: every frame fits in the heartbeat.
Because every controller steps in cycle 1, cycle 1 is always the heaviest
frame; dividing a rate lowers the CPU's utilisation (the average load), not
its worst frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import lcm

from rcsc.semantics import model as m
from rcsc.semantics.model import Design

# A CPU whose dividers have a larger least common multiple is summarised by
# its frame of cycle 1 only (the heaviest), so the table stays readable.
MAX_LISTED_CYCLES = 10_000


def fmt_ns(ns: int) -> str:
    """A duration in the largest unit that is at least 1, exact (3 decimals reach the next unit)."""
    sign = "-" if ns < 0 else ""
    ns = abs(ns)
    for unit, scale in (("s", 1_000_000_000), ("ms", 1_000_000), ("us", 1_000)):
        if ns >= scale and ns % (scale // 1000) == 0:
            text = f"{ns / scale:.3f}".rstrip("0").rstrip(".") if ns % scale else str(ns // scale)
            return f"{sign}{text} {unit}"
    return f"{sign}{ns} ns"


@dataclass
class Frame:
    """The cycles of the hyperperiod (numbered from 1) in which the same controllers are due."""

    cycles: list[int]
    controllers: list[str]  # in schedule order
    total_ns: int  # their budgets plus the CPU's overhead


def placed(design: Design, cpu: m.Cpu) -> list[m.Controller]:
    return [design.controllers[u.name] for u in cpu.schedule if u.name in design.controllers]


def hyperperiod(design: Design, cpu: m.Cpu) -> int:
    """The number of cycles after which the pattern of due controllers repeats."""
    return lcm(1, *(c.divider for c in placed(design, cpu)))


def frames(design: Design, cpu: m.Cpu) -> list[Frame]:
    """The distinct frames of the hyperperiod, in order of their first cycle."""
    ctrls = placed(design, cpu)
    cycles = hyperperiod(design, cpu)
    if cycles > MAX_LISTED_CYCLES:
        return [Frame([1], [c.name for c in ctrls], sum(c.budget_ns for c in ctrls) + cpu.overhead_ns)]
    by_set: dict[tuple[str, ...], Frame] = {}
    for k in range(1, cycles + 1):
        due = tuple(c.name for c in ctrls if (k - 1) % c.divider == 0)
        frame = by_set.get(due)
        if frame is None:
            total = sum(design.controllers[n].budget_ns for n in due) + cpu.overhead_ns
            frame = by_set[due] = Frame([], list(due), total)
        frame.cycles.append(k)
    return list(by_set.values())


def worst_frame(design: Design, cpu: m.Cpu) -> Frame:
    return max(frames(design, cpu), key=lambda f: (f.total_ns, -f.cycles[0]))


def _cycle_list(cycles: list[int]) -> str:
    """`cycle 1`, `cycles 2-5, 7-10`, or `cycles 1, 3, ... 9 (every 2)` for a long arithmetic run."""
    if len(cycles) == 1:
        return f"cycle {cycles[0]}"
    steps = {b - a for a, b in zip(cycles, cycles[1:])}
    if len(steps) == 1 and len(cycles) > 3 and steps != {1}:
        step = steps.pop()
        return f"cycles {cycles[0]}, {cycles[0] + step}, ... {cycles[-1]} (every {step})"
    runs: list[list[int]] = []
    for c in cycles:
        if runs and c == runs[-1][1] + 1:
            runs[-1][1] = c
        else:
            runs.append([c, c])
    parts = [f"{a}-{b}" if b > a else str(a) for a, b in runs]
    text = ", ".join(parts[:6]) + (f", ... ({len(cycles)} cycles)" if len(parts) > 6 else "")
    return f"cycles {text}"


def format_budget_table(design: Design) -> str:
    """Per CPU: each controller's budget, period and load; with divided rates, its frames too."""
    out = []
    for cpu in design.cpus.values():
        hb = cpu.heartbeat_ns
        ctrls = placed(design, cpu)
        divided = any(c.divider > 1 for c in ctrls)
        head = f"cpu {cpu.name}: heartbeat {fmt_ns(hb)}"
        if divided:
            n = hyperperiod(design, cpu)
            head += f", hyperperiod {fmt_ns(n * hb)} ({n} cycles)"
        out.append(head)
        rows = [(c.name, str(c.level) + (" sim" if c.simulator else ""), c.budget_ns, c.period_ns or hb) for c in ctrls]
        if cpu.overhead_ns:
            rows.append(("(overhead)", "", cpu.overhead_ns, hb))
        total = sum(r[2] for r in rows)
        load = sum(r[2] / r[3] for r in rows if r[3] > 0)
        width = max([len(r[0]) for r in rows] + [len("controller"), len("total")])
        extra = f" {'period':>9} {'load':>7}" if divided else ""
        out.append(f"  {'controller':<{width}}  {'level':<6} {'budget':>9} {'share':>7}{extra}")
        for name, level, b, period in rows:
            share = f"{100.0 * b / hb:6.1f}%" if hb > 0 else "      -"
            more = f" {fmt_ns(period):>9} {100.0 * b / period:6.1f}%" if divided and period > 0 else ""
            out.append(f"  {name:<{width}}  {level:<6} {fmt_ns(b):>9} {share}{more}")
        more = f" {'':>9} {100.0 * load:6.1f}%" if divided else ""
        share = f"{100.0 * total / hb:6.1f}%" if hb > 0 else "      -"
        out.append(f"  {'total':<{width}}  {'':<6} {fmt_ns(total):>9} {share}{more}")
        if divided and hb > 0:
            out.append("  frames (budgets due in a cycle, plus overhead):")
            listed = frames(design, cpu)
            labels = [_cycle_list(f.cycles) for f in listed]
            verdicts = [f"slack {fmt_ns(hb - f.total_ns)}" if f.total_ns <= hb else f"OVERRUN {fmt_ns(f.total_ns - hb)}" for f in listed]
            lw, vw = max(len(x) for x in labels), max(len(x) for x in verdicts)
            for f, label, verdict in zip(listed, labels, verdicts):
                out.append(f"    {label:<{lw}}  {fmt_ns(f.total_ns):>9}  {verdict:<{vw}}  {', '.join(f.controllers) or '(none due)'}")
        else:
            slack = hb - total
            out.append(f"  {'slack' if slack >= 0 else 'OVERRUN':<{width}}  {'':<6} {fmt_ns(abs(slack)):>9}")
        out.append("")
    return "\n".join(out)
