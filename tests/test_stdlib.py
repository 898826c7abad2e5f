"""The standard library: every std.math function at ordinary values and at its edges,
evaluated by the compiler's own evaluator (constant folding), and the verb sets of std.lifecycle."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from rcsc.driver import check_path
from rcsc.front.loader import stdlib_modules

CASES = [
    ("clamp(5.0, 0.0, 1.0)", "f64", 1.0),
    ("clamp(-5.0, 0.0, 1.0)", "f64", 0.0),
    ("clamp(0.5, 0.0, 1.0)", "f64", 0.5),
    ("clamp_i32(-7, -5, 5)", "i32", -5),
    ("clamp_i64(9000000000, 0, 8000000000)", "i64", 8000000000),
    ("clamp_abs(-3.0, -2.0)", "f64", -2.0),
    ("in_range(1.0, 1.0, 2.0)", "bool", True),
    ("in_range(2.5, 1.0, 2.0)", "bool", False),
    ("in_range(0.0 / 0.0, 0.0, 1.0)", "bool", False),
    ("in_range_i32(3, 4, 2)", "bool", False),
    ("sign(-0.0)", "f64", 0.0),
    ("sign(-3.5)", "f64", -1.0),
    ("sign_i32(7)", "i32", 1),
    ("signed_square(-3.0)", "f64", -9.0),
    ("deadband(0.5, 1.0)", "f64", 0.0),
    ("deadband(1.5, 1.0)", "f64", 1.5),
    ("dead_zone(1.5, 1.0)", "f64", 0.5),
    ("dead_zone(-1.5, 1.0)", "f64", -0.5),
    ("dead_zone(0.5, 1.0)", "f64", 0.0),
    ("hysteresis(0.5, true, 0.2, 0.8)", "bool", True),
    ("hysteresis(0.5, false, 0.2, 0.8)", "bool", False),
    ("hysteresis(0.8, false, 0.2, 0.8)", "bool", True),
    ("hysteresis(0.2, true, 0.2, 0.8)", "bool", False),
    ("approx_eq(1.0, 1.05, 0.1)", "bool", True),
    ("approx_eq(1.0, 1.2, 0.1)", "bool", False),
    ("within_pct(104.0, 100.0, 5.0)", "bool", True),
    ("within_pct(0.0, 0.0, 5.0)", "bool", True),
    ("safe_div(1.0, 0.0, 7.0)", "f64", 7.0),
    ("safe_div(1.0, 4.0, 7.0)", "f64", 0.25),
    ("percent_of(5.0, 0.0)", "f64", 0.0),
    ("percent_of(5.0, 20.0)", "f64", 25.0),
    ("lerp(2.0, 4.0, 0.0)", "f64", 2.0),
    ("lerp(2.0, 4.0, 1.0)", "f64", 4.0),
    ("lerp(2.0, 4.0, 0.5)", "f64", 3.0),
    ("interpolate(2.0, 0.0, 4.0, 1.0, 20.0)", "f64", 36.0),
    ("interpolate(5.0, 1.0, 3.0, 1.0, 9.0)", "f64", 3.0),
    ("interpolate_clamped(2.0, 0.0, 4.0, 1.0, 20.0)", "f64", 20.0),
    ("interpolate_clamped(-1.0, 0.0, 4.0, 1.0, 20.0)", "f64", 4.0),
    ("interpolate_clamped(0.5, 1.0, 10.0, 0.0, 0.0)", "f64", 5.0),
    ("ramp_toward(0.0, 10.0, 0.6)", "f64", 0.6),
    ("ramp_toward(0.0, -10.0, -0.6)", "f64", -0.6),
    ("ramp_toward(9.9, 10.0, 0.6)", "f64", 10.0),
    ("lowpass(0.0, 10.0, 0.25)", "f64", 2.5),
    ("lowpass(0.0, 10.0, 2.0)", "f64", 10.0),
    ("lowpass_alpha(1.0, 3.0)", "f64", 0.25),
    ("lowpass_alpha(1.0, 0.0)", "f64", 1.0),
    ("lag_step(0.0, 10.0, 1.0, 4.0)", "f64", 2.5),
    ("lag_step(0.0, 10.0, 1.0, 0.5)", "f64", 10.0),
    ("angle_diff_deg(350.0, 10.0)", "f64", 20.0),
    ("angle_diff_deg(10.0, 350.0)", "f64", -20.0),
    ("angle_diff_deg(0.0, 180.0)", "f64", 180.0),
    ("wrap_deg_360(370.0)", "f64", 10.0),
    ("wrap_deg_360(-10.0)", "f64", 350.0),
]


@pytest.fixture(scope="module")
def folded(tmp_path_factory) -> dict:
    folder = tmp_path_factory.mktemp("std")
    # A module checked on its own: declarations only (a design would need a CPU, E0605).
    lines = ["module stdlib_values", "import std.math"]
    for i, (expr, t, _) in enumerate(CASES):
        lines.append(f"const C{i}: {t} = {expr}")
    (folder / "d.rcs").write_text("\n".join(lines) + "\n")
    result = check_path(str(folder / "d.rcs"), as_module=True)
    assert not result.diags.items, [(d.code, d.message) for d in result.diags]
    return {name: c.value for name, c in result.model.consts.items()}


@pytest.mark.parametrize("i", range(len(CASES)), ids=[c[0] for c in CASES])
def test_math_function(folded, i) -> None:
    expr, _, expected = CASES[i]
    got = folded[f"C{i}"]
    if isinstance(expected, float):
        assert math.isclose(got, expected, rel_tol=0, abs_tol=1e-12), (expr, got)
        assert math.copysign(1.0, got) == math.copysign(1.0, expected) or expected == 0.0
    else:
        assert got == expected, (expr, got)


def test_every_math_function_is_tested() -> None:
    text = (Path(__file__).parent.parent / "stdlib" / "std" / "math.rcs").read_text()
    declared = {line.split()[1].split("(")[0] for line in text.splitlines() if line.startswith("fn ")}
    tested = {c[0].split("(")[0] for c in CASES}
    assert declared - tested == set(), f"untested: {sorted(declared - tested)}"


def test_lifecycle_verb_sets(tmp_path: Path) -> None:
    (tmp_path / "d.rcs").write_text(
        "design life\nimport std.lifecycle\n"
        "controller A level 1 budget 1 ms {\n  verbs Lifecycle\n"
        "  plan INIT { I0: true | new -> done; }\n  plan HALT { H0: true | new -> done; }\n  plan ABORT { B0: true | new -> done; }\n}\n"
        "controller B level 2 budget 1 ms {\n  verbs Basic\n  subordinates A\n"
        "  plan INIT { I0: true | new -> S1 | A.INIT(); I1: A.done | S1 -> done; I2: A.error | S1 -> error(1); }\n"
        "  plan HALT { H0: true | new -> done; }\n}\n"
        "cpu MAIN { heartbeat 10 ms schedule B, A }\n"
    )
    result = check_path(str(tmp_path / "d.rcs"))
    assert not result.diags.items, [(d.code, d.message) for d in result.diags]
    assert list(result.model.controllers["A"].verbs) == ["INIT", "HALT", "ABORT"]
    assert list(result.model.controllers["B"].verbs) == ["INIT", "HALT"]


def test_a_lifecycle_verb_without_plan_is_reported_at_the_verbs_line(tmp_path: Path) -> None:
    (tmp_path / "d.rcs").write_text(
        "design life\nimport std.lifecycle\ncontroller A level 1 budget 1 ms {\n  verbs Lifecycle\n"
        "  plan INIT { I0: true | new -> done; }\n}\ncpu MAIN { heartbeat 10 ms schedule A }\n"
    )
    result = check_path(str(tmp_path / "d.rcs"))
    found = sorted((d.code, d.span.line, d.span.col, d.message) for d in result.diags)
    assert found == [
        ("E0500", 4, 9, "verb `ABORT` of `A` has no plan"),
        ("E0500", 4, 9, "verb `HALT` of `A` has no plan"),
    ]


def test_stdlib_modules_listed() -> None:
    assert stdlib_modules() == ["std.blocks", "std.lifecycle", "std.math"]
