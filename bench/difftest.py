"""The differential tester: random designs through the simulator, C, Rust and Ada, traces compared.

    python bench/difftest.py --seeds 0..99
    python bench/difftest.py --seeds 0..49 --targets c --jobs 2
    python bench/difftest.py --seeds 0..19 --hostile-names --out difftest-repros
    python bench/difftest.py --seeds 17..17 --minimise

For every seed, bench/difftest_gen.py draws a design that checks clean and a
scenario for it; bench/difftest_run.py runs the scenario in the reference
simulator and in every build (C: gcc -O0, gcc -O2, clang -O2, clang with
ASan+UBSan; Rust: debug and release, plus clippy -D warnings; Ada: gprbuild -O0/-O2) and compares the
traces byte for byte.  Seeds go in batches (`--batch`, one cargo workspace per
batch).  It prints the figures (designs per minute, disagreements, warnings,
failures) and writes each failing seed's design, scenario and findings to the
output folder, minimised with `--minimise` (bench/difftest_min.py).  Exit
code 1 when anything was found.
"""

from __future__ import annotations

import argparse
import sys
import time
import traceback
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from difftest_gen import generate  # noqa: E402
from difftest_min import finding_predicate, minimise  # noqa: E402
from difftest_run import Finding, run_batch  # noqa: E402


def parse_seeds(text: str) -> range:
    a, _, b = text.partition("..")
    return range(int(a), int(b or a) + 1)


def write_repro(out: Path, case, findings: list[Finding], minimised=None) -> Path:
    folder = out / f"seed{case.seed}"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{case.name}.rcs").write_text(case.design, encoding="utf-8")
    (folder / f"{case.name}.scn").write_text(case.scenario, encoding="utf-8")
    (folder / "findings.txt").write_text("\n\n".join(f"{f.kind} in {f.where}:\n{f.detail}" for f in findings), encoding="utf-8")
    if minimised is not None:
        (folder / "min.rcs").write_text(minimised.design, encoding="utf-8")
        (folder / "min.scn").write_text(minimised.scenario, encoding="utf-8")
    return folder


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0..9", help="A..B, both included")
    ap.add_argument("--hostile-names", action="store_true", help="names that are C/Rust keywords, macros, colliding or long")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--targets", default="c,rust,ada")
    ap.add_argument("--batch", type=int, default=10, help="seeds per cargo workspace")
    ap.add_argument("--out", default="difftest-repros", help="folder for the repros of failing seeds")
    ap.add_argument("--max-seconds", type=float, default=0.0,
                    help="start no new batch after this many seconds (0: no limit); the figures cover the seeds run")
    ap.add_argument("--minimise", action="store_true", help="shrink each failing seed (slow)")
    ap.add_argument("--minimise-seconds", type=float, default=300.0)
    args = ap.parse_args(argv)
    targets = [t for t in args.targets.split(",") if t]
    seeds = list(parse_seeds(args.seeds))
    out = Path(args.out)
    start = time.monotonic()
    gen_time = 0.0
    kinds: Counter = Counter()
    failing: dict[int, list[Finding]] = {}
    cases = {}
    retries = 0
    ran = seeds
    for i in range(0, len(seeds), args.batch):
        if args.max_seconds and time.monotonic() - start > args.max_seconds:
            ran = seeds[:i]
            break
        t0 = time.monotonic()
        batch, crashed = [], []
        for s in seeds[i:i + args.batch]:
            try:
                batch.append(generate(s, hostile=args.hostile_names))
            except Exception:  # noqa: BLE001 - the checker crashed on a draw: a finding, and the run goes on
                crashed.append(Finding(s, "crash", "rcsc check (generator)", traceback.format_exc()))
        gen_time += time.monotonic() - t0
        retries += sum(c.attempt for c in batch)
        for c in batch:
            cases[c.seed] = c
        findings = crashed + run_batch(batch, targets, jobs=args.jobs)
        for f in findings:
            kinds[f.kind] += 1
            failing.setdefault(f.seed, []).append(f)
            print(f.line(), flush=True)
        done = min(i + args.batch, len(seeds))
        rate = done / (time.monotonic() - start) * 60
        print(f"[{done}/{len(seeds)}] {rate:.1f} designs/min, {len(failing)} failing seeds so far", flush=True)
    elapsed = time.monotonic() - start
    for seed, fs in sorted(failing.items()):
        case = cases.get(seed)
        if case is None:  # a finding of a whole batch (seed -1), or the checker crashed on a draw of the seed
            folder = out / (f"seed{seed}" if seed >= 0 else "")
            folder.mkdir(parents=True, exist_ok=True)
            name = "findings.txt" if seed >= 0 else "batch-findings.txt"
            (folder / name).write_text("\n\n".join(f"{f.where}:\n{f.detail}" for f in fs), encoding="utf-8")
            print(f"seed {seed}: findings in {folder / name}")
            continue
        small = None
        if args.minimise:
            f = fs[0]
            small, tries = minimise(case, finding_predicate(f.kind, f.where), args.minimise_seconds)
            print(f"seed {seed}: minimised in {tries} candidates to {len(small.design.splitlines())} design lines", flush=True)
        print(f"seed {seed}: repro in {write_repro(out, case, fs, small)}")
    print(f"\nseeds {ran[0]}..{ran[-1]}: {len(ran)} designs in {elapsed:.0f} s "
          f"({len(ran) / elapsed * 60:.1f} designs/min; generation and checks {gen_time:.0f} s, {retries} redraws), "
          f"targets {','.join(targets)}{', hostile names' if args.hostile_names else ''}")
    print(f"disagreements: {kinds['disagree']}, warnings: {kinds['warning']}, failures: {kinds['fail']}, "
          f"crashes: {kinds['crash']}, invalid designs: {kinds['invalid']}, failing seeds: {len(failing)}")
    return 1 if failing else 0


if __name__ == "__main__":
    sys.exit(main())
