#!/usr/bin/env python3
"""Speed of the reference interpreter (rcsc/sim/simulate.py + rcsc/sim/runner.py).

    python bench/bench_sim.py                  # both benchmarks
    python bench/bench_sim.py --profile        # and cProfile hotspots
    python bench/bench_sim.py --synthetic 200 5 10 --syn-cycles 500

Two workloads, each reported as cycles, controllers (entries of the
schedule, plant models included), controller steps (cycles x controllers),
seconds and steps per second:

1. the submarine example (the largest example by cycles a drill needs):
   10,000 cycles (300 s of ship time at 30 ms) of a realistic watch: start
   up, a 150 s leg at 12 knots ahead, then astern 4 knots (PR's R1 -> S2 ->
   R5 branch).  Goal: the whole run under 2 s.
2. the synthetic design of bench/synthetic.py (200 controllers x 20 plans x
   10 rules by default), put on one CPU (the simulator runs single-CPU
   designs): the generator spreads controllers over CPUs by level; here they
   are scheduled top-down on one CPU with a 10 ms heartbeat, and their
   budgets lowered from 100 us to 40 us so that the design still passes the
   timing check.  Every duration in its plans is a multiple of 10 ms, so the
   design stays clean.  The scenario commands the top controller C0 with a
   sequence of verbs, which the generated plans pass down the tree.

Each workload is timed twice: `run_scenario` (what `rcsc sim` and `rcsc
test` do per cycle: apply inputs, step every controller, take the
end-of-cycle snapshot; no trace output, no expectations) and the bare
stepping loop (`System.tick`: `Simulator.begin_cycle` + `run_cycle`).  Front-end time
(parse, sema, checks) is reported separately and is not part of steps/s.

If the submarine run misses its goal (or with --profile), the hottest
functions of the run are printed from cProfile.

3. long runs: `rcsc test` and `rcsc sim -o` (JSON-lines trace) of the
   submarine watch stretched to 20,000 and 200,000 cycles (30 min and
   100 min of ship time), each in a fresh process: CPU seconds and peak
   resident memory.  A run keeps no history (rcsc.sim.runner.ScenarioRun),
   so the goal is the memory of the long run within 1.2 x the short one's.
"""

from __future__ import annotations

import argparse
import cProfile
import importlib.util
import io
import os
import pstats
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from rcsc.diagnostics import Diagnostics  # noqa: E402
from rcsc.driver import check_path  # noqa: E402
from rcsc.sim.runner import drive, run_scenario  # noqa: E402
from rcsc.front.scenario import text_to_scenario  # noqa: E402
from rcsc.sim.timebase import System  # noqa: E402
from rcsc.front.source import SourceFile  # noqa: E402

SUBMARINE = ROOT / "examples" / "submarine" / "submarine.rcs"
SUB_GOAL_S = 2.0

SUB_SCENARIO = """
scenario "bench: a watch of 300 s"
cycles {cycles}
at 1: SM.INIT()
at 10: SM.TRANSIT(speed = 12.0, leg_time = 150 s)
at 5300: SM.TRANSIT(speed = -4.0, leg_time = 600 s)
expect within 3000..3600: PR.AT_GOAL
expect within 5200..5300: SM.done
expect at 5300: PR.rule == R1
expect always: not SM.error and not PR.error and not TB.error
"""

SYN_SCENARIO = """
scenario "bench: the top controller works through its verbs"
cycles {cycles}
at 1: C0.INIT()
at {c1}: C0.V4(target = 10.0)
at {c2}: C0.V5(target = 5.0, count = 3)
at {c3}: C0.V6(mode = Mode.RUN)
at {c4}: C0.V8(target = -20.0)
at {c5}: C0.HALT()
"""


def _scenario(design, text: str, name: str):
    diags = Diagnostics()
    sc = text_to_scenario(SourceFile(name, text), design, diags)
    if sc is None:
        raise SystemExit(f"bench: scenario {name} has errors: " + "; ".join(f"{d.code} {d.message}" for d in diags))
    return sc


