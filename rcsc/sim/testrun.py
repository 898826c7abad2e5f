"""`rcsc test`: find scenarios, run them, report like a test runner (`run_tests`).

Where scenarios live: `*.scn` files beside a design file or in a
`scenarios/` folder next to it.  A design file is a `.rcs` file that begins
with `design NAME` (after comments).  Paths given on the command line may be
design files, scenario files or folders (searched recursively).
"""

from __future__ import annotations

import os
import re
import time
from dataclasses import dataclass, field
from xml.sax.saxutils import escape, quoteattr

from rcsc.outputs import safeio
from rcsc.diagnostics import Diagnostics
from rcsc.driver import check_path
from rcsc.front.loader import InputError, read_source
from rcsc.sim.runner import RunResult, ScenarioRun
from rcsc.front.scenario import text_to_scenario

_DESIGN_HEADER = re.compile(r"\A(?:\s|//[^\n]*\n|/\*.*?\*/)*design\s", re.S)


def is_design_file(path: str) -> bool:
    if not path.endswith(".rcs"):
        return False
    # Only regular files: a FIFO or device in a design folder must not block
    # or flood the discovery (read_input opens without blocking).
    # The header is ASCII: a cut through a character at the end of the first
    # 64 KiB, or a file of another encoding (reported as E0010 when it is
    # checked), is still a design file.
    try:
        head = safeio.read_input(path)[:65536].decode("utf-8", "replace")
    except OSError:
        return False
    return bool(_DESIGN_HEADER.match(head))


def _stem(path: str) -> str:
    return os.path.basename(path).rsplit(".", 1)[0]


def _claims(design: str, scenario: str) -> bool:
    """Whether a design's name claims a scenario in a folder shared by
    several designs: `relay.rcs` claims `relay.scn` and `relay_stop.scn`."""
    d, s = _stem(design), _stem(scenario)
    return s == d or s.startswith(d + "_") or s.startswith(d + "-")


def _owner(designs: list[str], scenario: str) -> str | None:
    """The design of `designs` (all in one folder) that a scenario beside
    them belongs to: the only one, or among several the one whose name
    starts the scenario's name (the longest such name)."""
    if len(designs) == 1:
        return designs[0]
    claiming = [d for d in designs if _claims(d, scenario)]
    return max(claiming, key=lambda d: len(_stem(d))) if claiming else None


def _scenario_files(folder: str) -> list[str]:
    """The `*.scn` files beside a design in `folder` and in `folder/scenarios`."""
    found = []
    for where in (folder, os.path.join(folder, "scenarios")):
        if os.path.isdir(where):
            found += [os.path.join(where, f) for f in sorted(os.listdir(where)) if f.endswith(".scn")]
    return found


def _designs_in(folder: str) -> list[str]:
    return [os.path.join(folder, f) for f in sorted(os.listdir(folder)) if is_design_file(os.path.join(folder, f))]


def scenarios_of(design_path: str) -> list[str]:
    """The scenarios of a design: `*.scn` beside it or in `scenarios/` next
    to it; in a folder with several designs, those its name claims
    (`relay_stop.scn` is `relay.rcs`'s)."""
    folder = os.path.dirname(design_path) or "."
    designs = [design_path]
    if os.path.isdir(folder):
        others = [d for d in _designs_in(folder) if os.path.basename(d) != os.path.basename(design_path)]
        designs += others
    return [s for s in _scenario_files(folder) if _owner(designs, s) is designs[0]]


def design_of(scenario_path: str) -> str | None:
    """The design a scenario belongs to: the one design file in its folder or
    the folder above, or among several there the one whose name starts the
    scenario's name."""
    folder = os.path.dirname(scenario_path) or "."
    for where in (folder, os.path.dirname(os.path.abspath(folder))):
        designs = _designs_in(where)
        if not designs:
            continue
        owner = _owner(designs, scenario_path)
        if owner is not None:
            return owner if where == folder else os.path.relpath(owner)
        return None
    return None


