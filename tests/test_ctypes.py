"""Controller types with parameters and function blocks (std.blocks).

The conformance of the generated code is in the shared list
(tests/c_build.CONFORMANCE: tests/blocks/blocks.rcs, whose C and Rust traces
must equal `rcsc sim`'s byte for byte, and examples/machining_cell, whose axes
are two instances of one type).  Here: the instances are separate, a finding
inside a type names the type and the instance, and each block of std.blocks
does what docs/stdlib.md says, cycle by cycle, in the simulator.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from c_build import ROOT, reference_trace
from rcsc.driver import check_path
from rcsc.render import render_human

BLOCKS = ROOT / "tests/blocks/blocks.rcs"
BLOCKS_SCN = ROOT / "tests/blocks/blocks.scn"

TYPE_WITH_AN_ERROR = """design d
gm a: f64 = 0.0 to env
gm b: f64 = 0.0 to env
controller type Axis(gain: f64, out: gm) level 1 budget 1 ms {
    writes out
    post { out = gain * missing; }
}
controller TOP level 2 budget 1 ms { subordinates X, Y }
controller X: Axis(gain = 2.0, out = a)
controller Y: Axis(gain = 3.0, out = b)
cpu main { heartbeat 10 ms  schedule TOP, X, Y }
"""


@pytest.fixture(scope="module")
def trace() -> list[dict]:
    return [json.loads(line) for line in reference_trace(BLOCKS, BLOCKS_SCN).decode().splitlines()]


def _fields(trace: list[dict], ctrl: str, name: str) -> list:
    return [c["ctrl"][ctrl]["fields"][name] for c in trace]


def test_a_finding_inside_a_type_points_at_the_type_and_each_instance(tmp_path: Path) -> None:
    design = tmp_path / "d.rcs"
    design.write_text(TYPE_WITH_AN_ERROR, encoding="utf-8")
    result = check_path(str(design))
    found = [d for d in result.diags.items if d.code == "E0100"]
    assert len(found) == 2, [(d.code, d.message) for d in result.diags.items]
    for d, inst in zip(found, ("X", "Y")):
        assert d.span is not None and (d.span.line, d.span.col, d.span.text) == (6, 25, "missing")
        assert d.span.file.path == str(design)  # the real file, not the instance's view of it
        assert [(lb.span.line, lb.span.text, lb.message) for lb in d.labels] == [
            (9 if inst == "X" else 10, inst, f"in instance `{inst}` of `Axis` declared here")
        ]
    text = render_human(result.diags, color=False)
    assert "in instance `X` of `Axis` declared here" in text and "in instance `Y` of `Axis` declared here" in text


def test_a_finding_inside_a_block_names_the_block_instance_and_its_controller_instance(tmp_path: Path) -> None:
    design = tmp_path / "d.rcs"
    design.write_text(TYPE_WITH_AN_ERROR.replace("out = gain * missing;", "f(); out = f.y;").replace(
        "    writes out\n", "    writes out\n    block f: B()\n") + "block B() {\n    output y: f64 = 0.0\n    step { y = y + nothing; }\n}\n",
        encoding="utf-8")
    result = check_path(str(design))
    found = sorted((d for d in result.diags.items if d.code == "E0100"), key=lambda d: d.labels[-1].message)
    assert [d.span.text for d in found] == ["nothing", "nothing"]
    assert [[lb.message for lb in d.labels] for d in found] == [
        ["in block `f` of `X` declared here", "in instance `X` of `Axis` declared here"],
        ["in block `f` of `Y` declared here", "in instance `Y` of `Axis` declared here"],
    ]


def test_instances_have_their_own_parameters_buffers_and_state(trace) -> None:
    result = check_path(str(BLOCKS))
    assert result.ok, [(d.code, d.message) for d in result.diags.items]
    a, b = result.model.controllers["A"], result.model.controllers["B"]
    assert [w.name for w in a.writes] == ["ya"] and [w.name for w in b.writes] == ["yb"]
    # u = 0.8 from cycle 1: the first call primes each filter with u * gain.
    assert _fields(trace, "A", "lp__y")[0] == 0.8 and _fields(trace, "B", "lp__y")[0] == -2.0
    assert [c["gm"]["ya"] for c in trace][:3] == [0.8, 0.8, 0.8]
    assert [c["gm"]["yb"] for c in trace][:3] == [-2.0, -2.0, -2.0]
    # TOP commands KICK at cycle 4: a call from a job list moves A's filter only.
    assert _fields(trace, "A", "lp__y")[3] != 0.8 and _fields(trace, "B", "lp__y")[3] != -2.0
    assert _fields(trace, "A", "lp__y")[3] != _fields(trace, "B", "lp__y")[3]


def test_machining_cell_axes_are_one_type() -> None:
    cell = ROOT / "examples/machining_cell/machining_cell.rcs"
    text = cell.read_text(encoding="utf-8")
    assert "controller type Axis(" in text and "controller XAX: Axis(" in text and "controller YAX: Axis(" in text
    result = check_path(str(cell))
    assert result.ok and not result.diags.items, [(d.code, d.message) for d in result.diags.items]
    x, y = result.model.controllers["XAX"], result.model.controllers["YAX"]
    assert x.verbs["MOVE_TO"].params[0].range.hi == 600.0 and y.verbs["MOVE_TO"].params[0].range.hi == 400.0
    assert [w.name for w in x.writes] == ["x_pos_cmd"] and [w.name for w in y.writes] == ["y_pos_cmd"]


# ---- std.blocks, cycle by cycle (scenario tests/blocks/blocks.scn; 10 ms cycles) ----
# sw: true at 1, false at 2, true at 3..9, false at 10, true at 11, false at 12..17,
# true at 18..19, false from 20.  u: 0.8 at 1..7, -3.0 at 8..15, 0.25 from 16.

MS = 1_000_000


def test_ton_on_delay(trace) -> None:
    q, et = _fields(trace, "TOP", "ton__q"), _fields(trace, "TOP", "ton__et")
    assert [i + 1 for i, v in enumerate(q) if v] == [6, 7, 8, 9]  # 30 ms after the rise at 3
    assert et[2:6] == [0, 10 * MS, 20 * MS, 30 * MS] and et[8] == 30 * MS and et[9] == 0


def test_tof_off_delay(trace) -> None:
    q, et = _fields(trace, "TOP", "tof__q"), _fields(trace, "TOP", "tof__et")
    assert [i + 1 for i, v in enumerate(q) if not v] == [14, 15, 16, 17, 22, 23, 24]
    assert et[11:14] == [0, 10 * MS, 20 * MS] and et[16] == 20 * MS


def test_tp_pulse(trace) -> None:
    q, et = _fields(trace, "TOP", "tp__q"), _fields(trace, "TOP", "tp__et")
    # Rises at 1, 11 and 18 each start a 40 ms pulse; the rise at 3 falls inside the first.
    assert [i + 1 for i, v in enumerate(q) if v] == [1, 2, 3, 4, 11, 12, 13, 14, 18, 19, 20, 21]
    assert et[:5] == [0, 10 * MS, 20 * MS, 30 * MS, 40 * MS] and et[8] == 40 * MS and et[9] == 0


def test_debounce_and_edges(trace) -> None:
    q = _fields(trace, "TOP", "db__q")
    assert [i + 1 for i, v in enumerate(q) if v] == list(range(5, 14))  # 3 calls in a row
    assert [i + 1 for i, v in enumerate(_fields(trace, "TOP", "up__q")) if v] == [5]
    assert [i + 1 for i, v in enumerate(_fields(trace, "TOP", "down__q")) if v] == [14]
    assert _fields(trace, "TOP", "rises")[-1] == 1


def test_pid_clamps_and_does_not_wind_up(trace) -> None:
    y, integ = _fields(trace, "TOP", "pid__y"), _fields(trace, "TOP", "pid__integ")
    assert all(-1.0 <= v <= 1.0 for v in y)
    assert integ[:16] == [0] * 16  # saturated by the proportional term: no integration
    assert y[4] == pytest.approx(-0.8)  # the job-list call with err = 0: kd * (0 - 0.8) / 0.01
    assert integ[16:19] == pytest.approx([0.0125, 0.025, 0.0375])  # u = 0.25: ki * dt * err per cycle
    assert y[16] == pytest.approx(2.0 * 0.25 + 0.0125)


def test_lowpass_and_rate_limit(trace) -> None:
    lp, rl = _fields(trace, "TOP", "lp__y"), _fields(trace, "TOP", "rl__y")
    assert lp[:7] == [0.8] * 7  # primed by the first call
    assert lp[7] == pytest.approx(0.8 + (-3.0 - 0.8) * (0.01 / 0.06))
    assert rl[:4] == pytest.approx([0.2, 0.4, 0.6, 0.8])  # rise 20/s
    assert rl[7:10] == pytest.approx([0.3, -0.2, -0.7])  # fall 50/s
    assert rl[14:16] == pytest.approx([-3.0, -2.8])


def test_every_standard_block_is_in_the_conformance_design() -> None:
    import re

    library = (ROOT / "stdlib/std/blocks.rcs").read_text(encoding="utf-8")
    names = re.findall(r"^block (\w+)\(", library, re.M)
    assert len(names) == 9, names
    used = set(re.findall(r"^\s*block \w+: (\w+)\(", BLOCKS.read_text(encoding="utf-8"), re.M))
    assert set(names) <= used, set(names) - used
    from c_build import CONFORMANCE

    assert (BLOCKS, BLOCKS_SCN) in CONFORMANCE


def test_many_mistakes_at_once_are_findings_not_a_crash() -> None:
    result = check_path(str(ROOT / "tests/blocks/misuse.rcs"))
    codes = sorted({d.code for d in result.diags.items})
    assert codes == ["E0101", "E0206", "E0260", "E0262", "E0265", "E0266"], [(d.code, d.message) for d in result.diags.items]
    assert all(d.span is not None and d.span.file.path.endswith("misuse.rcs") for d in result.diags.items)


def test_editor_index_knows_types_and_instances() -> None:
    from rcsc.editor import symbols

    result = check_path(str(ROOT / "examples/machining_cell/machining_cell.rcs"))
    idx = symbols.build([f.tree for f in result.files if f.tree is not None])
    assert idx.controllers["XAX"].detail.startswith("controller XAX: Axis(lo = X_MIN")
    assert idx.globals["Axis"].detail == "controller type Axis level 1 budget 300 us"
    assert {"MOVE_TO", "INIT", "HALT", "following_mm"} <= set(idx.members["YAX"])  # completion of `YAX.`


def test_a_check_finding_inside_a_type_is_reported_per_instance(tmp_path: Path) -> None:
    """A finding of the plan checks (not of the type checker) in a type's plan."""
    design = tmp_path / "d.rcs"
    design.write_text("""design d
gm a: f64 = 0.0 to env
gm b: f64 = 0.0 to env
controller type Axis(lim: f64, out: gm) level 1 budget 1 ms {
    verb GO(v: f64)
    writes out
    plan GO {
        G0: true | new -> S1 | out = cmd.v;
        G1: out > lim | S1 -> done;
        G2: out > 0.0 | S1 -> error(1);
    }
}
controller TOP level 2 budget 1 ms { subordinates X, Y }
controller X: Axis(lim = 1.0, out = a)
controller Y: Axis(lim = 2.0, out = b)
cpu main { heartbeat 10 ms  schedule TOP, X, Y }
""", encoding="utf-8")
    result = check_path(str(design))
    overlaps = [d for d in result.diags.items if d.code == "W0517"]  # S1 can wait forever
    assert len(overlaps) == 2, [(d.code, d.message) for d in result.diags.items]
    assert sorted(lb.message for d in overlaps for lb in d.labels if lb.message.startswith("in instance")) == [
        "in instance `X` of `Axis` declared here", "in instance `Y` of `Axis` declared here"]
    assert all(d.span.line == 9 for d in overlaps)
    # Each instance's own witness: its own Global Memory.
    assert sorted(n for d in overlaps for n in d.notes if n.startswith("witness")) == [
        "witness: a = 0.0 (fixed while the plan waits)", "witness: b = 0.0 (fixed while the plan waits)"]


