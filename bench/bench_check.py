#!/usr/bin/env python3
"""Benchmark `rcsc check` on synthetic designs (bench/synthetic.py).

    python bench/bench_check.py                      # 50, 100, 200 controllers x 20 plans x 10 rules
    python bench/bench_check.py --sizes 20,50 --repeat 1 --profile

For each size it prints the wall time of the in-process front end
(`rcsc.driver.check_path`: parse, sema, checks; best of --repeat runs), the
number of rules, the findings, and the peak memory (tracemalloc peak of one
extra traced run, and the process's maximum resident set size).  For the
largest size it also times one cold run of the `rcsc` console script in a
subprocess (interpreter start-up, imports and grammar construction
included).  --profile prints the top cProfile hotspots of one run of the
largest size.

Goal: 200 controllers under 3 s.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import os
import pstats
import resource
import shutil
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT))

import synthetic  # noqa: E402  (bench/synthetic.py)

GOAL_CONTROLLERS = 200
GOAL_SECONDS = 3.0


def _maxrss_mib() -> float:
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return rss / (1024 * 1024) if sys.platform == "darwin" else rss / 1024


def _rule_count(result) -> int:
    if result.model is None:
        return 0
    return sum(len(p.rules) for c in result.model.controllers.values() for p in c.plans.values())


def _console_script() -> list[str]:
    exe = shutil.which("rcsc")
    return [exe] if exe else [sys.executable, "-m", "rcsc"]


def bench_size(path: Path, repeat: int, memory: bool) -> dict:
    from rcsc.driver import check_path

    times = []
    result = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = check_path(str(path))
        times.append(time.perf_counter() - t0)
    assert result is not None
    row = {
        "best": min(times),
        "times": times,
        "rules": _rule_count(result),
        "errors": len(result.diags.errors),
        "warnings": len(result.diags.warnings),
        "codes": sorted({d.code for d in result.diags}),
    }
    if memory:
        tracemalloc.start()
        check_path(str(path))
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        row["traced_peak_mib"] = peak / (1024 * 1024)
    row["maxrss_mib"] = _maxrss_mib()
    return row


def cold_run(path: Path) -> tuple[float, int]:
    cmd = _console_script() + ["check", str(path), "--format", "short"]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, check=False)
    return time.perf_counter() - t0, proc.returncode


def profile(path: Path, top: int) -> str:
    from rcsc.driver import check_path

    prof = cProfile.Profile()
    prof.enable()
    check_path(str(path))
    prof.disable()
    out = io.StringIO()
    stats = pstats.Stats(prof, stream=out)
    stats.sort_stats("cumulative").print_stats(top)
    stats.sort_stats("tottime").print_stats(top)
    return out.getvalue()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="50,100,200", help="controller counts (default 50,100,200)")
    ap.add_argument("--plans", type=int, default=20)
    ap.add_argument("--rules", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=3, help="in-process runs per size; the best counts (default 3)")
    ap.add_argument("--no-memory", action="store_true", help="skip the tracemalloc run")
    ap.add_argument("--no-cold", action="store_true", help="skip the subprocess run of the console script")
    ap.add_argument("--profile", action="store_true", help="print cProfile hotspots of the largest size")
    ap.add_argument("--top", type=int, default=25)
    args = ap.parse_args(argv)
    sizes = [int(s) for s in args.sizes.split(",") if s.strip()]

    print(f"rcsc check benchmark: N controllers x {args.plans} plans x {args.rules} rules (bench/synthetic.py)")
    print(f"goal: {GOAL_CONTROLLERS} controllers under {GOAL_SECONDS:.0f} s")
    print(f"python {sys.version.split()[0]} on {os.cpu_count()} CPUs; in-process driver.check_path, best of {args.repeat}")
    print()
    header = f"{'controllers':>11} {'rules':>7} {'size':>9} {'best s':>8} {'runs s':>22} {'peak traced':>12} {'max RSS':>9}  findings"
    print(header)
    print("-" * len(header))

    from rcsc.parse import _parser  # build the grammar once, outside the timings

    _parser()
    results = {}
    with tempfile.TemporaryDirectory(prefix="rcsc-bench-") as tmp:
        paths = {}
        for n in sizes:
            path = Path(tmp) / f"synthetic_{n}.rcs"
            path.write_text(synthetic.generate(n, args.plans, args.rules), encoding="utf-8")
            paths[n] = path
            row = bench_size(path, args.repeat, not args.no_memory)
            results[n] = row
            size_kib = path.stat().st_size / 1024
            runs = ", ".join(f"{t:.2f}" for t in row["times"])
            traced = f"{row['traced_peak_mib']:.0f} MiB" if "traced_peak_mib" in row else "-"
            finds = f"{row['errors']} errors, {row['warnings']} warnings" + (f" ({', '.join(row['codes'])})" if row["codes"] else "")
            print(f"{n:>11} {row['rules']:>7} {size_kib:>7.0f}Ki {row['best']:>8.2f} {runs:>22} {traced:>12} {row['maxrss_mib']:>6.0f}MiB  {finds}", flush=True)

        largest = max(sizes)
        if not args.no_cold:
            secs, rc = cold_run(paths[largest])
            print(f"\ncold `{' '.join(Path(c).name for c in _console_script())} check` subprocess, {largest} controllers: {secs:.2f} s (exit {rc})")
        print()
        if GOAL_CONTROLLERS in results:
            best = results[GOAL_CONTROLLERS]["best"]
            verdict = "MET" if best < GOAL_SECONDS else "MISSED"
            print(f"goal {GOAL_CONTROLLERS} controllers under {GOAL_SECONDS:.0f} s: {verdict} ({best:.2f} s, {best / GOAL_SECONDS:.1f}x the goal)")
        if args.profile:
            print(f"\ncProfile of one run, {largest} controllers:\n")
            print(profile(paths[largest], args.top))
    return 0


if __name__ == "__main__":
    sys.exit(main())
