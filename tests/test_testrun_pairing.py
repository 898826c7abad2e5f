"""`rcsc test`: which scenarios belong to which design (rcsc.sim.testrun).

One design in a folder owns every scenario beside it; where several designs
share a folder, a scenario belongs to the design whose name starts its own
(`relay.rcs` owns `relay_stop.scn`), and one that no design claims is
reported instead of being run against every design or skipped in silence."""

from __future__ import annotations

import shutil
from pathlib import Path

from rcsc.cli import main
from rcsc.sim.testrun import design_of, discover, scenarios_of

ROOT = Path(__file__).resolve().parent.parent
SUBMARINE = ROOT / "examples/submarine/submarine.rcs"
MC = ROOT / "tests" / "mc"


def _folder(tmp_path: Path) -> Path:
    two = tmp_path / "two"
    (two / "scenarios").mkdir(parents=True)
    for name in ("relay.rcs", "relay_run.scn", "relay_stop.scn", "single.rcs", "single_run.scn"):
        shutil.copy(MC / name, two / name)
    shutil.copy(MC / "single_stop.scn", two / "scenarios" / "single-stop.scn")
    (two / "orphan.scn").write_text("cycles 3\n")
    return two


def test_several_designs_in_a_folder_own_the_scenarios_named_after_them(tmp_path: Path) -> None:
    two = _folder(tmp_path)
    assert [Path(s).name for s in scenarios_of(str(two / "relay.rcs"))] == ["relay_run.scn", "relay_stop.scn"]
    assert [Path(s).name for s in scenarios_of(str(two / "single.rcs"))] == ["single_run.scn", "single-stop.scn"]
    assert design_of(str(two / "relay_stop.scn")) == str(two / "relay.rcs")
    assert design_of(str(two / "scenarios" / "single-stop.scn")).endswith("two/single.rcs")
    assert design_of(str(two / "orphan.scn")) is None
    plan, problems = discover([str(two)])
    assert [(Path(d).name, len(s)) for d, s in plan] == [("relay.rcs", 2), ("single.rcs", 2)]
    assert problems == [f"{two / 'orphan.scn'}: no design beside it is named like `orphan` (`NAME.rcs` owns `NAME.scn` and `NAME_*.scn`)"]


def test_one_design_owns_every_scenario_beside_it(tmp_path: Path) -> None:
    one = tmp_path / "one"
    one.mkdir()
    shutil.copy(MC / "relay.rcs", one / "relay.rcs")
    shutil.copy(MC / "relay_run.scn", one / "anything.scn")
    assert [Path(s).name for s in scenarios_of(str(one / "relay.rcs"))] == ["anything.scn"]
    assert design_of(str(one / "anything.scn")) == str(one / "relay.rcs")


def test_rcsc_test_runs_each_scenario_once_against_its_design(tmp_path: Path, capsys) -> None:
    two = _folder(tmp_path)
    (two / "orphan.scn").unlink()
    assert main(["test", str(two)]) == 0
    out = capsys.readouterr().out
    assert out.count("PASS ") == 4 and out.endswith("4 passed, 0 failed\n"), out


def test_a_scenario_kept_elsewhere_runs_on_the_design_named_with_it(tmp_path: Path) -> None:
    """`rcsc test plant.rcs soak/long.scn`: the scenario has no design beside
    it, and exactly one design is named, so it runs on that one (with the
    design's own scenarios); with no design or two named it is reported."""
    plant = tmp_path / "plant"
    plant.mkdir()
    design = plant / "submarine.rcs"
    design.write_text(SUBMARINE.read_text(encoding="utf-8"), encoding="utf-8")
    (plant / "init.scn").write_text("cycles 12\nat 1: SM.INIT()\nexpect within 1..12: SM.done\n", encoding="utf-8")
    soak = tmp_path / "soak"
    soak.mkdir()
    far = soak / "far.scn"
    far.write_text("cycles 12\nat 1: SM.INIT()\nexpect at 2: SM.done\n", encoding="utf-8")
    found, problems = discover([str(design), str(far)])
    assert problems == [] and found == [(str(design), sorted([str(plant / "init.scn"), str(far)]))]
    other = tmp_path / "other"
    other.mkdir()
    (other / "o.rcs").write_text(SUBMARINE.read_text(encoding="utf-8"), encoding="utf-8")
    for paths in ([str(far)], [str(design), str(other / "o.rcs"), str(far)]):
        found, problems = discover(paths)
        assert all(str(far) not in ss for _, ss in found)
        assert len(problems) == 1 and "no design for it" in problems[0] and "rcsc test DESIGN.rcs" in problems[0]


def test_the_design_named_with_a_scenario_wins_over_the_one_beside_it(tmp_path: Path) -> None:
    """`rcsc test plant.rcs other/s.scn` where `other/` has a design of its
    own: the scenario runs on the design named with it, as asked."""
    plant, other = tmp_path / "plant", tmp_path / "other"
    plant.mkdir()
    other.mkdir()
    named = plant / "submarine.rcs"
    named.write_text(SUBMARINE.read_text(encoding="utf-8"), encoding="utf-8")
    (other / "o.rcs").write_text(SUBMARINE.read_text(encoding="utf-8"), encoding="utf-8")
    scn = other / "s.scn"
    scn.write_text("cycles 3\nat 1: SM.INIT()\n", encoding="utf-8")
    found, problems = discover([str(named), str(scn)])
    assert problems == [] and found == [(str(named), [str(scn)])]
