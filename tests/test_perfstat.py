"""Performance instrumentation of the compiled Main Program (C and Rust).

tests/perf/perf.rcs: TOP's RUN plan calls an extern `spin` that busy-waits
(tests/perf/perf_externs.c, externs_impl.rs) far beyond TOP's 50 us budget;
the scenario sends INIT at cycle 1, RUN at 3 (TOP overruns in cycles 4-8)
and INIT again at 9, which restarts TOP's (and, passed down, LOW's)
performance window.  Checked on both targets:

- overrun lines on stderr while the program runs, rate-limited;
- `--trace-perf`: per cycle each controller's steps, last/min/max/mean and
  overruns since its last INIT; the main trace stays byte for byte the
  simulator's;
- `--timing-out`: the worst case per (verb, state, rule), the same rows in C
  and Rust, and `rcsc budget --measured` flags R1 (E0840);
- `--step-log`: the same lines in C, Rust and `rcsc sim --step-log`;
- `rcsc budget --callgrind`: instruction counts, identical on two runs.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rcsc import cli

# Real-time runs and machine-wide resources: these tests run alone, after the
# others (the README's test command, `-m serial`).
pytestmark = pytest.mark.serial

ROOT = Path(__file__).resolve().parent.parent
PERF = ROOT / "tests" / "perf"
DESIGN = PERF / "perf.rcs"
SCENARIO = PERF / "perf.scn"
R1_LINE = next(n for n, line in enumerate(DESIGN.read_text(encoding="utf-8").splitlines(), 1) if line.strip().startswith("R1:"))


def _rcsc(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "rcsc", *args], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def work(tmp_path_factory) -> Path:
    w = tmp_path_factory.mktemp("perf")
    assert cli.main(["events", str(DESIGN), str(SCENARIO), "-o", str(w / "perf.events")]) == 0
    assert cli.main(["sim", str(DESIGN), "--scenario", str(SCENARIO), "-o", str(w / "sim.jsonl")]) == 0
    return w


@pytest.fixture(scope="module")
def programs(work: Path) -> dict[str, Path]:
    """The Main Program of perf.rcs built for C (make) and Rust (cargo, release)."""
    out = {}
    c = work / "c"
    assert cli.main(["build", str(DESIGN), "--target", "c", "-o", str(c)]) == 0
    shutil.copy(PERF / "perf_externs.c", c / "perf_externs.c")
    subprocess.run(["nice", "-n", "10", "make", "-s"], cwd=c, check=True, capture_output=True)
    out["c"] = c / "perf_MAIN"
    rs = work / "rust"
    assert cli.main(["build", str(DESIGN), "--target", "rust", "-o", str(rs)]) == 0
    shutil.copy(PERF / "externs_impl.rs", rs / "src" / "externs_impl.rs")
    env = dict(os.environ, CARGO_TARGET_DIR=str(rs / "target"), CARGO_TERM_COLOR="never")
    r = subprocess.run(["nice", "-n", "10", "cargo", "build", "--offline", "--release", "--quiet"], cwd=rs, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    out["rust"] = rs / "target" / "release" / "perf_MAIN"
    return out


def _run(program: Path, work: Path, tag: str, *extra: str) -> tuple[subprocess.CompletedProcess, dict[str, Path]]:
    files = {k: work / f"{tag}.{k}" for k in ("trace", "perf", "timing", "steps")}
    cmd = [str(program), "--fast", "--no-console", "--scenario", str(work / "perf.events"), "--trace", str(files["trace"]),
           "--trace-perf", str(files["perf"]), "--timing-out", str(files["timing"]), "--step-log", str(files["steps"]), *extra]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    return r, files


@pytest.mark.parametrize("target", ["c", "rust"])
def test_perf_section_resets_on_init_and_leaves_the_trace_alone(programs, work: Path, target: str) -> None:
    r, files = _run(programs[target], work, target)
    # The main trace is the simulator's, byte for byte, with every performance output on.
    assert files["trace"].read_bytes() == (work / "sim.jsonl").read_bytes()
    lines = [json.loads(x) for x in files["perf"].read_text(encoding="utf-8").splitlines()]
    assert [x["cycle"] for x in lines] == list(range(1, 13))
    assert all(list(x["perf"]) == ["TOP", "LOW"] for x in lines)
    keys = ["steps", "last_ns", "min_ns", "max_ns", "mean_ns", "overruns", "since"]
    assert all(list(p) == keys for x in lines for p in x["perf"].values())
    top = {x["cycle"]: x["perf"]["TOP"] for x in lines}
    low = {x["cycle"]: x["perf"]["LOW"] for x in lines}
    # INIT at cycle 1 starts the window; RUN spins in cycles 4-8, far over 50 us.
    assert (top[3]["steps"], top[3]["overruns"], top[3]["since"]) == (3, 0, 1)
    assert (top[8]["steps"], top[8]["overruns"], top[8]["since"]) == (8, 5, 1)
    assert top[8]["max_ns"] > 50000 and top[8]["min_ns"] <= top[8]["mean_ns"] <= top[8]["max_ns"]
    assert top[8]["mean_ns"] * 8 <= sum(top[k]["last_ns"] for k in range(1, 9)) < (top[8]["mean_ns"] + 1) * 8
    # The INIT at cycle 9 resets TOP's window and, passed down in the same cycle, LOW's.
    assert (top[9]["steps"], top[9]["overruns"], top[9]["since"]) == (1, 0, 9)
    assert top[9]["min_ns"] == top[9]["max_ns"] == top[9]["last_ns"] == top[9]["mean_ns"]
    assert top[12]["max_ns"] < top[8]["max_ns"] and top[12]["steps"] == 4
    assert (low[8]["steps"], low[8]["since"], low[9]["steps"], low[9]["since"]) == (8, 1, 1, 9)
    # At exit the timing table still counts the whole run.
    row = next(line for line in r.stderr.splitlines() if line.startswith("TOP "))
    assert row.split()[-1] == "5"


@pytest.mark.parametrize("target", ["c", "rust"])
def test_overruns_are_reported_rate_limited(programs, work: Path, target: str) -> None:
    r, _ = _run(programs[target], work, target)
    over = [line for line in r.stderr.splitlines() if line.startswith("rcs: overrun:")]
    # TOP overruns in cycles 4..8: lines for its 1st, 2nd and 4th overrun only.
    assert len(over) == 3, r.stderr
    for line, (cycle, n) in zip(over, [(4, 1), (5, 2), (7, 4)]):
        assert line.startswith(f"rcs: overrun: TOP in cycle {cycle} took "), line
        assert line.endswith(f" us, budget 50.000 us (overrun {n}; the next line at overrun {2 * n})"), line
        assert float(line.split(" took ")[1].split(" us")[0]) > 50.0
    # The lines come before the timing table (printed at exit) ...
    assert r.stderr.index("rcs: overrun:") < r.stderr.index("rcs: timing of")
    # ... and --no-timing silences both.
    r2, _ = _run(programs[target], work, target + "-quiet", "--no-timing")
    assert r2.stderr == ""


@pytest.mark.parametrize("target", ["c", "rust"])
def test_overrun_line_arrives_while_the_program_runs(programs, work: Path, target: str) -> None:
    """On the heartbeat (10 ms, 300 cycles = 3 s): the first overrun line is on
    stderr while the process is still running, long before it ends."""
    cmd = [str(programs[target]), "--no-console", "--scenario", str(work / "perf.events"), "--cycles", "300"]
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        t0 = time.monotonic()
        line = proc.stderr.readline()
        assert line.startswith("rcs: overrun: TOP in cycle 4 took "), line
        assert proc.poll() is None and time.monotonic() - t0 < 2.5
    finally:
        proc.terminate()
        rest = proc.communicate(timeout=30)[1]
    assert proc.returncode == 0 and "rcs: timing of perf" in rest


def _shape(text: str) -> list[tuple]:
    """A run file's rows without the figures that depend on the clock."""
    doc = json.loads(text)
    return [(doc["design"], doc["cpu"], doc["unit"], doc["cycles"])] + [
        (c["name"], c["budget_ns"], c["steps"], r["verb"], r["state"], r["rule"], r["steps"]) for c in doc["controllers"] for r in c["rules"]
    ]


