"""Memory of a check: no garbage-collector cliff after it, compact nodes.

`rcsc.driver.check_path` pauses the cyclic collector during the run and
freezes what the run built when it resumes (the first collections would
otherwise walk the whole heap of a large design).  A finished check's
syntax trees and model are freed by reference counting (no cycle through
the passes that made them keeps them), and a long-lived process (the
language server, the check daemon) collects what cycles remain now and
then (`driver.collect_if_grown`): it does not grow with every check.
AST nodes, spans and model expressions have slots (no per-object dict).
"""

from __future__ import annotations

import gc
import os
import sys
import weakref
from pathlib import Path

from rcsc.front import ast
from rcsc.semantics import model as m
from rcsc.driver import check_path, collect_if_grown
from rcsc.front.source import SourceFile, Span

SUBMARINE = Path(__file__).resolve().parents[1] / "examples" / "submarine" / "submarine.rcs"


def test_check_freezes_its_objects_and_keeps_the_collector_state() -> None:
    assert gc.isenabled()
    result = check_path(str(SUBMARINE))
    assert gc.isenabled()
    first = gc.get_freeze_count()
    assert first > 10_000  # the design's objects are out of the collector's reach
    del result
    check_path(str(SUBMARINE))
    # The first run's objects were unfrozen (and freed), not frozen twice.
    assert gc.get_freeze_count() < 1.5 * first
    gc.disable()
    try:
        check_path(str(SUBMARINE))
        assert not gc.isenabled()  # a caller's choice is respected
    finally:
        gc.enable()


def test_nodes_have_no_per_object_dictionary() -> None:
    src = SourceFile("x.rcs", "x")
    span = Span(src, 0, 1)
    for node in (span, ast.Name(span, "x"), ast.Ident(span, "x"), m.Const(span, None, 1), m.Ref(span, None, "local", "x")):
        assert not hasattr(node, "__dict__"), type(node).__name__


def test_a_finished_check_is_freed_by_reference_counting() -> None:
    """The semantic pass and the file loader made cycles (a scope holding the
    pass's methods, a recursive reader's closure holding every tree) that
    kept a finished check's trees and model until a collection."""
    was = gc.isenabled()
    gc.disable()
    try:
        result = check_path(str(SUBMARINE))
        controller = weakref.ref(next(iter(result.model.controllers.values())))
        loaded = weakref.ref(result.files[0])  # holds the syntax tree
        design = weakref.ref(result.model)
        del result
        assert controller() is None and loaded() is None and design() is None
    finally:
        if was:
            gc.enable()


def test_a_long_lived_process_does_not_grow_with_every_check(monkeypatch) -> None:
    from rcsc.checks import cache, incremental

    monkeypatch.delenv("RCSC_NO_CACHE", raising=False)
    memory = incremental.memory_stores(cache.MemoryStore())
    real = os.path.realpath(SUBMARINE)
    text = SUBMARINE.read_text(encoding="utf-8")
    check_path(str(SUBMARINE), memory=memory)
    collect_if_grown(factor=0.0)  # now: the baseline
    base = gc.get_freeze_count()
    counts = []
    for k in range(12):
        # A comment at the end: outside every controller, so a full check each time.
        check_path(str(SUBMARINE), overlay={real: text + f"\n// edit {k}\n"}, memory=memory)
        collect_if_grown()
        counts.append(gc.get_freeze_count())
    assert max(counts) < 2 * base + 50_000 + 3 * (counts[0] - base), counts
    assert collect_if_grown(factor=0.0) and gc.get_freeze_count() < base + 50_000


def test_checks_in_a_loop_stay_bounded_without_collecting_by_hand(tmp_path: Path, monkeypatch) -> None:
    # A fuzzer, a script or a test that calls `check_path` again and again:
    # what only the collector frees (an expression's walk list names the
    # expression) stayed frozen for good, about 5 KB a check of a small
    # design, 800 MB over a 15-minute fuzzing run.  `check_path` now
    # collects when the memory in use has doubled; here the threshold is
    # ten checks' worth, so that the test sees collections in 60 checks.
    from rcsc import driver

    text = SUBMARINE.read_text(encoding="utf-8")
    path = str(tmp_path / "s.rcs")
    check_path(path, overlay={path: text})  # the modules, the grammar and the standard library loaded
    monkeypatch.setattr(driver, "_SLACK", 0)
    monkeypatch.setattr(driver, "_FACTOR", 1.0)
    assert collect_if_grown(factor=0.0)
    base, blocks = gc.get_freeze_count(), sys.getallocatedblocks()
    check_path(path, overlay={path: text + "\n// first\n"})
    per_check = gc.get_freeze_count() - base
    assert per_check > 500, per_check  # each check leaves garbage to collect: the test measures something
    monkeypatch.setattr(driver, "_SLACK", 10 * (sys.getallocatedblocks() - blocks))
    counts = []
    for k in range(60):
        check_path(path, overlay={path: text + f"\n// run {k}\n"})
        counts.append(gc.get_freeze_count())
    # Uncollected, the count would reach base + 61 * per_check.
    assert sum(b < a for a, b in zip(counts, counts[1:])) >= 3, counts  # collected on the way, again and again
    assert max(counts) < base + 25 * per_check, (base, per_check, counts)


