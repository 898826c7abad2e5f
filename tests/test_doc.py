"""`rcsc doc`: the one-page HTML description of a design (rcsc/outputs/doc.py).

- the page of each example, opened in a real headless browser (Debian's
  `chromium`): it loads with no JavaScript or console error, every controller
  and every plan is in the rendered DOM, and a screenshot is written for a
  person to look at (build/doc-screenshots/EXAMPLE.png, path printed);
- the page is deterministic, works offline, escapes user text, puts findings
  next to their rules, and still renders (tables, a note) without Graphviz;
- the template ships in the package.

The browser tests skip when chromium is missing, except in CI (.ci/run
installs it), where they fail.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from rcsc import cli

from rcsc.outputs import doc, graph
from rcsc.driver import CheckResult, check_path

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = {
    "submarine": ROOT / "examples" / "submarine" / "submarine.rcs",
    "machining_cell": ROOT / "examples" / "machining_cell" / "machining_cell.rcs",
    "machine_tool": ROOT / "examples" / "machine_tool" / "machine_tool.rcs",  # two CPUs, a divided rate
}
SCREENSHOTS = ROOT / "build" / "doc-screenshots"  # build/ is git-ignored

# Findings of every kind of home: E0505 inside rule E1's guard, E0506 at
# rule E4's label, W0403 at a Global Memory variable (the design's); the
# guard analysis may add more.  Guards E2 and E5 have a `<`: user text that
# HTML must escape.
FLAGGED = """\
design flagged

gm log_value: f64 = 0.0

controller TOP level 2 budget 1 ms {
    verb RUN
    subordinates LOW
    writes log_value
    local n: i32 = 0

    plan RUN {
        E0: true      | new -> S1 | LOW.GO(), n = 0;
        E1: LOW.done  | S1  -> S2 | n += 1, log_value = 1.0;
        E2: n < 3     | S2  -> S1;
        E3: true      | S2  -> done;
        E4: n == 1    | S2  -> error(7);
        E5: n < 0     | *   -> error(2);
    }
}

controller LOW level 1 budget 1 ms {
    verb GO
    plan GO {
        G0: true | new -> error(3);
    }
}

