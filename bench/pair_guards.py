#!/usr/bin/env python3
"""Paired CPU timing of the guard analysis of two checkouts of rcsc.

    git worktree add /tmp/rcsc-old bf4f6ab
    python bench/pair_guards.py /tmp/rcsc-old [--rounds 3] [--size 50]

For each checkout (the given one and this one), in a fresh process, it
builds the checked model of each example and of the synthetic design
(bench/synthetic.py SIZE 20 10) with every check family but the guard
analysis (not timed), then times `guards.check` with `time.process_time`,
best of 3 in the process: the examples together, then the synthetic design.
The versions alternate, --rounds times; it prints each figure, the medians
and the ratio new/old.  Both versions read the same synthetic file (written
by this checkout's generator).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time
root, syn = sys.argv[1], sys.argv[2]
sys.path.insert(0, root)
import rcsc
assert rcsc.__file__.startswith(root), rcsc.__file__
from pathlib import Path
from rcsc.checks import FAMILIES, guards
from rcsc.diagnostics import Diagnostics
from rcsc.front.loader import path_to_files
from rcsc.semantics.sema import ast_to_model
from rcsc.sim.testrun import is_design_file

def load(path):
    diags = Diagnostics()
    design = ast_to_model(path_to_files(path, diags), diags)
    for family in FAMILIES:
        if family is not guards:
            family.check(design, diags)
    return design

def best(designs):
    out = []
    for _ in range(3):
        t = time.process_time()
        for d in designs:
            guards.check(d, Diagnostics())
        out.append(time.process_time() - t)
    return min(out)

examples = [load(str(p)) for p in sorted((Path(root) / "examples").glob("*/*.rcs")) if is_design_file(str(p))]
synthetic = load(syn)
print(json.dumps({"examples": best(examples), "synthetic": best([synthetic])}))
"""


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old", help="the other checkout (e.g. a git worktree of an older commit)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--size", type=int, default=50, help="controllers of the synthetic design (default 50)")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT / "bench"))
    import synthetic

    roots = {"old": str(Path(args.old).resolve()), "new": str(ROOT)}
    got: dict = {k: {"examples": [], "synthetic": []} for k in roots}
    with tempfile.TemporaryDirectory(prefix="rcsc-pair-") as tmp:
        syn = Path(tmp) / f"synthetic_{args.size}.rcs"
        syn.write_text(synthetic.generate(args.size, 20, 10), encoding="utf-8")
        for i in range(args.rounds):
            for name, root in roots.items():
                out = subprocess.run([sys.executable, "-c", CHILD, root, str(syn)], capture_output=True, text=True, check=True)
                res = json.loads(out.stdout.strip().splitlines()[-1])
                for k, v in res.items():
                    got[name][k].append(v)
                print(f"round {i + 1} {name}: examples {res['examples']:.3f} s, synthetic {res['synthetic']:.3f} s", flush=True)
    for k in ("examples", "synthetic"):
        old, new = statistics.median(got["old"][k]), statistics.median(got["new"][k])
        print(f"{k}: median old {old:.3f} s, new {new:.3f} s, new/old {new / old:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
