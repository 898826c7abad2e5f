"""The `rcsc` command line: exit codes, streams, formats and error handling.

Most tests call `main([...])` in-process and replace the front end with a fake
(`cli._load_driver`) so that they test the CLI alone; one runs the real
front end on a missing file, and one runs `python -m rcsc` as a subprocess.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

import rcsc
from rcsc import cli
from rcsc.codes import CODES
from rcsc.diagnostics import Diagnostics
from rcsc.front.source import SourceFile, Span


class FakeInputError(Exception):
    pass


def _fake_driver(monkeypatch: pytest.MonkeyPatch, diags: Diagnostics | None = None, raises: BaseException | None = None):
    """Make `rcsc check` see `diags` (or raise `raises`) instead of running the front end."""
    calls: list[str] = []

    def check_path(path: str, as_module=False, overlay=None, cache_dir=None, keep_plans=True):
        calls.append(path)
        if raises is not None:
            raise raises
        return SimpleNamespace(diags=diags if diags is not None else Diagnostics(), model=None)

    fake = SimpleNamespace(check_path=check_path, InputError=FakeInputError)
    monkeypatch.setattr(cli, "_load_driver", lambda: fake)
    return calls


def _findings(*codes: str) -> Diagnostics:
    file = SourceFile("d.rcs", "alpha beta gamma\n")
    diags = Diagnostics()
    for i, code in enumerate(codes):
        diags.add(code, Span(file, 6 * i, 6 * i + 4), f"finding {i}", "here")
    return diags


@pytest.fixture(autouse=True)
def _no_color_env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.delenv("RCSC_BACKTRACE", raising=False)


# ---------------------------------------------------------------------------
# explain and --version
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("code", sorted(CODES))
def test_explain_every_code(code: str, capsys) -> None:
    assert cli.main(["explain", code]) == 0
    out, err = capsys.readouterr()
    assert out.startswith(f"{code} ({CODES[code].severity.value}): {CODES[code].title}\n")
    assert CODES[code].explanation.strip() in out
    assert err == ""


def test_explain_accepts_lowercase(capsys) -> None:
    assert cli.main(["explain", "e0100"]) == 0
    assert capsys.readouterr().out.startswith("E0100 ")


@pytest.mark.parametrize("code", ["E9999", "X", "W0000"])
def test_explain_unknown_code_is_a_usage_error(code: str, capsys) -> None:
    assert cli.main(["explain", code]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("error: unknown diagnostic code")


def test_explain_list(capsys) -> None:
    assert cli.main(["explain", "--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == len(CODES)
    assert lines[0].split() [:2] == ["E0001", "error"]
    assert any(line.startswith("W0310  warning  too many subordinates") for line in lines)


@pytest.mark.parametrize("argv", [["explain"], ["explain", "E0100", "--list"]])
def test_explain_needs_exactly_one_of_code_and_list(argv: list[str], capsys) -> None:
    assert cli.main(argv) == 2
    assert capsys.readouterr().err.startswith("error: give either a CODE or --list")


def test_version(capsys) -> None:
    assert cli.main(["--version"]) == 0
    assert capsys.readouterr().out == f"rcsc {rcsc.__version__}\n"


def test_python_dash_m_version() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "rcsc", "--version"], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == f"rcsc {rcsc.__version__}\n"
    assert proc.stderr == ""


# ---------------------------------------------------------------------------
# usage errors
# ---------------------------------------------------------------------------

@pytest.mark.parametrize(
    "argv",
    [
        [],
        ["frobnicate"],
        ["check"],
        ["check", "d.rcs", "--format", "xml"],
        ["check", "d.rcs", "--color", "sometimes"],
        ["check", "d.rcs", "--no-such-option"],
        ["--form"],  # abbreviations are refused so that options stay stable
    ],
)
def test_usage_errors_exit_2_without_traceback(argv: list[str], capsys, monkeypatch) -> None:
    calls = _fake_driver(monkeypatch)
    assert cli.main(argv) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert "usage: rcsc" in err and "Traceback" not in err
    assert calls == []


def test_help_exits_0(capsys) -> None:
    assert cli.main(["--help"]) == 0
    assert "check" in capsys.readouterr().out


# ---------------------------------------------------------------------------
# check
# ---------------------------------------------------------------------------

def test_check_missing_file_with_the_real_front_end(tmp_path: Path, capsys) -> None:
    missing = tmp_path / "no-such-design.rcs"
    assert cli.main(["check", str(missing)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("error: ") and "no-such-design.rcs" in err
    assert "Traceback" not in err


def test_check_input_error_exits_2(monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, raises=FakeInputError("d.rcs: no such file"))
    assert cli.main(["check", "d.rcs", "--format", "json"]) == 2
    assert capsys.readouterr() == ("", "error: d.rcs: no such file\n")


def test_check_clean_design(monkeypatch, capsys) -> None:
    calls = _fake_driver(monkeypatch)
    assert cli.main(["check", "d.rcs"]) == 0
    assert calls == ["d.rcs"]
    assert capsys.readouterr() == ("", "")


@pytest.mark.parametrize(
    ("codes", "deny", "expected"),
    [
        ((), False, 0),
        (("W0310",), False, 0),
        (("W0310",), True, 1),
        (("E0100",), False, 1),
        (("E0100", "W0310"), False, 1),
    ],
)
def test_check_exit_codes(codes, deny: bool, expected: int, monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, _findings(*codes))
    argv = ["check", "d.rcs", "--format", "short"] + (["--deny-warnings"] if deny else [])
    assert cli.main(argv) == expected
    out, err = capsys.readouterr()
    assert len(out.splitlines()) == len(codes)
    assert err == ""


@pytest.mark.parametrize("fmt", ["human", "short", "json", "sarif"])
def test_check_report_goes_to_stdout_only(fmt: str, monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, _findings("E0100", "W0310"))
    assert cli.main(["check", "d.rcs", "--format", fmt]) == 1
    out, err = capsys.readouterr()
    assert err == ""
    assert "E0100" in out
    if fmt in ("json", "sarif"):
        json.loads(out)


def test_check_json_report(monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, _findings("E0100"))
    cli.main(["check", "d.rcs", "--format", "json"])
    doc = json.loads(capsys.readouterr().out)
    assert doc["tool"] == {"name": "rcsc", "version": rcsc.__version__}
    assert doc["summary"] == {"errors": 1, "warnings": 0}


def test_check_output_file(tmp_path: Path, monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, _findings("E0100"))
    target = tmp_path / "report.sarif"
    assert cli.main(["check", "d.rcs", "--format", "sarif", "-o", str(target)]) == 1
    assert capsys.readouterr() == ("", "")
    assert json.loads(target.read_text(encoding="utf-8"))["version"] == "2.1.0"


def test_check_unwritable_output_is_an_io_error(tmp_path: Path, monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, _findings("E0100"))
    target = tmp_path / "missing-folder" / "report.json"
    assert cli.main(["check", "d.rcs", "--format", "json", "--output", str(target)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith("error: cannot write")


@pytest.mark.parametrize(
    ("color", "no_color", "expected"),
    [("always", None, True), ("always", "1", True), ("never", None, False), ("auto", None, False)],
)
def test_check_colour(color: str, no_color: str | None, expected: bool, monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, _findings("E0100"))
    if no_color:
        monkeypatch.setenv("NO_COLOR", no_color)
    cli.main(["check", "d.rcs", "--color", color])
    assert ("\x1b[" in capsys.readouterr().out) is expected


def test_auto_colour_needs_a_terminal_and_no_NO_COLOR(monkeypatch) -> None:
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True, raising=False)
    monkeypatch.delenv("TERM", raising=False)
    assert cli._use_color("auto", None) is True
    assert cli._use_color("auto", "report.txt") is False
    monkeypatch.setenv("NO_COLOR", "1")
    assert cli._use_color("auto", None) is False


# ---------------------------------------------------------------------------
# never a traceback
# ---------------------------------------------------------------------------

def test_internal_error_is_reported_without_traceback(monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, raises=RuntimeError("boom"))
    assert cli.main(["check", "d.rcs"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("error: internal compiler error: RuntimeError: boom\n")
    assert "report" in err and "Traceback" not in err


def test_internal_error_backtrace_on_request(monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, raises=RuntimeError("boom"))
    monkeypatch.setenv("RCSC_BACKTRACE", "1")
    assert cli.main(["check", "d.rcs"]) == 2
    assert "Traceback" in capsys.readouterr().err


def test_keyboard_interrupt_exits_130(monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, raises=KeyboardInterrupt())
    assert cli.main(["check", "d.rcs"]) == 130
    assert "interrupted" in capsys.readouterr().err


def test_broken_pipe_is_quiet(monkeypatch, capsys) -> None:
    _fake_driver(monkeypatch, _findings("E0100"))

    def broken(text, output):
        raise BrokenPipeError

    monkeypatch.setattr(cli, "_emit_report", broken)
    assert cli.main(["check", "d.rcs"]) == 2
    assert capsys.readouterr().err == ""


def test_unencodable_report_is_replaced_not_fatal(monkeypatch) -> None:
    import io

    stream = io.TextIOWrapper(io.BytesIO(), encoding="ascii")
    cli._write(stream, "caf\u00e9 \u65e5\n")
    stream.flush()
    assert stream.buffer.getvalue() == b"caf? ?\n"


def test_sim_refuses_a_scenario_whose_duration_is_finer_than_a_nanosecond(tmp_path: Path, capsys) -> None:
    """A parse-time finding in a scenario (E0210) stops the run, as any other error does."""
    scn = tmp_path / "fine.scn"
    scn.write_text("cycles 5\nat 1: SM.TRANSIT(speed = 1.0, leg_time = 0.0000000001 s)\n", encoding="utf-8")
    design = Path(__file__).resolve().parent.parent / "examples/submarine/submarine.rcs"
    rc = cli.main(["sim", str(design), "--scenario", str(scn), "-o", str(tmp_path / "t.jsonl")])
    assert rc == 1
    assert "error[E0210]" in capsys.readouterr().err
    assert not (tmp_path / "t.jsonl").exists()


def test_a_scenario_s_warnings_are_shown_when_it_passes(capsys) -> None:
    """W0707 (an input outside its variable's declared range) is a warning:
    `rcsc test` passes the scenario and prints it under the PASS line, and
    `rcsc sim` prints it on stderr; neither kept it to itself."""
    case = Path(__file__).resolve().parent / "cases/W0707_input_outside_range"
    assert cli.main(["test", str(case / "run.scn")]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].startswith(f"PASS {case / 'run.scn'}")
    assert out.count("warning[W0707]") == 2 and out.endswith("1 passed, 0 failed\n")
    assert cli.main(["sim", str(case / "main.rcs"), "--scenario", str(case / "run.scn"), "-o", "/dev/null"]) == 0
    assert capsys.readouterr().err.count("warning[W0707]") == 2
