"""`rcsc fmt`: the canonical layout never changes what a file means.

Every .rcs file of the repository and a few hundred generated designs (with
random extra blanks, tabs and blank lines) are formatted; the syntax trees
before and after must be equal (spans aside), formatting must be idempotent,
and every comment must still be there, in order.  The examples and the
standard library are kept formatted (`rcsc fmt --check` passes on them)."""

from __future__ import annotations

import os
import random
import re
import stat
from pathlib import Path

import pytest

from rcsc import cli
from rcsc.diagnostics import Diagnostics
from rcsc.editor.fmt import format_text, shape
from rcsc.front.parse import text_to_ast
from rcsc.front.source import SourceFile, normalized

ROOT = Path(__file__).resolve().parent.parent
def _utf8(path: Path) -> bool:
    try:
        path.read_bytes().decode("utf-8")
    except UnicodeDecodeError:
        return False  # E0010's case (tests/cases/E0010_not_utf8): nothing to format
    return True


ALL_RCS = sorted(p for p in ROOT.rglob("*.rcs") if not any(part.startswith(".") for part in p.relative_to(ROOT).parts) and _utf8(p))
_COMMENT = re.compile(r"//[^\n]*|/\*.*?\*/", re.S)


def _tree(text: str):
    return text_to_ast(SourceFile("x.rcs", text), Diagnostics())


def _assert_round_trip(text: str, where: str) -> str:
    before = _tree(text)
    if before is None:
        return text
    out = format_text(text)
    after = _tree(out)
    assert after is not None, f"{where}: formatted text does not parse"
    assert shape(after) == shape(before), f"{where}: formatting changed the syntax tree"
    assert format_text(out) == out, f"{where}: formatting is not idempotent"
    # A lone CR ends a line (and so a `//` comment) as LF does: the comments
    # are those of the text as the parser reads it.
    assert [c.rstrip() for c in _COMMENT.findall(out)] == [c.rstrip() for c in _COMMENT.findall(normalized(text))], f"{where}: comments changed"
    return out


def test_repository_has_designs_to_format() -> None:
    assert len(ALL_RCS) > 50


@pytest.mark.parametrize("path", ALL_RCS, ids=[str(p.relative_to(ROOT)) for p in ALL_RCS])
def test_every_repository_file_round_trips(path: Path) -> None:
    _assert_round_trip(path.read_text(encoding="utf-8"), str(path))


def _perturb(text: str, r: random.Random) -> str:
    out = []
    for line in text.split("\n"):
        if r.random() < 0.2:
            line = r.choice(["\t", "  ", " "]) + line
        if r.random() < 0.2:
            line += r.choice([" ", "\t", "   "])
        out.append(line)
        if r.random() < 0.1:
            out.append(r.choice(["", "   ", ""]))
    return "\n".join(out)


def test_generated_designs_round_trip() -> None:
    from test_fuzz import DesignGen

    parsed = 0
    for seed in range(300):
        text = _perturb(DesignGen(seed).design(), random.Random(seed))
        if _tree(text) is not None:
            parsed += 1
            _assert_round_trip(text, f"seed {seed}")
    assert parsed > 150


def test_state_table_is_aligned_in_columns_and_comments_stay() -> None:
    text = (
        "design d\n\n\n\n"
        "controller TOP level 1 budget 1 ms {  \n"
        "\tverb RUN\n"
        "  plan RUN {\n"
        "   //  event | state -> next | jobs\n"
        "E0: x > 1.0 | new -> S1 | x = 1.0, y = 2.0; // first\n"
        "   E1:   x <= 1.0   |   S1 -> done;\n"
        "     E2: otherwise | S1 -> error(3) | x = 0.0,\n"
        "           y = 0.0;\n"
        "  }\n"
        "}\n"
    )
    assert format_text(text) == (
        "design d\n\n"
        "controller TOP level 1 budget 1 ms {\n"
        "    verb RUN\n"
        "    plan RUN {\n"
        "        //  event | state -> next | jobs\n"
        "        E0: x > 1.0   | new -> S1       | x = 1.0, y = 2.0; // first\n"
        "        E1: x <= 1.0  | S1  -> done;\n"
        "        E2: otherwise | S1  -> error(3) | x = 0.0,\n"
        "                                          y = 0.0;\n"
        "    }\n"
        "}\n"
    )


