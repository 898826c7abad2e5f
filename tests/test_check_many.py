"""`rcsc check PATH...`: folders, globs, modules in context, one combined
report, configuration files and flags, `--quiet`, `--format github`, colour
environment variables (the real front end on small designs in tmp_path)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from rcsc import cli, render
from rcsc.diagnostics import Diagnostics
from rcsc.front.source import SourceFile, Span

# One design whose only finding is W0403 (`spare` is never read or written).
DESIGN = """design {name}
{imports}
gm spare: i32 = 0

controller TOP level 1 budget 1 ms {{
    verb RUN
    plan RUN {{
        E0: true | new -> done;
    }}
}}

cpu main {{
    heartbeat 10 ms
    schedule TOP
}}
"""

BAD_MODULE = "module mm\nconst X: i32 = true\n"  # E0200 at 2:16


@pytest.fixture(autouse=True)
def _clean_env(monkeypatch: pytest.MonkeyPatch) -> None:
    for var in ("NO_COLOR", "FORCE_COLOR", "RCSC_BACKTRACE"):
        monkeypatch.delenv(var, raising=False)


def _tree(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """proj/a.rcs imports sub/m.rcs (a module with an error); proj/b.rcs is
    another design; proj/sub/lonely.rcs is a module nobody imports."""
    proj = tmp_path / "proj"
    (proj / "sub").mkdir(parents=True)
    (proj / "a.rcs").write_text(DESIGN.format(name="a", imports='import "sub/m.rcs"'))
    (proj / "b.rcs").write_text(DESIGN.format(name="b", imports=""))
    (proj / "sub" / "m.rcs").write_text(BAD_MODULE)
    (proj / "sub" / "lonely.rcs").write_text("module lonely\nconst Y: i32 = 4\n")
    monkeypatch.chdir(tmp_path)
    return proj


def _short(argv: list[str], capsys) -> tuple[int, list[str], str]:
    rc = cli.main(["check", "--format", "short", *argv])
    out, err = capsys.readouterr()
    return rc, out.splitlines(), err


def test_folder_checks_every_design_and_module_once(tmp_path, monkeypatch, capsys) -> None:
    _tree(tmp_path, monkeypatch)
    rc, lines, err = _short(["proj"], capsys)
    assert rc == 1 and err == ""
    assert lines == [
        "proj/a.rcs:3:4: warning[W0403]: Global Memory variable `spare` is never read or written",
        "proj/b.rcs:3:4: warning[W0403]: Global Memory variable `spare` is never read or written",
        "proj/sub/m.rcs:2:16: error[E0200]: mismatched types: expected `i32`, found `bool`",
    ]


def test_module_alone_is_checked_through_the_design_that_imports_it(tmp_path, monkeypatch, capsys) -> None:
    _tree(tmp_path, monkeypatch)
    rc, lines, _ = _short(["proj/sub/m.rcs"], capsys)
    assert rc == 1
    assert "proj/sub/m.rcs:2:16: error[E0200]: mismatched types: expected `i32`, found `bool`" in lines
    assert not any("E0006" in line for line in lines)


def test_module_nobody_imports_is_checked_on_its_own_without_E0006(tmp_path, monkeypatch, capsys) -> None:
    _tree(tmp_path, monkeypatch)
    rc, lines, _ = _short(["proj/sub/lonely.rcs"], capsys)
    assert (rc, lines) == (0, [])
    (tmp_path / "proj" / "sub" / "lonely.rcs").write_text("module lonely\nconst Y: i32 = nope\n")
    rc, lines, _ = _short(["proj/sub/lonely.rcs"], capsys)
    assert rc == 1 and [line.split(": ")[1] for line in lines] == ["error[E0100]"]


def test_glob_pattern_is_expanded_without_a_shell(tmp_path, monkeypatch, capsys) -> None:
    _tree(tmp_path, monkeypatch)
    rc, lines, _ = _short(["proj/*.rcs"], capsys)
    assert rc == 1 and len(lines) == 3
    rc, _, err = _short(["proj/*.nothing"], capsys)
    assert rc == 2 and "no file matches" in err


def test_one_sarif_run_holds_every_design(tmp_path, monkeypatch, capsys) -> None:
    _tree(tmp_path, monkeypatch)
    assert cli.main(["check", "proj/a.rcs", "proj/b.rcs", "--format", "sarif"]) == 1
    log = json.loads(capsys.readouterr().out)
    assert len(log["runs"]) == 1
    uris = sorted(r["locations"][0]["physicalLocation"]["artifactLocation"]["uri"] for r in log["runs"][0]["results"])
    assert uris == ["proj/a.rcs", "proj/b.rcs", "proj/sub/m.rcs"]


def test_unreadable_path_among_others_exits_2_but_reports_the_rest(tmp_path, monkeypatch, capsys) -> None:
    _tree(tmp_path, monkeypatch)
    rc, lines, err = _short(["proj/b.rcs", "proj/missing.rcs"], capsys)
    assert rc == 2
    assert "missing.rcs: no such file" in err
    assert len(lines) == 1 and "W0403" in lines[0]


def test_quiet_drops_the_summary_line(tmp_path, monkeypatch, capsys) -> None:
    _tree(tmp_path, monkeypatch)
    assert cli.main(["check", "proj/b.rcs", "--color", "never"]) == 0
    assert capsys.readouterr().out.rstrip().endswith("warning: 1 warning emitted")
    assert cli.main(["check", "proj/b.rcs", "--color", "never", "-q"]) == 0
    out = capsys.readouterr().out
    assert "warning[W0403]" in out and "emitted" not in out


def test_short_version_flag(capsys) -> None:
    assert cli.main(["-V"]) == 0
    assert capsys.readouterr().out.startswith("rcsc ")


# ---------------------------------------------------------------------------
# configuration
# ---------------------------------------------------------------------------

def test_rcsc_toml_ignore_and_severity(tmp_path, monkeypatch, capsys) -> None:
    proj = _tree(tmp_path, monkeypatch)
    (proj / "rcsc.toml").write_text('ignore = ["W04"]\n')
    rc, lines, _ = _short(["proj/b.rcs"], capsys)
    assert (rc, lines) == (0, [])
    (proj / "rcsc.toml").write_text('[severity]\nW0403 = "error"\n')
    rc, lines, _ = _short(["proj/b.rcs"], capsys)
    assert rc == 1 and lines == ["proj/b.rcs:3:4: error[W0403]: Global Memory variable `spare` is never read or written"]


def test_pyproject_tool_table_and_per_file_ignores(tmp_path, monkeypatch, capsys) -> None:
    proj = _tree(tmp_path, monkeypatch)
    (tmp_path / "pyproject.toml").write_text('[project]\nname = "x"\n\n[tool.rcsc.per-file-ignores]\n"proj/a.rcs" = ["W0403"]\n')
    rc, lines, _ = _short(["proj/a.rcs", "proj/b.rcs"], capsys)
    assert [line.split(":")[0] for line in lines] == ["proj/b.rcs", "proj/sub/m.rcs"]
    # An rcsc.toml nearer to the file wins over the pyproject.toml above it.
    (proj / "rcsc.toml").write_text("select = []\n")
    rc, lines, _ = _short(["proj/a.rcs", "proj/b.rcs"], capsys)
    assert [line.split(":")[0] for line in lines] == ["proj/sub/m.rcs"]


def test_config_mistakes_are_findings_with_spans_not_tracebacks(tmp_path, monkeypatch, capsys) -> None:
    proj = _tree(tmp_path, monkeypatch)
    (proj / "rcsc.toml").write_text('select = "W"\nignore = [\n')
    rc, lines, err = _short(["proj/b.rcs"], capsys)
    assert rc == 1 and err == ""
    assert any(line.startswith("proj/rcsc.toml:3:1: error[E0009]: the configuration is not valid TOML") for line in lines)
    (proj / "rcsc.toml").write_text('select = "W"\n[per-file-ignores]\n"x" = [1]\n')
    rc, lines, _ = _short(["proj/b.rcs"], capsys)
    assert [line for line in lines if "rcsc.toml" in line] == [
        "proj/rcsc.toml:1:1: error[E0009]: `select` must be a list of strings",
        'proj/rcsc.toml:3:1: error[E0009]: `per-file-ignores."x"` must be a list of codes',
    ]
    (proj / "rcsc.toml").write_text('[severity]\nW0403 = ["error"]\n')
    rc, lines, _ = _short(["proj/b.rcs"], capsys)
    assert [line for line in lines if "rcsc.toml" in line] == [
        'proj/rcsc.toml:2:1: error[E0009]: the severity of `W0403` must be a string: "error", "warning" or "note"',
    ]


# Every kind of TOML value, for every place a value can stand in the
# configuration: each is a finding or accepted, never an internal error.
_TOML_VALUES = ['"W"', "3", "1.5", "true", "1979-05-27", '["W0403"]', "[1, 2]", '[["W"]]', "{a = 1}", '["error"]', "[]", "{}"]


@pytest.mark.parametrize("where", ["select = {}", "ignore = {}", "exclude = {}", "severity = {}", "per-file-ignores = {}",
                                   "[severity]\nW0403 = {}", "[severity]\nE0100 = {}", "[per-file-ignores]\n\"*.rcs\" = {}",
                                   "[severity.W0403]\nx = {}", "[[severity]]\nW0403 = {}"])
def test_every_toml_value_anywhere_is_a_finding_or_accepted(where, tmp_path, monkeypatch, capsys) -> None:
    proj = _tree(tmp_path, monkeypatch)
    for value in _TOML_VALUES:
        (proj / "rcsc.toml").write_text(where.format(value) + "\n")
        rc, lines, err = _short(["proj/b.rcs"], capsys)
        assert rc in (0, 1) and err == "", (where, value, err)
        assert not any("internal" in line for line in lines), (where, value, lines)


def test_command_line_overrides_and_no_config(tmp_path, monkeypatch, capsys) -> None:
    proj = _tree(tmp_path, monkeypatch)
    (proj / "rcsc.toml").write_text('ignore = ["W0403"]\n')
    assert _short(["proj/b.rcs"], capsys)[1] == []
    assert len(_short(["proj/b.rcs", "--no-config"], capsys)[1]) == 1
    rc, lines, _ = _short(["proj/b.rcs", "--no-config", "--severity", "W0403=note"], capsys)
    assert rc == 0 and "note[W0403]" in lines[0]
    assert _short(["proj/b.rcs", "--no-config", "--select", "W05"], capsys)[1] == []
    rc, _, err = _short(["proj/b.rcs", "--ignore", "E0100"], capsys)
    assert rc == 2 and "errors cannot be ignored" in err
    other = tmp_path / "other.toml"
    other.write_text('[severity]\nW0403 = "error"\n')
    assert _short(["proj/b.rcs", "--config", str(other)], capsys)[0] == 1


def test_exclude_skips_files_found_in_folders_only(tmp_path, monkeypatch, capsys) -> None:
    proj = _tree(tmp_path, monkeypatch)
    (proj / "rcsc.toml").write_text('exclude = ["b.rcs"]\n')
    lines = _short(["proj"], capsys)[1]
    assert not any(line.startswith("proj/b.rcs") for line in lines)
    assert _short(["proj/b.rcs"], capsys)[1] != []


# ---------------------------------------------------------------------------
# GitHub annotations and colour
# ---------------------------------------------------------------------------

def test_github_annotations_escape_data_and_properties() -> None:
    file = SourceFile("dir,a:b%.rcs", "alpha beta\n")
    diags = Diagnostics()
    diags.add("E0100", Span(file, 6, 10), "unknown name `beta`\r\n100% sure", "here").with_help("declare it")
    out = render.render_github(diags)
    assert out == (
        "::error file=dir%2Ca%3Ab%25.rcs,line=1,col=7,endLine=1,endColumn=11,title=E0100 unknown name"
        "::unknown name `beta`%0D%0A100%25 sure%0Ahelp: declare it\n"
    )
    assert out.count("\n") == 1


class _Tty:
    def isatty(self) -> bool:
        return True


class _Pipe:
    def isatty(self) -> bool:
        return False


@pytest.mark.parametrize(
    "env, stream, choice, expected",
    [
        ({}, _Tty(), "auto", True),
        ({}, _Pipe(), "auto", False),
        ({"FORCE_COLOR": "1"}, _Pipe(), "auto", True),
        ({"FORCE_COLOR": ""}, _Pipe(), "auto", False),
        ({"NO_COLOR": "1"}, _Tty(), "auto", False),
        ({"NO_COLOR": "1", "FORCE_COLOR": "1"}, _Pipe(), "auto", True),  # force-color.org: FORCE_COLOR wins
        ({"FORCE_COLOR": "1"}, _Tty(), "never", False),  # an explicit flag wins over the environment
        ({"NO_COLOR": "1"}, _Pipe(), "always", True),
    ],
)
def test_colour_choice(monkeypatch, env, stream, choice, expected) -> None:
    for k, v in env.items():
        monkeypatch.setenv(k, v)
    assert cli._use_color(choice, None, stream) is expected


def test_explicit_module_in_a_folder_outside_cwd(tmp_path, monkeypatch, capsys) -> None:
    """A module outside the current folder is looked up only beside itself."""
    proj = _tree(tmp_path, monkeypatch)
    monkeypatch.chdir(proj / "sub")
    os.makedirs("elsewhere")
    monkeypatch.chdir("elsewhere")
    rc, lines, _ = _short([str(proj / "sub" / "m.rcs")], capsys)
    # The importing design is in an ancestor folder that is not searched: the
    # module is checked on its own and its own error is still found.
    assert rc == 1 and any("E0200" in line for line in lines)


def test_junit_reports_a_design_error_as_error_with_its_diagnostic(tmp_path, monkeypatch, capsys) -> None:
    import xml.etree.ElementTree as ET

    monkeypatch.chdir(tmp_path)
    (tmp_path / "d.rcs").write_text(DESIGN.format(name="d", imports="").replace("gm spare: i32 = 0", "gm spare: i32 = nope"))
    (tmp_path / "s.scn").write_text("cycles 2\n")
    assert cli.main(["test", ".", "--junit", "r.xml"]) == 1
    capsys.readouterr()
    root = ET.parse(tmp_path / "r.xml").getroot()
    assert (root.get("failures"), root.get("errors")) == ("0", "1")
    error = root.find("./testsuite/testcase/error")
    assert error is not None and root.find("./testsuite/testcase/failure") is None
    assert error.get("message") == "d.rcs:3:17: error[E0100]: cannot find `nope` in this scope"
    assert "the design has errors" in error.text and "error[E0100]" in error.text


def test_a_select_that_names_no_warning_is_a_usage_error(tmp_path, monkeypatch, capsys) -> None:
    """`--select` chooses warnings; one that names none (empty, commas, only
    error codes) would hide every warning without a word."""
    _tree(tmp_path, monkeypatch)
    for value in ("", ",,,", "E0101", "e01, E"):
        rc, lines, err = _short(["proj/b.rcs", "--select", value], capsys)
        assert rc == 2 and lines == [] and err.startswith("error: --select: "), (value, err)
    rc, lines, err = _short(["proj/b.rcs", "--select", "W04,E01"], capsys)
    assert rc == 0 and err == ""


def test_select_of_only_errors_in_the_configuration_is_a_finding(tmp_path, monkeypatch, capsys) -> None:
    proj = _tree(tmp_path, monkeypatch)
    (proj / "rcsc.toml").write_text('select = ["E0100"]\n')
    rc, lines, _ = _short(["proj/b.rcs"], capsys)
    assert "proj/rcsc.toml:1:1: error[E0009]: `select` names no warning: errors are always reported, and `select` chooses the warnings" in lines


def test_pyproject_counts_when_toml_says_tool_rcsc(tmp_path, monkeypatch, capsys) -> None:
    """`tool.rcsc` however TOML spells it; a table merely named like it
    (`[tool.rcscx]`) is not rcsc's and does not hide a configuration above."""
    proj = _tree(tmp_path, monkeypatch)
    (proj / "rcsc.toml").write_text('ignore = ["W"]\n')
    sub = proj / "sub"
    (sub / "d.rcs").write_text(DESIGN.format(name="d", imports=""))
    (sub / "pyproject.toml").write_text("[tool.rcscx]\na = 1\n")
    rc, lines, _ = _short(["proj/sub/d.rcs"], capsys)
    assert not [line for line in lines if "warning[" in line], lines
    (proj / "rcsc.toml").unlink()
    rc, with_warnings, _ = _short(["proj/sub/d.rcs"], capsys)
    assert [line for line in with_warnings if "warning[" in line]
    (sub / "pyproject.toml").write_text('[tool]\nrcsc.ignore = ["W"]\n')
    rc, lines, _ = _short(["proj/sub/d.rcs"], capsys)
    assert not [line for line in lines if "warning[" in line], lines


def test_a_module_with_a_controller_checked_alone_needs_no_cpu(tmp_path, monkeypatch, capsys) -> None:
    _tree(tmp_path, monkeypatch)
    (tmp_path / "proj" / "sub" / "lonely.rcs").write_text(
        "module lonely\ngm x: f64 = 0.0 to env\nsimulator P level 0 budget 1 us { writes x post { x = x + 1.0; } }\n")
    rc, lines, _ = _short(["proj/sub/lonely.rcs"], capsys)
    assert not [line for line in lines if "E0605" in line], lines
