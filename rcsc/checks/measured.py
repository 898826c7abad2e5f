"""Measured step times beside the declared budgets (`rcsc budget --measured`).

A compiled Main Program run with `--timing-out RUN.json` writes, per
scheduled controller, the worst and mean time of its steps per (verb, state,
rule): the running plan's verb after the step, the state the step began in
("new" when it took a new command) and the rule that fired ("" for a step
in which none fired).  `rcsc budget --callgrind` writes the same file with
instruction counts instead of nanoseconds (`"unit": "insn"`).  This module
reads such files, checks them against the design (E0841) and flags every
(verb, state, rule) whose worst case exceeds the controller's budget
(E0840); a scheduled controller the runs never stepped is W0841.
The file format is documented in docs/backends.md ("Performance").
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

from rcsc.checks.frames import fmt_ns
from rcsc.diagnostics import Diagnostics
from rcsc.front.source import SourceFile, Span
from rcsc.semantics.model import Design

FORMAT = "rcs-timing-1"
UNITS = ("ns", "insn")


@dataclass
class RuleTiming:
    verb: str
    state: str
    rule: str
    steps: int
    max: int
    mean: int


@dataclass
class CtrlTiming:
    name: str
    steps: int
    max: int
    rules: list[RuleTiming] = field(default_factory=list)


@dataclass
class Run:
    """One run file: one CPU's Main Program."""

    path: str
    design: str
    cpu: str
    unit: str
    cycles: int
    controllers: list[CtrlTiming]
    source: SourceFile


def _int(x: object) -> int:
    if isinstance(x, bool) or not isinstance(x, int) or x < 0:
        raise ValueError(f"expected a whole number, not {json.dumps(x)}")
    return x


def _str(x: object) -> str:
    if not isinstance(x, str):
        raise ValueError(f"expected a string, not {json.dumps(x)}")
    return x


def parse_run(path: str, text: str, diags: Diagnostics) -> Run | None:
    """A run file, or None after an E0841."""
    source = SourceFile(path, text)
    span = Span(source, 0, min(len(text), 1))
    try:
        doc = json.loads(text)
        if not isinstance(doc, dict) or doc.get("format") != FORMAT:
            raise ValueError(f'not a run file (its "format" must be "{FORMAT}")')
        unit = _str(doc.get("unit"))
        if unit not in UNITS:
            raise ValueError(f'unknown "unit" {json.dumps(unit)} (one of {", ".join(UNITS)})')
        ctrls = []
        raw = doc.get("controllers")
        if not isinstance(raw, list):
            raise ValueError('"controllers" must be a list')
        for c in raw:
            if not isinstance(c, dict):
                raise ValueError("a controller must be an object")
            rules = []
            for r in c.get("rules", []):
                if not isinstance(r, dict):
                    raise ValueError("a rule must be an object")
                rules.append(RuleTiming(_str(r.get("verb")), _str(r.get("state")), _str(r.get("rule")), _int(r.get("steps")),
                                        _int(r.get(f"max_{unit}")), _int(r.get(f"mean_{unit}"))))
            ctrls.append(CtrlTiming(_str(c.get("name")), _int(c.get("steps")), _int(c.get(f"max_{unit}")), rules))
        return Run(path, _str(doc.get("design")), _str(doc.get("cpu")), unit, _int(doc.get("cycles")), ctrls, source)
    except (ValueError, RecursionError) as e:
        diags.add("E0841", span, f"`{path}` is not a readable run file: {e}", "here").with_help(
            "write one with the compiled Main Program's `--timing-out RUN.json`, or `rcsc budget --callgrind`")
        return None


def to_ns(value: int, unit: str, ns_per_insn: float) -> int:
    return value if unit == "ns" else int(round(value * ns_per_insn))


def _rule_span(design: Design, ctrl: str, t: RuleTiming) -> Span | None:
    c = design.controllers[ctrl]
    plan = c.plans.get(t.verb)
    if plan is not None and t.rule:
        for r in plan.rules:
            if r.label == t.rule:
                return r.label_span
    return c.budget_span or c.name_span


def _what(ctrl: str, t: RuleTiming) -> str:
    where = f"plan {t.verb}, " if t.verb else ""
    if t.rule:
        return f"rule `{t.rule}` of `{ctrl}` ({where}state {t.state})"
    return f"a step of `{ctrl}` in which no rule fired ({where}state {t.state or '-'})"


