#!/usr/bin/env python3
"""Instructions per controller step: generated Rust against generated C.

    python bench/bench_rust_step.py                  # gcc and clang, 10000 steps
    python bench/bench_rust_step.py --annotate       # also the costliest source lines
    python bench/bench_rust_step.py --compilers gcc --steps 20000 --keep /tmp/rstep

The subject is the one of bench/bench_c_step.py: the submarine's PR
controller running its AHEAD plan.  The script

1. generates examples/submarine/submarine.rcs twice with `rcsc build`, with
   `--target c` and with `--target rust`, into a temporary directory (so it
   always measures the current generator);
2. compiles bench/rust_ahead/driver_c.c with the generated submarine_PR.c
   and submarine.c, for each C compiler, with bench_c_step.py's flags
   (`-O2 -std=c99 -ffp-contract=off`);
3. builds bench/rust_ahead/driver.rs (a port of bench/c_ahead/driver.c: the
   same plant, TB model, AHEAD commands, TB status and ship speed sequence)
   as a Cargo crate of its own with a path dependency on the generated
   library crate: `cargo build --release --offline`, release profile with
   opt-level 3, overflow checks on (as in the generated Cargo.toml) and debug
   info (for callgrind_annotate; it does not change the code);
4. runs every driver natively: each prints the rule mix and an FNV-1a digest
   of what PR wrote after every step (its status head and tb_fault, TB's
   command head and rpm); the outputs must be identical, or the script shows
   the first step that differs and exits 1 - the proof that both compute the
   same thing;
5. runs each under `valgrind --tool=callgrind --toggle-collect=<step>`
   (`submarine_PR__step`, as bench_c_step.py, and `submarine::ctrl_PR::PR::step`;
   the drivers call them through never-inlined wrappers, bench_c_pr_step and
   bench_rust_pr_step, which are the fallback target) and divides the
   collected instruction count (Ir) by the number of steps.

Goal: Rust <= 1.1 x C, against each C compiler.  A missed goal is reported,
not an error: the script exits 0 whenever it could measure (1 if the drivers
disagree, 2 if a tool is missing or a build fails).
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import bench_c_step as cstep  # noqa: E402  (same directory: flags, Ir reader, annotator)

ROOT = HERE.parent
RSRC = HERE / "rust_ahead"
DESIGN = ROOT / "examples" / "submarine" / "submarine.rcs"
GOAL = 1.1

C_STEP = ("submarine_PR__step", "bench_c_pr_step")
RUST_STEP = ("submarine::ctrl_PR::PR::step", "bench_rust_pr_step")

CARGO_TOML = """\
# written by bench/bench_rust_step.py
[package]
name = "pr_ahead_bench"
version = "0.0.0"
edition = "2021"
publish = false

[[bin]]
name = "driver_rust"
path = "src/main.rs"

[dependencies]
submarine = {{ path = "{gen}" }}

# The root package's profile applies to the generated library too.
[profile.release]
opt-level = 3
overflow-checks = true
debug = true

