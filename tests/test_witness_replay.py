"""Every witness of the guard analysis replays, and its note agrees with the finding.

For every case and example: each finding with a witness was replayed by the
reference simulator (`data.replayed`), and what its text says fires is what
its data say: an E0506's witness names a rule that fires instead, and that
rule is one of the rules the note says hide it; a W0515's earlier rule is
the one that fires.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rcsc.driver import check_path

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "tests" / "cases"
DESIGNS = sorted(CASES.glob("*.rcs")) + sorted(CASES.glob("*/main.rcs")) + sorted(ROOT.glob("examples/*/*.rcs"))
GUARD_CODES = {"E0506", "E0513", "W0514", "W0515", "E0516", "W0517"}


@pytest.mark.parametrize("path", DESIGNS, ids=[p.parent.name if p.name == "main.rcs" else p.stem for p in DESIGNS])
def test_witnesses_replay_and_agree_with_their_notes(path: Path) -> None:
    result = check_path(str(path))
    for d in list(result.diags) + result.diags.suppressed:
        if d.code not in GUARD_CODES or "witness" not in d.data:
            continue
        where = f"{path.name}:{d.span.line}:{d.span.col} {d.code}"
        assert d.data.get("replayed") is True, f"{where}: the witness does not replay: {d.notes}"
        witness_notes = [n for n in d.notes if n.startswith("witness:")]
        assert len(witness_notes) == 1, where
        if d.code == "E0506" and "fires" in d.data:
            assert d.data["fires"] in d.data["covered_by"], f"{where}: the witness fires `{d.data['fires']}`, the note names {d.data['covered_by']}"
            assert f"`{d.data['fires']}` fires" in witness_notes[0], where
        if d.code == "W0515":
            assert d.data["fires"] == d.data["rules"][1], where
            assert d.notes[0].startswith(f"`{d.data['fires']}`"), where
