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


def test_the_file_runs_afresh_for_each_cpu_and_run(folder: Path) -> None:
    """State at module level is per CPU and per run, as each CPU's program
    starts afresh: two scenarios of `rcsc test` see the same first values."""
    (folder / "ext.py").write_text("import math\n\nCALLS = [0]\n\ndef count():\n    CALLS[0] += 1\n    return CALLS[0]\n\n"
                                   "def path_length(dx, dy):\n    return math.hypot(dx, dy)\n", encoding="utf-8")
    for name in ("a", "b"):
        (folder / f"{name}.scn").write_text('scenario "n"\ncycles 2\nexpect at 2: n == 2\n', encoding="utf-8")
    rc, out, _ = _run(["test", str(folder / "kin.rcs"), str(folder / "a.scn"), str(folder / "b.scn"), "--externs", str(folder / "ext.py")])
    assert "3 passed, 0 failed" in out, out
    # The missing stand-ins are said once, even though both scenarios pass.
    assert out.count("W0830") == 2 and "gear_of" in out and "mid" in out, out


def test_the_file_imports_like_a_script(folder: Path) -> None:
    """Modules beside the file import; dataclasses work (the module is registered)."""
    (folder / "helper.py").write_text("def hyp(a, b):\n    return (a * a + b * b) ** 0.5\n", encoding="utf-8")
    text = ("from __future__ import annotations\nfrom dataclasses import dataclass\nfrom helper import hyp\n\n"
            "@dataclass\nclass P:\n    x: float\n\ndef path_length(dx, dy):\n    return hyp(P(dx).x, dy)\n")
    rc, lines, err = _sim(folder, text)
    assert lines and lines[0]["gm"]["len"] == 5.0, err
    # A syntax error in an imported module is reported in that module.
    (folder / "broken.py").write_text("def f(:\n    pass\n", encoding="utf-8")
    rc, lines, err = _sim(folder, "import broken\n")
    assert rc == 1 and "error[E0830]" in err and f"{folder / 'broken.py'}:1:" in err, err


def test_a_result_too_large_for_f64_is_e0831(folder: Path) -> None:
    rc, lines, err = _sim(folder, "def path_length(dx, dy):\n    return 10 ** 400\n")
    assert rc == 1 and "error[E0831]" in err and "too large for `f64`" in err


def test_named_arguments_and_block_inputs_are_evaluated_in_parameter_order(tmp_path: Path) -> None:
    """docs/language.md, "Order of evaluation": whatever order names them."""
    design = """design order

record Pt { a: i32, b: i32 }

extern fn t(k: i32) -> i32 budget 1 us

block PAIR() {
    input a: i32 = 0
    input b: i32 = 0
    output y: i32 = 0
    step { y = a - b; }
}

gm q: Pt = Pt(a = 0, b = 0) to env
gm r: i32 = 0 to env

controller K level 1 budget 1 ms {
    writes q, r
    block blk: PAIR()
    pre {
        q = Pt(b = t(1), a = t(2));
        blk(b = t(3), a = t(4));
        r = blk.y;
    }
}

cpu MAIN {
    heartbeat 10 ms
    schedule K
}
"""
    (tmp_path / "order.rcs").write_text(design, encoding="utf-8")
    (tmp_path / "order.scn").write_text('scenario "o"\ncycles 1\n', encoding="utf-8")
    (tmp_path / "ext.py").write_text("import json, os\n\ndef t(k):\n    with open(os.environ['ORDER_LOG'], 'a') as f:\n"
                                     "        f.write(str(k) + '\\n')\n    return k\n", encoding="utf-8")
    import os

    os.environ["ORDER_LOG"] = str(tmp_path / "log.txt")
    try:
        rc, out, err = _run(["sim", str(tmp_path / "order.rcs"), "--scenario", str(tmp_path / "order.scn"), "--externs", str(tmp_path / "ext.py")])
    finally:
        del os.environ["ORDER_LOG"]
    assert rc == 0, err
    assert (tmp_path / "log.txt").read_text().split() == ["2", "1", "4", "3"]
    assert json.loads(out.splitlines()[0])["gm"]["r"] == 1


def test_an_exit_in_the_file_is_a_finding_not_the_end_of_rcsc(folder: Path) -> None:
    """`sys.exit()` raises SystemExit: in a stand-in it is a failed call, not rcsc's own exit code."""
    rc, lines, err = _sim(folder, "import sys\n\ndef count():\n    sys.exit(3)\n")
    assert rc == 1 and "error[E0831]: extern `count` failed in the simulator: it raised SystemExit: 3" in err
    rc, lines, err = _sim(folder, "import sys\nsys.exit(5)\n")
    assert rc == 1 and "error[E0830]: the externs file does not load: it raised SystemExit: 5" in err
