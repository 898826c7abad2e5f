"""`rcsc sim --externs FILE.py` and `rcsc test --externs`: Python stand-ins for extern functions (rcsc.sim.externs)."""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path

import pytest

from rcsc import cli
from rcsc.semantics.types import BOOL, DURATION, F64, I32, U32, ArrayType, EnumType, RecordType
from rcsc.sim.externs import conform

HERE = Path(__file__).resolve().parent

DESIGN = """design kin

enum Gear { LOW, HIGH }
record XY { x: f64, y: f64 }

extern fn path_length(dx: f64, dy: f64) -> f64 budget 2 us
extern fn gear_of(rpm: f64) -> Gear budget 1 us
extern fn count() -> i32 budget 1 us
extern fn mid(a: XY, b: XY) -> XY budget 1 us

gm dx: f64 = 3.0 from env
gm len: f64 = 0.0 to env
gm g: Gear = Gear.LOW to env
gm n: i32 = 0 to env
gm m: XY = XY(x = 0.0, y = 0.0) to env

controller K level 1 budget 1 ms {
    reads dx
    writes len, g, n, m
    post {
        len = path_length(dx, 4.0);
        g = gear_of(len * 1000.0);
        n = count();
        m = mid(XY(x = dx, y = 0.0), XY(x = 1.0, y = 2.0));
    }
}

cpu MAIN {
    heartbeat 10 ms
    schedule K
}
"""

SCENARIO = 'scenario "k"\ncycles 3\nat 2: dx = 6.0\nexpect at 3: len > 7.0\n'

FACTORY = """import math

def externs():
    state = {"n": 0}

    def path_length(dx, dy):
        return math.hypot(dx, dy)

    def gear_of(rpm):
        return "HIGH" if rpm > 6000 else "LOW"

    def count():
        state["n"] += 1
        return state["n"]

    def mid(a, b):
        a["x"] = 99.0  # a copy: the caller's record does not change
        return {"x": (1.0 + b["x"]) / 2, "y": (a["y"] + b["y"]) / 2}

    return {"path_length": path_length, "gear_of": gear_of, "count": count, "mid": mid}
"""


def _run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    assert "Traceback" not in out.getvalue() + err.getvalue()
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    (tmp_path / "kin.rcs").write_text(DESIGN, encoding="utf-8")
    (tmp_path / "kin.scn").write_text(SCENARIO, encoding="utf-8")
    return tmp_path


def _sim(folder: Path, externs: str | None) -> tuple[int, list[dict], str]:
    args = ["sim", str(folder / "kin.rcs"), "--scenario", str(folder / "kin.scn")]
    if externs is not None:
        (folder / "ext.py").write_text(externs, encoding="utf-8")
        args += ["--externs", str(folder / "ext.py")]
    rc, out, err = _run(args)
    return rc, [json.loads(x) for x in out.splitlines()], err


def test_python_externs_stand_in_for_the_design_externs(folder: Path) -> None:
    rc, lines, err = _sim(folder, FACTORY)
    assert rc == 0, err
    gm = [x["gm"] for x in lines]
    assert [g["len"] for g in gm] == [5.0, math.hypot(6.0, 4.0), math.hypot(6.0, 4.0)]
    assert [g["g"] for g in gm] == ["LOW", "HIGH", "HIGH"]
    assert [g["n"] for g in gm] == [1, 2, 3]  # state kept from call to call
    assert gm[0]["m"] == {"x": 1.0, "y": 1.0}
    # Without the file, the externs return zero values, as before.
    rc, lines, err = _sim(folder, None)
    assert [x["gm"]["len"] for x in lines] == [0.0, 0.0, 0.0] and rc == 1  # the expectation fails


def test_functions_of_the_module_serve_without_a_factory(folder: Path) -> None:
    text = "import math\n\ndef path_length(dx, dy):\n    return math.hypot(dx, dy)\n\ndef count():\n    return 7\n"
    rc, lines, err = _sim(folder, text)
    assert rc == 0
    assert lines[0]["gm"]["len"] == 5.0 and lines[0]["gm"]["n"] == 7
    # gear_of and mid are missing: a warning each, at the extern's name.
    assert err.count("warning[W0830]") == 2 and "--> " in err and "extern `gear_of` has no implementation" in err