def _fmt(value: int, unit: str) -> str:
    return fmt_ns(value) if unit == "ns" else f"{value} insn"


def check(design: Design, runs: list[Run], diags: Diagnostics, ns_per_insn: float) -> None:
    """E0841 for a run of another design or of a controller it does not have;
    E0840 per (verb, state, rule) whose worst case exceeds the budget; W0841
    for a scheduled controller that no run stepped."""
    measured: set[str] = set()
    for run in runs:
        span = design.span
        if run.design != design.name:
            diags.add("E0841", span, f"`{run.path}` is a run of design `{run.design}`, not `{design.name}`", "another design")
            continue
        for ct in run.controllers:
            if ct.name not in design.controllers:
                diags.add("E0841", span, f"`{run.path}` measures `{ct.name}`, which design `{design.name}` does not have", "unknown controller")
                continue
            if ct.steps:
                measured.add(ct.name)
            budget = design.controllers[ct.name].budget_ns
            for t in ct.rules:
                worst = to_ns(t.max, run.unit, ns_per_insn)
                if budget > 0 and worst > budget:
                    shown = _fmt(t.max, run.unit) + (f" (= {fmt_ns(worst)} at {ns_per_insn:g} ns per instruction)" if run.unit != "ns" else "")
                    diags.add("E0840", _rule_span(design, ct.name, t),
                              f"{_what(ct.name, t)} took up to {shown}, over the budget of {fmt_ns(budget)}",
                              "worst case over the budget").with_note(
                        f"measured in `{run.path}`: {t.steps} step{'s' if t.steps != 1 else ''}, mean {_fmt(t.mean, run.unit)}"
                    ).with_help(f"make the rule's work lighter, or raise the budget of `{ct.name}` (and check the CPU still fits: `rcsc budget`)")
    if any(r.design == design.name for r in runs):
        for cpu in design.cpus.values():
            if not any(r.cpu == cpu.name for r in runs if r.design == design.name):
                continue
            for use in cpu.schedule:
                if use.name not in measured:
                    diags.add("W0841", use.span, f"`{use.name}` was never stepped in the measured runs", "no measurement").with_help(
                        "run a scenario that exercises it (a controller due every N cycles needs at least one of them)")


def format_table(design: Design, runs: list[Run], ns_per_insn: float) -> str:
    """Per run: each controller's budget and measured worst case, then per
    (verb, state, rule) its steps, worst and mean, with OVER where the worst
    case exceeds the budget."""
    out = []
    for run in runs:
        unit = "ns" if run.unit == "ns" else "insn"
        conv = f", {ns_per_insn:g} ns per instruction" if unit == "insn" else ""
        out.append(f"cpu {run.cpu}: measured in {run.path} ({run.cycles} cycles, {'wall-clock time' if unit == 'ns' else 'instruction counts'}{conv})")
        rows = []
        for ct in run.controllers:
            c = design.controllers.get(ct.name)
            budget = c.budget_ns if c else 0
            rows.append((ct.name, "", "", fmt_ns(budget) if budget else "-", str(ct.steps), _fmt(ct.max, unit), "",
                         _verdict(to_ns(ct.max, unit, ns_per_insn), budget, ct.steps)))
            for t in ct.rules:
                rows.append(("  " + (t.rule or "(no rule)"), t.verb or "-", t.state or "-", "", str(t.steps), _fmt(t.max, unit),
                             _fmt(t.mean, unit), _verdict(to_ns(t.max, unit, ns_per_insn), budget, t.steps)))
        head = ("controller / rule", "verb", "state", "budget", "steps", "worst", "mean", "")
        widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]
        for r in [head, *rows]:
            cells = [r[0].ljust(widths[0]), r[1].ljust(widths[1]), r[2].ljust(widths[2])] + [r[i].rjust(widths[i]) for i in range(3, 7)] + [r[7]]
            out.append(("  " + "  ".join(cells)).rstrip())
        out.append("")
    return "\n".join(out)


def _verdict(worst_ns: int, budget: int, steps: int) -> str:
    if not steps or budget <= 0:
        return ""
    return f"OVER by {fmt_ns(worst_ns - budget)}" if worst_ns > budget else f"{100.0 * worst_ns / budget:.1f}%"
