"""The complete designs in the documentation check as documented.

Every fenced block tagged ```rcs in README.md and docs/*.md is a complete
design (it begins with `design NAME`).  It must produce exactly the findings
its `// expect: CODE @ LINE:COL` comments announce (lines counted from the
block's first line), warnings included: a block without annotations checks
clean with `--deny-warnings`.  Untagged blocks are fragments and are not run.
"""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import pytest

from rcsc.driver import check_path

ROOT = Path(__file__).resolve().parent.parent
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
_FENCE = re.compile(r"^```rcs\n(.*?)^```$", re.S | re.M)
_EXPECT = re.compile(r"//\s*expect:\s*([EW]\d{4})\s*@\s*(\d+):(\d+)\s*$")


def _blocks() -> list[tuple[str, str]]:
    out = []
    for doc in DOCS:
        text = doc.read_text(encoding="utf-8")
        for mt in _FENCE.finditer(text):
            line = text.count("\n", 0, mt.start()) + 2
            out.append((f"{doc.name}:{line}", mt.group(1)))
    return out


BLOCKS = _blocks()


def test_the_docs_have_complete_designs() -> None:
    names = {name.split(":")[0] for name, _ in BLOCKS}
    assert "language.md" in names, names


@pytest.mark.parametrize("name,text", BLOCKS, ids=[n for n, _ in BLOCKS])
def test_doc_design_checks_as_documented(name: str, text: str, tmp_path: Path) -> None:
    assert text.startswith("design "), f"{name}: an ```rcs block must be a complete design"
    path = tmp_path / "doc.rcs"
    path.write_text(text, encoding="utf-8")
    expected = Counter(
        (mt.group(1), int(mt.group(2)), int(mt.group(3)))
        for mt in map(_EXPECT.search, text.splitlines())
        if mt is not None
    )
    result = check_path(str(path))
    found = Counter((d.code, d.span.line, d.span.col) for d in result.diags if d.span is not None)
    assert all(d.span is not None for d in result.diags), [d.message for d in result.diags]
    assert found == expected, f"{name}: " + "; ".join(f"{d.code} {d.span.line}:{d.span.col} {d.message}" for d in result.diags)
