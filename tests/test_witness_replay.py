"""Every witness of the guard analysis replays, and its note agrees with the finding.

For every case and example: each finding with a witness was replayed by the
reference simulator (`data.replayed`), and what its text says fires is what
its data say: an E0506's witness names a rule that fires instead, and that
rule is one of the rules the note says hide it; a W0515's earlier rule is
the one that fires.  The held-status findings (W0540-W0542) carry a path
from `new` as their witness: it is replayed through the plan's state table
(each rule fires in the state the path is in and leads to the next), ends
in the finding's state, and agrees with the notes: the rule the note names
as the last command to a subordinate commands it on the path and no later
rule does; on a W0542 path no rule commands the subordinate.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rcsc.driver import check_path

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "tests" / "cases"
DESIGNS = sorted(CASES.glob("*.rcs")) + sorted(CASES.glob("*/main.rcs")) + sorted(ROOT.glob("examples/*/*.rcs"))
GUARD_CODES = {"E0506", "E0513", "W0514", "W0515", "E0516", "W0517", "W0540"}
HELD_CODES = {"W0540", "W0541", "W0542"}


@pytest.mark.parametrize("path", DESIGNS, ids=[p.parent.name if p.name == "main.rcs" else p.stem for p in DESIGNS])
def test_witnesses_replay_and_agree_with_their_notes(path: Path) -> None:
    result = check_path(str(path))
    for d in list(result.diags) + result.diags.suppressed:
        if d.code not in GUARD_CODES or "witness" not in d.data:
            continue
        where = f"{path.name}:{d.span.line}:{d.span.col} {d.code}"
        assert d.data.get("replayed") is True, f"{where}: the witness does not replay: {d.notes}"
        witness_notes = [n for n in d.notes if n.startswith("witness:")]
        assert len(witness_notes) == 1, where
        if d.code == "E0506" and "fires" in d.data:
            assert d.data["fires"] in d.data["covered_by"], f"{where}: the witness fires `{d.data['fires']}`, the note names {d.data['covered_by']}"
            assert f"`{d.data['fires']}` fires" in witness_notes[0], where
        if d.code == "W0515":
            assert d.data["fires"] == d.data["rules"][1], where
            assert d.notes[0].startswith(f"`{d.data['fires']}`"), where


def _commands(rule) -> set[str]:
    from rcsc.semantics import model as m

    return {j.sub for j in m.walk_stmts(rule.jobs) if isinstance(j, m.Command)}


def _replay_path(design, d) -> None:
    """Walk a held-status finding's path through its plan's state table and compare it with its notes."""
    from rcsc.checks.plans import rule_sources, rule_target, plan_states

    plan = design.controllers[d.data["controller"]].plans[d.data["plan"]]
    by_label = {r.label: r for r in plan.rules}
    states = plan_states(plan)
    where = f"{d.span.line}:{d.span.col} {d.code}"
    state, sent = "new", {}
    for label in d.data["path"]:
        r = by_label[label]
        assert state in rule_sources(r, states), f"{where}: `{label}` does not fire in `{state}`"
        for sub in _commands(r):
            sent[sub] = label
        state = rule_target(r, state)
    assert state == d.data["state"], f"{where}: the path ends in `{state}`, the finding is about `{d.data['state']}`"
    path_notes = [n for n in d.notes if n.startswith("path: ")]
    assert len(path_notes) == 1, where
    for label in d.data["path"]:
        assert f"`{label}`" in path_notes[0], where
    for sub, by in d.data["commanded_by"].items():
        if d.code == "W0542":
            assert sub not in sent and by is None, f"{where}: the path commands `{sub}`"
        elif by is not None:
            assert sent.get(sub) == by, f"{where}: `{sub}` is last commanded by {sent.get(sub)} on the path, the note says `{by}`"
            assert any(f"`{sub}`" in n and f"`{by}`" in n for n in d.notes), where


HELD_DESIGNS = sorted(CASES.glob("W054*.rcs")) + [CASES / "E0505_ignores_error.rcs"]


@pytest.mark.parametrize("path", DESIGNS, ids=[p.parent.name if p.name == "main.rcs" else p.stem for p in DESIGNS])
def test_held_status_paths_replay(path: Path) -> None:
    result = check_path(str(path))
    for d in list(result.diags) + result.diags.suppressed:
        if d.code in HELD_CODES:
            _replay_path(result.model, d)


def test_held_status_cases_have_paths() -> None:
    """The held-status cases do produce findings with paths (so the replay above checks something)."""
    seen = set()
    for path in HELD_DESIGNS:
        for d in check_path(str(path)).diags:
            if d.code in HELD_CODES:
                assert d.data["path"], f"{path.name}: {d.code} without a path"
                seen.add(d.code)
    assert seen == HELD_CODES


VALUE_CODES = {"W0524", "W0525", "W0251"}


def _at(rule, span):
    """The expression of `rule` (condition or jobs) whose span is `span`."""
    from rcsc.semantics import model as m

    exprs = ([rule.guard] if rule.guard is not None else []) + [e for j in m.walk_stmts(rule.jobs) for e in m.stmt_exprs(j)]
    for e in exprs:
        for x in m.walk_expr(e):
            if x.span.start == span.start and x.span.end == span.end:
                return x
    raise AssertionError(f"no expression at {span.line}:{span.col}")


def _replay_value(design, d) -> None:
    """Put the plan in the witness's state with its inputs: the rule fires, and the value leaves its range or wraps."""
    from types import SimpleNamespace

    from rcsc.checks.guard_replay import apply_witness, witness_keys
    from rcsc.semantics.evaluate import eval_expr
    from rcsc.semantics.types import DURATION, IntType
    from rcsc.sim.simulate import Simulator

    c = design.controllers[d.data["controller"]]
    plan = c.plans[d.data["plan"]]
    rule = next(r for r in plan.rules if r.label == d.data["rules"][0])
    where = f"{d.span.line}:{d.span.col} {d.code}"
    values = witness_keys(design, c.name, plan.verb, d.data["witness"])
    sim = SimpleNamespace(design=design, cycle=0, now=0, period_ns=design.cpus[c.cpu].heartbeat_ns, externs={})
    env = apply_witness(sim, c.name, plan, d.data["state"], values)
    fired = Simulator.select_rule(None, plan, d.data["state"], env)
    e = _at(rule, d.span)
    in_guard = rule.guard is not None and rule.guard.span.start <= e.span.start < rule.guard.span.end
    if in_guard:  # the condition is evaluated when no earlier rule fires
        assert fired is None or fired.index >= rule.index, f"{where}: at the witness the earlier `{fired.label}` fires"
    else:  # a job runs when its rule fires
        assert fired is rule, f"{where}: at the witness `{fired and fired.label}` fires, not `{rule.label}`"
    if d.code == "W0251":  # the index is outside the array
        v = eval_expr(e, env)
        assert not (0 <= v < d.data["size"]), f"{where}: the index {v} is inside 0..{d.data['size'] - 1}"
        return
    if d.code == "W0524":
        lo, hi = d.data["range"]
        v = eval_expr(e, env)
        assert not (lo <= v <= hi), f"{where}: the value {v} is inside {lo}..{hi}"
        return
    a, b = eval_expr(e.left, env), eval_expr(e.right, env)
    assert d.data["op"] == e.op, where
    if e.op in ("/", "%"):
        assert b == 0, f"{where}: the divisor is {b}"
    else:
        t = e.type if isinstance(e.type, IntType) else IntType("i64", 64, True) if e.type == DURATION else None
        exact = a + b if e.op == "+" else a - b if e.op == "-" else a * b
        assert not (t.min <= exact <= t.max), f"{where}: {a} {e.op} {b} = {exact} does not wrap"
    note = [n for n in d.notes if n.startswith("witness:")]
    assert len(note) == 1, where


@pytest.mark.parametrize("path", DESIGNS, ids=[p.parent.name if p.name == "main.rcs" else p.stem for p in DESIGNS])
def test_value_witnesses_replay(path: Path) -> None:
    result = check_path(str(path))
    for d in list(result.diags) + result.diags.suppressed:
        if d.code in VALUE_CODES and d.data.get("witness"):
            _replay_value(result.model, d)


def test_value_cases_are_replayed() -> None:
    """The value cases have witnesses with inputs (so the replay above checks something)."""
    n = 0
    for name in ("W0524_range_flow.rcs", "W0525_overflow_division.rcs", "W0251_index_may_be_out_of_range.rcs"):
        n += sum(1 for d in check_path(str(CASES / name)).diags if d.code in VALUE_CODES and d.data.get("witness"))
    assert n >= 5