def test_worst_case_per_rule_in_c_and_rust_and_the_measured_budget_table(programs, work: Path) -> None:
    c = _run(programs["c"], work, "c-rules", "--no-timing")[1]
    rs = _run(programs["rust"], work, "rust-rules", "--no-timing")[1]
    assert c["steps"].read_text() == rs["steps"].read_text()
    # The simulator keys the steps the same way (rcsc sim --step-log).
    sim_steps = work / "sim.steps"
    assert cli.main(["sim", str(DESIGN), "--scenario", str(SCENARIO), "-o", os.devnull, "--step-log", str(sim_steps)]) == 0
    assert sim_steps.read_text() == c["steps"].read_text()
    assert c["steps"].read_text().splitlines()[:3] == ["TOP\tINIT\tnew\tI0", "LOW\tINIT\tnew\tL0", "TOP\tINIT\tS1\tI1"]
    assert _shape(c["timing"].read_text()) == _shape(rs["timing"].read_text())
    doc = json.loads(c["timing"].read_text())
    top = doc["controllers"][0]
    rows = {(r["verb"], r["state"], r["rule"]): r for r in top["rules"]}
    assert set(rows) == {("RUN", "new", "R0"), ("RUN", "BUSY", "R1"), ("INIT", "new", "I0"), ("INIT", "S1", "I1"), ("INIT", "done", "")}
    assert rows[("RUN", "BUSY", "R1")]["steps"] == 5 and rows[("RUN", "BUSY", "R1")]["max_ns"] == top["max_ns"] > 50000
    for target, files in (("c", c), ("rust", rs)):
        r = _rcsc("budget", str(DESIGN), "--measured", str(files["timing"]))
        assert r.returncode == 1, (target, r.stdout, r.stderr)
        table = r.stdout.split("cpu MAIN: measured in ", 1)[1].splitlines()
        assert table[1].split()[:2] == ["controller", "/"]
        r1 = next(line.split() for line in table if line.split()[:1] == ["R1"])
        assert r1[1:4] == ["RUN", "BUSY", "5"] and "OVER" in r1
        assert next(line.split() for line in table if line.split()[:1] == ["L0"])[-1].endswith("%")
        assert f"error[E0840]: rule `R1` of `TOP` (plan RUN, state BUSY) took up to " in r.stderr
        assert f"perf.rcs:{R1_LINE}:9" in r.stderr
        assert r.stderr.count("error[") == 1


