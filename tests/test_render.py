"""Gold-text tests of the four renderings of diagnostics (rcsc.render).

The inputs are hand-made diagnostics over small source files (see
`make_render_cases` in conftest.py), so these tests do not depend on the front
end.  Regenerate the golden files after a deliberate change of output with

    python -m pytest tests/test_render.py --update-golden

(or RCSC_UPDATE_GOLDEN=1) and review the diff of tests/golden/render/.
"""

from __future__ import annotations

import json
import re

import pytest

from conftest import make_render_cases
from rcsc.diagnostics import Diagnostic, Diagnostics, Label, Severity
from rcsc.render import render_human, render_json, render_sarif, render_short
from rcsc.front.source import SourceFile, Span

VERSION = "0.0.0-test"  # fixed, so that goldens survive version bumps
CASES = sorted(make_render_cases())
ANSI = re.compile(r"\x1b\[[0-9;]*m")


def _diag(code: str, severity: Severity, file: SourceFile, needle: str, label: str = "") -> Diagnostic:
    start = file.text.index(needle)
    return Diagnostic(code, severity, f"finding {code}", Span(file, start, start + len(needle)), label)


def _caret_column(rendered: str, marker: str = "^") -> int:
    """Display column of the first underline, counted after the `| ` gutter."""
    for line in rendered.splitlines():
        body = line.split("| ", 1)[1] if "| " in line else ""
        if line.lstrip().startswith("|") and marker in body:
            return body.index(marker)
    raise AssertionError(f"no {marker!r} underline in:\n{rendered}")


# ---------------------------------------------------------------------------
# golden files
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("case", CASES)
def test_human_golden(case: str, render_cases: dict, golden) -> None:
    golden(f"render/{case}.txt", render_human(render_cases[case], color=False))


def test_human_color_golden(render_cases: dict, golden) -> None:
    golden("render/all.color.txt", render_human(render_cases["all"], color=True))


@pytest.mark.parametrize("case", ["all", "empty"])
def test_short_golden(case: str, render_cases: dict, golden) -> None:
    golden(f"render/{case}.short.txt", render_short(render_cases[case]))


@pytest.mark.parametrize("case", ["all", "empty"])
def test_json_golden(case: str, render_cases: dict, golden) -> None:
    golden(f"render/{case}.json", render_json(render_cases[case], VERSION))


def _without_rule_table(sarif: str) -> str:
    """The SARIF log minus the parts that change whenever a code is added.

    The rule table lists every code of rcsc.codes and ruleIndex points into
    it; test_sarif.py checks both against CODES, so the golden file need not
    be regenerated for each new code.
    """
    log = json.loads(sarif)
    for run in log["runs"]:
        run["tool"]["driver"]["rules"] = "<every code of rcsc.codes.CODES, checked in test_sarif.py>"
        for result in run["results"]:
            result["ruleIndex"] = "<index of ruleId in rules>"
    return json.dumps(log, indent=2, ensure_ascii=True) + "\n"


@pytest.mark.parametrize("case", ["all", "empty"])
def test_sarif_golden(case: str, render_cases: dict, golden) -> None:
    golden(f"render/{case}.sarif", _without_rule_table(render_sarif(render_cases[case], VERSION)))


# ---------------------------------------------------------------------------
# human
# ---------------------------------------------------------------------------

def test_human_shape_of_one_finding(render_cases: dict) -> None:
    text = render_human(render_cases["primary-label-note-help"], color=False)
    assert text.splitlines()[:6] == [
        "error[E0100]: unknown name `foo`",
        " --> examples/demo.rcs:6:13",
        "  |",
        "6 |         E0: foo > 1 | new -> S1;",
        "  |             ^^^ not declared here",
        "  |",
    ]
    assert "  = note: visible names" in text
    assert "  = help: declare `foo`" in text
    assert text.endswith("\nerror: 1 error emitted\n")


def test_human_has_no_colour_unless_asked(render_cases: dict) -> None:
    assert not ANSI.search(render_human(render_cases["all"], color=False))
    coloured = render_human(render_cases["all"], color=True)
    assert "\x1b[1;31merror[E0100]\x1b[0m" in coloured  # bold red errors
    assert "\x1b[1;33mwarning[W0311]\x1b[0m" in coloured  # yellow warnings
    assert "\x1b[1;34m6 |\x1b[0m" in coloured  # blue gutter
    # Colour changes nothing but the escapes.
    assert ANSI.sub("", coloured) == render_human(render_cases["all"], color=False)


def test_human_expands_tabs_and_moves_the_caret() -> None:
    file = SourceFile("t.rcs", "\tx\t= foo;\n")
    text = render_human([_diag("E0100", Severity.ERROR, file, "foo")], color=False)
    assert "\t" not in text
    assert "1 |     x    = foo;" in text
    # `\t` `x` `\t` `= ` before foo: 4 + 1 + 4 + 2 display columns.
    assert _caret_column(text) == 11


def test_human_wide_characters_take_two_columns(render_cases: dict) -> None:
    text = render_human(render_cases["wide-characters"], color=False)
    assert "^^^^ not part of the language" in text


def test_human_multi_line_span_underlines_first_line_to_its_end(render_cases: dict) -> None:
    text = render_human(render_cases["multi-line-span"], color=False)
    assert "5 |     plan go {\n  |     ^^^^^^^^^ this plan\n" in text


def test_human_zero_width_span_gets_one_caret(render_cases: dict) -> None:
    text = render_human(render_cases["zero-width-at-eof"], color=False)
    assert "   | ^ expected `}`" in text


