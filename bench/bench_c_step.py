#!/usr/bin/env python3
"""Instructions per controller step: generated C against hand-written C.

    python bench/bench_c_step.py                  # gcc and clang, 10000 steps
    python bench/bench_c_step.py --annotate       # also the costliest source lines
    python bench/bench_c_step.py --compilers gcc --steps 20000 --keep /tmp/cstep

The subject is the submarine's PR controller running its AHEAD plan (the
plan of Appendix C of the RCS methodology paper).  The script

1. generates the C of examples/submarine/submarine.rcs with `rcsc build
   --target c` into a temporary directory (so it always measures the current
   generator; only the controller files are used, not the runtime);
2. compiles bench/c_ahead/driver.c with the generated submarine_PR.c and
   submarine.c and with bench/c_ahead/handwritten_pr.c (PR's AHEAD plan
   written by hand in the style of the paper, with the echo-serial check),
   for each compiler, with `-O2 -std=c99 -ffp-contract=off`;
3. runs the driver once natively: it steps both controllers on identical
   inputs (a new AHEAD command every 1000 cycles, TB spooling then done, the
   ship speed varying, so that E0, E1, E2, E3, E4, E5, E9 and the waiting
   cycles all occur) and stops with an error at the first step after which
   their buffers differ - the proof that the two compute the same thing;
4. runs it under `valgrind --tool=callgrind --toggle-collect=<step>` once per
   variant, reads the collected instruction count (Ir) from the callgrind
   output and divides it by the number of steps.

Goal: generated <= 1.0 x hand-written.  A missed goal is reported, not an
error: the script exits 0 whenever it could measure (1 if the two versions
disagree, 2 if a tool is missing or a build fails).
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
CSRC = HERE / "c_ahead"
DESIGN = ROOT / "examples" / "submarine" / "submarine.rcs"

CFLAGS = ["-O2", "-std=c99", "-ffp-contract=off"]
# -g for callgrind_annotate's source lines; DWARF 4 because valgrind 3.19
# cannot read clang 14's default DWARF 5.  Debug info does not change the code.
DEBUG = ["-gdwarf-4"]
GOAL = 1.0

VARIANTS = [("generated", "submarine_PR__step"), ("hand-written", "hand_pr_step")]


def generate(out: Path, target: str = "c") -> None:
    """The current generator's output for the submarine (exit 2 if it fails)."""
    cmd = [sys.executable, "-m", "rcsc", "build", str(DESIGN), "--target", target, "-o", str(out)]
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        print(f"rcsc build --target {target} failed ({r.returncode}):\n{r.stdout}{r.stderr}", file=sys.stderr)
        sys.exit(2)