def _load(path: str):
    t = time.perf_counter()
    result = check_path(path)
    seconds = time.perf_counter() - t
    if not result.ok or result.model is None:
        errors = [f"{d.code} {d.message}" for d in result.diags.errors]
        raise SystemExit(f"bench: {path} has errors: {errors[:5]}")
    return result.model, seconds


def _bare_steps(design, sc) -> float:
    """The stepping loop alone: inputs and commands applied, no snapshots."""
    sim = System(design)
    t = time.perf_counter()
    for _ in drive(sim, sc):
        pass
    return time.perf_counter() - t


def _row(label: str, cycles: int, controllers: int, seconds: float) -> str:
    steps = cycles * controllers
    rate = steps / seconds if seconds > 0 else float("inf")
    return f"{label:<44} {cycles:>7} {controllers:>11} {steps:>9} {seconds:>9.3f} {rate:>11,.0f}"


HEADER = f"{'workload':<44} {'cycles':>7} {'controllers':>11} {'steps':>9} {'seconds':>9} {'steps/s':>11}"


def _profile(design, sc, top: int) -> str:
    prof = cProfile.Profile()
    prof.enable()
    run_scenario(design, sc)
    prof.disable()
    out = io.StringIO()
    stats = pstats.Stats(prof, stream=out)
    stats.sort_stats("tottime").print_stats(top)
    return out.getvalue()


def bench_submarine(cycles: int, profile: bool, top: int) -> list[str]:
    design, load_s = _load(str(SUBMARINE))
    sc = _scenario(design, SUB_SCENARIO.format(cycles=cycles), "bench_submarine.scn")
    n = len(design.cpus[next(iter(design.cpus))].schedule)
    t = time.perf_counter()
    run = run_scenario(design, sc)
    full = time.perf_counter() - t
    bare = _bare_steps(design, sc)
    lines = [
        f"submarine: front end {load_s:.2f} s; scenario expectations {'pass' if run.passed else 'FAIL'}",
        _row("submarine  run_scenario (sim/test loop)", cycles, n, full),
        _row("submarine  stepping only", cycles, n, bare),
        f"submarine: {cycles} cycles in {full:.2f} s wall (goal < {SUB_GOAL_S:.0f} s): {'met' if full < SUB_GOAL_S else 'MISSED'}",
    ]
    if profile or full >= SUB_GOAL_S:
        lines.append(f"cProfile of the submarine run_scenario, top {top} by own time:")
        lines.append(_profile(design, sc, top))
    return lines


def _synthetic_text(n: int, p: int, r: int) -> str:
    """bench/synthetic.py's design, rescheduled onto one CPU (see the module doc)."""
    spec = importlib.util.spec_from_file_location("rcsc_bench_synthetic", ROOT / "bench" / "synthetic.py")
    if spec is None or spec.loader is None:
        raise SystemExit("bench: bench/synthetic.py not found")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    text = mod.generate(n, p, r)
    cut = text.find("\ncpu ")
    if cut < 0:
        raise SystemExit("bench: synthetic design has no cpu block")
    text = text[: cut + 1].replace(f"budget {mod.BUDGET_US} us", "budget 40 us")
    if n * 40 + 1000 > 10_000:
        raise SystemExit("bench: more than 225 controllers do not fit one 10 ms CPU at 40 us each")
    schedule = ", ".join(f"C{i}" for i in range(n))  # breadth-first: supervisors before subordinates
    return text + f"cpu MAIN {{\n    heartbeat 10 ms\n    overhead 1 ms\n    schedule {schedule}\n}}\n"


