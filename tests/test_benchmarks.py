"""The benchmark scripts keep working (their figures are read by people, not asserted).

bench/bench_c_step.py also proves something: its driver compares the buffers
of the generated and the hand-written AHEAD step after every one of 10,000
steps, so the instruction counts compare two programs that do the same.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_callgrind_benchmark_compares_equivalent_steps() -> None:
    proc = subprocess.run([sys.executable, str(ROOT / "bench/bench_c_step.py")], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "buffers identical after every step: yes" in proc.stdout, proc.stdout
    rows = re.findall(r"^(gcc|clang)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)x", proc.stdout, re.M)
    assert {r[0] for r in rows} == {"gcc", "clang"}, proc.stdout
    for _, gen, hand, ratio in rows:
        assert float(gen) > 0 and float(hand) > 0
        assert abs(float(gen) / float(hand) - float(ratio)) < 0.01
