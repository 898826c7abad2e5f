"""`rcsc check --format json` of every example and every tests/cases input, byte for byte.

The golden files under tests/golden/check/ were written with the reference
(Lark) parser before the fast front end, caching and the faster checks
came in; they pin the findings (codes, spans, messages, notes, witnesses)
that users see.  `--update-golden` rewrites them, again through the
reference parser (RCSC_PARSER=lark), so that a regeneration cannot hide a
difference of the fast path.
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest

from rcsc.cli import main
from rcsc.testrun import is_design_file

ROOT = Path(__file__).resolve().parents[1]


def _roots() -> list[Path]:
    roots = [p for p in sorted(ROOT.glob("examples/**/*.rcs")) if is_design_file(str(p))]
    cases = ROOT / "tests" / "cases"
    roots += sorted(cases.glob("*.rcs"))
    roots += sorted(d / "main.rcs" for d in cases.iterdir() if d.is_dir())
    return [p.relative_to(ROOT) for p in roots]


ROOTS = _roots()


def _check_json(path: Path) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        main(["check", str(path), "--format", "json"])
    return out.getvalue()


@pytest.mark.parametrize("path", ROOTS, ids=[str(p) for p in ROOTS])
def test_check_output_is_unchanged(path: Path, golden, monkeypatch, request) -> None:
    monkeypatch.chdir(ROOT)
    if request.config.getoption("--update-golden"):
        monkeypatch.setenv("RCSC_PARSER", "lark")
    golden("check/" + str(path.with_suffix(".json")).replace("/", "__"), _check_json(path))


def test_every_example_is_covered() -> None:
    assert any(str(p).startswith("examples/") for p in ROOTS)
    assert len(ROOTS) > 90