def test_a_call_that_raises_stops_the_run_with_the_line(folder: Path) -> None:
    text = "def count():\n    return 1 // 0\n"
    rc, lines, err = _sim(folder, text)
    assert rc == 1 and lines == []
    assert "error[E0831]: extern `count` failed in the simulator: it raised ZeroDivisionError" in err
    assert f"raised at {folder / 'ext.py'}:2" in err
    assert "called in cycle 1 of CPU MAIN, controller K" in err


def test_a_file_that_raises_while_loading_is_e0830_at_the_line(folder: Path) -> None:
    text = "import math\n\nLIMIT = 1 / 0\n"
    rc, lines, err = _sim(folder, text)
    assert rc == 1 and lines == []
    assert "error[E0830]: the externs file does not load: it raised ZeroDivisionError" in err
    assert "ext.py:3:1" in err


def test_a_missing_file_is_e0830(folder: Path) -> None:
    rc, _, err = _run(["sim", str(folder / "kin.rcs"), "--scenario", str(folder / "kin.scn"), "--externs", str(folder / "nope.py")])
    assert rc == 1 and "error[E0830]: cannot read the externs file" in err


def test_the_factory_is_called_once_per_cpu() -> None:
    """Each CPU's Main Program has its own externs: so has each simulated CPU."""
    import tempfile

    text = "calls = []\n\ndef externs():\n    n = {'k': 0}\n    calls.append(1)\n\n    def tick(k):\n        n['k'] += 1\n        return n['k']\n\n    return {'tick': tick}\n"
    with tempfile.TemporaryDirectory() as tmp:
        ext = Path(tmp) / "ext.py"
        ext.write_text(text, encoding="utf-8")
        rc, out, err = _run(["sim", str(HERE / "externs/percpu.rcs"), "--scenario", str(HERE / "externs/percpu.scn"), "--externs", str(ext)])
    assert rc == 0, err
    fast = [json.loads(x)["gm"]["fast_out"] for x in out.splitlines() if json.loads(x)["cpu"] == "fast"]
    # FAST alone calls tick twice per cycle: 1 + 2, 3 + 4, ... whatever SLOW calls.
    assert fast == [(4 * k + 3) for k in range(len(fast))]


def test_rcsc_test_takes_externs_for_the_simulator_only(folder: Path) -> None:
    (folder / "ext.py").write_text(FACTORY, encoding="utf-8")
    rc, out, _ = _run(["test", str(folder / "kin.rcs"), "--externs", str(folder / "ext.py")])
    assert rc == 0 and "PASS" in out, out
    rc, out, _ = _run(["test", str(folder / "kin.rcs")])
    assert rc == 1 and "FAIL" in out
    rc, _, err = _run(["test", str(folder / "kin.rcs"), "--target", "c", "--externs", str(folder / "ext.py")])
    assert rc == 2 and "--externs is for the simulator" in err


def test_results_must_be_of_the_extern_type() -> None:
    assert conform(3, F64) == 3.0 and isinstance(conform(3, F64), float)
    assert conform(-(2**31), I32) == -(2**31)
    for value, t in [(2**31, I32), (True, I32), (1.5, I32), (-1, U32), (1, BOOL), ("x", F64), (2**63, DURATION)]:
        with pytest.raises(TypeError):
            conform(value, t)
    gear = EnumType("Gear", ["LOW", "HIGH"])
    assert conform("HIGH", gear) == "HIGH"
    with pytest.raises(TypeError):
        conform(1, gear)
    xy = RecordType("XY", [("x", F64), ("y", F64)])
    assert conform({"x": 1, "y": 2.0}, xy) == {"x": 1.0, "y": 2.0}
    with pytest.raises(TypeError):
        conform({"x": 1.0}, xy)
    arr = ArrayType(name="[i32; 2]", elem=I32, size=2)
    assert conform((1, 2), arr) == [1, 2]
    with pytest.raises(TypeError):
        conform([1, 2, 3], arr)
