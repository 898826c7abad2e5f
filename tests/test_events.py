"""Event files (docs/events.md) and `rcsc test --target c|rust`.

- `rcsc events` resolves a scenario, computed values included, into ids and
  bit patterns under the design's interface hash;
- a computed scenario value gives the same trace in the simulator, the C
  Main Program and the Rust one;
- a Main Program refuses an event file made for another design;
- `rcsc test --target c|rust` passes every example scenario, and fails
  (exit 1, the expectation shown, a JUnit <failure>) on one made to fail;
  the build is made once and reused.
"""

from __future__ import annotations

import contextlib
import io
import re
import shutil
import struct
import subprocess
from pathlib import Path

import pytest

from c_build import Builds, first_difference, reference_trace

from rcsc import cli

ROOT = Path(__file__).resolve().parent.parent
SUBMARINE = ROOT / "examples/submarine/submarine.rcs"
MACHINE_TOOL = ROOT / "examples/machine_tool/machine_tool.rcs"

COMPUTED = """\
// Computed values: arithmetic on constants, a function call, a duration sum.
cycles 300
at 1: SM.INIT()
at 10: SM.TRANSIT(speed = MAX_AHEAD_KNOTS * 0.75 - abs(-1.5), leg_time = 2 s + 500 ms)
expect at 10: SM.executing
"""


