"""rcsc's SARIF output against the official SARIF 2.1.0 JSON schema.

The schema is vendored in tests/data/ (see tests/data/README.md for where it
came from), so this runs without a network.  Besides schema validity it checks
what code-scanning services rely on: the rule table, ruleIndex, exclusive end
columns and fingerprints that do not move with line numbers.
"""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest

from conftest import make_render_cases
from rcsc.codes import CODES
from rcsc.diagnostics import Diagnostic, Label, Severity
from rcsc.render import FINGERPRINT_KEY, render_sarif
from rcsc.front.source import SourceFile, Span

SCHEMA_PATH = Path(__file__).parent / "data" / "sarif-schema-2.1.0.json"


@pytest.fixture(scope="module")
def validator() -> jsonschema.Draft7Validator:
    schema = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
    # The schema says which draft it is written in; hold it to that.
    assert schema["$schema"] == "http://json-schema.org/draft-07/schema#"
    jsonschema.Draft7Validator.check_schema(schema)
    return jsonschema.Draft7Validator(schema, format_checker=jsonschema.Draft7Validator.FORMAT_CHECKER)


def _assert_valid(validator: jsonschema.Draft7Validator, log: dict) -> None:
    errors = sorted(validator.iter_errors(log), key=lambda e: list(e.absolute_path))
    assert not errors, "\n".join(f"{list(e.absolute_path)}: {e.message}" for e in errors[:10])


def _finding(file: SourceFile, needle: str, **kw) -> Diagnostic:
    start = file.text.index(needle)
    return Diagnostic("E0100", Severity.ERROR, f"unknown name `{needle}`", Span(file, start, start + len(needle)), **kw)


@pytest.mark.parametrize("case", sorted(make_render_cases()))
def test_every_render_case_is_valid_sarif(case: str, validator) -> None:
    log = json.loads(render_sarif(make_render_cases()[case], "0.1.0"))
    _assert_valid(validator, log)


def test_valid_with_root_uri_and_odd_paths(validator, tmp_path: Path) -> None:
    files = [
        SourceFile("dir with space/d\u00e9sign.rcs", "x\n"),
        SourceFile("/abs/path/design.rcs", "x\n"),
        SourceFile("./rel/a:b.rcs", "x\n"),
        SourceFile("<std>/math.rcs", "x\n"),
    ]
    log = json.loads(render_sarif([_finding(f, "x") for f in files], "0.1.0", root_uri=str(tmp_path)))
    _assert_valid(validator, log)
    run = log["runs"][0]
    assert run["originalUriBaseIds"]["%SRCROOT%"]["uri"].startswith("file:///")
    assert run["originalUriBaseIds"]["%SRCROOT%"]["uri"].endswith("/")
    uris = {r["locations"][0]["physicalLocation"]["artifactLocation"]["uri"] for r in run["results"]}
    assert uris == {"dir%20with%20space/d%C3%A9sign.rcs", "file:///abs/path/design.rcs", "rel/a%3Ab.rcs", "%3Cstd%3E/math.rcs"}
    for r in run["results"]:
        location = r["locations"][0]["physicalLocation"]["artifactLocation"]
        assert ("uriBaseId" in location) == (not location["uri"].startswith("file:"))


def test_rules_are_every_code_and_rule_index_points_at_the_rule(validator) -> None:
    log = json.loads(render_sarif(make_render_cases()["all"], "0.1.0"))
    run = log["runs"][0]
    rules = run["tool"]["driver"]["rules"]
    assert [rule["id"] for rule in rules] == sorted(CODES)
    for rule in rules:
        code = CODES[rule["id"]]
        assert rule["shortDescription"]["text"] == code.title
        assert rule["defaultConfiguration"]["level"] == code.severity.value
        assert rule["name"][0].isupper() and rule["name"].isalnum()
    assert run["results"]
    for result in run["results"]:
        assert rules[result["ruleIndex"]]["id"] == result["ruleId"]


def test_results_levels_regions_and_messages() -> None:
    file = SourceFile("d.rcs", "a\n  foo bar\n")
    d = _finding(file, "foo", label="here")
    d.notes.append("a note")
    d.helps.append("a help")
    d.labels.append(Label(_finding(file, "bar").span, "related"))
    warning = Diagnostic("W0310", Severity.WARNING, "too many subordinates", None)
    log = json.loads(render_sarif([d, warning], "0.1.0"))
    by_rule = {r["ruleId"]: r for r in log["runs"][0]["results"]}
    result = by_rule["E0100"]
    assert result["level"] == "error" and by_rule["W0310"]["level"] == "warning"
    assert "locations" not in by_rule["W0310"]
    assert result["message"]["text"] == "unknown name `foo`\nnote: a note\nhelp: a help"
    location = result["locations"][0]
    # 1-based columns; endColumn is exclusive, as SARIF says.
    assert location["physicalLocation"]["region"] == {"startLine": 2, "startColumn": 3, "endLine": 2, "endColumn": 6}
    assert location["message"]["text"] == "here"
    (related,) = result["relatedLocations"]
    assert related["id"] == 1 and related["message"]["text"] == "related"
    assert related["physicalLocation"]["region"]["startColumn"] == 7


def test_fingerprints_ignore_line_moves_but_separate_twins() -> None:
    before = SourceFile("d.rcs", "foo\n")
    after = SourceFile("d.rcs", "\n\n// moved\nfoo\n")
    twins = SourceFile("d.rcs", "foo\nfoo\n")

    def prints(file: SourceFile, diags: list[Diagnostic]) -> list[str]:
        log = json.loads(render_sarif(diags, "0.1.0"))
        return [r["partialFingerprints"][FINGERPRINT_KEY] for r in log["runs"][0]["results"]]

    assert prints(before, [_finding(before, "foo")]) == prints(after, [_finding(after, "foo")])
    second = Diagnostic("E0100", Severity.ERROR, "unknown name `foo`", Span(twins, 4, 7))
    first, other = prints(twins, [_finding(twins, "foo"), second])
    assert first != other
    assert first == prints(before, [_finding(before, "foo")])[0]


def test_sarif_output_is_deterministic() -> None:
    assert render_sarif(make_render_cases()["all"], "0.1.0") == render_sarif(make_render_cases()["all"], "0.1.0")


def test_the_validator_rejects_a_broken_log(validator) -> None:
    # Guards against a schema or validator set-up that accepts anything.
    log = json.loads(render_sarif(make_render_cases()["primary-label-note-help"], "0.1.0"))
    log["runs"][0]["results"][0]["locations"][0]["physicalLocation"]["region"]["startLine"] = 0
    log["runs"][0]["results"][0]["level"] = "fatal"
    assert len(list(validator.iter_errors(log))) == 2


def test_windows_paths() -> None:
    from rcsc.render import _artifact_location

    assert _artifact_location("C:\\work\\design.rcs") == {"uri": "file:///C:/work/design.rcs"}
    assert _artifact_location("sub\\design.rcs") == {"uri": "sub/design.rcs", "uriBaseId": "%SRCROOT%"}
    assert _artifact_location("C:design.rcs") == {"uri": "C%3Adesign.rcs", "uriBaseId": "%SRCROOT%"}
