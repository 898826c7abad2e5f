"""The guard analysis's fast paths around z3 give exactly what the Python API gives.

z3's answers (and so the witnesses) depend on the terms made before a
question, so these shortcuts must make the very same terms: checked by term
id (z3 terms are hash-consed) and by the values read from a model.
"""

from __future__ import annotations

import z3

from rcsc.checks import held, smt
from rcsc.checks.guard_analysis import rule_vector
from rcsc.semantics import model as m


def test_and_or_not_make_the_python_api_terms() -> None:
    a, b, c = z3.Bools("gs.a gs.b gs.c")
    assert smt._and(a, b, c).get_id() == z3.And(a, b, c).get_id()
    assert smt._or(a, z3.Not(b)).get_id() == z3.Or(a, z3.Not(b)).get_id()
    assert smt.neg(a).get_id() == z3.Not(a).get_id()
    assert smt._not(smt._and(a, b)).get_id() == z3.Not(z3.And(a, b)).get_id()
    # not Boolean terms of the class the shortcut expects: the Python API is used
    x = z3.Int("gs.x")
    assert smt._and(x > 0, x < 3).get_id() == z3.And(x > 0, x < 3).get_id()


def test_rule_vector_reads_what_eval_reads() -> None:
    x = z3.Int("gs.y")
    p = {0: z3.Bool("gs.r0"), 1: z3.Bool("gs.r1"), 3: z3.Bool("gs.r3"), 7: z3.Bool("gs.unused")}
    s = z3.Solver()
    s.add(p[0] == (x > 2), p[1] == (x < 0), p[3] == (x == 5))
    for want in (x == 5, x == -1, x == 1):
        assert s.check(want) == z3.sat
        model = s.model()
        got = rule_vector(model, p)
        assert got == {i: z3.is_true(model.eval(b, model_completion=True)) for i, b in p.items()}
    assert rule_vector(model, p) == {0: False, 1: False, 3: False, 7: False}


def _cmd(sub: str) -> m.Command:
    return m.Command(span=None, sub=sub, verb="GO", args=[])


def test_held_commands_top_and_nested() -> None:
    top, inner = _cmd("A"), _cmd("B")
    flat = m.Rule.__new__(m.Rule)
    flat.jobs = [top]
    assert held.commands(flat) == ([top], [])
    nested = m.Rule.__new__(m.Rule)
    nested.jobs = [top, m.If(span=None, branches=[(m.Const(span=None, type=None, value=True), [inner])], else_body=[])]
    got_top, got_nested = held.commands(nested)
    assert got_top == [top] and len(got_nested) == 1 and got_nested[0] is inner