def discover(paths: list[str]) -> tuple[list[tuple[str, list[str]]], list[str]]:
    """[(design, [scenario, ...])] in a stable order, and problems found on the way."""
    plan: dict[str, list[str]] = {}
    problems: list[str] = []
    unclaimed: list[str] = []  # scenarios beside several designs that none of them claims
    # A scenario named with exactly one design runs on that design
    # (`rcsc test plant.rcs soak/long.scn`), whatever lies beside it.
    named = [p for p in paths if not p.endswith(".scn") and os.path.isfile(p)]
    named_design = named[0] if len(named) == 1 else None
    for p in paths:
        if os.path.isdir(p):
            for root, dirs, files in os.walk(p):
                dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in ("__pycache__", "node_modules"))
                claimed: set[str] = set()
                designs = [os.path.join(root, f) for f in sorted(files) if is_design_file(os.path.join(root, f))]
                for full in designs:
                    mine = scenarios_of(full)
                    plan.setdefault(full, []).extend(mine)
                    claimed.update(mine)
                if len(designs) > 1:  # with one design every scenario beside it is its own
                    orphans = [s for s in _scenario_files(root) if s not in claimed]
                    unclaimed += orphans
                    problems += [f"{o}: no design beside it is named like `{_stem(o)}` (`NAME.rcs` owns `NAME.scn` and `NAME_*.scn`)"
                                 for o in orphans]
        elif p.endswith(".scn") and os.path.isfile(p):
            d = named_design or design_of(p)
            if d is None:
                problems.append(f"{p}: no design for it: no design file beside it or in the folder above, "
                                f"or several and none named like `{_stem(p)}` (`NAME.rcs` owns `NAME.scn` and `NAME_*.scn`); "
                                f"name the design with it: `rcsc test DESIGN.rcs {p}`")
            else:
                plan.setdefault(d, []).append(p)
        elif os.path.isfile(p):
            plan.setdefault(p, []).extend(scenarios_of(p))
        else:
            problems.append(f"{p}: no such file or folder")
    # One entry per file however it was reached (`a.scn` named and `./a.scn`
    # found beside `a.rcs` are one scenario, run once).
    merged: dict[str, set[str]] = {}
    for d, ss in plan.items():
        merged.setdefault(os.path.normpath(d), set()).update(os.path.normpath(s) for s in ss)
    found = [(d, sorted(ss)) for d, ss in merged.items()]
    # Every design and scenario found is an input of the run, read or not
    # (a design with errors stops before its scenarios are read): no report
    # (`--junit`) may replace one.
    safeio.claim_inputs([d for d, _ in found] + [s for _, ss in found for s in ss] + unclaimed)
    return found, problems


@dataclass
class Outcome:
    design: str
    scenario: str
    passed: bool
    seconds: float
    cycles: int = 0
    message: str = ""  # failure report (several lines) or error text
    diags: Diagnostics | None = None
    result: RunResult | None = None
    # Warnings to show even when the scenario passes (the externs file's
    # W0830), on the first scenario of the design only.
    notes: Diagnostics | None = None


@dataclass
class Report:
    outcomes: list[Outcome] = field(default_factory=list)

    @property
    def failed(self) -> int:
        return sum(not o.passed for o in self.outcomes)

    @property
    def passed(self) -> int:
        return sum(o.passed for o in self.outcomes)


def failure_text(result: RunResult) -> str:
    lines = []
    for r in result.results:
        if r.passed:
            continue
        x = r.expect
        when = {"at": f"at {x.lo}", "within": f"within {x.lo}..{x.hi}", "always": "always", "final": "final"}[x.kind]
        lines.append(f"expect {when}: {x.text}")
        lines.append(f"  {x.span.file.path}:{x.span.line}:{x.span.col}")
        unit = "tick" if result.multi_cpu else "cycle"  # several CPUs: scenarios count base ticks
        seen = f"never true in the window; at {unit}" if x.kind == "within" else f"false at {unit}"
        values = ", ".join(f"{k} = {v}" for k, v in r.values) or "(no inputs)"
        lines.append(f"  {seen} {r.cycle}: {values}")
    return "\n".join(lines)


def run_one(design_path: str, scenario_path: str, design_cache: dict, target: str = "sim", build_root: str = "build/rcsc-test",
            externs: str | None = None) -> Outcome:
    """One scenario in the simulator (`target` "sim", with the Python externs
    of the file `externs`, rcsc.sim.externs) or on the design's compiled
    Main Program (`target` "c" or "rust", built under `build_root`)."""
    start = time.perf_counter()
    if design_path not in design_cache:
        try:
            design_cache[design_path] = check_path(design_path)
        except InputError as exc:
            design_cache[design_path] = exc
    checked = design_cache[design_path]
    if isinstance(checked, InputError):
        return Outcome(design_path, scenario_path, False, 0.0, message=str(checked))
    if not checked.ok or checked.model is None:
        return Outcome(design_path, scenario_path, False, 0.0, message="the design has errors (run `rcsc check`)", diags=checked.diags)
    diags = Diagnostics()
    try:
        source, utf8 = read_source(scenario_path, diags)
    except (OSError, InputError) as exc:
        return Outcome(design_path, scenario_path, False, 0.0, message=f"cannot read the scenario: {getattr(exc, 'strerror', None) or exc}")
    sc = text_to_scenario(source, checked.model, diags) if utf8 else None
    if sc is None:
        return Outcome(design_path, scenario_path, False, 0.0, message="the scenario has errors", diags=diags)
    # The scenario's own warnings (W0706, W0707) are shown whether it passes or not.
    notes = diags if diags.items else None
    if target == "sim":
        from rcsc.sim import externs as sim_externs

        key = ("externs", design_path)
        if externs and key not in design_cache:
            loading = Diagnostics()
            design_cache[key] = (sim_externs.load(externs, checked.model, loading), loading)
        made, loading = design_cache.get(key, (None, None))
        if loading is not None and loading.has_errors():
            return Outcome(design_path, scenario_path, False, 0.0, message="the externs file does not load", diags=loading, notes=notes)
        if loading is not None and loading.items and not design_cache.get(("externs shown", design_path)):
            design_cache[("externs shown", design_path)] = True
            if notes is None:
                notes = loading
            else:
                notes.extend(loading)
        try:
            result = ScenarioRun(checked.model, sc, externs=made).run()  # keeps no history: any length
        except sim_externs.ExternCallError as exc:
            failed = Diagnostics()
            exc.report(failed)
            return Outcome(design_path, scenario_path, False, time.perf_counter() - start, message="an extern failed", diags=failed,
                           notes=notes)
    else:
        from pathlib import Path

        from rcsc.sim import compiled

        key = (design_path, target)
        try:
            if key not in design_cache:
                design_cache[key] = compiled.build(checked.model, target, build_root)
            built = design_cache[key]
            if isinstance(built, compiled.CompiledError):
                raise built
            result = compiled.run_compiled(checked.model, sc, built, built.folder / "runs")
        except compiled.CompiledError as exc:
            design_cache.setdefault(key, exc)
            return Outcome(design_path, scenario_path, False, time.perf_counter() - start, message=f"{target}: {exc}", notes=notes)
    seconds = time.perf_counter() - start
    return Outcome(design_path, scenario_path, result.passed, seconds, sc.cycles, "" if result.passed else failure_text(result), result=result,
                   notes=notes)


