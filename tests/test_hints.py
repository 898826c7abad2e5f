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


@pytest.mark.parametrize(
    "target,first_help",
    [
        ("std.lifecycl", "did you mean `std.lifecycle`?"),
        ("lifecycle", "did you mean `std.lifecycle`?"),
        ("helpers", 'to import a file of the design, quote its path: `import "helpers.rcs"`'),
    ],
)
def test_a_misspelt_module_gets_the_closest_one(tmp_path: Path, target: str, first_help: str) -> None:
    helps = _helps(tmp_path, TYPOS.replace("design d\n", f"design d\nimport {target}\n"))
    # The failed import is reported alone (the names of the module it meant
    # would all be unknown).
    assert list(helps) == [("E0005", target)], helps
    assert helps[("E0005", target)][0] == first_help, helps


def test_a_declared_name_out_of_reach_gets_no_guess(tmp_path: Path) -> None:
    # `level_m` is declared: it is missing from the `reads`, and another
    # name is no fix for that.
    helps = _helps(tmp_path, TYPOS.replace("reads level_m, pos", "reads pos").replace("levl_m", "level_m"))
    assert helps[("E0100", "level_m")] == ["add `reads level_m` to controller `TOP`"], helps


@pytest.mark.parametrize("written,meant", [("LWO", "LOW"), ("LOWW", "LOW"), ("LO", "LOW")])
def test_a_short_name_with_one_typo_gets_a_guess(tmp_path: Path, written: str, meant: str) -> None:
    helps = _helps(tmp_path, TYPOS.replace("schedule TOP, LOW", f"schedule TOP, {written}"))
    # The guess stands in for the name: LOW is not also "in no schedule".
    assert ("E0104", written) in helps, helps
    assert helps[("E0104", written)][0] == f"did you mean `{meant}`?", helps
    assert not any(code == "E0603" for code, _ in helps), helps


@pytest.mark.parametrize(
    "old,new,key,meant",
    [
        ("gm level_m: f64", "gm level_m: f46", ("E0102", "f46"), "f64"),
        ("verb FILL_TO(mode: Mode)", "verb FILL_TO(mode: Mdoe)", ("E0102", "Mdoe"), "Mode"),
        ("| new -> AT_LOAD | LOW.GOO();", "| new -> AT_LOAD | LOW.GO(spede = 1.0);", ("E0202", "spede"), "speed"),
        ("    verb RUN\n", "    verb RUN\n    reports READY\n", ("E0107", "REDY"), "READY"),
    ],
)
def test_misspelt_types_arguments_and_status_values(tmp_path: Path, old: str, new: str, key: tuple, meant: str) -> None:
    text = TYPOS.replace(old, new).replace("verb GO\n", "verb GO(speed: f64)\n")
    if key[0] == "E0107":
        text = text.replace("E1: LOW.dne | AT_LOAD -> AT_UNLOAD;", "E1: LOW.dne | AT_LOAD -> AT_UNLOAD | report REDY;")
    helps = _helps(tmp_path, text)
    assert key in helps, sorted(helps)
    assert helps[key][0] == f"did you mean `{meant}`?", helps[key]


