"""Start-up time of the `rcsc` command: fresh processes, timed from outside.

Prints the median wall time of N fresh runs of each command side by side with
`python -c pass` (the interpreter's own start-up), and the difference, which
is what rcsc adds.  Goals: `rcsc --version` within 0.15 s of `python -c pass`,
`rcsc check examples/submarine/submarine.rcs` within 0.35 s.  The first run of
each command is a warm-up (it also fills lark's grammar cache) and is not
counted.  Run from the repository root:

    python bench/bench_startup.py            # 7 runs each
    python bench/bench_startup.py --runs 15
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SUBMARINE = ROOT / "examples" / "submarine" / "submarine.rcs"


def _rcsc() -> list[str]:
    script = Path(sys.executable).parent / "rcsc"
    return [str(script)] if script.is_file() else [sys.executable, "-m", "rcsc"]


def _time(argv: list[str], runs: int) -> float:
    subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=7)
    args = ap.parse_args()
    rcsc = _rcsc()
    rows = [
        ("python -c pass", [sys.executable, "-c", "pass"], None),
        ("rcsc --version", [*rcsc, "--version"], 0.15),
        ("rcsc explain E0505", [*rcsc, "explain", "E0505"], 0.15),
        ("rcsc check submarine.rcs", [*rcsc, "check", str(SUBMARINE)], 0.35),
    ]
    base = None
    print(f"{'command':<28} {'median s':>9} {'+python s':>10} {'goal s':>7}")
    for name, argv, goal in rows:
        t = _time(argv, args.runs)
        base = t if base is None else base
        extra = t - base
        verdict = "" if goal is None else ("ok" if extra <= goal else "missed")
        goal_text = "" if goal is None else f"{goal:.2f}"
        print(f"{name:<28} {t:9.3f} {extra:10.3f} {goal_text:>7} {verdict}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
