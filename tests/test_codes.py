"""The diagnostic code table (rcsc.codes) is complete and consistent."""

from __future__ import annotations

import re

import pytest

from rcsc.codes import CODES, explain
from rcsc.diagnostics import Severity


@pytest.mark.parametrize("code", sorted(CODES))
def test_code_entry(code: str) -> None:
    entry = CODES[code]
    assert entry.code == code
    assert re.fullmatch(r"[EW]\d{4}", code)
    expected = Severity.ERROR if code.startswith("E") else Severity.WARNING
    assert entry.severity is expected
    assert entry.title.strip() and entry.title == entry.title.strip()
    # An explanation says what is wrong and why: a couple of sentences at least.
    assert len(entry.explanation.strip()) >= 80, entry.explanation


def test_explain_is_case_insensitive_and_rejects_unknown_codes() -> None:
    assert explain("e0100") == explain("E0100")
    assert explain("E0100").startswith("E0100 (error): unknown name\n\n")
    assert explain("E9999") is None


def test_docs_codes_md_is_generated_from_the_table(request) -> None:
    """docs/codes.md is the published page that SARIF helpUri links point into;
    `--update-golden` regenerates it."""
    import os
    from pathlib import Path

    from rcsc.codes import help_uri, markdown

    page = Path(__file__).resolve().parent.parent / "docs" / "codes.md"
    text = markdown()
    for code in CODES:
        assert f'<a id="{code.lower()}"></a>' in text
        assert help_uri(code).endswith("/codes.html#" + code.lower())
    if request.config.getoption("--update-golden") or os.environ.get("RCSC_UPDATE_GOLDEN") == "1":
        page.write_text(text, encoding="utf-8", newline="\n")
    assert page.exists() and page.read_text(encoding="utf-8") == text, "docs/codes.md is stale: run pytest --update-golden"


# The checker's findings about the mistakes designers make: each explanation
# shows the mistake and its fix, so that `rcsc explain` teaches the idiom.
WITH_EXAMPLES = [
    "W0008", "W0403", "E0505", "W0515", "W0519", "W0520", "W0521", "W0522", "W0523",
    "W0524", "W0525", "W0526", "W0527", "W0540", "W0541", "W0542", "W0610", "E0611",
    "E0840", "E0841", "W0841",
    "E0260", "E0261", "E0262", "E0263", "E0264", "E0265", "E0266", "E0267", "W0260", "W0261",
    "E0250", "E0251", "E0252", "E0253", "E0254", "W0250", "W0251",
]


@pytest.mark.parametrize("code", WITH_EXAMPLES)
def test_explanation_has_a_wrong_and_a_fixed_example(code: str) -> None:
    text = explain(code)
    assert text is not None
    wrong, fixed = text.find("\nWrong"), text.find("\nFixed")
    assert 0 < wrong < fixed, text
    # Each example is an indented block after its heading.
    assert "\n    " in text[wrong:fixed] and "\n    " in text[fixed:], text