[workspace]
"""


def fail(msg: str, code: int) -> None:
    print(msg, file=sys.stderr)
    sys.exit(code)


def compile_c(cc: str, gen: Path, exe: Path) -> None:
    srcs = [RSRC / "driver_c.c", gen / "submarine_PR.c", gen / "submarine.c"]
    cmd = [cc, *cstep.CFLAGS, *cstep.DEBUG, "-Wall", "-Wextra", f"-I{gen}", f"-I{cstep.CSRC}", *map(str, srcs), "-o", str(exe)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        fail(" ".join(cmd) + "\n" + r.stderr, 2)


def build_rust(gen: Path, crate: Path) -> Path:
    (crate / "src").mkdir(parents=True, exist_ok=True)
    (crate / "Cargo.toml").write_text(CARGO_TOML.format(gen=gen.as_posix()))
    shutil.copyfile(RSRC / "driver.rs", crate / "src" / "main.rs")
    target = crate / "target"
    cmd = ["cargo", "build", "--release", "--offline", "--target-dir", str(target)]
    r = subprocess.run(cmd, cwd=crate, capture_output=True, text=True)
    if r.returncode != 0:
        fail(" ".join(cmd) + "\n" + r.stdout + r.stderr, 2)
    return target / "release" / "driver_rust"


def run(exe: Path, steps: int, *extra: str) -> str:
    r = subprocess.run([str(exe), str(steps), *extra], capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"{exe} failed ({r.returncode}):\n{r.stdout[-2000:]}{r.stderr[-2000:]}", 2)
    return r.stdout


def first_difference(a: Path, b: Path, steps: int) -> str:
    """The first step whose trace line differs between drivers a and b."""
    ta, tb = run(a, steps, "trace").splitlines(), run(b, steps, "trace").splitlines()
    fields = "cycle echo status verb state rule err stamp tb_fault | TB serial verb rpm_bits"
    for la, lb in zip(ta, tb):
        if la != lb:
            return f"first difference (step {la.split()[0]}; {fields}):\n  {a.name}: {la}\n  {b.name}: {lb}"
    return "traces identical: the difference is in the final lines"


def callgrind(exe: Path, steps: int, fns: tuple[str, ...], out: Path) -> tuple[str, int]:
    """Instructions executed inside the first of `fns` that collects any (and its callees)."""
    for fn in fns:
        ir = cstep.callgrind(exe, steps, fn, out)
        if ir > 0:
            return fn, ir
    fail(f"callgrind collected nothing in {exe} ({', '.join(fns)})", 2)
    raise AssertionError


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=10000, help="controller steps per run (default 10000)")
    ap.add_argument("--compilers", default="gcc,clang", help="C compilers, comma-separated (default gcc,clang)")
    ap.add_argument("--annotate", action="store_true", help="print the costliest source lines of each variant")
    ap.add_argument("--top", type=int, default=15, help="lines per variant with --annotate (default 15)")
    ap.add_argument("--keep", metavar="DIR", help="build in DIR and keep it (default: a temporary directory)")
    args = ap.parse_args(argv)

    for tool in ("valgrind", "cargo"):
        if shutil.which(tool) is None:
            print(f"{tool} not found", file=sys.stderr)
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
        work = Path(args.keep).resolve()
        work.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="bench_rust_step_")
        work = Path(tmp.name)
    try:
        gen_c, gen_rs = work / "gen_c", work / "gen_rust"
        cstep.generate(gen_c, "c")
        cstep.generate(gen_rs, "rust")
        exes: list[tuple[str, Path, tuple[str, ...]]] = []
        for cc in compilers:
            exe = work / f"driver_{cc}"
            compile_c(cc, gen_c, exe)
            exes.append((f"C {cc} -O2", exe, C_STEP))
        rust_exe = build_rust(gen_rs, work / "driver_rust")
        exes.append(("Rust release", rust_exe, RUST_STEP))

        # Cross-check: identical rule mix, final buffers and per-step digest.
        outputs = {name: run(exe, args.steps) for name, exe, _ in exes}
        ref_name, ref_exe, _ = exes[-1]
        for name, exe, _ in exes[:-1]:
            if outputs[name] != outputs[ref_name]:
                print(f"FAIL: {name} and {ref_name} disagree\n--- {name}\n{outputs[name]}--- {ref_name}\n{outputs[ref_name]}",
                      file=sys.stderr)
                print(first_difference(exe, ref_exe, args.steps), file=sys.stderr)
                return 1
        ref = outputs[ref_name].splitlines()
        mix = [ln.split()[1:] for ln in ref if ln.startswith("count ")]
        digest = next((ln.split()[1] for ln in ref if ln.startswith("digest ")), "?")

        per_step: dict[str, float] = {}
        toggled: dict[str, str] = {}
        notes: dict[str, list[tuple[float, str]]] = {}
        for name, exe, fns in exes:
            out = work / f"callgrind.{exe.name}.out"
            toggled[name], ir = callgrind(exe, args.steps, fns, out)
            per_step[name] = ir / args.steps
            if args.annotate:
                notes[name] = cstep.annotate(out, args.steps, args.top, (work, gen_c, gen_rs))

        rustc = subprocess.run(["rustc", "--version"], capture_output=True, text=True).stdout.strip()
        print(f"PR AHEAD plan (submarine.rcs), {args.steps} steps; C: {' '.join(cstep.CFLAGS)}; "
              f"Rust: {rustc}, release, opt-level 3, overflow-checks on")
        print("rule mix per run: " + ", ".join(f"{k} {v}" for k, v in mix))
        print(f"cross-check: every driver wrote the same PR status and TB command after every step "
              f"(digest {digest}): yes")
        print()
        rust = per_step[ref_name]
        header = f"{'variant':<14} {'instr/step':>10} {'Rust/this':>10}  goal (Rust <= {GOAL:.1f}x C)"
        print(header)
        print("-" * len(header))
        missed = False
        for name, _, _ in exes[:-1]:
            ratio = rust / per_step[name]
            ok = ratio <= GOAL
            missed |= not ok
            print(f"{name:<14} {per_step[name]:>10.1f} {ratio:>9.2f}x  {'met' if ok else 'MISSED'}")
        print(f"{ref_name:<14} {rust:>10.1f} {'':>10}")
        print("(instructions per step: callgrind Ir inside " + ", ".join(sorted(set(toggled.values()))) + " and callees)")
        if missed:
            print(f"\ngoal missed: the Rust step executes more than {GOAL:.1f}x the instructions of the C one "
                  f"(run with --annotate for the costliest lines)")
        if args.annotate:
            for name, rows in notes.items():
                print(f"\n{name}: costliest source lines (Ir per step)")
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
