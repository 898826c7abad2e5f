"""Shared pytest configuration and fixtures for the rcsc test suite."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
GOLDEN = TESTS / "golden"


# ---------------------------------------------------------------------------
# no on-disk cache by default
# ---------------------------------------------------------------------------

def pytest_configure(config: pytest.Config) -> None:
    """`rcsc check` would write `.rcsc-cache/` next to every design it checks,
    examples/ and the designs module fixtures build included: off for the
    whole run.  Tests of the cache turn it back on with `monkeypatch.delenv`,
    which puts this setting back after them."""
    os.environ["RCSC_NO_CACHE"] = "1"


# ---------------------------------------------------------------------------
# golden files
# ---------------------------------------------------------------------------

def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--update-golden",
        action="store_true",
        default=False,
        help="rewrite tests/golden/ files from the current output instead of comparing",
    )


def _updating(config: pytest.Config) -> bool:
    return bool(config.getoption("--update-golden")) or os.environ.get("RCSC_UPDATE_GOLDEN") == "1"


@pytest.fixture
def golden(request: pytest.FixtureRequest):
    """`golden(relpath, text)` compares `text` with tests/golden/RELPATH.

    With `--update-golden` (or RCSC_UPDATE_GOLDEN=1) it writes the file
    instead, so a deliberate change of output is one command and one diff to
    review.
    """
    updating = _updating(request.config)

    def check(relpath: str, actual: str) -> None:
        path = GOLDEN / relpath
        if updating:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(actual, encoding="utf-8", newline="\n")
            return
        if not path.exists():
            pytest.fail(f"missing golden file {path}; run pytest with --update-golden to create it")
        expected = path.read_text(encoding="utf-8")
        assert actual == expected, f"output differs from {path}; run pytest with --update-golden if intended"

    return check


# ---------------------------------------------------------------------------
# hand-made diagnostics for the renderers (test_render.py, test_sarif.py)
# ---------------------------------------------------------------------------

RENDER_DESIGN = (
    "design demo\n"
    "\n"
    "controller Spindle {\n"
    "\tlevel 1\n"
    "    plan go {\n"
    "        E0: foo > 1 | new -> S1;\n"
    "        E1: x and y | S1 -> done;\n"
    "    }\n"
    "    note: \"\u00e9t\u00e9 \u65e5\u672c\" ;\n"
    "}\n"
)
RENDER_LIB = "module util\nfn bar(x: i32) -> i32 { x }\n"


def _span(file, needle: str, length: int | None = None):
    from rcsc.front.source import Span

    start = file.text.index(needle)
    return Span(file, start, start + (len(needle) if length is None else length))


def make_render_cases() -> dict:
    """Named lists of diagnostics, each showing one feature of the renderings.

    Built fresh on every call because diagnostics are mutable.
    """
    from rcsc.diagnostics import Diagnostic, Severity
    from rcsc.front.source import SourceFile, Span

    design = SourceFile("examples/demo.rcs", RENDER_DESIGN)
    lib = SourceFile("examples/lib/util.rcs", RENDER_LIB)
    E, W = Severity.ERROR, Severity.WARNING

    unknown = Diagnostic("E0100", E, "unknown name `foo`", _span(design, "foo"), "not declared here")
    unknown.with_note("visible names are constants, functions, enums and listed GM variables")
    unknown.with_help("declare `foo` or list it in `reads`")

    mismatch = Diagnostic("E0200", E, "mismatched types", _span(design, "y |", 1), "expected bool, found i32")
    mismatch.with_label(_span(design, "x and", 1), "this is bool")
    mismatch.with_label(_span(design, "and"), "operator of bools")

    other_file = Diagnostic("E0201", E, "wrong number of arguments", _span(design, "level"), "called with 0 arguments")
    other_file.with_label(_span(lib, "bar"), "declared here with 1 parameter")

    start = RENDER_DESIGN.index("plan go")
    multi_line = Diagnostic(
        "W0311", W, "plan has many rules", Span(design, start, RENDER_DESIGN.index("    }\n")), "this plan"
    )
    multi_line.with_note("a state table of more than about ten rules is hard to review\n(paper section 3.4)")

    eof = Diagnostic("E0001", E, "syntax error", Span(design, len(RENDER_DESIGN), len(RENDER_DESIGN)), "expected `}`")

    wide = Diagnostic(
        "E0002", E, "unexpected character", _span(design, "\u65e5\u672c"), "not part of the language"
    )

    spanless = Diagnostic("E0605", E, "design has no CPU", None)
    spanless.with_help("add a `cpu NAME { heartbeat 1 ms; schedule ...; }`")

    witness = Diagnostic("E0506", E, "rule can never fire", _span(design, "E1"), "dead rule")
    witness.with_label(_span(design, "E0"), "always fires first")
    witness.data = {"witness": {"x": True, "y": 3}, "states": {"S1", "new"}, "ratio": 0.5}

    cases = {
        "primary-label-note-help": [unknown],
        "secondary-labels-same-line": [mismatch],
        "tab-and-label-in-other-file": [other_file],
        "multi-line-span": [multi_line],
        "zero-width-at-eof": [eof],
        "wide-characters": [wide],
        "no-span": [spanless],
        "data-and-two-lines": [witness],
    }
    cases["all"] = [d for ds in cases.values() for d in ds]
    cases["empty"] = []
    return cases


@pytest.fixture
def render_cases() -> dict:
    return make_render_cases()
