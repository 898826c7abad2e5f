#!/usr/bin/env python3
"""Benchmark the guard analysis (rcsc.checks.guards, z3) alone.

    python bench/bench_guards.py                    # the examples, then synthetic 200 x 20 x 10
    python bench/bench_guards.py --sizes 50,200 --repeat 3 --no-cache

For each design it builds the checked model once (parse, sema and every
other check family: not timed; parsing the 200-controller design takes
tens of seconds) and then times `guards.check(model, diags)` alone, best of
--repeat runs, with the number of plans, of plans answered from the
same-shape cache, of solver queries (calls of z3's check, the exists-forall
ones included), of questions answered by an earlier model, and the findings.
--no-cache also runs without the same-shape cache, to show what it saves.

Goals: all examples together under 1 s; the synthetic 200-controller design
(bench/synthetic.py 200 20 10) under 20 s.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT))

import synthetic  # noqa: E402  (bench/synthetic.py)

GOAL_EXAMPLES_S = 1.0
GOAL_SYNTHETIC_S = 20.0


def load(path: str):
    """The checked model of `path`, every check family but the guard analysis run."""
    from rcsc.checks import FAMILIES, guards
    from rcsc.diagnostics import Diagnostics
    from rcsc.front.loader import path_to_files
    from rcsc.semantics.sema import ast_to_model

    diags = Diagnostics()
    files = path_to_files(path, diags)
    design = ast_to_model(files, diags)
    for family in FAMILIES:
        if family is not guards:
            family.check(design, diags)
    return design, diags


def time_guards(design, repeat: int, cache: bool):
    from rcsc.checks import guards
    from rcsc.diagnostics import Diagnostics

    best, stats, diags = None, None, None
    for _ in range(repeat):
        st = guards.Stats()
        d = Diagnostics()
        t0 = time.perf_counter()
        guards.check(design, d, guards.Options(cache=cache), st)
        dt = time.perf_counter() - t0
        if best is None or dt < best:
            best, stats, diags = dt, st, d
    return best, stats, diags


def row(name: str, secs: float, st, diags) -> str:
    codes = sorted({x.code for x in diags})
    finds = f"{len(diags)}" + (f" ({', '.join(codes)})" if codes else "")
    return (
        f"{name:<34} {secs:>8.3f} {st.plans:>6} {st.plans_cached:>7} {st.queries:>8} "
        f"{st.forall_queries:>7} {st.reused:>7}  {finds}"
    )


HEADER = f"{'design':<34} {'best s':>8} {'plans':>6} {'cached':>7} {'queries':>8} {'forall':>7} {'reused':>7}  findings"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="200", help="synthetic controller counts (default 200; empty for none)")
    ap.add_argument("--plans", type=int, default=20)
    ap.add_argument("--rules", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=3, help="timed runs per design; the best counts (default 3)")
    ap.add_argument("--no-cache", action="store_true", help="also time without the same-shape cache")
    args = ap.parse_args(argv)
    import z3

    print("rcsc guard analysis benchmark (rcsc.checks.guards alone, model built beforehand)")
    print(f"python {sys.version.split()[0]}, z3 {z3.get_version_string()}, {os.cpu_count()} CPUs; best of {args.repeat}")
    print()
    print(HEADER)
    print("-" * len(HEADER))
    caches = [True, False] if args.no_cache else [True]

    from rcsc.sim.testrun import is_design_file

    examples = sorted(str(p) for p in (ROOT / "examples").glob("*/*.rcs") if is_design_file(str(p)))
    total = {c: 0.0 for c in caches}
    for path in examples:
        design, _ = load(path)
        for cache in caches:
            secs, st, diags = time_guards(design, args.repeat, cache)
            total[cache] += secs
            name = Path(path).parent.name + ("" if cache else " (no cache)")
            print(row(name, secs, st, diags), flush=True)
    for cache in caches:
        verdict = "MET" if total[cache] < GOAL_EXAMPLES_S else "MISSED"
        print(f"{'all examples' + ('' if cache else ' (no cache)'):<34} {total[cache]:>8.3f}   goal < {GOAL_EXAMPLES_S:.0f} s: {verdict}")

    sizes = [int(s) for s in args.sizes.split(",") if s.strip()]
    with tempfile.TemporaryDirectory(prefix="rcsc-bench-guards-") as tmp:
        for n in sizes:
            path = Path(tmp) / f"synthetic_{n}.rcs"
            path.write_text(synthetic.generate(n, args.plans, args.rules), encoding="utf-8")
            t0 = time.perf_counter()
            design, front = load(str(path))
            load_s = time.perf_counter() - t0
            rules = sum(len(p.rules) for c in design.controllers.values() for p in c.plans.values())
            print(f"\nsynthetic {n} x {args.plans} x {args.rules}: {rules} rules; model built in {load_s:.1f} s (not timed), "
                  f"{len(front)} findings of the other families")
            for cache in caches:
                secs, st, diags = time_guards(design, 1 if n >= 100 and not cache else args.repeat, cache)
                name = f"synthetic {n}" + ("" if cache else " (no cache)")
                print(row(name, secs, st, diags), flush=True)
                if n == 200 and cache:
                    verdict = "MET" if secs < GOAL_SYNTHETIC_S else "MISSED"
                    print(f"goal synthetic 200 under {GOAL_SYNTHETIC_S:.0f} s: {verdict} ({secs:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
