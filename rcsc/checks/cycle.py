"""The design's own numbers against its cycle: period constants and extern budgets.

W0610 a period constant that is not the heartbeat
    Plant models and filters integrate with a constant time step (`DT =
    0.03`, in seconds, or a duration).  Used by a controller whose CPU beats
    at another period, every integration is off by the ratio.  A constant
    counts as a period when its name says so (DT, TS, PERIOD, CYCLE,
    SAMPLE_TIME, TICK, or ending in _DT or _PERIOD), and it is reported at
    each controller that uses it, once per controller.
E0611 an extern's budget does not fit in the calling controller's budget
    An `extern fn` declares its worst-case time (`budget 5 us`).  One call of
    an extern that takes longer than the whole step of the controller that
    calls it, or the externs that `pre` and `post` call in every cycle
    together, cannot fit in the controller's declared budget.
"""

from __future__ import annotations

import re

from rcsc.semantics import model as m
from rcsc.checks.timing import fmt_ns
from rcsc.diagnostics import Diagnostics
from rcsc.semantics.model import Design
from rcsc.semantics.types import DURATION, FloatType

_PERIOD_NAME = re.compile(r"^(DT|TS|PERIOD|CYCLE|CYCLE_TIME|SAMPLE_TIME|TICK)$|_(DT|PERIOD)$", re.I)


def check(design: Design, diags: Diagnostics) -> None:
    for c in m.checked_controllers(design):
        cpu = design.cpus.get(c.cpu) if c.cpu else None
        exprs = list(_controller_exprs(c))  # walked once for both questions
        if cpu is not None and cpu.heartbeat_ns > 0:
            _period_constants(design, c, cpu, diags, exprs)
        _extern_budgets(design, c, diags, exprs)


def _exprs(c: m.Controller, stmts: list[m.Stmt]):
    for s in m.walk_stmts(stmts):
        for e in m.stmt_exprs(s):
            yield from m.walk_expr(e)


def _controller_exprs(c: m.Controller):
    yield from _exprs(c, c.pre)
    yield from _exprs(c, c.post)
    for plan in c.plans.values():
        for r in plan.rules:
            if r.guard is not None:
                yield from m.walk_expr(r.guard)
            yield from _exprs(c, r.jobs)


def _as_ns(const: m.ConstDef) -> float | None:
    if const.type == DURATION and isinstance(const.value, int):
        return float(const.value)
    if isinstance(const.type, FloatType) and isinstance(const.value, (int, float)):
        return float(const.value) * 1e9
    return None


def _period_constants(design: Design, c: m.Controller, cpu: m.Cpu, diags: Diagnostics, exprs: list[m.Expr]) -> None:
    seen: set[str] = set()
    for e in exprs:
        if not isinstance(e, m.Const) or e.name is None or e.name in seen or not _PERIOD_NAME.search(e.name):
            continue
        const = design.consts.get(e.name)
        ns = _as_ns(const) if const is not None else None
        if ns is None or ns <= 0:
            continue
        seen.add(e.name)
        if abs(ns - cpu.heartbeat_ns) <= 1e-6 * cpu.heartbeat_ns:
            continue
        shown = fmt_ns(round(ns)) if ns == int(ns) else f"{ns / 1e9:g} s"
        diag = diags.add("W0610", e.span, f"`{e.name}` ({shown}) is used as the cycle period by `{c.name}`, whose CPU `{cpu.name}` beats every {fmt_ns(cpu.heartbeat_ns)}", "not the heartbeat")
        diag.with_label(const.span, "declared here")  # type: ignore[union-attr]
        diag.with_note(f"a time step that is not the period `{c.name}` runs at makes every integration off by {ns / cpu.heartbeat_ns:.4g} times")
        diag.with_help(f"make `{e.name}` equal to the heartbeat ({fmt_ns(cpu.heartbeat_ns)}), or change the heartbeat")


def _extern_budgets(design: Design, c: m.Controller, diags: Diagnostics, exprs: list[m.Expr]) -> None:
    def calls(exprs):
        return [e for e in exprs if isinstance(e, m.Call) and e.kind == "extern" and e.func in design.functions]

    for call in calls(exprs):
        fn = design.functions[call.func]
        if fn.budget_ns > c.budget_ns:
            diag = diags.add("E0611", call.span, f"`{call.func}` takes up to {fmt_ns(fn.budget_ns)}, more than the whole budget of `{c.name}` ({fmt_ns(c.budget_ns)})", "does not fit")
            diag.with_label(fn.span, f"budget {fmt_ns(fn.budget_ns)}")
            diag.with_help(f"raise the budget of `{c.name}`, or call `{call.func}` from a controller with room for it")
            return
    every = calls(list(_exprs(c, c.pre)) + list(_exprs(c, c.post)))
    total = sum(design.functions[x.func].budget_ns for x in every)
    if every and total > c.budget_ns:
        diag = diags.add("E0611", every[0].span, f"the externs that `pre` and `post` of `{c.name}` call every cycle take up to {fmt_ns(total)}, more than its budget ({fmt_ns(c.budget_ns)})", "does not fit")
        for x in every[1:]:
            diag.with_label(x.span, f"`{x.func}`: {fmt_ns(design.functions[x.func].budget_ns)}")
        diag.with_help(f"raise the budget of `{c.name}`, or call fewer externs every cycle")
