"""The witnesses of the value and wait findings say what the case files mean.

tests/cases asserts code, line and column; these tests assert the witness
values too, where the finding has one.
"""

from __future__ import annotations

from pathlib import Path

from rcsc.driver import check_path

CASES = Path(__file__).parent / "cases"


def _by_line(name: str, code: str) -> dict[int, dict]:
    result = check_path(str(CASES / name))
    return {d.span.line: d.data for d in result.diags if d.code == code}


def test_range_flow_witnesses() -> None:
    found = _by_line("W0524_range_flow.rcs", "W0524")
    assert found[20]["witness"] == {}  # a constant: no input needed
    assert found[21]["witness"]["depth"] > 11  # depth - 1 > 10
    assert found[22]["witness"]["depth"] not in range(-11, 0)  # n = depth + 11 outside 0..10
    assert found[23]["witness"]["cmd.k"] > 10 and found[23]["witness"]["depth"] == 1


def test_overflow_and_division_witnesses() -> None:
    found = _by_line("W0525_overflow_division.rcs", "W0525")
    w = found[21]["witness"]
    assert w["a"] > 0 and w["a"] + w["b"] > 2**31 - 1
    assert abs(found[22]["witness"]["a"] * 3) > 2**31 - 1
    assert found[23]["witness"]["b"] == 0 and found[23]["witness"]["a"] < -10


def test_nan_reaches_a_parameter_only_through_a_supervisor() -> None:
    found = _by_line("W0517_nan_from_supervisor.rcs", "W0517")
    assert list(found) == [25]
    assert found[25]["witness"] == {"cmd.x": "NaN"} and found[25]["replayed"] is True


def test_a_duration_parameter_is_not_a_wait_for_ever() -> None:
    result = check_path(str(CASES / "ok_duration_waits.rcs"))
    assert [d.code for d in result.diags] == []


def test_held_stall_witnesses() -> None:
    found = _by_line("W0540_held_stall.rcs", "W0540")
    assert sorted(found) == [24, 30, 35]
    assert found[24]["witness"] == {"ARM": "done"} and found[24]["path"] == ["L0", "L1"]
    assert found[24]["held"] == {"ARM": "done"} and found[24]["commanded_by"] == {"ARM": "L0"}
    assert found[30]["witness"] == {"ARM": "done"} and found[30]["state"] == "BACK"
    # Behind the `*` error rule: ARM still runs on entry, settles DONE, and a zero count stalls.
    assert found[35]["witness"] == {"ARM": "done", "cmd.n": 0} and found[35]["held"] == {"ARM": "run"}
    assert all(d["replayed"] is True for d in found.values())


def test_done_unreachable_witnesses() -> None:
    found = _by_line("W0541_done_unreachable.rcs", "W0541")
    assert found[21]["path"] == ["P0", "P1"] and found[21]["held"] == {"V": "done"} and found[21]["rules"] == ["P2"]
    assert found[29]["path"] == ["C0", "C1"] and found[29]["held"] == {"AX": "done"} and found[29]["rules"] == ["C3"]


def test_stale_wait_witnesses() -> None:
    found = _by_line("W0542_stale_wait.rcs", "W0542")
    assert found[22]["path"] == ["F1"] and found[22]["commanded_by"] == {"ARM": None}
    assert found[27]["path"] == ["P0"]
    assert found[34]["path"] == ["S0", "S1"] and found[34]["state"] == "S2"


def test_held_status_explanations_fixed_examples_are_clean(tmp_path: Path) -> None:
    """The fixed forms that `rcsc explain W0541` / `W0542` teach check clean in a whole design."""
    tank = """design d
gm level: f64 = 0.0 from env
controller TOP level 2 budget 1 ms {
    subordinates V, H
    reads level
    verb TANK
    plan TANK {
        P0: true                      | new  -> FILL | V.OPEN();
        P9: V.error or H.error        | *    -> error(1);
        P1: V.done                    | FILL -> HEAT | H.ON();
        P2: H.done and level >= 90.0  | HEAT -> done;
        P3: H.done and level < 90.0   | HEAT -> FILL | V.OPEN();
    }
}
controller V level 1 budget 1 ms {
    reports AT_LEVEL
    verb OPEN
    plan OPEN { O0: true | new -> S1 | report AT_LEVEL; O1: in_state >= 50 ms | S1 -> error(2); O2: otherwise | S1 -> done; }
}
controller H level 1 budget 1 ms {
    verb ON
    plan ON { N0: true | new -> S1; N1: in_state >= 50 ms | S1 -> error(2); N2: otherwise | S1 -> done; }
}
cpu main {
    heartbeat 10 ms
    schedule TOP, V, H
}
"""
    path = tmp_path / "tank.rcs"
    path.write_text(tank, encoding="utf-8")
    assert [d.code for d in check_path(str(path)).diags] == []
    # The wrong form of the same table: P2 waits for a status V no longer reports.
    wrong = tank.replace("H.done and level >= 90.0 ", "H.done and V.AT_LEVEL    ").replace("H.done and level < 90.0 ", "H.done and not V.AT_LEVEL")
    path.write_text(wrong, encoding="utf-8")
    assert [d.code for d in check_path(str(path)).diags] == ["W0541"]


