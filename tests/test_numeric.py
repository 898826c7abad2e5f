"""The numeric rules (docs/language.md §5), each at its edge, in the simulator and the folder.

Integers wrap (two's complement), integer division truncates toward zero,
division or remainder by zero gives 0, i32 MIN / -1 wraps to MIN, f64 is
IEEE-754 (x / 0.0 is inf or NaN), float->int saturates and NaN gives 0.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from rcsc.semantics import numeric
from rcsc.driver import check_path
from rcsc.sim.simulate import Simulator
from rcsc.semantics.types import I32, I64, U32

I32_MIN, I32_MAX = -(2**31), 2**31 - 1


@pytest.fixture(scope="module")
def design():
    result = check_path(str(Path(__file__).parent / "sim" / "numeric.rcs"))
    assert not result.diags.items, [d.message for d in result.diags]
    return result.model


def run(design, **inputs):
    sim = Simulator(design)
    for name, value in inputs.items():
        sim.set_input(name, value)
    sim.begin_cycle()
    sim.run_cycle()
    return sim.statuses["N"].fields


def test_i32_overflow_wraps(design) -> None:
    f = run(design, a=I32_MAX, b=1, y=1.0)
    assert f["sum"] == I32_MIN
    f = run(design, a=I32_MIN, b=-1, y=1.0)
    assert f["sum"] == I32_MAX
    assert f["neg"] == I32_MIN  # -MIN wraps to MIN


def test_u32_underflow_wraps(design) -> None:
    assert run(design, u=0, b=1)["diff_u"] == 2**32 - 1


def test_i64_overflow_wraps(design) -> None:
    assert run(design, big=2**62, b=1)["prod64"] == -(2**63)


def test_division_by_zero_gives_zero(design) -> None:
    f = run(design, a=7, b=0)
    assert f["quot"] == 0 and f["rem"] == 0


def test_division_truncates_toward_zero(design) -> None:
    f = run(design, a=-7, b=2)
    assert f["quot"] == -3 and f["rem"] == -1
    f = run(design, a=7, b=-2)
    assert f["quot"] == -3 and f["rem"] == 1


def test_i32_min_divided_by_minus_one_wraps(design) -> None:
    f = run(design, a=I32_MIN, b=-1)
    assert f["quot"] == I32_MIN and f["rem"] == 0


def test_float_division_by_zero_is_ieee(design) -> None:
    assert run(design, x=1.0, y=0.0, b=1)["fquot"] == math.inf
    assert run(design, x=-1.0, y=0.0, b=1)["fquot"] == -math.inf
    assert math.isnan(run(design, x=0.0, y=0.0, b=1)["fquot"])


def test_nan_to_int_is_zero(design) -> None:
    f = run(design, x=math.nan, y=1.0, b=1)
    assert (f["to_i32"], f["to_u32"], f["to_i64"]) == (0, 0, 0)


def test_float_to_int_saturates(design) -> None:
    f = run(design, x=1e30, y=1.0, b=1)
    assert (f["to_i32"], f["to_u32"], f["to_i64"]) == (I32_MAX, 2**32 - 1, 2**63 - 1)
    f = run(design, x=-1e30, y=1.0, b=1)
    assert (f["to_i32"], f["to_u32"], f["to_i64"]) == (I32_MIN, 0, -(2**63))
    f = run(design, x=math.inf, y=1.0, b=1)
    assert f["to_i32"] == I32_MAX
    f = run(design, x=-2.9, y=1.0, b=1)
    assert (f["to_i32"], f["to_u32"]) == (-2, 0)  # toward zero; negative saturates to u32 0


def test_int_narrowing_wraps(design) -> None:
    assert run(design, big=2**32 + 5, b=1)["narrowed"] == 5
    assert run(design, big=2**31, b=1)["narrowed"] == I32_MIN


@pytest.mark.parametrize(
    "a,b,t,q,r",
    [
        (7, 0, I32, 0, 0),
        (I32_MIN, -1, I32, I32_MIN, 0),
        (-(2**63), -1, I64, -(2**63), 0),
        (-7, 2, I32, -3, -1),
        (2**32 - 1, 2, U32, 2**31 - 1, 1),
    ],
)
def test_numeric_module_edges(a, b, t, q, r) -> None:
    assert numeric.int_div(a, b, t) == q
    assert numeric.int_rem(a, b, t) == r


def test_constant_folding_uses_the_same_rules(tmp_path: Path) -> None:
    src = tmp_path / "fold.rcs"
    src.write_text(
        "design fold\n"
        "const WRAP: i32 = 2147483647 + 1\n"
        "const DIV0: i32 = 5 / 0\n"
        "const MINDIV: i32 = -2147483648 / -1\n"
        "const NAN_INT: i32 = i32(0.0 / 0.0)\n"
        "const SAT: u32 = u32(-5.0)\n"
    )
    result = check_path(str(src))
    consts = {k: v.value for k, v in result.model.consts.items()}
    assert consts == {"WRAP": I32_MIN, "DIV0": 0, "MINDIV": I32_MIN, "NAN_INT": 0, "SAT": 0}


def test_abs_of_a_duration_is_a_duration(tmp_path: Path) -> None:
    """abs() of a duration stays whole nanoseconds (it was once computed as a float)."""
    src = tmp_path / "d.rcs"
    src.write_text(
        "design d\nconst TICK: duration = 5 ms\nconst A: duration = abs(-TICK)\n"
        "gm t: duration = 0 ms from env\n"
        "controller C level 1 budget 1 ms {\n    reads t\n    status a: duration = 0 ms\n    pre { a = abs(t - TICK); }\n}\n"
        "cpu MAIN {\n    heartbeat 10 ms\n    schedule C\n}\n",
        encoding="utf-8",
    )
    result = check_path(str(src))
    assert result.ok, [d.message for d in result.diags]
    assert result.model.consts["A"].value == 5_000_000
    sim = Simulator(result.model)
    sim.set_input("t", 2_000_000)
    sim.begin_cycle()
    sim.run_cycle()
    assert sim.statuses["C"].fields["a"] == 3_000_000
    assert type(sim.statuses["C"].fields["a"]) is int


def _solver_value(t, a: int, b: int, op: str, constant_divisor: bool) -> int:
    """What the guard and value analyses' encoding (`rcsc.checks.smt.int_divide`) says `a op b` is."""
    import z3

    from rcsc.checks.smt import int_divide

    x = z3.Int("a")
    y = z3.IntVal(b) if constant_divisor else z3.Int("b")
    s = z3.Solver()
    s.add(x == a)
    if not constant_divisor:
        s.add(y == b)
    r = z3.Int("r")
    s.add(r == int_divide(x, y, op, t))
    assert s.check() == z3.sat
    return s.model()[r].as_long()


_EDGES = {
    I32: [I32_MIN, I32_MIN + 1, -7, -2, -1, 0, 1, 2, 7, I32_MAX - 1, I32_MAX],
    I64: [-(2**63), -(2**63) + 1, -100_000, -3, -1, 0, 1, 3, 3037000500, 2**63 - 1],
    U32: [0, 1, 2, 7, 2**31, 2**32 - 2, 2**32 - 1],
}


@pytest.mark.parametrize("t", [I32, I64, U32], ids=lambda t: t.name)
def test_the_solver_divides_as_the_numeric_rules(t) -> None:
    """The solver's encoding of `/` and `%` (by a constant and by a variable)
    agrees with rcsc.semantics.numeric on every pair of edge values: the
    analyses must prove facts about the program that runs."""
    for a in _EDGES[t]:
        for b in _EDGES[t]:
            for constant in (True, False):
                assert _solver_value(t, a, b, "/", constant) == numeric.int_div(a, b, t), (a, b, constant)
                assert _solver_value(t, a, b, "%", constant) == numeric.int_rem(a, b, t), (a, b, constant)
