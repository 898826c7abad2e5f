"""Trace formats of `rcsc sim`: canonical JSON lines, CSV, and VCD read back by an independent parser."""

from __future__ import annotations

import csv
import io
import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from vcd.reader import TokenKind, tokenize

from rcsc.cli import main
from rcsc.sim.trace import fmt_float

SIM = Path(__file__).parent / "sim"
DESIGN = str(SIM / "ahead_paper.rcs")
SCENARIO = str(SIM / "ahead_branches.scn")


def sim(capsys, *extra: str) -> tuple[int, str, str]:
    code = main(["sim", DESIGN, "--scenario", SCENARIO, *extra])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_jsonl_schema_and_determinism(capsys) -> None:
    code, out, err = sim(capsys)
    assert code == 0, err
    lines = out.splitlines()
    assert len(lines) == 12
    first = json.loads(lines[0])
    assert list(first) == ["cycle", "gm", "ctrl"]
    assert list(first["gm"]) == ["ship_dir", "speed_status"]
    assert list(first["ctrl"]) == ["PR", "TB"]
    assert list(first["ctrl"]["PR"]) == ["echo", "status", "verb", "state", "rule", "error_code", "fields"]
    assert first["ctrl"]["PR"] == {"echo": 1, "status": "EXEC", "verb": "AHEAD", "state": "S2", "rule": "E1", "error_code": 0, "fields": {"prop_speed": 0}}
    assert " " not in lines[0]
    assert [json.loads(x)["cycle"] for x in lines] == list(range(1, 13))
    code2, out2, _ = sim(capsys)
    assert out2 == out  # same input, same bytes


@pytest.mark.parametrize(
    "x,text",
    [(0.0, "0"), (-0.0, "-0"), (1.0, "1"), (0.1, "0.10000000000000001"), (1e300, "1.0000000000000001e+300"),
     (math.nan, '"nan"'), (math.inf, '"inf"'), (-math.inf, '"-inf"'), (5e-324, "4.9406564584124654e-324")],
)
def test_float_format_is_printf_17g(x, text) -> None:
    assert fmt_float(x) == text
    if not text.startswith('"'):
        assert float(text) == x or (x == 0 and float(text) == 0)


def test_csv_has_one_row_per_cycle(capsys, tmp_path: Path) -> None:
    out_file = tmp_path / "run.csv"
    code, out, err = sim(capsys, "-o", str(out_file))
    assert code == 0 and out == "", err
    rows = list(csv.DictReader(io.StringIO(out_file.read_text())))
    assert len(rows) == 12
    assert rows[2]["PR.rule"] == "E5" and rows[2]["PR.prop_speed"] == "50" and rows[2]["TB.state"] == "RUN"
    assert rows[6]["PR.status"] == "AT_GOAL"
    assert rows[0]["ship_dir"] == "BACK"


def test_vcd_reads_back_with_an_independent_parser(capsys, tmp_path: Path) -> None:
    out_file = tmp_path / "run.vcd"
    code, _, err = sim(capsys, "-o", str(out_file))
    assert code == 0, err
    names: dict[str, str] = {}
    scopes: list[str] = []
    values: dict[str, list[tuple[int, object]]] = {}
    time = 0
    with open(out_file, "rb") as fh:
        for tok in tokenize(fh):
            if tok.kind is TokenKind.SCOPE:
                scopes.append(tok.scope.ident)
            elif tok.kind is TokenKind.UPSCOPE:
                scopes.pop()
            elif tok.kind is TokenKind.VAR:
                names[tok.var.id_code] = ".".join(scopes[1:] + [tok.var.reference])
            elif tok.kind is TokenKind.CHANGE_TIME:
                time = tok.time_change
            elif tok.kind in (TokenKind.CHANGE_VECTOR, TokenKind.CHANGE_SCALAR, TokenKind.CHANGE_STRING, TokenKind.CHANGE_REAL):
                data = tok.data
                values.setdefault(names[data.id_code], []).append((time, data.value))
    period = 30_000_000
    assert values["PR.prop_speed"] == [(period, 0), (3 * period, 50), (5 * period, 51), (9 * period, 50)]
    assert ("PR.state") in values and values["PR.state"][0] == (period, "S2")
    assert values["PR.status"][:3] == [(period, "EXEC"), (7 * period, "AT_GOAL"), (9 * period, "EXEC")]
    assert values["gm.ship_dir"][0] == (period, "BACK")