def test_a_plan_closed_on_its_last_rule_line_keeps_the_depth() -> None:
    """`R1: ... | S -> done; }` closes the plan on a rule's line: what follows
    was indented one level too deep (the controller's `}` and the next CPU)."""
    text = ("design f\ncontroller TOP level 1 budget 1 ms {\n  verb RUN\n  plan RUN {\n  R0: true | new -> S;\n"
            "  R1: true | S -> done; }\n  verb GO\n  plan GO { G0: true | new -> done; }\n}\ncpu C { heartbeat 10 ms schedule TOP }\n")
    got = format_text(text)
    assert got.splitlines()[-5:] == ["        R1: true | S -> done; }", "    verb GO", "    plan GO { G0: true | new -> done; }", "}",
                                     "cpu C { heartbeat 10 ms schedule TOP }"], got
    assert format_text(got) == got
    assert shape(text_to_ast(SourceFile("a.rcs", got), Diagnostics())) == shape(text_to_ast(SourceFile("b.rcs", text), Diagnostics()))


def test_examples_and_stdlib_are_formatted(capsys) -> None:
    assert cli.main(["fmt", "--check", str(ROOT / "examples"), str(ROOT / "stdlib")]) == 0
    assert "0 files would be reformatted" in capsys.readouterr().err


def test_fmt_writes_atomically_keeps_mode_and_check_diff_change_nothing(tmp_path: Path, capsys) -> None:
    f = tmp_path / "d.rcs"
    f.write_text("design d\nconst X: i32 = 1   \n\n\n\nconst Y: i32 = 2\n")
    f.chmod(0o640)
    assert cli.main(["fmt", "--check", str(f)]) == 1
    assert cli.main(["fmt", "--diff", str(f)]) == 0
    out = capsys.readouterr().out
    assert "\n-const X: i32 = 1   \n" in out and "\n+const X: i32 = 1\n" in out
    assert f.read_text().endswith("\n\n\n\nconst Y: i32 = 2\n")  # untouched so far
    assert cli.main(["fmt", str(f)]) == 0
    assert f.read_text() == "design d\nconst X: i32 = 1\n\nconst Y: i32 = 2\n"
    assert stat.S_IMODE(f.stat().st_mode) == 0o640
    assert not [p for p in os.listdir(tmp_path) if p != "d.rcs"]  # no temporary left behind
    assert cli.main(["fmt", "--check", str(f)]) == 0


def test_fmt_leaves_a_file_with_syntax_errors_alone(tmp_path: Path, capsys) -> None:
    f = tmp_path / "bad.rcs"
    f.write_text("design d\nconst X: i32 =   \n")
    assert cli.main(["fmt", str(f)]) == 1
    assert "error[E0001]" in capsys.readouterr().err
    assert f.read_text() == "design d\nconst X: i32 =   \n"


def test_fmt_refuses_to_replace_a_symbolic_link(tmp_path: Path, capsys) -> None:
    target = tmp_path / "real.rcs"
    target.write_text("design d\nconst X: i32 = 1   \n")
    link = tmp_path / "link.rcs"
    link.symlink_to(target)
    assert cli.main(["fmt", str(link)]) == 2
    assert link.is_symlink() and target.read_text().endswith("1   \n")
    capsys.readouterr()


def test_fmt_stdin_to_stdout(monkeypatch, capsys) -> None:
    import io

    monkeypatch.setattr("sys.stdin", io.StringIO("design d\n\n\n\nconst X: i32 = 1\t\n"))
    assert cli.main(["fmt", "-"]) == 0
    assert capsys.readouterr().out == "design d\n\nconst X: i32 = 1\n"


class _Stdin:
    """Standard input as bytes, as a terminal or a pipe gives it."""

    def __init__(self, data: bytes) -> None:
        import io

        self.buffer = io.BytesIO(data)