def test_human_secondary_label_in_another_file_has_its_own_arrow(render_cases: dict) -> None:
    text = render_human(render_cases["tab-and-label-in-other-file"], color=False)
    assert " --> examples/demo.rcs:4:2" in text
    assert " --> examples/lib/util.rcs:2:4" in text
    assert "  |    --- declared here with 1 parameter" in text


def test_human_hanging_labels_do_not_collide(render_cases: dict) -> None:
    text = render_human(render_cases["secondary-labels-same-line"], color=False)
    assert (
        "  |             - --- ^ expected bool, found i32\n"
        "  |             | |\n"
        "  |             | operator of bools\n"
        "  |             this is bool\n"
    ) in text


def test_human_control_characters_and_crlf_are_not_echoed() -> None:
    file = SourceFile("t.rcs", "x = \x1b[31m foo;\r\n")
    text = render_human([_diag("E0100", Severity.ERROR, file, "foo")], color=False)
    assert "\x1b" not in text and "\r" not in text
    assert _caret_column(text) == len("x = \ufffd[31m ")


def test_human_summary_lines() -> None:
    file = SourceFile("t.rcs", "a b c\n")
    e1 = _diag("E0100", Severity.ERROR, file, "a")
    e2 = _diag("E0101", Severity.ERROR, file, "b")
    w1 = _diag("W0310", Severity.WARNING, file, "c")
    assert render_human([], color=False) == ""
    assert render_human([e1], color=False).endswith("\nerror: 1 error emitted\n")
    assert render_human([w1], color=False).endswith("\nwarning: 1 warning emitted\n")
    assert render_human([e1, e2, w1], color=False).endswith("\nerror: 2 errors and 1 warning emitted\n")


def test_human_skips_distant_lines_with_an_ellipsis() -> None:
    file = SourceFile("t.rcs", "".join(f"line{i}\n" for i in range(1, 13)))
    d = _diag("E0101", Severity.ERROR, file, "line12", "second")
    d.labels.append(Label(_diag("E0101", Severity.ERROR, file, "line1\n").span, "first"))
    near = _diag("E0101", Severity.ERROR, file, "line3", "here")
    near.labels.append(Label(_diag("E0101", Severity.ERROR, file, "line1\n").span, "there"))
    far_text = render_human([d], color=False)
    assert "...\n12 | line12" in far_text
    near_text = render_human([near], color=False)
    assert "2 | line2" in near_text and "..." not in near_text


# ---------------------------------------------------------------------------
# short and JSON
# ---------------------------------------------------------------------------

def test_short_is_one_line_per_finding(render_cases: dict) -> None:
    lines = render_short(render_cases["all"]).splitlines()
    assert len(lines) == len(render_cases["all"])
    pattern = re.compile(r"^(\S+:\d+:\d+|rcsc): (error|warning)\[[EW]\d{4}\]: \S.*$")
    assert all(pattern.match(line) for line in lines), lines
    assert "examples/demo.rcs:6:13: error[E0100]: unknown name `foo`" in lines


def test_renderings_use_the_sorted_order(render_cases: dict) -> None:
    bag = Diagnostics()
    bag.items.extend(reversed(render_cases["all"]))
    assert render_short(bag) == render_short(render_cases["all"])
    assert render_short(list(reversed(render_cases["all"]))) == render_short(bag)


def test_json_document(render_cases: dict) -> None:
    text = render_json(render_cases["all"], VERSION)
    assert text == render_json(make_render_cases()["all"], VERSION)  # deterministic
    doc = json.loads(text)
    assert doc["version"] == 1
    assert doc["tool"] == {"name": "rcsc", "version": VERSION}
    assert doc["summary"] == {"errors": 7, "warnings": 1}
    by_code = {d["code"]: d for d in doc["diagnostics"]}
    foo = by_code["E0100"]
    # 1-based start, exclusive end: `foo` is columns 13..15 of line 6.
    assert (foo["file"], foo["line"], foo["column"], foo["end_line"], foo["end_column"]) == (
        "examples/demo.rcs", 6, 13, 6, 16)
    assert foo["label"] == "not declared here" and foo["notes"] and foo["helps"]
    assert by_code["E0605"]["file"] is None and by_code["E0605"]["line"] is None
    assert by_code["E0506"]["data"]["states"] == ["S1", "new"]
    assert by_code["E0506"]["labels"][0]["message"] == "always fires first"


def test_json_survives_odd_data() -> None:
    from fractions import Fraction

    d = Diagnostic("E0206", Severity.ERROR, "value outside its declared range", None)
    d.data = {1: Fraction(3, 2), "inf": float("inf"), "sev": Severity.ERROR, "t": (1, 2)}
    doc = json.loads(render_json([d], VERSION))
    assert doc["diagnostics"][0]["data"] == {"1": "3/2", "inf": "inf", "sev": "error", "t": [1, 2]}


def test_escape_controls_fast_path_misses_no_control_character() -> None:
    """`escape_controls` returns a printable text as it is: that is safe only
    while every character it escapes is one `str.isprintable` refuses."""
    import unicodedata

    from rcsc.front.source import BIDI_CONTROLS
    from rcsc.render import escape_controls

    escaped = [chr(c) for c in range(0x110000) if unicodedata.category(chr(c)) == "Cc"] + sorted(BIDI_CONTROLS)
    assert not any(ch.isprintable() for ch in escaped)
    assert escape_controls("plain text, é, 日本") == "plain text, é, 日本"
    assert escape_controls("a\x1b[2Jb\u202ec\td\n") == "a\\x1b[2Jb\\u202ec\td\n"
