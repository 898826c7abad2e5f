"""The diagnostic test corpus: tests/cases.

Every case is a small design whose comments state every finding it must
produce, one annotation per finding:

    // expect: E0100 @ 12:9

(code, then 1-based line:column of the start of the finding's primary span,
in the file that holds the annotation).  The test runs the front end
(`rcsc.driver.check_path`) and requires the multiset of findings to equal the
multiset of annotations: nothing missing, nothing extra.

A case is either one file `tests/cases/NAME.rcs`, or a folder
`tests/cases/NAME/` whose root file is `main.rcs` (for imports and
scenarios); the annotations of every `.rcs` and `.scn` file in the folder
count.  Every `*.scn` file of a folder is checked as a scenario of the design
(`rcsc.front.scenario.text_to_scenario`), except `sim.scn`, which is run with
`rcsc sim` when the design has no errors (for the findings only that command
reports; they are read from its human-readable output; with `--externs
externs.py` when the folder has that file, whose `# expect:` lines count
too), and except folders
with a file `build-target` (holding a target name, then any other build
options, e.g. `c --transport dds`), where `rcsc build --target NAME ...` runs
and its findings count too.  Cases named `ok_*`
are clean designs and carry no annotations.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
from collections import Counter
from pathlib import Path

import pytest

from rcsc.codes import CODES
from rcsc.driver import check_path
from rcsc.front.source import SourceFile

CASES = Path(__file__).parent / "cases"
ROOT_FILE = "main.rcs"

SIM_SCENARIO = "sim.scn"
# A folder case with this file runs `sim.scn` with `--externs externs.py`
# (annotations in it are `# expect: CODE @ LINE:COL`).
EXTERNS = "externs.py"
# A folder case with this file is checked under it, as `rcsc check` does
# (annotations in it are `# expect: CODE @ LINE:COL`).
CONFIG = "rcsc.toml"

# Codes that no stage emits yet, so no case can expect them.  The coverage
# test fails when a code here gets a case (remove it from this list then).
PENDING: dict[str, str] = {
    # A case cannot give `--transport`: tests/test_dds.py checks the refusal
    # with a target made for the test, tests/test_ada_backend.py with Ada.
    "E0820": "a target without the DDS transport given --transport dds",
    # `rcsc console` findings concern a running Main Program, not a design:
    # tests/test_console.py drives each against running C and Rust programs.
    "E0810": "no running Main Program to attach to",
    "E0811": "a running program built from another interface",
    "E0812": "a console line that is not a command",
    "E0813": "a console command naming no controller of the program",
    "E0814": "a scenario-file action typed at the console",
    "E0815": "a request the program refused",
    "E0816": "a second console or a second program on one run",
    "W0810": "the Main Program ended",
}

_EXPECT = re.compile(r"(?://|#)\s*expect:\s*([EW]\d{4})\s*@\s*(\d+):(\d+)\s*$")


def _roots() -> list[Path]:
    roots = sorted(CASES.glob("*.rcs"))
    for d in sorted(p for p in CASES.iterdir() if p.is_dir() and not p.name.startswith(".")):  # not .rcsc-cache
        root = d / ROOT_FILE
        assert root.is_file(), f"case folder {d.name} has no {ROOT_FILE}"
        roots.append(root)
    return roots


def _case_files(root: Path) -> list[Path]:
    if root.parent == CASES:
        return [root]
    return (sorted(root.parent.rglob("*.rcs")) + sorted(root.parent.rglob("*.scn")) + sorted(root.parent.glob(CONFIG))
            + sorted(root.parent.glob(EXTERNS)))


def _annotations(path: Path) -> list[tuple[str, int, int]]:
    out = []
    for n, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
        if "expect:" not in line:
            continue
        mt = _EXPECT.search(line)
        assert mt, f"{path.name}:{n}: malformed annotation (write `// expect: CODE @ LINE:COL`)"
        assert mt.group(1) in CODES, f"{path.name}:{n}: unknown code {mt.group(1)}"
        out.append((mt.group(1), int(mt.group(2)), int(mt.group(3))))
    return out


def _expected(root: Path) -> Counter:
    exp: Counter = Counter()
    for f in _case_files(root):
        for code, line, col in _annotations(f):
            exp[(os.path.realpath(f), code, line, col)] += 1
    return exp


def _found(result, sim: Counter | None = None) -> Counter:
    got: Counter = Counter(sim or {})
    for d in result.diags:
        if d.span is None:
            got[("<no span>", d.code, 0, 0)] += 1
        else:
            got[(os.path.realpath(d.span.file.path), d.code, d.span.line, d.span.col)] += 1
    return got


def _fmt(items: Counter, root: Path) -> str:
    rows = []
    for (path, code, line, col), n in sorted(items.items()):
        rel = os.path.relpath(path, root.parent) if path != "<no span>" else path
        rows.append(f"  {code} @ {rel}:{line}:{col}" + (f" (x{n})" if n > 1 else ""))
    return "\n".join(rows)


ROOTS = _roots()


def _case_id(root: Path) -> str:
    return root.stem if root.parent == CASES else root.parent.name


def _check(root: Path):
    """The front end on the case's design, then its scenarios (if the design loaded)."""
    result = check_path(str(root))
    if root.parent != CASES and (root.parent / CONFIG).is_file():
        from rcsc import config

        conf = config.load(str(root.parent / CONFIG), False, result.diags)
        result.diags = conf.apply(result.diags)
    scenarios = sorted(root.parent.glob("*.scn")) if root.parent != CASES else []
    if scenarios and result.model is not None:
        from rcsc.front.scenario import text_to_scenario

        for scn in scenarios:
            if scn.name == SIM_SCENARIO:
                continue
            source = SourceFile(str(scn), scn.read_text(encoding="utf-8"))
            text_to_scenario(source, result.model, result.diags)
    return result


