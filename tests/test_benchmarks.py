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


def test_rust_benchmark_cross_checks_rust_against_c() -> None:
    """bench/bench_rust_step.py runs the same 10,000 AHEAD steps in Rust and C and compares every one."""
    proc = subprocess.run([sys.executable, str(ROOT / "bench/bench_rust_step.py")], capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert re.search(r"cross-check: .* after every step \(digest [0-9a-f]+\): yes", proc.stdout), proc.stdout
    rust = re.search(r"^Rust release\s+([\d.]+)", proc.stdout, re.M)
    assert rust and float(rust.group(1)) > 0, proc.stdout


def test_check_benchmark_prints_every_column_and_stage() -> None:
    """bench/bench_check.py on tiny designs: fresh-process cold/warm/edit runs and the stage breakdown."""
    script = Path(__file__).resolve().parents[1] / "bench" / "bench_check.py"
    proc = subprocess.run([sys.executable, str(script), "--sizes", "2,3", "--plans", "3", "--rules", "4"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    rows = [line for line in proc.stdout.splitlines() if line.strip().startswith(("2 ", "3 "))]
    assert len(rows) == 2 and all(len(r.split("|")) == 6 for r in rows), proc.stdout
    assert "parse" in proc.stdout and "names+types" in proc.stdout and "guards" in proc.stdout
    assert "language server re-check after one edit" in proc.stdout
    assert re.search(r"edit of a declaration outside the controllers[^\n]*\n[^\n]*\n +2: \d+\.\d\d\n +3: \d+\.\d\d$", proc.stdout, re.M), proc.stdout
    assert re.search(r"^ +3: system \d+\.\d\d s of \d+\.\d\d s CPU, [\d,]+ minor page faults$", proc.stdout, re.M), proc.stdout


def test_lsp_benchmark_times_every_example_with_the_servers_store() -> None:
    """bench/bench_lsp.py prints a row per example; it uses the memory that
    `rcsc lsp` keeps (the last check, the solver's analyses), so it times what
    the server does."""
    root = Path(__file__).resolve().parents[1]
    proc = subprocess.run([sys.executable, str(root / "bench" / "bench_lsp.py"), "--runs", "1"], capture_output=True, text=True,
                          cwd=root, timeout=300)
    assert proc.returncode == 0, proc.stderr
    for example in sorted((root / "examples").glob("*/*.rcs")):
        row = next((ln for ln in proc.stdout.splitlines() if ln.startswith(example.relative_to(root).as_posix())), None)
        assert row is not None, proc.stdout
        assert float(row.split()[1]) > 0 and row.split()[-1] in ("ok", "missed"), row
    assert "memory=memory" in (root / "bench" / "bench_lsp.py").read_text(encoding="utf-8")
    assert "memory=self.stores" in (root / "rcsc" / "editor" / "lsp.py").read_text(encoding="utf-8")