SCENARIO_DESIGN = """\
design d
const LIMIT: i32 = 3
gm level_m: f64 = 0.0 from env
controller TOP level 2 budget 1 ms {
    subordinates LOW
    reads level_m
    status count: i32 = 0
    verb FILL(speed: f64)
    plan FILL {
        E0: level_m > 1.0 | new -> FILLING | LOW.GO();
        E3: otherwise     | new -> error(2);
        E1: LOW.done | FILLING -> done;
        E2: LOW.error | FILLING -> error(1);
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


@pytest.mark.parametrize(
    "line,key,meant",
    [
        ("at 1: TPO.FILL(speed = 1.0)", ("E0104", "TPO"), "TOP"),
        ("at 1: TOP.FIL(speed = 1.0)", ("E0105", "FIL"), "FILL"),
        ("at 1: TOP.FILL(sped = 1.0)", ("E0202", "sped"), "speed"),
        ("at 1: levl_m = 2.0", ("E0100", "levl_m"), "level_m"),
        ("expect final: TOP.cont == 0", ("E0103", "cont"), "count"),
        ("expect final: TOP.state == FILING", ("E0703", "FILING"), "FILLING"),
        ("expect final: TOP.count < LIMT", ("E0100", "LIMT"), "LIMIT"),
        ("expect final: TPO.state == FILLING", ("E0100", "TPO"), "TOP"),
    ],
)
def test_misspelt_names_in_a_scenario(tmp_path: Path, line: str, key: tuple, meant: str) -> None:
    from rcsc.diagnostics import Diagnostics
    from rcsc.front.scenario import text_to_scenario
    from rcsc.front.source import SourceFile

    path = tmp_path / "d.rcs"
    path.write_text(SCENARIO_DESIGN, encoding="utf-8")
    result = check_path(str(path))
    assert result.ok, [d.message for d in result.diags]
    diags = Diagnostics()
    text_to_scenario(SourceFile(str(tmp_path / "d.scn"), f"cycles 10\n{line}\n"), result.model, diags)
    helps = {(d.code, d.span.text): d.helps for d in diags}
    assert list(helps) == [key], helps
    assert helps[key][0] == f"did you mean `{meant}`?", helps


@pytest.mark.parametrize("name", ["done", "error"])
def test_a_next_state_in_a_condition(tmp_path: Path, name: str) -> None:
    text = SCENARIO_DESIGN.replace("E1: LOW.done | FILLING", f"E1: {name} | FILLING")
    helps = _helps(tmp_path, text)
    assert helps[("E0100", name)] == [f"test a subordinate's status with `SUB.{name}`"], helps


def test_not_a_subordinate_says_where_it_stands(tmp_path: Path) -> None:
    path = Path(__file__).parent / "cases" / "E0507_up_and_across_the_hierarchy.rcs"
    found = {(d.span.line, d.message): d.helps for d in check_path(str(path)).diags}
    # Adding `subordinates` is no fix for any of these: it would give LOW a
    # second supervisor, MID itself, TOP a cycle.
    assert found[(15, "`LOW` is not a subordinate of `TOP`")] == ["command `MID`, which commands `LOW`"]
    assert found[(17, "`LOW` is not a subordinate of `TOP`")] == ["read `MID`'s status, or share the data through Global Memory"]
    assert found[(26, "`MID` cannot command itself")] == ["to go on with other work, move to another state of the plan"]
    assert found[(27, "`TOP` is not a subordinate of `MID`")] == ["`TOP` reads `MID`'s status; share other data through Global Memory"]


@pytest.mark.parametrize(
    "old,new,meant",
    [
        ("    subordinates LOW\n", "    subordinate LOW\n", "subordinates"),
        ("    overhead", "    overheed", "overhead"),
        ("    plan RUN {", "    plna RUN {", "plan"),
        ("    plan RUN {", "    plan RUN orderd {", "ordered"),
        ("and count < LIMT", "adn count < LIMT", "and"),
    ],
)
def test_a_misspelt_keyword(tmp_path: Path, old: str, new: str, meant: str) -> None:
    text = TYPOS.replace("    heartbeat 10 ms\n", "    heartbeat 10 ms\n    overhead 1 ms\n")
    helps = _helps(tmp_path, text.replace(old, new, 1))
    assert [h[0] for h in helps.values()] == [f"did you mean `{meant}`?"], helps


def test_the_rule_help_only_in_a_plan(tmp_path: Path) -> None:
    # After `heartbeat 10 ms` a `;` may follow, but this is no rule.
    helps = _helps(tmp_path, TYPOS.replace("    heartbeat 10 ms\n", "    heartbeat 10 ms\n    xyzzy 3\n"))
    assert list(helps.values()) == [[]], helps
    helps = _helps(tmp_path, TYPOS.replace("E9: LOW.error | * -> error(1);", "E9: LOW.error | * -> error(1)"))
    assert list(helps.values()) == [["a rule ends with `;`: `LABEL: condition | state -> next | jobs;`"]], helps


def test_a_bare_enum_member(tmp_path: Path) -> None:
    helps = _helps(tmp_path, TYPOS.replace("Mode.AUT == Mode.AUTO", "Mode.AUTO == MANUAL"))
    assert helps[("E0100", "MANUAL")] == ["write `Mode.MANUAL`: a member is named with its enum"], helps


def test_a_command_outside_a_rule(tmp_path: Path) -> None:
    helps = _helps(tmp_path, TYPOS.replace("    verb RUN\n", "    post { LOW.GO(); }\n    verb RUN\n"))
    assert list(helps.values()) == [["a command is a job of a plan's rule (`E1: condition | S1 -> S2 | SUB.VERB();`), not a statement"]]


def test_no_rule_help_inside_a_condition(tmp_path: Path) -> None:
    # `(` inside a condition is no missing `;` at the end of a rule.
    helps = _helps(tmp_path, TYPOS.replace("E9: LOW.error |", "E9: LOW.error() |"))
    assert list(helps.values()) == [[]], helps


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


@pytest.mark.parametrize("where", ["period", "budget"])
def test_a_named_constant_for_a_duration_keyword_says_it_takes_a_literal(tmp_path: Path, where: str) -> None:
    """`period STALE` or `budget LIMIT`: a syntax error whose help says these
    take a duration literal (it said only: expected a number)."""
    header = "controller TOP level 2 budget 1 ms {"
    changed = "controller TOP level 2 budget 1 ms period STALE {" if where == "period" else "controller TOP level 2 budget LIMIT {"
    helps = _helps(tmp_path, TYPOS.replace(header, changed))
    token = "STALE" if where == "period" else "LIMIT"
    assert helps[("E0001", token)] == [f"`{where}` takes a duration literal such as `100 ms` or `2 us`, not a named constant"], helps