_RENDERED = re.compile(r"^(?:error|warning)\[([EW]\d{4})\]:.*\n\s*--> (.+):(\d+):(\d+)$", re.M)


def _sim_findings(root: Path, ok: bool) -> Counter:
    """Findings of `rcsc sim DESIGN --scenario sim.scn`, read from its stderr.

    A clean case (`ok_*`) must also run to the end with every expectation met.
    """
    scn = root.parent / SIM_SCENARIO
    if root.parent == CASES or not scn.is_file() or not ok:
        return Counter()
    from rcsc import cli

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        externs = ["--externs", str(root.parent / EXTERNS)] if (root.parent / EXTERNS).is_file() else []
        rc = cli.main(["sim", str(root), "--scenario", str(scn), "-o", os.devnull, *externs])
    if _case_id(root).startswith("ok_"):
        assert rc == 0, f"rcsc sim exited with {rc}:\n{err.getvalue()}"
    return Counter(
        (os.path.realpath(path), code, int(line), int(col)) for code, path, line, col in _RENDERED.findall(err.getvalue())
    )


BUILD_TARGET = "build-target"


def _build_findings(root: Path, ok: bool, tmp: Path) -> Counter:
    """Findings of `rcsc build DESIGN --target T` for a folder with a `build-target` file."""
    marker = root.parent / BUILD_TARGET
    if root.parent == CASES or not marker.is_file() or not ok:
        return Counter()
    from rcsc import cli

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        target, *options = marker.read_text().split()
        cli.main(["build", str(root), "--target", target, *options, "-o", str(tmp / "out")])
    return Counter(
        (os.path.realpath(path), code, int(line), int(col)) for code, path, line, col in _RENDERED.findall(err.getvalue())
    )


MEASURED = "measured.json"


def _measured_findings(root: Path, ok: bool) -> Counter:
    """Findings of `rcsc budget DESIGN --measured measured.json` for a folder with that run file."""
    run = root.parent / MEASURED
    if root.parent == CASES or not run.is_file() or not ok:
        return Counter()
    from rcsc import cli

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        cli.main(["budget", str(root), "--measured", str(run)])
    return Counter(
        (os.path.realpath(path), code, int(line), int(col)) for code, path, line, col in _RENDERED.findall(err.getvalue())
    )


@pytest.mark.parametrize("root", ROOTS, ids=[_case_id(r) for r in ROOTS])
def test_case(root: Path, tmp_path: Path) -> None:
    result = _check(root)
    expected = _expected(root)
    found = _found(result, _sim_findings(root, result.ok) + _build_findings(root, result.ok, tmp_path) + _measured_findings(root, result.ok))
    missing, extra = expected - found, found - expected
    if missing or extra:
        details = "\n".join(
            f"  got {d.code} @ {d.span.line}:{d.span.col}: {d.message}" if d.span else f"  got {d.code}: {d.message}"
            for d in result.diags.sorted()
        )
        pytest.fail(
            f"{_case_id(root)}:\nmissing:\n{_fmt(missing, root) or '  -'}\nextra:\n{_fmt(extra, root) or '  -'}\nall findings:\n{details}",
            pytrace=False,
        )


def test_clean_cases_have_no_annotations() -> None:
    bad = [r.name for r in ROOTS if _case_id(r).startswith("ok_") and _expected(r)]
    assert not bad, f"clean cases with annotations: {bad}"


def test_every_code_has_a_case() -> None:
    covered = {code for root in ROOTS for (_, code, _, _) in _expected(root)}
    missing = sorted(set(CODES) - covered - set(PENDING))
    assert not missing, "codes without a test case: " + ", ".join(missing)
    stale = sorted(set(PENDING) & covered)
    assert not stale, "codes listed in PENDING that now have a case: " + ", ".join(stale)
    unknown = sorted(set(PENDING) - set(CODES))
    assert not unknown, "codes listed in PENDING that are not in rcsc.codes: " + ", ".join(unknown)


@pytest.mark.parametrize("root", ROOTS, ids=[_case_id(r) for r in ROOTS])
def test_spans_lie_inside_their_file(root: Path) -> None:
    result = _check(root)
    for d in result.diags:
        assert d.span is not None, f"{d.code} has no span: {d.message}"
        src = d.span.file
        line, col = d.span.line, d.span.col
        assert 1 <= line <= src.line_count, f"{d.code}: line {line} outside {src.path}"
        assert 1 <= col <= len(src.line_text(line)) + 1, f"{d.code}: column {col} outside line {line} of {src.path}"
        assert 0 <= d.span.start <= d.span.end <= len(src.text), f"{d.code}: span {d.span.start}..{d.span.end} outside {src.path}"