def test_every_solver_context_is_freed_when_its_plan_is_analysed(monkeypatch) -> None:
    """Each plan is analysed in a z3 context of its own (`smt.own_context`),
    and no cycle may keep one: the collector does not run during a check, so
    a context held by a cycle would stay with all its terms.  Every example
    and test case is checked; the contexts made must all be gone."""
    import z3

    alive: weakref.WeakSet = weakref.WeakSet()
    made = [0]
    init = z3.Context.__init__

    def counting_init(self, *args, **kwargs) -> None:
        init(self, *args, **kwargs)
        made[0] += 1
        alive.add(self)

    monkeypatch.setattr(z3.Context, "__init__", counting_init)
    monkeypatch.setenv("RCSC_NO_CACHE", "1")
    root = SUBMARINE.parents[2]
    files = sorted([*(root / "examples").rglob("*.rcs"), *(root / "tests" / "cases").glob("*.rcs")])
    assert len(files) > 100
    left = []
    for path in files:
        before = len(alive)
        check_path(str(path))
        if len(alive) > before:
            left.append(path.name)
    assert made[0] > 100  # the plans were analysed in contexts of their own
    assert left == []


def test_a_solver_context_of_its_own_nests_and_holds_no_encoder_made_outside() -> None:
    """`own_context` gives the caller's context back on leaving (an
    enclosing analysis keeps making terms in its own), and an encoder made
    outside any (as the tests of the encoding do) is not held by the next
    check (found by a second read of the change)."""
    import z3

    from rcsc.checks import smt

    with smt.own_context():
        a = z3.Int("a")
        with smt.own_context():
            inner = z3.Int("a")
        b = z3.Int("b")
        assert a.ctx is b.ctx and inner.ctx is not a.ctx
        solver = z3.Solver()
        solver.add(a > 0, b > a)
        assert solver.check() == z3.sat
    result = check_path(str(SUBMARINE))
    top = next(c for c in result.model.controllers.values() if c.verbs)
    encoder = smt.Encoder(result.model, top, next(iter(top.verbs.values())), 10_000_000)
    held = weakref.ref(encoder)
    check_path(str(SUBMARINE))
    assert smt._open_encoders == []
    del encoder
    assert held() is None


# Checks a 10-controller synthetic design (about 130 solver contexts) in a
# fresh process and prints the page faults of the check alone; with "off",
# the allocator is left as glibc sets it.
_FAULTS = """
import os, resource, sys, tempfile
sys.path.insert(0, {bench!r})
import synthetic
from rcsc.checks import smt
from rcsc.driver import check_path
if sys.argv[1] == "off":
    smt._allocator_tuned = True
path = os.path.join(tempfile.mkdtemp(), "s.rcs")
with open(path, "w", encoding="utf-8") as f:
    f.write(synthetic.generate(10))
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
check_path(path)
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def test_solver_contexts_reuse_the_memory_of_the_ones_before() -> None:
    # Each z3 context takes two blocks of about 8.5 MB and frees them;
    # glibc's adaptive thresholds gave that memory back to the system at
    # once, and the next context faulted it in again page by page
    # (`smt._keep_solver_memory`).  Measured: about 11,000 faults with the
    # thresholds set, 270,000 without, for this design.
    import subprocess
    import sys

    bench = str(Path(__file__).resolve().parents[1] / "bench")

    def faults(mode: str) -> int:
        out = subprocess.run([sys.executable, "-c", _FAULTS.format(bench=bench), mode], capture_output=True, text=True, check=True)
        return int(out.stdout.split()[-1])

    tuned, untuned = faults("on"), faults("off")
    assert tuned < 40_000, tuned
    assert untuned > 4 * tuned, (tuned, untuned)