cpu main {
    heartbeat 10 ms
    schedule TOP, LOW
}
"""


@functools.cache
def checked(name: str) -> CheckResult:
    return check_path(str(EXAMPLES[name]))


@functools.cache
def page(name: str) -> str:
    result = checked(name)
    return doc.render_html(result.model, result.diags.items)


@pytest.fixture
def flagged(tmp_path: Path) -> CheckResult:
    path = tmp_path / "flagged.rcs"
    path.write_text(FLAGGED, encoding="utf-8")
    result = check_path(str(path))
    assert {"E0505", "E0506", "W0403"} <= {d.code for d in result.diags}, [d.message for d in result.diags]
    return result


def need(tool: str) -> str:
    """The path of `tool`; skip without it, except in CI, where it is a failure."""
    path = shutil.which(tool)
    if path is None:
        if os.environ.get("CI"):
            pytest.fail(f"`{tool}` is missing in CI (.ci/run should install it)")
        pytest.skip(f"`{tool}` is not installed")
    return path


def anchors(html: str) -> set[str]:
    return set(re.findall(r'\sid="([^"]+)"', html))


# ---------------------------------------------------------------------------
# the page itself
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("example", list(EXAMPLES))
def test_page_has_every_controller_and_plan(example: str) -> None:
    design = checked(example).model
    html = page(example)
    assert html.startswith(f"<!DOCTYPE html>\n<!-- {graph.BANNER} -->\n")
    ids = anchors(html)
    for c in design.controllers.values():
        assert doc.controller_anchor(c.name) in ids
        for verb in c.plans:
            assert doc.plan_anchor(c.name, verb) in ids
    for var in design.gm:
        assert doc.gm_anchor(var) in ids
    assert len(ids) == len(re.findall(r'\sid="', html)), "ids repeat (several SVGs on one page)"


def test_state_table_is_laid_out_like_appendix_c() -> None:
    html = page("submarine")
    start = html.index('id="plan-PR-AHEAD"')
    section = html[start: html.index("</section>", start)]
    heads = re.findall(r"<th[^>]*>([^<]+)</th>", section)
    assert heads[:6] == ["IF", "THEN", "Event", "Current State", "Next State", "Job list"]
    assert '<span class="label">E0</span>: <code>ship_dir == ShipDir.AHEAD or ship_dir == ShipDir.STOPPED</code>' in section
    assert "<li><code>TB.AHEAD(rpm = prop_rpm)</code></li>" in section
    assert '<td class="state next error">error(ERR_TURBINE)</td>' in section
    assert "<svg" in section  # the state graph beside the table
    assert section.index("<table") < section.index("<svg")


def test_page_is_deterministic() -> None:
    result = check_path(str(EXAMPLES["submarine"]))
    again = doc.render_html(result.model, result.diags.items)
    assert again == page("submarine")


def test_page_works_offline() -> None:
    for example in EXAMPLES:
        html = page(example)
        assert not re.search(r"<(link|img|iframe|object|embed)\b", html)
        assert not re.search(r"<script[^>]*\ssrc=", html)
        assert not re.search(r'\s(src|href|xlink:href)="(?!#)', html), "only in-page links"
        assert "@import" not in html and "url(" not in html


def test_findings_stand_next_to_their_rules(flagged: CheckResult) -> None:
    html = doc.render_html(flagged.model, flagged.diags.items)
    table = html[html.index('id="plan-TOP-RUN"'):]
    e1, e2 = table.index('<span class="label">E1</span>'), table.index('<span class="label">E2</span>')
    e4, e5 = table.index('<span class="label">E4</span>'), table.index('<span class="label">E5</span>')
    assert e1 < table.index('<span class="code">E0505</span>') < e2
    assert e4 < table.index('<span class="code">E0506</span>') < e5
    assert re.search(r'<tr class="rule flagged"><td class="event"><span class="label">E1</span>', table)
    assert re.search(r'<tr class="rule"><td class="event"><span class="label">E0</span>', table)
    # the names a message quotes are code; notes and help come along
    assert "state <code>S1</code> waits on <code>LOW</code> but never tests <code>LOW.error</code>" in table
    assert "help: add a rule such as <code>" in table
    # W0403 is about a Global Memory variable: a finding of the design
    findings = html[html.index('id="findings"'): html.index("</section>", html.index('id="findings"'))]
    assert '<span class="code">W0403</span>' in findings
    assert 'class="chip bad">' in html  # the header counts the errors


def test_user_text_is_escaped(flagged: CheckResult) -> None:
    html = doc.render_html(flagged.model, flagged.diags.items)
    assert "<code>n &lt; 3</code>" in html and "<code>n &lt; 0</code>" in html
    assert "n < 3" not in html and "n < 0" not in html, "a raw `<` of user text (the SVG tooltips too)"
    assert "LOW.GO()" in html


def test_page_without_graphviz(monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no `dot` here
    assert cli.main(["doc", str(EXAMPLES["submarine"]), "-o", str(tmp_path / "site")]) in (0, 1)
    html = (tmp_path / "site" / "index.html").read_text(encoding="utf-8")
    assert "<svg" not in html
    assert "Graphviz `dot` is not installed" in html
    assert 'id="plan-PR-AHEAD"' in html and "<table" in html
    err = capsys.readouterr().err
    assert "note: Graphviz `dot` is not installed" in err and "Traceback" not in err


def test_cli_doc(tmp_path: Path, capsys) -> None:
    out = tmp_path / "new" / "site"
    assert cli.main(["doc", str(EXAMPLES["machining_cell"]), "-o", str(out)]) in (0, 1)
    assert (out / "index.html").read_text(encoding="utf-8") == page("machining_cell")
    assert capsys.readouterr().out == ""
    blocker = tmp_path / "file"
    blocker.write_text("x", encoding="utf-8")
    assert cli.main(["doc", str(EXAMPLES["submarine"]), "-o", str(blocker)]) == 2
    assert f"`{blocker}` exists and is not a folder" in capsys.readouterr().err


def test_template_ships_in_the_package() -> None:
    pyproject = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    assert re.search(r'^"rcsc\.outputs" = \[[^\]]*"templates/\*"', pyproject, re.M)
    assert {"doc.html.j2", "doc.css"} <= {p.name for p in doc.TEMPLATES.iterdir()}


# ---------------------------------------------------------------------------
# a real headless browser
# ---------------------------------------------------------------------------

def chromium(args: list[str], profile: Path) -> subprocess.CompletedProcess:
    exe = need("chromium")
    flags = [
        "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync",
        f"--user-data-dir={profile}", "--enable-logging=stderr", "--v=0",
    ]
    return subprocess.run([exe, *flags, *args], capture_output=True, text=True, timeout=120)


def console_errors(stderr: str) -> list[str]:
    """Chromium's log lines of console messages that are errors."""
    return [ln for ln in stderr.splitlines() if "CONSOLE" in ln and re.search(r"Uncaught|Error|error|Failed", ln)]


