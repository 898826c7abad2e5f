"""The example designs are clean and their scenarios pass.

For every example design (`examples/*/*.rcs` and `tests/designs/*/*.rcs`
that begins with `design`):

- `rcsc check --deny-warnings` exits 0: an example must not teach a warning;
- `rcsc test <its folder>` runs at least three scenarios and passes them all
  (the scenarios are drills an engineer would run; each explains its cycle
  windows in its header comment);

and `rcsc test` really fails a run: a copy of a scenario with one expectation
made false exits 1 and reports the expectation, where it is written and the
cycle it failed at.

All runs are in-process through `rcsc.cli.main`, as CI would call it.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from c_build import example_designs

from rcsc.cli import main
from rcsc.sim.testrun import is_design_file, scenarios_of

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
# The examples, and the designs of tests/designs (c_build.DESIGN_GLOBS):
# written from docs/ alone, as a new user would (a robot work cell, a
# pick-and-place, a tank farm, a mobile robot), held to the same standard.
DESIGNS = [p for p in example_designs() if is_design_file(str(p))]
MIN_SCENARIOS = 3


def test_examples_are_found() -> None:
    names = {p.parent.name for p in DESIGNS}
    assert {"submarine", "machining_cell", "machine_tool"} <= names, names


@pytest.mark.parametrize("design", DESIGNS, ids=lambda p: p.parent.name)
def test_check_is_clean_with_deny_warnings(design: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["check", "--deny-warnings", str(design)])
    out, err = capsys.readouterr()
    assert code == 0, f"rcsc check --deny-warnings {design}: exit {code}\n{out}{err}"


@pytest.mark.parametrize("design", DESIGNS, ids=lambda p: p.parent.name)
def test_every_scenario_passes(design: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scenarios = scenarios_of(str(design))
    assert len(scenarios) >= MIN_SCENARIOS, f"{design.parent.name}: only {len(scenarios)} scenarios: {scenarios}"
    code = main(["test", str(design.parent)])
    out, err = capsys.readouterr()
    assert code == 0, f"rcsc test {design.parent}: exit {code}\n{out}{err}"
    for scn in scenarios:
        assert f"PASS {scn}" in out, f"{scn} did not pass:\n{out}"
    assert f"{len(scenarios)} passed, 0 failed" in out, out


@pytest.mark.parametrize("design", DESIGNS, ids=lambda p: p.parent.name)
def test_scenarios_are_documented(design: Path) -> None:
    """Each scenario opens with a comment saying what it checks, and has a name."""
    for scn in scenarios_of(str(design)):
        text = Path(scn).read_text(encoding="utf-8")
        assert text.startswith("//"), f"{scn}: start with a comment saying what the drill checks and why its windows are what they are"
        assert re.search(r'^scenario "[^"]+"', text, re.M), f"{scn}: give the scenario a display name"


# ---- a false expectation is reported ------------------------------------------

SUBMARINE = EXAMPLES / "submarine" / "submarine.rcs"
BASE = EXAMPLES / "submarine" / "scenarios" / "trip_at_init.scn"

# (what the scenario says, the false version, what `rcsc test` must print:
# the failing cycle, and a value the condition read there)
MUTATIONS = {
    "at": (
        "expect at 4: SM.error and SM.error_code == ERR_PROPULSION and SM.rule == I2",
        "expect at 4: SM.error and SM.error_code == ERR_TURBINE and SM.rule == I2",
        "false at cycle 4",
        "SM.error_code = 31",
    ),
    "within": (  # a window that closes before TB can have spooled up to 57 rpm
        "expect within 165..180: TB.done and approx_eq(turbine_rpm, 57.0, RPM_TOL)",
        "expect within 100..160: TB.done and approx_eq(turbine_rpm, 57.0, RPM_TOL)",
        "never true in the window; at cycle 160",
        "TB.status = EXEC",
    ),
}


@pytest.mark.parametrize("kind", sorted(MUTATIONS))
def test_false_expectation_fails_with_expectation_and_cycle(kind: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    original, false, where, value = MUTATIONS[kind]
    text = BASE.read_text(encoding="utf-8")
    assert original in text, f"{BASE} changed: update MUTATIONS[{kind!r}]"
    shutil.copy(SUBMARINE, tmp_path / SUBMARINE.name)
    (tmp_path / "scenarios").mkdir()
    scn = tmp_path / "scenarios" / BASE.name
    mutated = text.replace(original, false)
    scn.write_text(mutated, encoding="utf-8")
    line = mutated[: mutated.index(false)].count("\n") + 1

    # the unchanged copy passes, so the failure below is the one expectation
    shutil.copy(BASE, tmp_path / "scenarios" / "unchanged.scn")
    assert main(["test", str(tmp_path / "scenarios" / "unchanged.scn")]) == 0, capsys.readouterr().out
    capsys.readouterr()

    code = main(["test", str(scn)])
    out, _ = capsys.readouterr()
    assert code == 1, out
    assert f"FAIL {scn}" in out, out
    assert false in out, out  # the expectation as written
    assert f"{scn}:{line}:1" in out, out  # where it is written
    assert where in out, out  # the cycle it failed at
    assert value in out, out  # what the condition read there
    assert "0 passed, 1 failed" in out, out