def bench_synthetic(n: int, p: int, r: int, cycles: int, profile: bool, top: int) -> list[str]:
    text = _synthetic_text(n, p, r)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, f"synthetic_{n}_{p}_{r}.rcs")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
        design, load_s = _load(path)
    step = max(cycles // 6, 1)
    verbs_needed = {"V4", "V5", "V6", "V8"}
    if not verbs_needed <= set(design.controllers["C0"].verbs):
        raise SystemExit(f"bench: the synthetic scenario needs P >= 9 (verbs {sorted(verbs_needed)})")
    sc = _scenario(design, SYN_SCENARIO.format(cycles=cycles, c1=step, c2=2 * step, c3=3 * step, c4=4 * step, c5=5 * step), "bench_synthetic.scn")
    ctrls = len(design.cpus["MAIN"].schedule)
    t = time.perf_counter()
    run = run_scenario(design, sc)
    full = time.perf_counter() - t
    bare = _bare_steps(design, sc)
    last = run.snapshots[-1].ctrl
    active = sum(1 for s in last.values() if s.status != "UNINITIALIZED")
    lines = [
        f"synthetic {n}x{p}x{r}: front end {load_s:.2f} s ({len(text.splitlines())} lines); {active} of {ctrls} controllers got a command",
        _row(f"synthetic {n}x{p}x{r}  run_scenario", cycles, ctrls, full),
        _row(f"synthetic {n}x{p}x{r}  stepping only", cycles, ctrls, bare),
    ]
    if profile:
        lines.append(f"cProfile of the synthetic run_scenario, top {top} by own time:")
        lines.append(_profile(design, sc, top))
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sub-cycles", type=int, default=10_000, help="cycles of the submarine run (default 10000)")
    ap.add_argument("--syn-cycles", type=int, default=1_000, help="cycles of the synthetic run (default 1000)")
    ap.add_argument("--synthetic", nargs=3, type=int, metavar=("N", "P", "R"), default=(200, 20, 10), help="synthetic design size (default 200 20 10)")
    ap.add_argument("--skip-synthetic", action="store_true", help="only the submarine run")
    ap.add_argument("--skip-long", action="store_true", help="skip the long runs' memory")
    ap.add_argument("--profile", action="store_true", help="print cProfile hotspots of every run")
    ap.add_argument("--top", type=int, default=20, help="hotspot lines to print (default 20)")
    args = ap.parse_args(argv)

    print(HEADER)
    for line in bench_submarine(args.sub_cycles, args.profile, args.top):
        print(line, flush=True)
    if not args.skip_synthetic:
        n, p, r = args.synthetic
        for line in bench_synthetic(n, p, r, args.syn_cycles, args.profile, args.top):
            print(line, flush=True)
    if not args.skip_long:
        for line in bench_long():
            print(line, flush=True)
    return 0


LONG_GOAL = 1.2


def _child(argv: list[str]) -> tuple[float, float]:
    """CPU seconds and peak RSS (MiB) of one command in a fresh process."""
    import subprocess

    # No cache: every run checks the design itself, so the runs compare.
    env = dict(os.environ, RCSC_NO_CACHE="1")
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    _, _, usage = os.wait4(proc.pid, 0)
    proc.returncode = 0
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def bench_long() -> list[str]:
    """`rcsc test` and `rcsc sim` on long runs: memory must not grow with the cycles."""
    out = ["", f"{'long run (fresh process)':<44} {'cycles':>7} {'CPU s':>9} {'peak MiB':>9}"]
    peaks: dict[tuple[str, int], float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "submarine.rcs").write_text(SUBMARINE.read_text(encoding="utf-8"), encoding="utf-8")
        for cycles in (20_000, 200_000):
            scn = folder / f"soak_{cycles}.scn"
            scn.write_text(SUB_SCENARIO.format(cycles=cycles), encoding="utf-8")
            for what, argv in (
                ("rcsc test", [sys.executable, "-m", "rcsc", "test", str(scn)]),
                ("rcsc sim -o trace.jsonl", [sys.executable, "-m", "rcsc", "sim", str(folder / "submarine.rcs"),
                                             "--scenario", str(scn), "-o", str(folder / "trace.jsonl")]),
            ):
                cpu, peak = _child(argv)
                peaks[(what, cycles)] = peak
                out.append(f"{what:<44} {cycles:>7} {cpu:>9.2f} {peak:>9.0f}")
    for what in ("rcsc test", "rcsc sim -o trace.jsonl"):
        ratio = peaks[(what, 200_000)] / peaks[(what, 20_000)]
        verdict = "met" if ratio <= LONG_GOAL else "MISSED"
        out.append(f"{what}: peak memory at 200,000 cycles / at 20,000 = {ratio:.2f} (goal <= {LONG_GOAL}): {verdict}")
    return out


if __name__ == "__main__":
    sys.exit(main())
