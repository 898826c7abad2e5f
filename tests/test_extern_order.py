"""Extern functions with effects: every target calls them as the simulator does.

tests/externs/callorder.rcs calls extern functions that keep a journal of
their calls (tests/externs/callorder_impl.py for `rcsc sim`, and the same in
C, Rust and Ada next to it).  Its trace shows which calls happened, in which
order and with which arguments.  C and Ada leave the order of the operands
of most operators and of the arguments of a call to the compiler (gcc
evaluates them right to left); the language fixes it left to right
(docs/language.md, "Order of evaluation"), so the generated code must too.
Each compiler configuration is compared with the simulator, byte for byte.
"""

from __future__ import annotations

import importlib.util
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from c_build import ADA_OPTS, C_CONFIGS, ROOT, cargo_build, compile_c, event_file, first_difference, generate, gprbuild, run_main
from rcsc.driver import check_path
from rcsc.front.scenario import text_to_scenario
from rcsc.front.source import SourceFile
from rcsc.sim.runner import run_scenario
from rcsc.sim.trace import run_to_jsonl

HERE = Path(__file__).resolve().parent / "externs"
DESIGN = HERE / "callorder.rcs"
SCENARIO = HERE / "callorder.scn"

# The hand-written implementation of each target, and where it goes in the
# generated code (rcsc writes its stubs only when the file is missing).
IMPLS = {"c": ("callorder_externs.c", "callorder_externs.c"), "rust": ("externs_impl.rs", "src/externs_impl.rs"),
         "ada": ("callorder_0_externs.adb", "callorder_0_externs.adb")}


def _python_externs() -> dict:
    spec = importlib.util.spec_from_file_location("callorder_impl", HERE / "callorder_impl.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.externs()


@pytest.fixture(scope="module")
def reference() -> bytes:
    result = check_path(str(DESIGN))
    assert result.ok and result.model is not None
    sc = text_to_scenario(SourceFile(str(SCENARIO), SCENARIO.read_text(encoding="utf-8")), result.model, result.diags)
    assert sc is not None
    return run_to_jsonl(result.model, run_scenario(result.model, sc, externs=_python_externs())).encode("utf-8")


def _source(target: str, tmp: Path) -> Path:
    out = tmp / target
    name, dest = IMPLS[target]
    (out / dest).parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(HERE / name, out / dest)
    generate(DESIGN, target, out)
    assert (out / dest).read_bytes() == (HERE / name).read_bytes(), "rcsc build replaced the hand-written externs"
    return out


def _compare(exe: Path, tmp: Path, reference: bytes) -> None:
    trace = tmp / "trace.jsonl"
    proc = run_main(exe, DESIGN, SCENARIO, trace)
    assert proc.returncode == 0, proc.stderr
    got = trace.read_bytes()
    assert got == reference, first_difference(reference, got)


def test_the_journal_sees_every_call(reference: bytes) -> None:
    """The reference itself: the stub externs (zero values) give another trace,
    so the comparisons below test the calls, not only the rest of the design."""
    result = check_path(str(DESIGN))
    assert result.model is not None
    sc = text_to_scenario(SourceFile(str(SCENARIO), SCENARIO.read_text(encoding="utf-8")), result.model, result.diags)
    assert sc is not None
    stubs = run_to_jsonl(result.model, run_scenario(result.model, sc)).encode("utf-8")
    assert stubs != reference
    # Each rule that calls an extern in its condition or its jobs fired.
    text = reference.decode()
    for rule in ("R1", "R2", "R3", "R4", "R5", "C2", "C3", "C4"):
        assert f'"rule":"{rule}"' in text, rule


@pytest.mark.parametrize("config", sorted(C_CONFIGS))
def test_c_calls_externs_as_the_simulator(config: str, tmp_path: Path, reference: bytes) -> None:
    cc, flags = C_CONFIGS[config]
    exe = tmp_path / "main"
    compile_c(_source("c", tmp_path), cc, flags, exe)
    _compare(exe, tmp_path, reference)


@pytest.mark.parametrize("profile", ["debug", "release"])
def test_rust_calls_externs_as_the_simulator(profile: str, tmp_path: Path, reference: bytes) -> None:
    import os

    env = dict(os.environ, CARGO_TARGET_DIR=str(tmp_path / "target"), CARGO_TERM_COLOR="never")
    exe = cargo_build(_source("rust", tmp_path), profile, env)
    _compare(exe, tmp_path, reference)


@pytest.mark.parametrize("opt", ADA_OPTS)
def test_ada_calls_externs_as_the_simulator(opt: str, tmp_path: Path, reference: bytes) -> None:
    exe = tmp_path / "main"
    gprbuild(_source("ada", tmp_path), opt, exe)
    _compare(exe, tmp_path, reference)


# ---- several CPUs: each has its own externs ---------------------------------------------------

PERCPU = HERE / "percpu.rcs"
PERCPU_SCN = HERE / "percpu.scn"


def _journal_sim(design_path: Path, scn: Path, per_cpu: bool) -> bytes:
    sys.path.insert(0, str(ROOT / "bench"))
    from difftest_externs import python_externs

    result = check_path(str(design_path))
    assert result.ok and result.model is not None
    model = result.model
    sc = text_to_scenario(SourceFile(str(scn), scn.read_text(encoding="utf-8")), model, result.diags)
    assert sc is not None
    externs = (lambda: python_externs(model)) if per_cpu else python_externs(model)
    return run_to_jsonl(model, run_scenario(model, sc, externs=externs)).encode("utf-8")


def test_each_cpu_of_the_simulator_has_its_own_externs() -> None:
    """A function given as `externs` is called once per CPU: FAST's calls do
    not move SLOW's journal (a shared dictionary would)."""
    sys.path.insert(0, str(ROOT / "bench"))
    from difftest_externs import python_externs

    own, shared = _journal_sim(PERCPU, PERCPU_SCN, True), _journal_sim(PERCPU, PERCPU_SCN, False)
    assert own != shared
    # FAST calls tick(1), then tick(2), in each of its cycles (the trace's
    # lines of CPU fast): with a journal of its own, its values are those of
    # a journal that sees only its calls.
    model = check_path(str(PERCPU)).model
    assert model is not None
    tick = python_externs(model)["tick"]
    fast = [x["gm"]["fast_out"] for x in map(json.loads, own.decode().splitlines()) if x["cpu"] == "fast"]
    assert len(fast) == 8 and fast == [tick(1) + tick(2) for _ in fast]


def test_c_launcher_calls_externs_per_cpu_as_the_simulator(tmp_path: Path) -> None:
    sys.path.insert(0, str(ROOT / "bench"))
    from difftest_externs import c_source

    result = check_path(str(PERCPU))
    assert result.model is not None
    src = tmp_path / "c"
    src.mkdir()
    name, text = c_source(result.model)
    (src / name).write_text(text, encoding="utf-8")
    generate(PERCPU, "c", src)
    assert (src / name).read_text(encoding="utf-8") == text
    proc = subprocess.run(["make", "-s", "CFLAGS=-O2 -Werror"], cwd=src, capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    trace = tmp_path / "trace.jsonl"
    run = subprocess.run([str(src / "run_percpu"), "--lockstep", "--no-timing", "--scenario", str(event_file(PERCPU, PERCPU_SCN)),
                          "--trace", str(trace)], capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    assert run.returncode == 0, run.stderr
    want = _journal_sim(PERCPU, PERCPU_SCN, True)
    assert trace.read_bytes() == want, first_difference(want, trace.read_bytes())