INT_LITERAL_ARGS = """design lits
gm o1: f64 = 0.0 to env
gm o2: u32 = 0 to env
gm o3: f64 = 0.0 to env
gm o4: u32 = 0 to env
block B(g: f64) {
    input x: f64 = 0.0
    output y: f64 = 0.0
    step { y = f64(g / 4) + x; }
}
controller type T(k: u32, g: f64, a: gm, b: gm) level 1 budget 100 us {
    writes a, b
    verb GO
    block q: B(g = 2)
    pre { q(0.0); a = f64(g / 4) + q.y; b = -k; }
    plan GO { R0: true | new -> done; }
}
controller X1: T(k = 4294967295, g = 2, a = o1, b = o2)
controller X2: T(k = 1, g = 2.0, a = o3, b = o4)
controller TOP level 2 budget 100 us {
    subordinates X1, X2
    verb GO
    plan GO { R0: true | new -> S1 | X1.GO(), X2.GO(); R1: X1.done and X2.done | S1 -> done; }
}
cpu MAIN {
    heartbeat 10 ms
    schedule TOP, X1, X2
}
"""


def test_integer_literal_arguments_take_the_parameters_type(tmp_path: Path) -> None:
    """A parameter `k: u32` given `4294967295` or `g: f64` given `2` is a value of
    that type where it is used: `-k` wraps as a u32 (it was an out-of-range
    literal, E0207) and `f64(g / 4)` is 0.5 (it was the i32 division 2 / 4),
    in a controller type and in a block alike (found by the differential
    tester drawing controller types).  A block's arguments are checked
    against its parameters' types at the block instance."""
    design = tmp_path / "lits.rcs"
    design.write_text(INT_LITERAL_ARGS, encoding="utf-8")
    result = check_path(str(design))
    assert result.ok, [(d.code, d.message) for d in result.diags.items]
    scn = tmp_path / "lits.scn"
    scn.write_text('scenario "lits"\ncycles 2\n', encoding="utf-8")
    last = json.loads(reference_trace(design, scn).decode().splitlines()[-1])
    assert last["gm"] == {"o1": 1, "o2": 1, "o3": 1, "o4": 4294967295}
    assert last["ctrl"]["X1"]["fields"]["q__y"] == 0.5
    bad = tmp_path / "bad.rcs"
    bad.write_text(INT_LITERAL_ARGS.replace("block B(g: f64)", "block B(g: u32)").replace("f64(g / 4) + x", "f64(g) + x")
                   .replace("B(g = 2)", "B(g = -1)"), encoding="utf-8")
    found = [d for d in check_path(str(bad)).diags.errors]
    assert [d.code for d in found] == ["E0207", "E0207"] and all(d.span.text == "-1" for d in found)
