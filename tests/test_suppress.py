"""In-source suppression: `// rcsc: allow(CODE) reason` (rcsc.checks.suppress)."""

from __future__ import annotations

import json
from pathlib import Path

from rcsc import cli
from rcsc.driver import check_path
from rcsc.render import render_json, render_sarif

CASE = Path(__file__).parent / "cases" / "W0008_suppressions.rcs"


def test_allowed_findings_leave_the_report_but_not_sarif() -> None:
    result = check_path(str(CASE))
    assert {(d.code, d.span.line) for d in result.diags.suppressed} == {("W0403", 17), ("W0515", 32)}
    assert not any(d.code == "W0515" for d in result.diags)
    doc = json.loads(render_json(result.diags, "test"))
    assert "W0515" not in {d["code"] for d in doc["diagnostics"]}
    sarif = json.loads(render_sarif(result.diags, "test"))
    suppressed = [r for r in sarif["runs"][0]["results"] if "suppressions" in r]
    assert sorted(r["ruleId"] for r in suppressed) == ["W0403", "W0515"]
    w0515 = next(r for r in suppressed if r["ruleId"] == "W0515")
    assert w0515["suppressions"] == [{"kind": "inSource", "justification": "below 50 we drain first, on purpose"}]
    assert w0515["properties"]["suppression"]["line"] == 31
    assert w0515["locations"][0]["physicalLocation"]["region"]["startLine"] == 32


def test_a_fully_allowed_design_passes_deny_warnings(tmp_path: Path, capsys) -> None:
    text = CASE.read_text(encoding="utf-8")
    # Keep only the well-formed suppressions and the variables they cover.
    lines = [ln for ln in text.splitlines() if not any(f"log_{x}: i32" in ln for x in "bcdef")]
    text = "\n".join(lines).replace(", log_b, log_c, log_d, log_e, log_f", "")
    text = text.replace(", log_b = 1, log_c = 1, log_d = 1, log_e = 1, log_f = 1", "")
    path = tmp_path / "ok.rcs"
    path.write_text(text, encoding="utf-8")
    assert cli.main(["check", "--deny-warnings", str(path)]) == 0, capsys.readouterr()
    # Without the comment the same design fails: the suppression did the work.
    path.write_text(text.replace("// rcsc: allow(W0515)", "// "), encoding="utf-8")
    assert cli.main(["check", "--deny-warnings", str(path)]) == 1
