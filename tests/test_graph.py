"""`rcsc graph`: the hierarchy, data-flow and plan pictures (rcsc/outputs/graph.py).

- golden DOT files of every example: its hierarchy, its data flow and every
  plan, in tests/golden/graph/EXAMPLE/ (regenerate all of them with
  `python -m pytest tests/test_graph.py --update-golden`, then review the diff);
- Graphviz renders the hierarchy of each example and the submarine's AHEAD
  plan of PR, and the SVG has a node for every controller / state;
- the plan view's conventions (entry, terminals, `*`, `otherwise`, findings);
- Mermaid output: structure and determinism;
- the command line: formats, errors, Graphviz missing (exit 2, no traceback);
- no design of the diagnostic corpus breaks the graph builders.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from rcsc import cli

from rcsc.outputs import graph
from rcsc.driver import CheckResult, check_path

ROOT = Path(__file__).resolve().parent.parent
GOLDEN_GRAPH = Path(__file__).resolve().parent / "golden" / "graph"
EXAMPLES = {
    "submarine": ROOT / "examples" / "submarine" / "submarine.rcs",
    "machining_cell": ROOT / "examples" / "machining_cell" / "machining_cell.rcs",
    "machine_tool": ROOT / "examples" / "machine_tool" / "machine_tool.rcs",  # two CPUs, a divided rate
}
SVG = "{http://www.w3.org/2000/svg}"
# Exit codes of a command that drew its picture: 0, or 1 when the design has
# error findings (drawn anyway).  The examples' own cleanliness is
# tests/test_examples.py's business; the exact codes are tested on TINY.
DRAWN = (0, 1)

TINY = """\
design tiny

controller TOP level 1 budget 1 ms {
    verb RUN
    plan RUN {
        E0: true | new -> done;
    }
}

cpu main {
    heartbeat 10 ms
    schedule TOP
}
"""

# A design whose plan RUN has findings: E1 waits on LOW without testing
# LOW.error (E0505), E4 is dead behind E3 (E0506); the guard analysis may
# add more (overlapping conditions), so the tests ask for these two at least.
FLAGGED = """\
design flagged

