"""bench/synthetic.py keeps generating a valid design, so the benchmark
(bench/bench_check.py) measures a clean check and cannot silently rot."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SYNTHETIC = ROOT / "bench" / "synthetic.py"


def _synthetic():
    spec = importlib.util.spec_from_file_location("rcsc_bench_synthetic", SYNTHETIC)
    module = importlib.util.module_from_spec(spec)
    assert spec.loader is not None
    spec.loader.exec_module(module)
    return module


def _check(tmp_path: Path, text: str):
    from rcsc.driver import check_path

    path = tmp_path / "synthetic.rcs"
    path.write_text(text, encoding="utf-8")
    return check_path(str(path))


@pytest.mark.parametrize(
    "n, p, r",
    [
        (12, 3, 4),   # the small case of the brief
        (12, 5, 10),  # the benchmark's shape: lifecycle verbs, every parameter kind, a continuous plan
        (1, 1, 1),    # degenerate: one controller, one plan, one rule
        (9, 2, 2),
        (60, 4, 3),   # three levels, several CPUs per level
    ],
)
def test_synthetic_design_checks_clean(tmp_path, n, p, r):
    result = _check(tmp_path, _synthetic().generate(n, p, r))
    findings = [f"{d.code} {d.span}: {d.message}" for d in result.diags]
    assert findings == [], "\n".join(findings)
    model = result.model
    assert model is not None
    assert len(model.controllers) == n
    assert all(len(c.plans) == p for c in model.controllers.values())
    assert all(len(plan.rules) == r for c in model.controllers.values() for plan in c.plans.values())
    # a tree with one root, at most 9 subordinates each, levels descending
    roots = [c for c in model.controllers.values() if c.supervisor is None]
    assert len(roots) == 1
    for c in model.controllers.values():
        assert len(c.subordinates) <= 9
        for use in c.subordinates:
            assert model.controllers[use.name].level < c.level


def test_synthetic_command_line(tmp_path):
    out = subprocess.run(
        [sys.executable, str(SYNTHETIC), "3", "2", "4"], capture_output=True, text=True, check=True
    ).stdout
    assert out.startswith("// synthetic design: 3 controllers x 2 plans x 4 rules")
    assert "design synthetic_3_2_4" in out
    assert _check(tmp_path, out).diags.items == []