def test_run_files_that_do_not_fit(tmp_path: Path, work: Path, programs) -> None:
    timing = _run(programs["c"], work, "c-fit", "--no-timing")[1]["timing"]
    doc = json.loads(timing.read_text())
    bad = tmp_path / "bad.json"
    bad.write_text("{", encoding="utf-8")
    r = _rcsc("budget", str(DESIGN), "--measured", str(bad))
    assert r.returncode == 1 and "error[E0841]: `" in r.stderr and "is not a readable run file" in r.stderr
    other = tmp_path / "other.json"
    other.write_text(json.dumps(dict(doc, design="other")), encoding="utf-8")
    r = _rcsc("budget", str(DESIGN), "--measured", str(other))
    assert r.returncode == 1 and "is a run of design `other`, not `perf`" in r.stderr
    # Without LOW and without the slow rule: a warning for LOW, no error.
    top = dict(doc["controllers"][0], rules=[x for x in doc["controllers"][0]["rules"] if x["rule"] != "R1"])
    part = tmp_path / "part.json"
    part.write_text(json.dumps(dict(doc, controllers=[top])), encoding="utf-8")
    r = _rcsc("budget", str(DESIGN), "--measured", str(part))
    assert r.returncode == 0 and "warning[W0841]: `LOW` was never stepped in the measured runs" in r.stderr
    assert "error[" not in r.stderr


def test_callgrind_counts_are_the_same_on_every_run(tmp_path: Path) -> None:
    assert shutil.which("valgrind"), "valgrind is required (.ci installs it)"
    texts = []
    for k in (1, 2):
        out = tmp_path / f"cg{k}.json"
        r = _rcsc("budget", str(DESIGN), "--callgrind", str(SCENARIO), "--build-dir", str(tmp_path / "build"), "--timing-out", str(out))
        assert r.returncode == 0, r.stderr
        assert "instruction counts, 1 ns per instruction" in r.stdout
        texts.append(out.read_text(encoding="utf-8"))
    assert texts[0] == texts[1]
    doc = json.loads(texts[0])
    assert doc["unit"] == "insn" and [c["name"] for c in doc["controllers"]] == ["TOP", "LOW"]
    top = doc["controllers"][0]
    assert top["steps"] == 12 and all(r["max_insn"] > 0 for r in top["rules"])
    assert {(r["verb"], r["state"], r["rule"]) for r in top["rules"]} >= {("RUN", "BUSY", "R1"), ("INIT", "new", "I0")}
    # A tiny exchange rate of instructions to time flags nothing; a huge one flags every rule.
    r = _rcsc("budget", str(DESIGN), "--measured", str(tmp_path / "cg1.json"), "--ns-per-insn", "100000")
    assert r.returncode == 1 and "error[E0840]" in r.stderr and "ns per instruction" in r.stderr


def test_each_cpu_of_a_multi_cpu_design_writes_its_own_run_file(tmp_path: Path) -> None:
    """Under the launcher every CPU gets the same options: each writes FILE.CPU,
    and `rcsc budget` takes one --measured per CPU."""
    from rcsc.driver import check_path
    from rcsc.sim import compiled

    design_path = ROOT / "examples" / "machine_tool" / "machine_tool.rcs"
    scn = sorted((design_path.parent / "scenarios").glob("*.scn"))[0]
    design = check_path(str(design_path)).model
    built = compiled.build(design, "c", str(tmp_path / "build"))
    assert cli.main(["events", str(design_path), str(scn), "-o", str(tmp_path / "mt.events")]) == 0
    run = tmp_path / "run.json"
    r = subprocess.run([str(built.program), "--lockstep", "--no-timing", "--scenario", str(tmp_path / "mt.events"), "--timing-out", str(run)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    files = [tmp_path / f"run.json.{cpu}" for cpu in design.cpus]
    assert not run.exists() and all(f.is_file() for f in files)
    assert sorted(json.loads(f.read_text())["cpu"] for f in files) == sorted(design.cpus)
    r = _rcsc("budget", str(design_path), *[x for f in files for x in ("--measured", str(f))])
    assert r.returncode == 0 and "warning[" not in r.stderr and "error[" not in r.stderr, r.stderr
    assert r.stdout.count(": measured in ") == len(design.cpus)