def _xml_safe(text: str) -> str:
    """`text` with every character that XML 1.0 forbids (most C0 controls,
    U+FFFE/U+FFFF, lone surrogates) shown as a visible `\\xNN` escape, so a
    control byte in a scenario cannot make the report unreadable."""
    out = []
    for ch in text:
        o = ord(ch)
        ok = ch in "\t\n\r" or 0x20 <= o <= 0xD7FF or 0xE000 <= o <= 0xFFFD or 0x10000 <= o <= 0x10FFFF
        out.append(ch if ok else f"\\x{o:02x}" if o < 0x100 else f"\\u{o:04x}")
    return "".join(out)


def _attr(text: str) -> str:
    return quoteattr(_xml_safe(text))


def _is_error(o: Outcome) -> bool:
    """A scenario that could not run (design or scenario with errors, unreadable
    file) is a JUnit `error`; one that ran and missed an expectation a `failure`."""
    return not o.passed and o.result is None


def _error_text(o: Outcome) -> tuple[str, str]:
    """The `message` (the first error, else the outcome's message) and the
    text (the message, then every finding) of an `<error>`."""
    from rcsc.render import render_short

    if o.diags is None or not o.diags.items:
        return (o.message.splitlines() or ["error"])[0], o.message
    errors = [d for d in o.diags.sorted() if d.severity.value == "error"]
    first = render_short(errors[:1] or o.diags.sorted()[:1]).strip()
    return first, o.message + "\n" + render_short(o.diags)


def to_junit(report: Report) -> str:
    """JUnit XML: one testsuite per design, one testcase per scenario.

    A scenario that ran and missed an expectation is a `<failure>`; one that
    could not run is an `<error>` whose message is the first finding and whose
    text lists every finding (`file:line:col: severity[CODE]: message`)."""
    suites: dict[str, list[Outcome]] = {}
    for o in report.outcomes:
        suites.setdefault(o.design, []).append(o)
    errors_total = sum(_is_error(o) for o in report.outcomes)
    out = ['<?xml version="1.0" encoding="UTF-8"?>']
    out.append(
        f'<testsuites name="rcsc" tests="{len(report.outcomes)}" failures="{report.failed - errors_total}" errors="{errors_total}">'
    )
    for design, items in suites.items():
        errs = sum(_is_error(o) for o in items)
        fails = sum(not o.passed for o in items) - errs
        total = sum(o.seconds for o in items)
        out.append(f'  <testsuite name={_attr(design)} tests="{len(items)}" failures="{fails}" errors="{errs}" time="{total:.3f}">')
        for o in items:
            name = os.path.basename(o.scenario)
            out.append(f'    <testcase classname={_attr(design)} name={_attr(name)} file={_attr(o.scenario)} time="{o.seconds:.3f}">')
            if _is_error(o):
                first, body = _error_text(o)
                out.append(f"      <error message={_attr(first)} type=\"rcsc\">{escape(_xml_safe(body))}</error>")
            elif not o.passed:
                first = o.message.splitlines()[0] if o.message else "failed"
                out.append(f"      <failure message={_attr(first)}>{escape(_xml_safe(o.message))}</failure>")
            out.append("    </testcase>")
        out.append("  </testsuite>")
    out.append("</testsuites>")
    return "\n".join(out) + "\n"
