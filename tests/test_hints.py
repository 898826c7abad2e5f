""""Did you mean" helps for misspelt names and foreign operators (rcsc.checks.hints)."""

from __future__ import annotations

from pathlib import Path

import pytest

from rcsc.driver import check_path

TYPOS = """\
design d
const LIMIT: i32 = 3
enum Mode { AUTO, MANUAL }
record XY { east: f64, north: f64 }
gm level_m: f64 = 0.0 from env
gm pos: XY = XY(east = 0.0, north = 0.0) from env
controller TOP level 2 budget 1 ms {
    subordinates LOW
    reads level_m, pos
    local count: i32 = 0
    verb FILL_TO(mode: Mode)
    plan FILL_T0 {
        E0: true | new -> done;
    }
    verb RUN
    plan RUN {
        E0: levl_m > pos.est and count < LIMT and Mode.AUT == Mode.AUTO | new -> AT_LOAD | LOW.GOO();
        E9: LOW.error | * -> error(1);
        E1: LOW.dne | AT_LOAD -> AT_UNLOAD;
        E2: true | AT_UNLOD -> done;
        E3: LOW.done | AT_UNLOAD -> done;
    }
}
controller LOW level 1 budget 1 ms {
    verb GO
    plan GO { E0: true | new -> done; }
}
cpu main {
    heartbeat 10 ms
    schedule TOP, LOW
}
"""


def _helps(tmp_path: Path, text: str) -> dict[tuple[str, str], list[str]]:
    path = tmp_path / "d.rcs"
    path.write_text(text, encoding="utf-8")
    return {(d.code, d.span.text): d.helps for d in check_path(str(path)).diags}


def test_misspelt_names_get_the_closest_declared_name(tmp_path: Path) -> None:
    helps = _helps(tmp_path, TYPOS)
    expected = {
        ("E0501", "FILL_T0"): "FILL_TO",
        ("E0100", "levl_m"): "level_m",
        ("E0100", "LIMT"): "LIMIT",
        ("E0103", "AUT"): "AUTO",
        ("E0103", "est"): "east",
        ("E0105", "GOO"): "GO",
        ("E0103", "dne"): "done",
    }
    for key, name in expected.items():
        assert key in helps, (key, sorted(helps))
        assert helps[key][0] == f"did you mean `{name}`?", (key, helps[key])


def test_a_misspelt_state_is_not_a_new_state(tmp_path: Path) -> None:
    text = TYPOS.replace("levl_m > pos.est and count < LIMT and Mode.AUT", "level_m > pos.east and count < LIMIT and Mode.AUTO")
    text = text.replace("FILL_T0", "FILL_TO").replace("GOO", "GO").replace("dne", "done")
    helps = _helps(tmp_path, text)
    assert helps[("E0502", "AT_UNLOD")][0].startswith("did you mean `AT_UNLOAD`?")


def test_unrelated_names_get_no_guess(tmp_path: Path) -> None:
    helps = _helps(tmp_path, TYPOS.replace("levl_m", "pressure"))
    assert not any(h.startswith("did you mean") for h in helps[("E0100", "pressure")])


@pytest.mark.parametrize(
    "written,word",
    [("count < LIMIT && count > 0", "and"), ("count < LIMIT || count > 0", "or"), ("!(count < LIMIT)", "not")],
)
def test_foreign_operators(tmp_path: Path, written: str, word: str) -> None:
    text = TYPOS.replace("levl_m > pos.est and count < LIMT and Mode.AUT == Mode.AUTO", written)
    helps = _helps(tmp_path, text)
    assert len(helps) == 1, helps
    (code, _), hs = next(iter(helps.items()))
    assert code in ("E0001", "E0002") and hs[0].startswith(f"rcs writes `{word}`"), hs


def test_else_if_is_elif(tmp_path: Path) -> None:
    text = TYPOS.replace("    verb RUN\n", "    verb RUN\n    pre { if count > 0 { count = 1; } else if count < 0 { count = 2; } }\n")
    helps = _helps(tmp_path, text)
    assert [h[0] for h in helps.values()] == ["rcs writes `elif` for `else if`"], helps


