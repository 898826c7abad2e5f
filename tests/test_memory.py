"""Memory of a check: no garbage-collector cliff after it, compact nodes.

`rcsc.driver.check_path` pauses the cyclic collector during the run and
freezes what the run built when it resumes (the first collections would
otherwise walk the whole heap of a large design); a later run unfreezes
first, so a long-lived process does not accumulate every run's objects.
AST nodes, spans and model expressions have slots (no per-object dict).
"""

from __future__ import annotations

import gc
from pathlib import Path

from rcsc.front import ast
from rcsc.semantics import model as m
from rcsc.driver import check_path
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
