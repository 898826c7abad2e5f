"""`rcsc.front.fields`: the node classes' equality and repr behave as a dataclass's generated ones.

The AST and model classes generate only `__init__` (import time); here each
behaviour is compared with a dataclass that generates all three.
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from rcsc.front import ast
from rcsc.front.fields import Fields, node
from rcsc.front.source import SourceFile, Span
from rcsc.semantics import model as m
from rcsc.semantics.types import F64


@node
class Pair(Fields):
    a: object
    b: object = None
    hidden: int = dataclasses.field(default=0, compare=False, repr=False)


@dataclasses.dataclass(slots=True)
class GeneratedPair:
    a: object
    b: object = None
    hidden: int = dataclasses.field(default=0, compare=False, repr=False)


@pytest.mark.parametrize("x, y", [(1, 2), (1, 1), (math.nan, math.nan), ([1], [1]), ("s", "t")])
def test_equality_as_generated(x, y) -> None:
    nan = math.nan
    for a, b in [(x, y), (nan, nan)]:
        assert (Pair(a, b, 1) == Pair(a, b, 2)) == (GeneratedPair(a, b, 1) == GeneratedPair(a, b, 2))
        assert (Pair(a) == Pair(b)) == (GeneratedPair(a) == GeneratedPair(b))
        assert (Pair(a) != Pair(b)) == (GeneratedPair(a) != GeneratedPair(b))


def test_other_classes_are_not_equal_and_nodes_stay_unhashable() -> None:
    f = SourceFile("x.rcs", "abc")
    ident = ast.Ident(Span(f, 0, 1), "x")
    assert ident == ast.Ident(Span(f, 0, 1), "x")
    assert ident != ast.Ident(Span(f, 0, 1), "y")
    assert Pair(1) != GeneratedPair(1)
    with pytest.raises(TypeError):
        hash(ident)
    with pytest.raises(TypeError):
        hash(m.Const(Span(f, 0, 1), F64, 1.0))


def test_repr_as_generated_and_guarded_against_cycles() -> None:
    assert repr(Pair(1, "b")).replace("Pair", "X") == repr(GeneratedPair(1, "b")).replace("GeneratedPair", "X")
    p = Pair(1)
    p.b = p
    assert repr(p) == "Pair(a=1, b=...)"