def test_record_field_range_witnesses() -> None:
    found = _by_line("W0524_record_fields.rcs", "W0524")
    assert sorted(found) == [27, 28, 29]
    assert found[27]["witness"]["cmd.x"] not in range(0, 11) and found[27]["range"] == [0, 10]
    assert found[28]["witness"] == {}  # the constant 4000.0: no input needed
    assert not 0.0 <= found[29]["witness"]["cmd.r"] * 2.0 <= 3000.0


def test_division_by_a_variable_is_decided(tmp_path) -> None:
    """A sum of remainders by an i64 variable (from a random design, seed 3001
    of the differential tester): the solver once ran out of its budget on it
    (W0518, "canceled") when `/` and `%` went through bit-vectors; it now
    decides it, and the witness divides by zero."""
    src = tmp_path / "rem.rcs"
    src.write_text(
        "design d\n\n"
        "gm n: i64 = 0 from env\n"
        "gm total: i64 = 0 to env\n\n"
        "controller TOP level 1 budget 1 ms {\n"
        "    reads n\n"
        "    writes total\n"
        "    verb RUN\n"
        "    plan RUN {\n"
        "        R1: true | new -> done | total = (((100_000 % n) + 3037000500) % n) + 65537;\n"
        "    }\n"
        "}\n\n"
        "cpu main {\n    heartbeat 10 ms\n    schedule TOP\n}\n",
        encoding="utf-8",
    )
    result = check_path(str(src))
    codes = [d.code for d in result.diags]
    assert "W0518" not in codes, [d.message for d in result.diags]
    found = [d for d in result.diags if d.code == "W0525"]
    assert found and all(d.data["witness"]["n"] == 0 for d in found)


def test_a_real_beyond_the_f64_range_is_an_infinity_in_the_witness(tmp_path) -> None:
    """The solver reasons about f64 values as reals: a witness may need a real
    larger than the largest finite f64 (here `x / 2.0` above it).  It reads as
    +inf (what the real rounds to), where the checker once stopped with an
    internal error (seed 4060 of the differential tester)."""
    src = tmp_path / "big.rcs"
    src.write_text(
        "design d\n\n"
        "gm x: f64 = 0.0 from env\n\n"
        "gm n: i32 = 0 from env\n\n"
        "controller TOP level 1 budget 1 ms {\n"
        "    reads x, n\n"
        "    local k: i32 = 0\n"
        "    verb GO\n"
        "    plan GO {\n"
        "        R0: x / 2.0 > 1.7976931348623157e308 | new -> done | k = n + 1;\n"
        "        R1: otherwise | new -> done;\n"
        "    }\n"
        "}\n\n"
        "cpu main {\n    heartbeat 10 ms\n    schedule TOP\n}\n",
        encoding="utf-8",
    )
    result = check_path(str(src))
    (d,) = [d for d in result.diags if d.code == "W0525"]
    assert d.data["witness"] == {"n": 2147483647, "x": float("inf")}
    assert "x = inf" in "\n".join(d.notes)


CLAMPED_NAN = """design d
import std.math
gm raw: f64 = 0.0 from env
controller TOP level 2 budget 1 ms {
    verb GO
    subordinates AX
    reads raw
    plan GO {
        G0: true    | new -> S1 | AX.MOVE(x = clamp(raw, 0.0, 10.0));
        G1: AX.done | S1  -> done;
    }
}
controller AX level 1 budget 1 ms {
    verb MOVE(x: f64 in 0.0..10.0)
    plan MOVE { M0: true | new -> done; }
}
cpu C { heartbeat 10 ms
 schedule TOP, AX }
"""


