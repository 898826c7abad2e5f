"""Scenarios of any length: `rcsc sim` and `rcsc test` keep no history.

A run is a stream of ticks (`rcsc.sim.runner.ScenarioRun`): expectations are
decided as it goes, the trace and the step log are written as it goes, and
once every CPU has stopped the quiet ticks up to the next scenario event are
one step.  These tests hold the streamed run to what a run that steps and
keeps every tick sees, and to the compiled programs, which step every tick.
"""

from __future__ import annotations

import contextlib
import io
import re
import tracemalloc
from pathlib import Path

from rcsc import cli
from rcsc.diagnostics import Diagnostics
from rcsc.driver import check_path
from rcsc.front.scenario import text_to_scenario
from rcsc.front.source import SourceFile
from rcsc.sim import trace
from rcsc.sim.runner import ScenarioRun, run_scenario

ROOT = Path(__file__).resolve().parent.parent
APART = ROOT / "tests/mc/apart.rcs"  # two CPUs (10 ms and 20 ms), two inputs `from env`
SUBMARINE = ROOT / "examples/submarine/submarine.rcs"  # one CPU, MAIN; input `turbine_trip`

# Both CPUs stop at tick 9; the inputs go on changing what expectations see.
APART_STOPS = """scenario "apart: both CPUs stop, the inputs go on"
cycles {cycles}
at 2: flow = 3.0
at 3: PUMPS.RUN()
at 5: heat = 150.0
at 9: stop pumps
at 9: stop oven
at 20: flow = 7.0
at {late}: heat = 1.0
expect within 10..30: flow == 7.0
expect at {after}: heat == 1.0
expect always: heat >= 0.0
expect within 12..19: flow == 7.0
expect at 15: heat == 1.0
expect always: flow < 5.0
expect final: flow == 7.0 and heat == 1.0 and valve == 1.5
"""


def _rcsc(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(list(argv))
    return rc, out.getvalue(), err.getvalue()


def _untimed(report: str) -> str:
    return re.sub(r" \([0-9]+ (cycles|ticks), [0-9.]+ s\)", "", report)


def _scenario(design: Path, text: str, tmp_path: Path):
    result = check_path(str(design))
    assert result.ok, result.diags
    path = tmp_path / "s.scn"
    path.write_text(text, encoding="utf-8")
    diags = Diagnostics()
    sc = text_to_scenario(SourceFile(str(path), text), result.model, diags)
    assert sc is not None, diags.items
    return result.model, sc


def test_a_total_stop_makes_the_rest_of_a_huge_scenario_one_step(tmp_path: Path) -> None:
    """The longest scenario the language allows (2**32 - 1 ticks) with every
    CPU stopped early runs at once, and each kind of expectation is decided
    at the tick it would be on a run that steps every tick."""
    text = APART_STOPS.format(cycles=2**32 - 1, late=3_000_000_000, after=4_000_000_000)
    design = tmp_path / "apart.rcs"
    design.write_text(APART.read_text(encoding="utf-8"), encoding="utf-8")
    scn = tmp_path / "apart_huge.scn"
    scn.write_text(text, encoding="utf-8")
    rc, out, _ = _rcsc("test", str(scn))
    assert rc == 1, out
    assert "expect within 12..19: flow == 7.0" in out and "never true in the window; at tick 19: flow = 3" in out
    assert "expect at 15: heat == 1.0" in out and "false at tick 15: heat = 150" in out
    assert "expect always: flow < 5.0" in out and "false at tick 20: flow = 7" in out
    assert out.count("expect ") == 3, "the four other expectations pass"
    # The trace has the cycles that ran, and no more.
    rc, _, _ = _rcsc("sim", str(design), "--scenario", str(scn), "-o", str(tmp_path / "t.jsonl"))
    lines = (tmp_path / "t.jsonl").read_text(encoding="utf-8").splitlines()
    assert rc == 1 and len(lines) == 8 + 4  # pumps: ticks 1..8; oven (every 2nd tick): 1, 3, 5, 7


def test_quiet_spans_see_what_every_tick_sees(tmp_path: Path) -> None:
    """The same scenario, short: the streamed run's per-tick CSV view equals
    the one `run_scenario` spreads over the ticks, the expectations' report
    equals the compiled C program's (which steps every tick and whose
    expectations are evaluated tick by tick on its trace), on two CPUs and
    on one."""
    cases = [
        (APART, APART_STOPS.format(cycles=60, late=41, after=45)),
        (SUBMARINE, "cycles 300\nat 1: SM.INIT()\nat 10: stop MAIN\nat 200: turbine_trip = true\n"
                    "expect within 150..250: turbine_trip\nexpect at 250: SM.done\nexpect always: not turbine_trip\n"
                    "expect final: SM.executing\n"),
    ]
    for source, text in cases:
        folder = tmp_path / source.stem
        folder.mkdir()
        design = folder / source.name
        design.write_text(source.read_text(encoding="utf-8"), encoding="utf-8")
        model, sc = _scenario(design, text, folder)
        scn = folder / "s.scn"
        kept = run_scenario(model, sc)
        assert [s.cycle for s in kept.snapshots] == list(range(1, sc.cycles + 1))
        csv_path = tmp_path / "t.csv"
        rc, _, _ = _rcsc("sim", str(design), "--scenario", str(scn), "-o", str(csv_path))
        assert rc == 1
        assert csv_path.read_text(encoding="utf-8") == trace.to_csv(model, kept.snapshots)
        streamed = ScenarioRun(model, sc).run()
        assert streamed.snapshots == [] and streamed.results == kept.results
        sim = _rcsc("test", str(scn))
        c = _rcsc("test", "--target", "c", "--build-dir", str(tmp_path / "b"), str(scn))
        assert sim[0] == c[0] == 1, (sim, c)
        assert "FAIL" in sim[1] and _untimed(sim[1]) == _untimed(c[1])


def test_a_long_run_takes_the_memory_of_a_short_one(tmp_path: Path) -> None:
    """`rcsc test` and `rcsc sim` runs keep no snapshot per tick: ten times the
    ticks take about the same peak memory (a run that kept them took 4 KB a
    tick of the submarine)."""
    scenario = (ROOT / "examples/submarine/scenarios/ahead_12_knots.scn").read_text(encoding="utf-8")

    def peak(cycles: int) -> int:
        model, sc = _scenario(SUBMARINE, re.sub(r"(?m)^cycles .*$", f"cycles {cycles}", scenario), tmp_path)
        tracemalloc.start()
        try:
            run = ScenarioRun(model, sc)
            for tick in run.ticks():
                for record in tick.ran:
                    trace.jsonl_line(model, record)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    short, long = peak(6000), peak(60000)
    assert long < short * 1.5 + 1_000_000, (short, long)


def test_streamed_reports_are_whole_or_absent(tmp_path: Path) -> None:
    """The trace and the step log are written as the run goes, into
    temporary files that replace the targets when the run is through."""
    scn = tmp_path / "s.scn"
    scn.write_text("cycles 40\nat 1: SM.INIT()\n", encoding="utf-8")
    out, steps = tmp_path / "t.csv", tmp_path / "steps.txt"
    rc, _, _ = _rcsc("sim", str(SUBMARINE), "--scenario", str(scn), "-o", str(out), "--step-log", str(steps))
    assert rc == 0
    rows = out.read_text(encoding="utf-8").splitlines()
    assert len(rows) == 41 and [r.split(",")[0] for r in rows[1:]] == [str(k) for k in range(1, 41)]
    assert steps.read_text(encoding="utf-8").count("\n") >= 40
    assert not list(tmp_path.glob(".rcsc-*")), "no temporary file is left"


STREAMING = ROOT / "tests/streaming"


def test_a_quiet_span_comes_out_of_the_csv_writer_in_pieces() -> None:
    """A CSV row per tick of a long quiet span: the writer yields them in
    pieces, so the span does not become one string in memory (it took 617 MB
    for 2,000,000 ticks)."""
    model, sc = _scenario(SUBMARINE, "cycles 3\nat 1: SM.INIT()\n", Path("/tmp"))
    view = run_scenario(model, sc).snapshots[0]
    tracemalloc.start()
    try:
        rows = 0
        biggest = 0
        for chunk in trace.csv_chunks(model, [(view, 200_000)]):
            rows += chunk.count("\n")
            biggest = max(biggest, len(chunk))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert rows == 1 + 200_000
    assert biggest < 2_000_000 and peak < 20_000_000, (biggest, peak)


def _sim(*args: str):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "rcsc", "sim", *args], capture_output=True, text=True, timeout=300,
                          cwd=STREAMING)