def test_fmt_stdin_check_and_diff_say_whether_it_would_change(monkeypatch, capsys) -> None:
    """A CI step that pipes a file through `rcsc fmt --check -` must fail on
    unformatted text (it used to print the formatted text and pass)."""
    messy, tidy = b"design d\n\n\n\nconst X: i32 = 1\t\n", b"design d\n\nconst X: i32 = 1\n"
    monkeypatch.setattr("sys.stdin", _Stdin(messy))
    assert cli.main(["fmt", "--check", "-"]) == 1
    out, err = capsys.readouterr()
    assert out == "" and err == "would reformat <stdin>\n"
    monkeypatch.setattr("sys.stdin", _Stdin(messy))
    assert cli.main(["fmt", "--diff", "-"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("--- <stdin>\n+++ <stdin>\n") and "\n+const X: i32 = 1\n" in out
    monkeypatch.setattr("sys.stdin", _Stdin(tidy))
    assert cli.main(["fmt", "--check", "--diff", "-"]) == 0
    assert capsys.readouterr() == ("", "")
    monkeypatch.setattr("sys.stdin", _Stdin(b"design d\xff\n"))
    assert cli.main(["fmt", "-"]) == 2
    assert capsys.readouterr().err == "error: <stdin>: cannot read: not UTF-8 text (byte 8)\n"


def test_fmt_refuses_read_only_files_and_hard_links_and_counts_only_what_it_wrote(tmp_path: Path, capsys) -> None:
    messy = "design d\nconst X: i32 = 1   \n"
    ro, linked, ok = tmp_path / "ro.rcs", tmp_path / "linked.rcs", tmp_path / "ok.rcs"
    for f in (ro, linked, ok):
        f.write_text(messy)
    ro.chmod(0o444)
    os.link(linked, tmp_path / "other_name.rcs")
    assert cli.main(["fmt", str(ro), str(linked), str(ok)]) == 2
    err = capsys.readouterr().err
    assert f"cannot write `{ro}`: it is read-only (mode 444); not reformatted" in err
    assert f"cannot write `{linked}`: it has 2 hard links, which replacing it would separate; not reformatted" in err
    assert err.endswith("1 file reformatted, 0 unchanged\n")
    assert ro.read_text() == messy and linked.read_text() == messy and (tmp_path / "other_name.rcs").read_text() == messy
    assert ok.read_text() == "design d\nconst X: i32 = 1\n"
    assert cli.main(["fmt", "--check", str(ro)]) == 1  # reading is fine
    capsys.readouterr()


def test_a_name_plan_at_the_start_of_a_line_is_not_a_plan(monkeypatch, capsys) -> None:
    """`plan` is a keyword only where a plan is declared: a constant named
    `plan` continuing an expression made the next block (a record) a state
    table, and the indentation after it went wrong."""
    text = ("design p\nconst plan: i32 = 1\nconst B: i32 = 2 +\n    plan\nrecord XY {\n    x: f64,\n    y: f64,\n}\n"
            "gm pos: XY = XY(x = 0.0, y = 0.0)\nsimulator P level 0 budget 1 us {\n    writes pos\n    post {\n"
            "        pos = XY(x = pos.x + 1.0, y = pos.y);\n    }\n}\ncpu M {\n    heartbeat 10 ms\n    schedule P\n}\n")
    monkeypatch.setattr("sys.stdin", _Stdin(text.encode()))
    assert cli.main(["fmt", "-"]) == 0
    assert capsys.readouterr().out == text


def test_a_local_named_plan_continuing_an_expression_is_not_a_plan(monkeypatch, capsys) -> None:
    """`plan or ready;` inside `post` is an expression: it made the next
    record a state table, and formatting stopped with an internal error."""
    text = 'design g\nimport std.lifecycle\ngm ready: bool = false from env\ngm out: bool = false to env\ncontroller C level 1 budget 100 us {\n    verbs Lifecycle\n    reads ready\n    writes out\n    local plan: bool = false\n    plan INIT {\n        E0: ready | new -> done;\n        E1: otherwise | new -> done;\n    }\n    plan HALT { E0: true | new -> done; }\n    plan ABORT { E0: true | new -> done; }\n    post {\n        out = ready and\n            plan or ready;\n    }\n}\nrecord Spec {\n    count: i32,\n    gain_long_name: f64,\n}\ncpu MAIN {\n    heartbeat 10 ms\n    schedule C\n}\n'
    monkeypatch.setattr("sys.stdin", _Stdin(text.encode()))
    assert cli.main(["fmt", "-"]) == 0
    out = capsys.readouterr().out
    assert out == text.replace("E0: ready | new", "E0: ready     | new")
