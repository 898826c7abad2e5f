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
import shutil
from pathlib import Path

import pytest

from c_build import ADA_OPTS, C_CONFIGS, compile_c, cargo_build, first_difference, generate, gprbuild, run_main
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