def test_a_nan_that_clamp_passes_on_is_not_told_to_clamp(tmp_path: Path) -> None:
    """A value already clamped can leave its range only as a NaN: the finding
    says so and does not advise clamping it (which it already is)."""
    (tmp_path / "d.rcs").write_text(CLAMPED_NAN, encoding="utf-8")
    found = [d for d in check_path(str(tmp_path / "d.rcs")).diags if d.code == "W0524"]
    assert len(found) == 1 and found[0].data["witness"] == {"raw": "NaN"}
    assert any("NaN here" in n for n in found[0].notes), found[0].notes
    assert "clamp it" not in " ".join(found[0].helps) and "in_range" in " ".join(found[0].helps)


SHORT_CIRCUIT = """design d
record Spec { parts: u32 in 1..10 }
gm k: i32 = 0 from env
gm a: i32 = 0 from env
gm flag: bool = false from env
gm xs: [f64; 3] = [0.0; 3] from env
gm out: f64 = 0.0 to env
controller TOP level 1 budget 1 ms {
    verb RUN(spec: Spec)
    reads k, a, flag, xs
    writes out
    status made: u32 = 0
    plan RUN ordered {
        R0: k >= 0 and k < 3 and xs[k] > 1.0 | new -> done | out = if k >= 0 and k < 3 then xs[k] else 0.0;
        R1: flag and a + 1 >= i32(cmd.spec.parts) | new -> done;
        R2: made + 1 >= cmd.spec.parts | new -> done | made += 1;
        R3: otherwise | new -> done;
    }
}
cpu C { heartbeat 10 ms
 schedule TOP }
"""


def test_value_questions_follow_and_or_and_if(tmp_path: Path) -> None:
    """`and`, `or` and `if` evaluate a side only when it is needed (docs/language.md,
    "Order of evaluation"): an index bounded by the left side of an `and` is not
    W0251, the overflow witness makes the left side true, and it shows no input
    outside its declared range (a record field's included).  An unranged status
    field (`made`) holds what earlier cycles made of it: not judged (section 12)."""
    (tmp_path / "d.rcs").write_text(SHORT_CIRCUIT, encoding="utf-8")
    found = [d for d in check_path(str(tmp_path / "d.rcs")).diags]
    assert [d.code for d in found] == ["W0525"], [(d.code, d.message) for d in found]
    (d,) = found
    assert d.span.line == 15 and d.data["witness"]["flag"] is True and d.data["witness"]["a"] == 2**31 - 1
    assert 1 <= d.data["witness"]["cmd.spec.parts"] <= 10


CONTINUOUS_SUB = """design c
gm camera_ok: bool = true from env
controller TOP level 2 budget 1 ms {
    verb RUN
    subordinates VISION
    plan RUN {
        R0: true             | new     -> LOOKING | VISION.LOOK();
        R1: VISION.FOUND     | LOOKING -> done;
        R2: VISION.NOT_FOUND | LOOKING -> error(1);
    }
}
controller VISION level 1 budget 1 ms {
    verb LOOK
    reads camera_ok
    reports FOUND, NOT_FOUND
    plan LOOK continuous {
        L0: camera_ok     | new -> SEEN | report FOUND;
        L1: not camera_ok | new -> SEEN | report NOT_FOUND;
    }
}
cpu C { heartbeat 10 ms
 schedule TOP, VISION }
"""


def test_a_continuous_subordinate_holds_what_it_reports(tmp_path: Path) -> None:
    """A continuous plan need not end: VISION holds FOUND or NOT_FOUND, which
    LOOKING handles, so it is no stall (W0540 said VISION ends in DONE, which
    its plan never reaches).  Without R1, holding FOUND is a stall, and the
    finding says what a continuous plan holds."""
    (tmp_path / "c.rcs").write_text(CONTINUOUS_SUB, encoding="utf-8")
    assert [d.code for d in check_path(str(tmp_path / "c.rcs")).diags] == []
    (tmp_path / "c2.rcs").write_text(CONTINUOUS_SUB.replace("        R1: VISION.FOUND     | LOOKING -> done;\n", ""), encoding="utf-8")
    (d,) = check_path(str(tmp_path / "c2.rcs")).diags
    assert d.code == "W0540" and d.data["witness"] == {"VISION": "FOUND"} and d.data["replayed"] is True
    assert "`VISION` is executing `LOOK` sent by `R0`, a continuous plan; then it holds FOUND or NOT_FOUND" in d.notes
