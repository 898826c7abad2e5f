"""Hostile and careless input: answered at once, read as written, reported safely.

Each test is one way a design, a scenario or a command line used to hang
rcsc, crash it, or produce output that breaks its consumer (a terminal, a
JUnit reader, a file named for another format).
"""

from __future__ import annotations

import time
import xml.dom.minidom
from pathlib import Path

import pytest

from rcsc.cli import main
from rcsc.front.parse import TOO_LARGE, literal_fraction, literal_int

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "tests" / "cases"
SUBMARINE = ROOT / "examples" / "submarine" / "submarine.rcs"

DESIGN = """design d

const SPEED: f64 = 2.0

controller TOP level 1 budget 1 ms {
    verb RUN(speed: f64)
    plan RUN {
        E0: cmd.speed > SPEED | new -> done;
        E1: not (cmd.speed > SPEED) | new -> error(1);
    }
}

cpu main {
    heartbeat 10 ms
    schedule TOP
}
"""


@pytest.mark.parametrize("text", ["0e100000000", "1e100000000", "1e-100000000", "9" * 100000 + "e-99999", "0." + "0" * 100000 + "1"])
def test_duration_literals_take_no_time(text: str) -> None:
    start = time.monotonic()
    value = literal_fraction(text)
    assert time.monotonic() - start < 0.5
    assert value == 0 or value >= TOO_LARGE or value <= 1 or value.denominator > 1


def test_huge_integer_literal_is_out_of_range_not_a_crash(tmp_path: Path, capsys) -> None:
    assert literal_int("1" * 5000) == TOO_LARGE
    design = tmp_path / "d.rcs"
    design.write_text(DESIGN.replace("const SPEED: f64 = 2.0", "const SPEED: f64 = 2.0\nconst N: i64 = " + "7" * 5000))
    start = time.monotonic()
    assert main(["check", str(design), "--format", "short"]) == 1
    out = capsys.readouterr().out
    assert "error[E0207]: integer literal out of range for `i64`" in out and "internal" not in out
    assert time.monotonic() - start < 5


def test_a_scenario_duration_with_a_huge_exponent_is_answered_at_once(tmp_path: Path, capsys) -> None:
    design = tmp_path / "d.rcs"
    design.write_text(DESIGN)
    scn = tmp_path / "s.scn"
    scn.write_text("cycles 3\nat 1: TOP.RUN(speed = 3.0)\nexpect always: 0e999999999999 s == 0 s\n")
    start = time.monotonic()
    assert main(["sim", str(design), "--scenario", str(scn), "-o", str(tmp_path / "t.jsonl")]) == 0
    assert time.monotonic() - start < 5


def test_cr_only_and_bom_files_report_real_lines(tmp_path: Path, capsys) -> None:
    text = (CASES / "E0212_float_literal_range.rcs").read_text()
    (tmp_path / "cr.rcs").write_bytes(text.replace("\n", "\r").encode())
    (tmp_path / "bom.rcs").write_bytes(b"\xef\xbb\xbf" + text.encode())
    (tmp_path / "crlf.rcs").write_bytes(text.replace("\n", "\r\n").encode())
    for name in ("cr.rcs", "bom.rcs", "crlf.rcs"):
        assert main(["check", str(tmp_path / name), "--format", "short"]) == 1
        out = capsys.readouterr().out
        assert f"{name}:5:19: error[E0212]" in out, out
        assert "E0002" not in out and "E0001" not in out


def _failing_scenario(tmp_path: Path, comment: str, name: str = "bad.scn") -> Path:
    (tmp_path / "d.rcs").write_text(DESIGN)
    scn = tmp_path / name
    scn.write_text(f"// {comment}\ncycles 3\nat 1: TOP.RUN(speed = 1.0)\nexpect final: TOP.done // \x1b[2J{comment}\n")
    return scn


def test_junit_stays_well_formed_with_control_bytes(tmp_path: Path, capsys) -> None:
    _failing_scenario(tmp_path, "comment", "bell\x07escape\x1b\x01.scn")
    junit = tmp_path / "report.xml"
    assert main(["test", str(tmp_path), "--junit", str(junit)]) == 1
    doc = xml.dom.minidom.parse(str(junit))  # raises if not well-formed XML 1.0
    failures = doc.getElementsByTagName("failure")
    assert len(failures) == 1