def test_elif_in_an_if_expression_is_else_if(tmp_path: Path) -> None:
    """`elif` inside an `if ... then ... else` expression: the help names the
    expression's `else if` instead of the rule's `;`, which is not missing."""
    text = TYPOS.replace("    verb RUN\n", "    verb RUN\n    pre { count = if count > 0 then 1 elif count < 0 then 2 else 0; }\n")
    helps = _helps(tmp_path, text)
    assert list(helps.values()) == [[
        "an `if` expression chains with `else if` (`if a then x else if b then y else z`); `elif` is for `if` statements"]], helps


def test_elif_of_an_if_statement_gets_no_expression_hint(tmp_path: Path) -> None:
    text = TYPOS.replace("    verb RUN\n", "    verb RUN\n    pre { if count > 0 { count = 1; } elif count < 0 { count = 2 } }\n")
    helps = _helps(tmp_path, text)
    assert not any("`if` expression" in h for hs in helps.values() for h in hs), helps


def test_a_declared_name_missing_from_reads_gets_no_other_name(tmp_path: Path) -> None:
    """`age(v1_fb)` where `v1_fb` exists but is not in `reads`: the help says to
    add it to `reads`, and does not guess the similar `v2_fb` (not read either)."""
    text = TYPOS.replace("gm level_m: f64 = 0.0 from env\n", "gm level_m: f64 = 0.0 from env\ngm v1_fb: i32 = 0 from env\ngm v2_fb: i32 = 0 from env\n")
    text = text.replace("E0: true | new -> done;\n    }\n    verb RUN", "E0: v1_fb > 0 | new -> done;\n        E1: otherwise | new -> done;\n    }\n    verb RUN")
    helps = _helps(tmp_path, text)
    assert not any(h.startswith("did you mean") for h in helps[("E0100", "v1_fb")]), helps[("E0100", "v1_fb")]
    assert "add `reads v1_fb` to controller `TOP`" in helps[("E0100", "v1_fb")]


def test_mismatched_operands_get_helps_that_name_them(tmp_path: Path) -> None:
    """An `f64` compared with an `i32` constant: the help converts the operands
    as written (it said "e.g. `f64(x)`", with `x` the f64 side here); a duration
    compared with a bare number is told to write its unit."""
    text = TYPOS.replace("E0: true | new -> done;\n    }\n    verb RUN",
                         "E0: level_m > LIMIT | new -> done;\n        E1: in_state >= 5 | new -> done;\n    }\n    verb RUN")
    helps = _helps(tmp_path, text)
    assert helps[("E0200", ">")] == ["convert one side explicitly: `level_m > f64(LIMIT)` or `i32(level_m) > LIMIT`"]
    assert helps[("E0200", ">=")] == ["a duration is written with its unit (`5 ms`, `2 s`); `seconds(d)` gives a duration as f64 seconds"]


@pytest.mark.parametrize("target", ["grid[0].east", "grid[0][1]"])
def test_an_index_before_a_field_in_an_assignment_is_explained(tmp_path: Path, target: str) -> None:
    """`a[i].x = v` and `a[i][j] = v` are not assignable (docs/language.md 4.1):
    the syntax error says the index comes last instead of only "expected `=`"."""
    text = TYPOS.replace("    verb RUN\n", f"    verb RUN\n    post {{ {target} = 1.0; }}\n")
    helps = _helps(tmp_path, text)
    assert [hs[0] for (code, _), hs in helps.items() if code == "E0001"] == [
        "in an assignment the index comes last (`a[i] = v`, `r.xs[i] = v`): assign the whole element (`a[i] = P(...)`)"], helps


def test_error_code_of_a_subordinate_is_not_a_constant(tmp_path: Path) -> None:
    """`error(LOW.error_code)`: `LOW` exists (it was "cannot find `LOW`"); the
    finding says an error code is a constant and how to pass a code up."""
    text = TYPOS.replace("E9: LOW.error | * -> error(1);", "E9: LOW.error | * -> error(LOW.error_code);")
    path = tmp_path / "d.rcs"
    path.write_text(text, encoding="utf-8")
    found = [d for d in check_path(str(path)).diags if d.span is not None and d.span.text == "LOW" and d.span.line == 18]
    assert [d.code for d in found] == ["E0204"], [(d.code, d.message) for d in found]
    assert found[0].message == "`LOW` is a controller, whose status is known only when the design runs: a constant expression cannot read it"
    assert any("copy it (`SUB.error_code`) into a status field" in h for h in found[0].helps)