def compile_driver(cc: str, gen: Path, exe: Path) -> None:
    srcs = [CSRC / "driver.c", CSRC / "handwritten_pr.c", gen / "submarine_PR.c", gen / "submarine.c"]
    cmd = [cc, *CFLAGS, *DEBUG, "-Wall", "-Wextra", f"-I{gen}", f"-I{CSRC}", *map(str, srcs), "-o", str(exe)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        print(" ".join(cmd), file=sys.stderr)
        print(r.stderr, file=sys.stderr)
        sys.exit(2)


def run_native(exe: Path, steps: int) -> dict[str, int]:
    """Runs the driver (both variants, buffers compared every step); returns the rule mix."""
    r = subprocess.run([str(exe), str(steps)], capture_output=True, text=True)
    if r.returncode != 0:
        print(r.stdout + r.stderr, file=sys.stderr)
        print("FAIL: the generated and the hand-written PR disagree (see above)", file=sys.stderr)
        sys.exit(1)
    return {m.group(1): int(m.group(2)) for m in re.finditer(r"^count (\S+) (\d+)$", r.stdout, re.M)}


def callgrind(exe: Path, steps: int, fn: str, out: Path) -> int:
    """Instructions executed inside `fn` (and its callees) over the run."""
    cmd = [
        "valgrind", "--tool=callgrind", "--collect-atstart=no", f"--toggle-collect={fn}",
        f"--callgrind-out-file={out}", str(exe), str(steps),
    ]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        print(r.stderr[-3000:], file=sys.stderr)
        sys.exit(2)
    return read_ir(out)


def read_ir(out: Path) -> int:
    """The Ir total of a callgrind output file (`events:` names the columns)."""
    events: list[str] = ["Ir"]
    total = None
    for line in out.read_text().splitlines():
        if line.startswith("events:"):
            events = line.split()[1:]
        elif line.startswith(("summary:", "totals:")):
            total = [int(x) for x in line.split()[1:]]
    if total is None:
        raise ValueError(f"no summary in {out}")
    return total[events.index("Ir")]


def annotate(out: Path, steps: int, top: int, dirs: tuple[Path, ...] = ()) -> list[tuple[float, str]]:
    """The `top` costliest source lines of a callgrind run: (Ir per step, source line).

    `dirs`: where callgrind_annotate looks for sources it cannot find by their recorded path."""
    inc = [f"--include={d}" for d in dirs]
    for opts in (["--show-percs=no"], []):  # older callgrind_annotate has no --show-percs
        r = subprocess.run(["callgrind_annotate", "--auto=yes", *opts, *inc, str(out)], capture_output=True, text=True)
        if r.returncode == 0:
            break
    rows = []
    in_source = False
    for line in r.stdout.splitlines():
        if "Auto-annotated source" in line:
            in_source = True
            continue
        m = re.match(r"^\s*([\d,]+)\s+(?:\([\s\d.]+%\)\s+)?(.*)$", line)
        if not in_source or not m or m.group(2).startswith("<") or "events annotated" in m.group(2):
            continue
        rows.append((int(m.group(1).replace(",", "")) / steps, m.group(2).strip()))
    rows.sort(key=lambda t: -t[0])
    return rows[:top]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=10000, help="controller steps per run (default 10000)")
    ap.add_argument("--compilers", default="gcc,clang", help="comma-separated (default gcc,clang)")
    ap.add_argument("--annotate", action="store_true", help="print the costliest source lines of each variant")
    ap.add_argument("--top", type=int, default=15, help="lines per variant with --annotate (default 15)")
    ap.add_argument("--keep", metavar="DIR", help="build in DIR and keep it (default: a temporary directory)")
    args = ap.parse_args(argv)

    if shutil.which("valgrind") is None:
        print("valgrind not found", file=sys.stderr)
        return 2
    compilers = [c for c in args.compilers.split(",") if c]
    missing = [c for c in compilers if shutil.which(c) is None]
    for c in missing:
        print(f"note: compiler {c} not found, skipped", file=sys.stderr)
    compilers = [c for c in compilers if c not in missing]
    if not compilers:
        return 2

    tmp = None
    if args.keep:
        work = Path(args.keep)
        work.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="bench_c_step_")
        work = Path(tmp.name)
    try:
        gen = work / "gen"
        generate(gen)
        results = []  # (compiler, {variant: ir_per_step})
        notes = {}
        mix = None
        for cc in compilers:
            exe = work / f"driver_{cc}"
            compile_driver(cc, gen, exe)
            mix = run_native(exe, args.steps)
            per_step = {}
            for variant, fn in VARIANTS:
                out = work / f"callgrind.{cc}.{fn}.out"
                per_step[variant] = callgrind(exe, args.steps, fn, out) / args.steps
                if args.annotate:
                    notes[(cc, variant)] = annotate(out, args.steps, args.top)
            results.append((cc, per_step))

        print(f"PR AHEAD plan (submarine.rcs), {args.steps} steps, {' '.join(CFLAGS)}")
        if mix:
            print("rule mix per run: " + ", ".join(f"{k} {v}" for k, v in mix.items()))
        print("buffers identical after every step: yes (checked by the driver)")
        print()
        header = f"{'compiler':<9} {'generated':>12} {'hand-written':>13} {'ratio gen/hand':>15}  goal (<= {GOAL:.1f}x)"
        print(header)
        print("-" * len(header))
        missed = False
        for cc, per in results:
            ratio = per["generated"] / per["hand-written"]
            ok = ratio <= GOAL
            missed |= not ok
            print(f"{cc:<9} {per['generated']:>12.1f} {per['hand-written']:>13.1f} {ratio:>14.2f}x  {'met' if ok else 'MISSED'}")
        print("(instructions per step, callgrind Ir inside the step function and its callees)")
        if missed:
            print(f"\ngoal missed: the generated step executes more instructions than the hand-written one "
                  f"(run with --annotate for the costliest lines)")
        if args.annotate:
            for (cc, variant), rows in notes.items():
                print(f"\n{cc}, {variant}: costliest source lines (Ir per step)")
                for ir, src in rows:
                    print(f"  {ir:7.2f}  {src[:130]}")
        if args.keep:
            print(f"\nbuild kept in {work}")
    finally:
        if tmp is not None:
            tmp.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main())