def test_terminal_output_escapes_control_characters(tmp_path: Path, capsys) -> None:
    # The file name carries the escapes: it is printed in the PASS/FAIL line
    # and in the expectation's location.
    _failing_scenario(tmp_path, "plain", "bad\x1b[2J\u202e.scn")
    assert main(["test", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\u202e" not in out
    assert "\\x1b[2J" in out and "0 passed, 1 failed" in out


def test_graph_refuses_an_output_name_it_cannot_write(tmp_path: Path, capsys) -> None:
    target = tmp_path / "x.pdf"
    assert main(["graph", str(SUBMARINE), "-o", str(target)]) == 2
    assert "cannot tell the format" in capsys.readouterr().err
    assert not target.exists()
    assert main(["graph", str(SUBMARINE), "-o", str(target), "--format", "dot"]) == 0
    assert target.read_text().startswith("//")


def test_nul_in_an_import_path_is_a_finding_not_a_crash(tmp_path: Path, capsys) -> None:
    """The front-end fuzzer's find: the system's path functions refuse a NUL
    (`ValueError: embedded null byte`), which ended in an internal error."""
    design = tmp_path / "d.rcs"
    design.write_bytes(DESIGN.replace("const SPEED", 'import "a\0b.rcs"\n\nconst SPEED').encode())
    assert main(["check", str(design)]) == 1
    out = capsys.readouterr().out
    assert "error[E0003]: cannot read the imported file: its path holds a NUL character" in out
    assert "internal" not in out and "\0" not in out


@pytest.mark.parametrize("fmt", ["human", "short"])
def test_control_characters_quoted_in_a_finding_are_escaped(tmp_path: Path, capsys, fmt: str) -> None:
    """An import path that holds an escape sequence is quoted in the finding's
    message: shown as `\\x1b`, so that it cannot drive the terminal."""
    design = tmp_path / "d.rcs"
    design.write_bytes(DESIGN.replace("const SPEED", 'import "a\x1b[2Jb.rcs"\n\nconst SPEED').encode())
    assert main(["check", str(design), "--format", fmt]) == 1
    out = capsys.readouterr().out
    assert "cannot read `a\\x1b[2Jb.rcs`" in out
    assert "\x1b" not in out


def test_a_file_of_another_encoding_is_e0010_at_its_first_bad_byte(tmp_path: Path, capsys) -> None:
    """A design, an imported module, a scenario or a configuration saved as
    Latin-1 is one E0010 finding that points at the byte (line, column, the
    byte's value), exit 1: it used to be a bare "not UTF-8 text (byte N)"
    usage error without a span (the root, scenarios, rcsc.toml), an E0003 at
    the import, or, in a pyproject.toml, a configuration silently ignored."""
    design = tmp_path / "d.rcs"
    design.write_bytes(b"design d\n// caf\xe9 au lait\nconst K: i32 = 1\n")
    assert main(["check", str(design)]) == 1
    err = "".join(capsys.readouterr())
    assert f"error[E0010]: this file is not UTF-8 text\n --> {design}:2:7\n" in err
    assert "byte 0xe9 is not UTF-8" in err and "at byte 15 of the file" in err

    folder = tmp_path / "imp"
    folder.mkdir()
    (folder / "m.rcs").write_bytes(b"module m\nconst K: i32 = 1 // \xff\n")
    (folder / "d.rcs").write_text('design d\nimport "m.rcs"\n', encoding="utf-8")
    assert main(["check", "--format", "json", str(folder / "d.rcs")]) == 1
    out = capsys.readouterr().out
    assert '"code": "E0010"' in out and '"line": 2' in out and "E0003" not in out

    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / "submarine.rcs").write_text(SUBMARINE.read_text(encoding="utf-8"), encoding="utf-8")
    scn = sub / "s.scn"
    scn.write_bytes(b"cycles 3\n// \xe9\n")
    assert main(["sim", str(sub / "submarine.rcs"), "--scenario", str(scn)]) == 1
    assert f" --> {scn}:2:4\n" in "".join(capsys.readouterr())
    assert main(["test", str(scn)]) == 1
    assert f"{scn}:2:4: error[E0010]: this file is not UTF-8 text" in "".join(capsys.readouterr())

    for name, text in (("rcsc.toml", b'ignore = ["W0403"] # caf\xe9\n'),
                       ("pyproject.toml", b'[tool.rcsc]\nignore = ["W0403"] # caf\xe9\n')):
        cfg = tmp_path / name.replace(".", "_")
        cfg.mkdir()
        (cfg / "submarine.rcs").write_text(SUBMARINE.read_text(encoding="utf-8"), encoding="utf-8")
        (cfg / name).write_bytes(text)
        assert main(["check", str(cfg / "submarine.rcs")]) == 1, name
        err = "".join(capsys.readouterr())
        line = text.count(b"\n")
        assert "error[E0010]" in err and f"{name}:{line}:25" in err, err


def test_rcsc_test_finds_a_design_cut_through_a_character_at_64_kib(tmp_path: Path, capsys) -> None:
    """Discovery reads a file's first 64 KiB for its `design` header: a
    character cut at that boundary made the file "not a design", and
    `rcsc test` on the folder ran nothing."""
    text = SUBMARINE.read_text(encoding="utf-8")
    pad = 65536 - len(text.encode("utf-8")) - 1
    assert pad > 0
    (tmp_path / "submarine.rcs").write_text(text + "//" + "x" * (pad - 2) + "é\n", encoding="utf-8")
    assert (tmp_path / "submarine.rcs").read_bytes()[65535:65537] == "é".encode("utf-8")
    (tmp_path / "s.scn").write_text("cycles 3\nat 1: SM.INIT()\n", encoding="utf-8")
    assert main(["test", str(tmp_path)]) == 0
    assert "1 passed, 0 failed" in capsys.readouterr().out