def rcsc(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(list(argv))
    return rc, out.getvalue(), err.getvalue()


def untimed(report: str) -> str:
    return re.sub(r" \(\d+ (cycles|ticks), [\d.]+ s\)", "", report)


@pytest.fixture(scope="module")
def builds(tmp_path_factory) -> Builds:
    return Builds(tmp_path_factory.mktemp("ev_builds"))


def test_events_resolve_names_and_computed_values(tmp_path: Path) -> None:
    scn = tmp_path / "computed.scn"
    scn.write_text(COMPUTED, encoding="utf-8")
    rc, text, err = rcsc("events", str(SUBMARINE), str(scn))
    assert (rc, err) == (0, "")
    lines = text.splitlines()
    magic, version, design, digest = lines[0].split(" ")
    assert (magic, version, design, len(digest)) == ("rcsc-events", "1", "submarine", 16)
    assert lines[1] == "cycles 300"
    # SM is controller 0; INIT its verb 2, TRANSIT its verb 0 (declaration order)
    assert lines[2] == "command 1 0 2 0"
    kw, tick, ctrl, verb, n, speed, leg = lines[3].split(" ")
    assert (kw, tick, ctrl, verb, n) == ("command", "10", "0", "0", "2")
    assert struct.unpack("<d", int(speed, 16).to_bytes(8, "little"))[0] == 24.0 * 0.75 - 1.5
    assert int(leg, 16) == 2_500_000_000
    assert lines[4:] == ["end 2"]
    # the same file twice: deterministic; -o writes it
    out = tmp_path / "c.events"
    assert rcsc("events", str(SUBMARINE), str(scn), "-o", str(out))[0] == 0
    assert out.read_text(encoding="utf-8") == text


def test_events_refuses_a_bad_scenario_with_its_diagnostics(tmp_path: Path) -> None:
    scn = tmp_path / "bad.scn"
    scn.write_text("cycles 5\nat 1: PR.AHEAD(speed = 3.0)\n", encoding="utf-8")
    rc, out, err = rcsc("events", str(SUBMARINE), str(scn), "-o", str(tmp_path / "x.events"))
    assert rc == 1 and out == ""
    assert "error[E0700]" in err and "bad.scn:2:7" in err
    assert not (tmp_path / "x.events").exists()


def test_computed_value_same_trace_in_sim_c_and_rust(builds: Builds, tmp_path: Path) -> None:
    scn = tmp_path / "computed.scn"
    scn.write_text(COMPUTED, encoding="utf-8")
    events = tmp_path / "computed.events"
    assert rcsc("events", str(SUBMARINE), str(scn), "-o", str(events))[0] == 0
    want = reference_trace(SUBMARINE, scn)
    assert b'"verb":"TRANSIT"' in want
    for exe in (builds.c_binary(SUBMARINE, "gcc-O2"), builds.rust_binary(SUBMARINE, "debug")):
        trace = tmp_path / f"{exe.name}.jsonl"
        r = subprocess.run([str(exe), "--fast", "--no-console", "--no-timing", "--scenario", str(events), "--trace", str(trace)],
                           capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
        assert (r.returncode, r.stderr) == (0, "")
        got = trace.read_bytes()
        assert got == want, first_difference(want, got)


def test_a_main_program_refuses_another_designs_event_file(builds: Builds, tmp_path: Path) -> None:
    events = tmp_path / "mt.events"
    scn = ROOT / "examples/machine_tool/scenarios/spindle_hangs.scn"
    assert rcsc("events", str(MACHINE_TOOL), str(scn), "-o", str(events))[0] == 0
    for exe in (builds.c_binary(SUBMARINE, "gcc-O2"), builds.rust_binary(SUBMARINE, "debug")):
        r = subprocess.run([str(exe), "--fast", "--no-console", "--scenario", str(events)], capture_output=True, text=True, timeout=60)
        assert r.returncode == 2
        assert r.stderr.startswith(f"{events}:1: error: the event file is for design `machine_tool`"), r.stderr
        assert "rcsc events" in r.stderr


@pytest.mark.parametrize("target", ["c", "rust"])
def test_every_example_scenario_passes_on_the_compiled_program(target: str, tmp_path: Path) -> None:
    builds = tmp_path / "b"
    junit = tmp_path / "junit.xml"
    rc, out, _ = rcsc("test", "--target", target, "--build-dir", str(builds), "--junit", str(junit), str(ROOT / "examples"))
    n = len(list(ROOT.glob("examples/*/scenarios/*.scn")))
    assert rc == 0, out
    assert out.count("PASS ") == n and out.endswith(f"{n} passed, 0 failed\n"), out
    assert f'tests="{n}" failures="0" errors="0"' in junit.read_text(encoding="utf-8")


@pytest.mark.parametrize("target", ["c", "rust", "ada"])
def test_expectations_see_what_the_simulator_sees_on_every_target(target: str, tmp_path: Path) -> None:
    """Negative zero keeps its sign from the program's trace to the
    expectations (JSON reads `-0` as the integer 0), and array arguments of
    types and blocks take their parameters' element types: the same
    expectations pass in the simulator and on each compiled target."""
    design = ROOT / "tests/params/array_params.rcs"
    sim = rcsc("test", str(design))
    assert sim[0] == 0 and sim[1].endswith("1 passed, 0 failed\n"), sim[1]
    rc, out, _ = rcsc("test", "--target", target, "--build-dir", str(tmp_path / "b"), str(design))
    assert rc == 0, out
    assert untimed(out) == untimed(sim[1])


@pytest.mark.parametrize("target", ["c", "rust"])
def test_a_relative_build_dir_builds_and_runs(target: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`rcsc test --target rust` with a relative build folder (the default is
    `build/rcsc-test`) found no program: cargo ran inside the build folder and
    took the relative CARGO_TARGET_DIR from there."""
    monkeypatch.chdir(tmp_path)
    rc, out, _ = rcsc("test", "--target", target, "--build-dir", "b", str(ROOT / "tests/params/array_params.rcs"))
    assert rc == 0 and out.endswith("1 passed, 0 failed\n"), out
    assert not list((tmp_path / "b").glob("*/b")), "nothing is built inside the build folder"


def test_a_failing_scenario_fails_on_c_and_rust_and_the_build_is_reused(tmp_path: Path) -> None:
    folder = tmp_path / "sub"
    (folder / "scenarios").mkdir(parents=True)
    shutil.copy(SUBMARINE, folder / "submarine.rcs")
    bad = folder / "scenarios" / "made_to_fail.scn"
    bad.write_text("cycles 12\nat 1: SM.INIT()\nexpect at 4: SM.done and ship_speed > 1.0\n", encoding="utf-8")
    good = folder / "scenarios" / "init.scn"
    good.write_text("cycles 12\nat 1: SM.INIT()\nexpect within 1..12: SM.done\n", encoding="utf-8")
    builds = tmp_path / "b"
    sim = rcsc("test", str(folder))
    for target in ("c", "rust"):
        junit = tmp_path / f"{target}.xml"
        rc, out, _ = rcsc("test", "--target", target, "--build-dir", str(builds), "--junit", str(junit), str(folder))
        assert rc == 1, out
        assert f"FAIL {bad}" in out and f"PASS {good}" in out
        assert "    expect at 4: SM.done and ship_speed > 1.0\n" in out
        assert f"    {bad}:3:1\n      false at cycle 4: SM.status = DONE, ship_speed = 0\n" in out
        assert out.endswith("1 passed, 1 failed\n")
        assert untimed(out) == untimed(sim[1]), "the same report as the simulator's"
        xml = junit.read_text(encoding="utf-8")
        assert 'failures="1" errors="0"' in xml and '<failure message="expect at 4: SM.done and ship_speed &gt; 1.0">' in xml
    # one build folder per target, reused by a second run
    made = sorted(p.name for p in builds.iterdir())
    assert len(made) == 2 and made[0].startswith("submarine-c-") and made[1].startswith("submarine-rust-")
    c_program = next((builds / made[0]).glob("submarine_MAIN"))
    stamp = c_program.stat().st_mtime_ns
    rc, out, _ = rcsc("test", "--target", "c", "--build-dir", str(builds), str(good))
    assert rc == 0 and out.endswith("1 passed, 0 failed\n")
    assert c_program.stat().st_mtime_ns == stamp


def test_a_deployment_build_has_its_own_ids_and_hash(tmp_path: Path) -> None:
    """Without the simulators the controller ids and the interface hash are the deployment build's."""
    scn = tmp_path / "s.scn"
    scn.write_text("cycles 5\nat 1: SM.INIT()\nat 2: freeze SHIP_SIM\nat 3: freeze TB\n", encoding="utf-8")
    full = rcsc("events", str(SUBMARINE), str(scn))[1].splitlines()
    deploy = rcsc("events", str(SUBMARINE), str(scn), "--exclude-simulators")[1].splitlines()
    assert full[0].split(" ")[:3] == deploy[0].split(" ")[:3] and full[0] != deploy[0]
    # SM, PR, TB, TURBINE_SIM, SHIP_SIM; the deployment build has SM, PR, TB
    assert full[2:] == ["command 1 0 2 0", "freeze 2 4", "freeze 3 2", "end 3"]
    assert deploy[2:] == ["command 1 0 2 0", "freeze 3 2", "end 2"]