def test_failing_expectation_is_reported(capsys, tmp_path: Path) -> None:
    bad = tmp_path / "bad.scn"
    bad.write_text("cycles 12\nat 1: PR.AHEAD(speed = 5)\nexpect at 4: PR.prop_speed == 51\n")
    code = main(["sim", DESIGN, "--scenario", str(bad)])
    out = capsys.readouterr()
    assert code == 1
    assert "expect at 4: PR.prop_speed == 51" in out.err
    assert "false at cycle 4: PR.prop_speed = 50" in out.err


def test_scenario_errors_are_diagnostics(capsys, tmp_path: Path) -> None:
    bad = tmp_path / "bad.scn"
    bad.write_text("cycles 5\nat 1: TB.AHEAD(rpm = 3)\nat 9: ship_dir = ShipDir.AHEAD\nexpect at 2: PR.state == S7\n")
    code = main(["sim", DESIGN, "--scenario", str(bad)])
    err = capsys.readouterr().err
    assert code == 1
    assert "error[E0700]" in err and "bad.scn:2:7" in err  # chain of command
    assert "error[E0702]" in err and "bad.scn:3:4" in err  # cycle 9 of 5
    assert "error[E0703]" in err and "bad.scn:4:26" in err  # no state S7
    assert "Traceback" not in err


def test_misspelt_names_in_a_scenario_get_the_closest_declared_name(capsys, tmp_path: Path) -> None:
    """A scenario's unknown names get the "did you mean" of a design's (a
    controller, a verb, an input, a CPU, a state, a status, a name in an
    expectation); a name close to nothing gets none."""
    bad = tmp_path / "bad.scn"
    bad.write_text(
        "cycles 5\nat 1: PRR.AHEAD(speed = 3)\nat 1: PR.AHAED(speed = 3)\nat 1: ship_dri = ShipDir.AHEAD\nat 2: stop MAINN\n"
        "expect at 2: PR.state == S11\nexpect at 2: PR.prop_sped == 1\nexpect at 2: PR.verb == AHED\nexpect at 2: speed_stats == SpeedStatus.AT\n"
        "expect at 2: PR.AT_GAOL\nexpect at 2: zebra\n"
    )
    code = main(["sim", DESIGN, "--scenario", str(bad)])
    err = capsys.readouterr().err
    assert code == 1
    helps = {}
    for block in ("\n" + err).split("\nerror[")[1:]:
        line = int(block.split("bad.scn:", 1)[1].split(":", 1)[0])
        helps[(block[:5], line)] = [x.split("= help: ", 1)[1] for x in block.splitlines() if "= help: " in x]
    expected = {("E0104", 2): "PR", ("E0105", 3): "AHEAD", ("E0100", 4): "ship_dir", ("E0705", 5): "MAIN", ("E0703", 6): "S1",
                ("E0103", 7): "prop_speed", ("E0703", 8): "AHEAD", ("E0100", 9): "speed_status", ("E0103", 10): "AT_GOAL"}
    for key, name in expected.items():
        assert helps[key][:1] == [f"did you mean `{name}`?"], (key, helps)
    assert not any(h.startswith("did you mean") for h in helps[("E0100", 11)])


def test_rcsc_test_reports_and_writes_junit(capsys, tmp_path: Path) -> None:
    folder = tmp_path / "proj"
    folder.mkdir()
    (folder / "ahead_paper.rcs").write_text(Path(DESIGN).read_text())
    (folder / "good.scn").write_text(Path(SCENARIO).read_text())
    (folder / "broken.scn").write_text("cycles 3\nat 1: PR.AHEAD(speed = 1)\nexpect final: PR.prop_speed == 99\n")
    junit = tmp_path / "report.xml"
    code = main(["test", str(folder), "--junit", str(junit)])
    out = capsys.readouterr().out
    assert code == 1
    assert f"FAIL {folder / 'broken.scn'}" in out
    assert f"PASS {folder / 'good.scn'}" in out
    assert "expect final: PR.prop_speed == 99" in out and "false at cycle 3: PR.prop_speed = 10" in out
    assert out.rstrip().endswith("1 passed, 1 failed")
    root = ET.parse(junit).getroot()
    assert root.get("tests") == "2" and root.get("failures") == "1"
    cases = {c.get("name"): c for c in root.iter("testcase")}
    assert cases["broken.scn"].find("failure") is not None and cases["good.scn"].find("failure") is None


def test_rcsc_test_with_nothing_to_run_is_a_usage_error(capsys, tmp_path: Path) -> None:
    assert main(["test", str(tmp_path)]) == 2
    assert "no scenarios found" in capsys.readouterr().err