@pytest.mark.parametrize("example", list(EXAMPLES))
def test_page_in_a_headless_browser(example: str, tmp_path: Path) -> None:
    need("dot")
    site = tmp_path / "site"
    index = doc.write_site(checked(example).model, checked(example).diags.items, str(site))
    url = index.resolve().as_uri()

    dom = chromium(["--dump-dom", url], tmp_path / "profile-dom")
    assert dom.returncode == 0, dom.stderr[-2000:]
    html = dom.stdout
    assert 'data-loaded="yes"' in html, "the page's script did not run to the load event"
    errors = re.search(r'data-js-errors="([^"]*)"', html)
    assert errors is None, f"JavaScript errors: {errors.group(1) if errors else ''}"
    assert console_errors(dom.stderr) == []
    ids = anchors(html)
    design = checked(example).model
    for c in design.controllers.values():
        assert doc.controller_anchor(c.name) in ids
        for verb in c.plans:
            assert doc.plan_anchor(c.name, verb) in ids
    assert html.count("<svg") == 2 + sum(len(c.plans) for c in design.controllers.values())

    shot = tmp_path / f"{example}.png"
    run = chromium([f"--screenshot={shot}", "--window-size=1400,3000", url], tmp_path / "profile-shot")
    assert run.returncode == 0, run.stderr[-2000:]
    assert shot.read_bytes().startswith(b"\x89PNG")
    assert console_errors(run.stderr) == []
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    kept = SCREENSHOTS / shot.name
    shutil.copyfile(shot, kept)
    print(f"screenshot of the {example} page: {kept} (and {shot})")


def test_browser_check_catches_a_script_error(tmp_path: Path) -> None:
    """The checks above are not vacuous: a page with a broken script fails both."""
    broken = page("submarine").replace("</body>", "<script>no_such_function();</script></body>")
    path = tmp_path / "broken.html"
    path.write_text(broken, encoding="utf-8")
    dom = chromium(["--dump-dom", path.resolve().as_uri()], tmp_path / "profile")
    assert "no_such_function is not defined" in (re.search(r'data-js-errors="([^"]*)"', dom.stdout) or [""])[0]
    assert console_errors(dom.stderr)


def test_doc_never_overwrites_a_page_a_person_wrote(tmp_path: Path, capsys) -> None:
    from rcsc.cli import main

    site = tmp_path / "site"
    site.mkdir()
    mine = site / "index.html"
    mine.write_text("<html><body>my notes</body></html>\n")
    design = str(Path(__file__).parent.parent / "examples" / "submarine" / "submarine.rcs")
    assert main(["doc", design, "-o", str(site)]) == 2
    assert "refusing to replace" in capsys.readouterr().err
    assert mine.read_text() == "<html><body>my notes</body></html>\n"
    mine.unlink()
    assert main(["doc", design, "-o", str(site)]) == 0  # rcsc's own page is replaced freely
    first = mine.read_bytes()
    assert main(["doc", design, "-o", str(site)]) == 0
    assert mine.read_bytes() == first