controller TOP level 2 budget 1 ms {
    verb RUN
    subordinates LOW
    local n: i32 = 0

    plan RUN {
        E0: true      | new -> S1 | LOW.GO(), n = 0;
        E1: LOW.done  | S1  -> S2 | n += 1;
        E2: n > 3     | S2  -> done;
        E3: true      | S2  -> S1;
        E4: n == 1    | S2  -> error(7);
        E5: otherwise | S1  -> S1;
        E6: n < 0     | *   -> error(2);
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


def need_dot() -> None:
    """Skip without Graphviz, except in CI (.ci/run installs it): fail there."""
    if shutil.which("dot") is None:
        if os.environ.get("CI"):
            pytest.fail("Graphviz `dot` is missing in CI (.ci/run should install it)")
        pytest.skip("Graphviz `dot` is not installed")


@pytest.fixture
def flagged(tmp_path: Path) -> CheckResult:
    path = tmp_path / "flagged.rcs"
    path.write_text(FLAGGED, encoding="utf-8")
    result = check_path(str(path))
    assert {"E0505", "E0506"} <= {d.code for d in result.diags}, [d.message for d in result.diags]
    return result


# ---------------------------------------------------------------------------
# golden DOT files
# ---------------------------------------------------------------------------

def golden_names(example: str) -> dict[str, tuple]:
    """golden file name -> (view, controller, verb) for one example."""
    names: dict[str, tuple] = {"hierarchy.dot": ("hierarchy", None, None), "dataflow.dot": ("dataflow", None, None)}
    design = checked(example).model
    assert design is not None
    for c in design.controllers.values():
        for verb in c.plans:
            names[f"plan-{c.name}-{verb}.dot"] = ("plan", c.name, verb)
    return names


GOLDEN_CASES = [(example, name) for example in EXAMPLES for name in golden_names(example)]


@pytest.mark.parametrize(("example", "name"), GOLDEN_CASES, ids=[f"{e}/{n}" for e, n in GOLDEN_CASES])
def test_golden_dot(example: str, name: str, golden) -> None:
    # Drawn without the checker's findings, so that the golden files change
    # with the examples and the drawing only; the marking of findings has
    # its own tests below.
    view, controller, verb = golden_names(example)[name]
    g = graph.select_graph(checked(example).model, view, controller, verb, [])
    golden(f"graph/{example}/{name}", graph.to_dot(g))


@pytest.mark.parametrize("example", list(EXAMPLES))
def test_no_stale_golden_files(example: str, request: pytest.FixtureRequest) -> None:
    """Every golden file belongs to a graph that exists (a removed plan takes its file along)."""
    folder = GOLDEN_GRAPH / example
    expected = set(golden_names(example))
    present = {p.name for p in folder.glob("*.dot")} if folder.exists() else set()
    stale = sorted(present - expected)
    if stale and request.config.getoption("--update-golden"):
        for name in stale:
            (folder / name).unlink()
        return
    assert not stale, f"stale golden files in {folder}: {stale}; run pytest with --update-golden"


def test_dot_is_deterministic() -> None:
    a = check_path(str(EXAMPLES["submarine"]))
    b = check_path(str(EXAMPLES["submarine"]))
    for view, c, v in [("hierarchy", None, None), ("dataflow", None, None), ("plan", "PR", "AHEAD")]:
        ga = graph.select_graph(a.model, view, c, v, a.diags.sorted())
        gb = graph.select_graph(b.model, view, c, v, b.diags.sorted())
        assert graph.to_dot(ga) == graph.to_dot(gb)
        assert graph.to_mermaid(ga) == graph.to_mermaid(gb)


# ---------------------------------------------------------------------------
# Graphviz renders them
# ---------------------------------------------------------------------------

def svg_titles(svg: bytes, cls: str) -> set[str]:
    """The <title> of every <g class=CLS> of a Graphviz SVG (node or edge names)."""
    root = ET.fromstring(svg)
    return {g.findtext(f"{SVG}title") for g in root.iter(f"{SVG}g") if g.get("class") == cls}


@pytest.mark.parametrize("example", list(EXAMPLES))
def test_hierarchy_svg_has_every_controller(example: str) -> None:
    need_dot()
    result = checked(example)
    svg = graph.render(graph.to_dot(graph.hierarchy_graph(result.model)), "svg")
    nodes = svg_titles(svg, "node")
    assert set(result.model.controllers) <= nodes
    edges = svg_titles(svg, "edge")
    for c in result.model.controllers.values():
        for use in c.subordinates:
            assert f"{c.name}->{use.name}" in edges


def test_ahead_plan_svg_has_every_state() -> None:
    need_dot()
    result = checked("submarine")
    pr = result.model.controllers["PR"]
    svg = graph.render(graph.to_dot(graph.plan_graph(pr, pr.plans["AHEAD"], result.diags.sorted())), "svg")
    nodes = svg_titles(svg, "node")
    assert {"new", "S1", "S2", graph.ANY, "<error 21>"} <= nodes
    assert set(pr.plans["AHEAD"].states) <= nodes
    text = svg.decode("utf-8")
    for rule in pr.plans["AHEAD"].rules:
        assert f">{rule.label}: " in text  # every rule labels an edge


def test_png_renders() -> None:
    need_dot()
    result = checked("submarine")
    data = graph.output_bytes(graph.hierarchy_graph(result.model), "png")
    assert data.startswith(b"\x89PNG\r\n\x1a\n")


# ---------------------------------------------------------------------------
# what the pictures say
# ---------------------------------------------------------------------------

def test_hierarchy_edges_carry_the_issued_verbs_and_simulators_stand_apart() -> None:
    design = checked("submarine").model
    g = graph.hierarchy_graph(design)
    edges = {(e.src, e.dst): e for e in g.edges if e.kind != "invisible"}
    assert set(edges) == {("SM", "PR"), ("PR", "TB")}
    assert edges[("SM", "PR")].label.replace("\n", " ") == "AHEAD, ASTERN, STOP, INIT, HALT, ABORT"
    kinds = {n.id: n.kind for n in g.nodes}
    assert kinds["TURBINE_SIM"] == kinds["SHIP_SIM"] == "simulator"
    assert kinds["PR"] == "controller"
    assert all(n.cluster == "cpu_MAIN" for n in g.nodes)
    assert "level 2, budget 2 ms" in g.node("PR").label
    dot = graph.to_dot(g)
    assert 'subgraph "cluster_cpu_MAIN"' in dot
    assert '"TURBINE_SIM" [label="TURBINE_SIM\\nlevel 0, budget 200 us\\n(simulator)", shape="box", style="rounded,dashed,filled"' in dot


def test_dataflow_runs_writer_variable_readers() -> None:
    design = checked("submarine").model
    g = graph.dataflow_graph(design)
    pairs = {(e.src, e.dst) for e in g.edges}
    assert ("TB", "gm:turbine_rpm_cmd") in pairs and ("gm:turbine_rpm_cmd", "TURBINE_SIM") in pairs
    assert (graph.ENV_NODE, "gm:turbine_trip") in pairs
    assert ("gm:turbine_trip", "TB") in pairs and ("gm:turbine_trip", "TURBINE_SIM") in pairs
    assert g.direction == "LR"


def test_plan_view_entry_terminals_any_and_otherwise(flagged: CheckResult) -> None:
    top = flagged.model.controllers["TOP"]
    g = graph.plan_graph(top, top.plans["RUN"], flagged.diags.sorted())
    kinds = {n.id: n.kind for n in g.nodes}
    assert kinds == {"new": "entry", graph.ANY: "any", "S1": "state", "S2": "state", graph.DONE: "done", "<error 7>": "error", "<error 2>": "error"}
    edges = {e.label.split(":")[0]: e for e in g.edges}
    assert (edges["E6"].src, edges["E6"].dst, edges["E6"].kind) == (graph.ANY, "<error 2>", "any")
    assert (edges["E5"].src, edges["E5"].dst, edges["E5"].kind, edges["E5"].label) == ("S1", "S1", "otherwise", "E5: otherwise")
    assert edges["E2"].label == "E2: n > 3"
    # A rule is flagged when a finding's span lies inside the rule's text:
    # E1 (E0505 inside its guard) and E4 (E0506 at its label) at least.
    rules = {r.label: r for r in top.plans["RUN"].rules}
    with_findings = {k for k, r in rules.items() if any(graph.span_inside(d.span, r.span) for d in flagged.diags)}
    assert {"E1", "E4"} <= with_findings
    assert {k for k, e in edges.items() if e.flagged} == with_findings
    assert "E0505 error: state `S1` waits on `LOW`" in edges["E1"].tooltip
    dot = graph.to_dot(g)
    lines = {k: next(ln for ln in dot.splitlines() if f'label="{k}:' in ln) for k in rules}
    assert 'color="#c62828"' in lines["E1"] and "E0505" in lines["E1"]
    for k in set(rules) - with_findings:
        assert "#c62828" not in lines[k]
    assert lines["E6"].startswith('  "<*>" -> "<error 2>"') and 'style="dashed"' in lines["E6"]
    assert 'style="dotted"' in lines["E5"]
    assert '"<done>" [label="done", shape="doublecircle"' in dot
    compact = graph.plan_graph(top, top.plans["RUN"], flagged.diags.sorted(), compact=True)
    assert [e.label for e in compact.edges] == ["E0", "E1", "E2", "E3", "E4", "E5: otherwise", "E6"]


def test_several_loops_of_one_state_take_different_sides() -> None:
    result = checked("submarine")
    pr = result.model.controllers["PR"]
    g = graph.plan_graph(pr, pr.plans["AHEAD"], [])
    loops = [e.loop_side for e in g.edges if e.src == e.dst == "S1"]
    assert loops == [None, "w", "s"]


def test_labels_are_shortened_and_quoted() -> None:
    text = "E2: TB.done and speed_status(ship_speed, cmd.speed, ship_accel) == SpeedStatus.BELOW"
    assert graph.abbreviate(text, 64) == "E2: TB.done and speed_status(...) == SpeedStatus.BELOW"
    short = graph.abbreviate("x" * 100, 20)
    assert len(short) == 20 and "..." in short
    assert graph.dot_quote('a "b" \\n\nc') == '"a \\"b\\" \\\\n\\nc"'
    assert graph.mermaid_text('a < "b" | c#\nd & e>') == "a #lt; #quot;b#quot; #124; c#35;<br/>d #amp; e#gt;"


def test_mermaid_plan_uses_named_entities_and_one_loop_per_state() -> None:
    """The submarine's TRANSIT plan: `>=`/`<` in guards, and two loops on UNDERWAY."""
    result = checked("submarine")
    sm = result.model.controllers["SM"]
    text = graph.to_mermaid(graph.plan_graph(sm, sm.plans["TRANSIT"]))
    assert "#60;" not in text and "#62;" not in text
    assert '|"T0: cmd.speed #gt;= 0.0"|' in text and '|"T1: cmd.speed #lt; 0.0"|' in text
    loops = [line for line in text.splitlines() if re.fullmatch(r"\s*(n\d+) -->\|.*\| \1", line)]
    assert loops == ['  n2 -->|"T3: PR.AT_GOAL<br/>T4: not PR.AT_GOAL"| n2']


def test_mermaid_structure() -> None:
    result = checked("machining_cell")
    design = result.model
    for g in (graph.hierarchy_graph(design), graph.dataflow_graph(design), graph.plan_graph(design.controllers["MH"], design.controllers["MH"].plans["LOAD"])):
        text = graph.to_mermaid(g)
        lines = text.splitlines()
        assert lines[0] == f"%% {graph.BANNER}"
        assert lines[2] == f"flowchart {g.direction}"
        assert sum(1 for ln in lines if ln.strip().startswith("subgraph ")) == sum(1 for ln in lines if ln.strip() == "end")
        defined = set(re.findall(r"^\s+(n\d+)[\[(>{]", text, re.M))
        assert len(defined) == len(g.nodes)
        links = [ln for ln in lines if re.match(r"^\s+n\d+ (-->|-\.->)", ln)]
        assert len(links) == sum(1 for e in g.edges if e.kind != "invisible")
        for ln in links:
            assert set(re.findall(r"\bn\d+\b", ln)) <= defined
        for ln in lines:
            if ln.strip().startswith("linkStyle "):
                assert int(ln.split()[1]) < len(links)
        assert text == graph.to_mermaid(g)
    hierarchy = graph.to_mermaid(graph.hierarchy_graph(design))
    assert 'subgraph c0["cpu CELL: heartbeat 10 ms, overhead 1 ms"]' in hierarchy
    assert "class n0,n1,n2,n3,n4,n5,n6,n7,n8 rcsc_controller" in hierarchy


def test_every_corpus_design_draws() -> None:
    """No design of the diagnostic corpus, however broken, breaks a builder."""
    cases = ROOT / "tests" / "cases"
    roots = sorted(cases.glob("*.rcs")) + sorted(cases.glob("*/main.rcs"))
    drawn = 0
    for root in roots:
        result = check_path(str(root))
        if result.model is None:
            continue
        design, diags = result.model, result.diags.sorted()
        graphs = [graph.hierarchy_graph(design), graph.dataflow_graph(design)]
        graphs += [graph.plan_graph(c, p, diags) for c in design.controllers.values() for p in c.plans.values()]
        for g in graphs:
            assert graph.to_dot(g).startswith(f"// {graph.BANNER}\n")
            graph.to_mermaid(g)
            drawn += 1
    assert drawn > 100


# ---------------------------------------------------------------------------
# the command line
# ---------------------------------------------------------------------------

def test_cli_dot_to_stdout(capsysbinary) -> None:
    assert cli.main(["graph", str(EXAMPLES["submarine"])]) in DRAWN
    out = capsysbinary.readouterr().out.decode("utf-8")
    assert out.startswith(f"// {graph.BANNER}\n") and '"submarine_hierarchy"' in out


def test_cli_formats_from_the_suffix(tmp_path: Path, capsys) -> None:
    path = str(EXAMPLES["submarine"])
    assert cli.main(["graph", path, "--view", "dataflow", "-o", str(tmp_path / "d.mmd")]) in DRAWN
    assert (tmp_path / "d.mmd").read_text(encoding="utf-8").startswith(f"%% {graph.BANNER}\n")
    assert cli.main(["graph", path, "--plan", "TRANSIT", "-o", str(tmp_path / "t.gv")]) in DRAWN
    assert 'digraph "SM.TRANSIT"' in (tmp_path / "t.gv").read_text(encoding="utf-8")
    assert capsys.readouterr().out == ""  # the pictures went to the files


def test_cli_svg_file(tmp_path: Path) -> None:
    need_dot()
    out = tmp_path / "ahead.svg"
    assert cli.main(["graph", str(EXAMPLES["submarine"]), "--controller", "PR", "--plan", "AHEAD", "-o", str(out)]) in DRAWN
    assert {"new", "S1", "S2"} <= svg_titles(out.read_bytes(), "node")


def test_cli_without_graphviz(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no `dot` here
    code = cli.main(["graph", str(EXAMPLES["submarine"]), "--format", "svg"])
    err = capsys.readouterr().err
    assert code == 2
    assert "Graphviz `dot` is not installed" in err and "apt-get install graphviz" in err
    assert "Traceback" not in err
    # DOT and Mermaid need no Graphviz
    assert cli.main(["graph", str(EXAMPLES["submarine"]), "--format", "mermaid"]) in DRAWN


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--view", "plan"], "needs `--controller NAME` and `--plan VERB`"),
        (["--plan", "AHEAD"], "several controllers have a plan `AHEAD` (PR, TB)"),
        (["--controller", "PR", "--plan", "NOPE"], "controller `PR` has no plan `NOPE` (plans: INIT, HALT, ABORT, AHEAD, ASTERN, STOP)"),
        (["--controller", "XX", "--plan", "AHEAD"], "has no controller `XX`"),
    ],
)
def test_cli_usage_errors(args: list[str], message: str, capsys) -> None:
    assert cli.main(["graph", str(EXAMPLES["submarine"]), *args]) == 2
    captured = capsys.readouterr()
    assert message in captured.err and captured.out == ""


def test_cli_exit_code_of_a_clean_design(tmp_path: Path, capsys) -> None:
    path = tmp_path / "tiny.rcs"
    path.write_text(TINY, encoding="utf-8")
    assert cli.main(["graph", str(path), "--plan", "RUN"]) == 0
    captured = capsys.readouterr()
    assert captured.err == "" and '"new" -> "<done>"' in captured.out


def test_cli_design_with_findings_still_draws(flagged: CheckResult, tmp_path: Path, capsys) -> None:
    path = flagged.diags.items[0].span.file.path
    out = tmp_path / "run.dot"
    assert cli.main(["graph", path, "--plan", "RUN", "-o", str(out)]) == 1
    assert "E0505" in out.read_text(encoding="utf-8")
    assert "error[E0505]" in capsys.readouterr().err


def test_cli_unparsable_design(tmp_path: Path, capsys) -> None:
    bad = tmp_path / "bad.rcs"
    bad.write_text("design bad\ncontroller {\n", encoding="utf-8")
    assert cli.main(["graph", str(bad)]) == 1
    captured = capsys.readouterr()
    assert captured.out == "" and "error[E0001]" in captured.err


def test_python_m_rcsc_graph() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "rcsc", "graph", str(EXAMPLES["machining_cell"]), "--format", "mermaid"],
        capture_output=True, text=True, cwd=ROOT, timeout=60,
    )
    assert proc.returncode in (0, 1), proc.stderr  # 1: the example has error findings (drawn anyway)
    assert proc.stdout.startswith(f"%% {graph.BANNER}\n")
    assert "Traceback" not in proc.stderr


def test_plan_options_with_another_view_are_refused(capsys: pytest.CaptureFixture[str]) -> None:
    """`--plan`, `--controller` and `--compact` draw nothing in the hierarchy
    or data-flow view: given there they are a usage error, not ignored."""
    path = str(EXAMPLES["submarine"])
    assert cli.main(["graph", path, "--view", "hierarchy", "--plan", "AHEAD"]) == 2
    assert "error: `--plan` only applies to `--view plan`, not `--view hierarchy`" in capsys.readouterr().err
    assert cli.main(["graph", path, "--view", "dataflow", "--controller", "PR", "--compact"]) == 2
    assert "`--controller`, `--compact` only apply to `--view plan`, not `--view dataflow`" in capsys.readouterr().err
    assert cli.main(["graph", path, "--compact"]) == 2  # the default view is the hierarchy
    capsys.readouterr()
    assert cli.main(["graph", path, "--controller", "PR", "--plan", "AHEAD", "--compact"]) in DRAWN