def test_the_verdict_survives_a_reader_that_goes_away() -> None:
    """`rcsc sim ... | head -1`: the trace's reader leaves early; the run
    goes on without it and still gives its verdict (exit 1 and the failed
    expectations on stderr), as when the trace was written at the end."""
    import subprocess
    import sys

    cmd = f"{sys.executable} -m rcsc sim two_cpus.rcs --scenario two_cpus_stops.scn --trace-format csv | head -1 > /dev/null; echo $?"
    shell = f"set -o pipefail; {cmd}"
    r = subprocess.run(["bash", "-c", shell], capture_output=True, text=True, timeout=300, cwd=STREAMING)
    assert r.stdout.strip() == "1", (r.stdout, r.stderr)
    assert "expect at 15: y == 99" in r.stderr and "Traceback" not in r.stderr


def test_a_step_log_to_stdout_comes_before_the_trace() -> None:
    """`--step-log /dev/stdout` with the trace on stdout: the step log, then
    the trace, each whole (two writers to one stream would mix them)."""
    r = _sim("two_cpus.rcs", "--scenario", "two_cpus_stops.scn", "--step-log", "/dev/stdout")
    lines = r.stdout.splitlines()
    first_trace = next(i for i, line in enumerate(lines) if line.startswith("{"))
    assert first_trace > 0 and all(not line.startswith("{") for line in lines[:first_trace])
    assert all(line.startswith("{") for line in lines[first_trace:])


def test_an_extern_that_fails_keeps_the_scenario_s_warnings(capsys) -> None:
    """The scenario's W0707 is shown with the E0831 of an extern that fails
    mid-run (it was dropped with the run)."""
    rc, out, _ = _rcsc("test", "--externs", str(STREAMING / "extern_fails_externs.py"), str(STREAMING / "extern_fails_run.scn"))
    assert rc == 1
    assert "warning[W0707]: `x` = 50.0 is outside its declared range 0.0..10.0" in out and "error[E0831]" in out
