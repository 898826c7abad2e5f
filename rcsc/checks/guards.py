"""Determinism and coverage of state tables, proven with z3 (docs/language.md, the guard analysis).

For every state of every plan this family asks the solver, over the inputs
the controller reads when it decides (`rcsc.checks.smt` says how each input and
each type is encoded), which rules can never fire, which rules can be true
together so that the order of the table decides, and for which inputs no
rule fires.  Each finding carries a witness: values of the inputs that show
it, in the text (`= note: witness: x = 1, TB = done`) and in
`Diagnostic.data["witness"]` for JSON and SARIF.

The rules of a state are the rules written for it and the `*` rules, in table
order; the `otherwise` rule of the state fires when none of them does.

Findings
--------
E0506 (error) dead rule
    A rule (or an `otherwise`) that can never fire because earlier rules of
    each of its states cover every input for which its condition holds.  The
    literal case (a rule after a `true` rule) is found by
    `rcsc.checks.plans` without a solver; this family finds the rest and
    never reports a rule twice.  A `*` rule is dead only if it is dead in
    every state: a `*` error rule that the `new` rules hide in `new` is the
    idiom of the stale-status pitfall (docs/language.md 9.2), not dead logic.
    The witness is an input where the rule's condition holds and shows which
    rule fires instead.
E0513 (error) condition always false
    The condition cannot be true for any input (given the types and the
    declared ranges): the rule is dead whatever its place in the table.
W0514 (warning) condition always true
    A condition that is not the literal `true` but holds for every input, in
    a state where later rules follow (which it hides).  Write `true` if that
    is meant.  A tautology in the last rule of its states hides nothing and
    is not reported.
W0515 (warning) order-dependent rules
    Two rules of a state whose conditions can both be true (with no earlier
    rule true) and which lead to different outcomes: a different next state
    or different jobs, compared structurally.  Not reported:
    - in a plan declared `ordered` (`plan X ordered { ... }`): the designer
      states that the table is prioritized, the paper's "prioritized events";
    - when the earlier rule leads to `error(...)`: a fault or time-out rule
      written before the progress rules is the paper's prioritized style, and
      its priority is the point;
    - when the later rule can never fire in that state (e.g. a `*` error rule
      in `new`, hidden by `new` rules that cover every input);
    - in `new`, between a `new` rule and a `*` rule after it: the `*` rule
      fires in `new` only where the `new` rules leave a gap, which E0516
      reports once (not once per `*` rule);
    - once per pair of rules, not once per state.
E0516 (error) a new command can go unanswered
    Inputs for which no rule of `new` fires and `new` has no `otherwise`: the
    command is accepted (status EXEC) and nothing happens.
W0517 (warning) a state can wait forever
    In a named state a cycle in which no rule fires is how a plan waits (for
    `TB.done`, a sensor, a time-out), so a transient "nothing fires" is not a
    finding.  What is reported is a wait that cannot end: values of the
    inputs that cannot change while the plan waits in the state (the
    command's parameters; locals, status fields and Global Memory that only
    this controller writes, when `pre` and `post` do not assign them) for
    which no rule of the state can fire *whatever* the other inputs do
    (subordinates' status, sensors, time in state, extern results).  This is
    an exists-forall query.  Only the fixed inputs are the witness; the data
    also holds one full sample input.  Not reported for a `continuous` plan,
    which holds its state until the next command by design.  A subordinate's
    status is not fixed here: whether it was commanded on the way into the
    state is a path property, which W0540 follows.
W0540, W0541, W0542 (warnings) held subordinate status
    `rcsc.checks.held` follows the plan's paths with each subordinate's
    DONE/ERROR held until it is commanded again: W0540 is W0517 with the
    held statuses among the fixed inputs (asked only where W0517 finds
    nothing), W0541 a state from which only `error(...)` remains reachable
    along the held statuses, W0542 a wait on a subordinate not commanded on a
    path into the state.  Their witness is the path of rules from `new`.
W0518 (warning) guard analysis incomplete
    The solver answered `unknown` or ran out of its budget (per query: a
    wall-clock timeout, `TIMEOUT_MS`, and a deterministic resource limit,
    `RLIMIT`, so that results do not depend on the machine), or a condition
    could not be encoded.  Never a silent pass: the rest of that plan is not
    analysed and the finding says what was being asked.

f64 and externs make some results approximate (see `rcsc.checks.smt`): findings
say so in a note.  Every witness is replayed by the reference simulator's
rule selection (`rcsc.sim.simulate.Simulator.select_rule`) before it is reported;
a witness that does not show the claim after rounding to doubles is marked
approximate.

The analysis runs when names and types check (no E00xx-E02xx error): with
such errors the model holds placeholders that would only give follow-on
findings.

How it asks: one z3 solver per plan, with a Boolean `rule.i == condition_i`
per rule, so that every question is a check under assumptions (`rule.i`,
`not rule.j`, ...) and an unsat core names the rules that hide a dead one.
Each model found is kept with the truth value of every rule's condition, and
a later question that such a model already answers is not asked again.
Witnesses are then made readable (initial values, 0, small magnitudes,
round numbers) with a few extra queries per finding, never per question.

Plans with the same shape (the same conditions up to the names of their
inputs, e.g. XAX and YAX, or the Lifecycle plans of many controllers) are
analysed once: the result is cached under a canonical form of the plan and
renamed for each plan of that shape (`Options(cache=False)` turns it off).

Where it lives: this module is the family (its options, the NaN-able
parameters, and what happens to each plan: shared, read from the store or
analysed); `rcsc.checks.guard_analysis` asks the questions of one plan;
`rcsc.checks.guard_shapes` writes a plan's canonical shape and keeps results
on disk; `rcsc.checks.guard_report` turns findings into diagnostics; and
`rcsc.checks.guard_replay` replays a witness in the reference simulator.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

from rcsc.semantics import model as m
from rcsc.checks.plans import literal_dead_rules
from rcsc.diagnostics import Diagnostics, Severity
from rcsc.semantics.model import Design
from rcsc.checks.smt import HasTypeError, own_context
from rcsc.semantics.types import FloatType, RecordType
from rcsc.checks.guard_analysis import RLIMIT, TIMEOUT_MS, _Analysis, _assigned_in_pre_post, _Finding, _Incomplete
from rcsc.checks.guard_report import _report
from rcsc.checks.guard_shapes import _Canon, _load, _rename, _save, _stored_key


def _env_int(name: str, default: int) -> int:
    try:
        return int(os.environ.get(name, default))
    except ValueError:
        return default


@dataclass
class Options:
    """Settings of one run.  The budget defaults can also be set from the
    environment: RCSC_GUARD_TIMEOUT_MS and RCSC_GUARD_RLIMIT."""

    timeout_ms: int = field(default_factory=lambda: _env_int("RCSC_GUARD_TIMEOUT_MS", TIMEOUT_MS))
    rlimit: int = field(default_factory=lambda: _env_int("RCSC_GUARD_RLIMIT", RLIMIT))
    cache: bool = True
    # Where results outlive the run (`rcsc.checks.cache`); None: kept in memory only.
    store: object = None


@dataclass
class Stats:
    """What one run of the family did (for the benchmark)."""

    plans: int = 0
    plans_cached: int = 0
    plans_stored: int = 0  # answered by the on-disk cache
    queries: int = 0  # solver calls
    reused: int = 0  # questions answered by an earlier model
    forall_queries: int = 0
    seconds: float = 0.0


def check(design: Design, diags: Diagnostics, options: Options | None = None, stats: Stats | None = None) -> None:
    opts = options or Options()
    st = stats if stats is not None else Stats()
    if front_end_errors(diags):
        return
    t0 = time.perf_counter()
    cache: dict = {}
    nan = nan_params(design)
    for c in m.checked_controllers(design):
        assigned = _assigned_in_pre_post(c)
        for plan in c.plans.values():
            st.plans += 1
            _analyse_plan(design, c, plan, assigned, opts, st, diags, cache, (c.name, plan.verb) in nan)
    st.seconds += time.perf_counter() - t0


def nan_params(design: Design) -> set[tuple[str, str]]:
    """The (controller, verb) pairs whose f64 parameters can be NaN.

    Operator commands (scenarios, the top controller's command input) carry
    numbers, never NaN (a scenario's NaN argument is refused, E0206), so the
    parameters of a verb can be NaN only when its supervisor sends that verb
    with an argument that can carry a NaN (see `_may_be_nan`).  Computed once
    per design, to a fixed point (a parameter passed on down the hierarchy),
    and remembered for the design (the guard and the value analyses both
    ask; a weak reference, so the memo does not keep a checked design alive).
    """
    import weakref

    if _nan_memo[0] is not None and _nan_memo[0]() is design:
        return set(_nan_memo[1])
    sends = [(sup.name, *send) for sup in design.controllers.values() for send in commands_sent(design, sup)]
    out: set[tuple[str, str]] = set()
    changed = True
    while changed:
        changed = False
        for sup, verb, sub, sub_verb, nan_if_numbers, nan_if_nan in sends:
            key = (sub, sub_verb)
            if key not in out and (nan_if_nan if (sup, verb) in out else nan_if_numbers):
                out.add(key)
                changed = True
    _nan_memo[:] = [weakref.ref(design), frozenset(out)]
    return out


# The design `nan_params` answered for last (a weak reference) and its answer.
_nan_memo: list = [None, frozenset()]


def commands_sent(design: Design, sup: m.Controller) -> list[tuple[str, str, str, bool, bool]]:
    """The commands `sup`'s plans send its own subordinates, as the NaN
    analysis sees them: (plan verb, subordinate, verb, can an argument be NaN
    when `sup`'s parameters are numbers, ... when they can be NaN).  Part of
    what other controllers' checks read of `sup`'s plans, so an incremental
    re-check keeps it for the controllers it does not parse again."""
    if m.is_elided(sup):
        return [tuple(x) for x in sup.plans.summary["sends"]]  # type: ignore[attr-defined]
    out = []
    for plan in sup.plans.values():
        for r in plan.rules:
            for job in m.walk_stmts(r.jobs):
                if isinstance(job, m.Command):
                    sub = design.controllers.get(job.sub)
                    if sub is not None and sub.supervisor == sup.name:
                        out.append((plan.verb, job.sub, job.verb, any(_may_be_nan(a, False) for a in job.args),
                                    any(_may_be_nan(a, True) for a in job.args)))
    return out


def _may_be_nan(e: m.Expr, params_nan: bool) -> bool:
    """Whether a supervisor's argument can carry a NaN into a command.

    A NaN enters from outside or from arithmetic that makes one: a Global
    Memory value (a sensor, another controller's output), an extern's
    result, an f64 division, or a parameter that can itself be NaN.  The
    controller's own locals and status fields are taken as numbers: they
    hold what its own jobs computed from those sources, and a NaN there is
    reported where it enters.
    """
    for x in m.walk_expr(e):
        if not isinstance(x.type, (FloatType, RecordType)):
            continue
        if isinstance(x, m.Ref) and (x.kind == "gm" or (x.kind == "param" and params_nan)):
            return True
        if isinstance(x, m.Call) and x.kind == "extern":
            return True
        if isinstance(x, m.Binary) and x.op == "/":
            return True
    return False


def front_end_errors(diags: Diagnostics) -> bool:
    """Whether names or types failed (E00xx-E02xx, or E0507: a command to or a
    status read of a controller that is not a subordinate): the model then
    holds placeholders (error types, values replaced by 0, commands left out)
    that would only give follow-on findings."""
    return any(d.severity is Severity.ERROR and (d.code[1:3] in ("00", "01", "02") or d.code == "E0507") for d in diags)


# ---- one plan: shared, stored or analysed ---------------------------------------------------


def _analyse_plan(design: Design, c: m.Controller, plan: m.Plan, assigned, opts: Options, st: Stats, diags: Diagnostics, cache: dict, nan: bool = True) -> None:
    if not any(r.guard is not None for r in plan.rules):
        return
    if plan.verb not in c.verbs:
        return
    period = c.period_ns or None
    canon = None
    pkey = None
    if opts.cache:
        # Ages count base ticks: a design whose base tick differs from this
        # controller's period analyses the same plan differently.
        unit = period if design.base_tick_ns in (0, period) else (period, design.base_tick_ns)
        canon = _Canon(design, c, plan, assigned, unit, nan, cache.setdefault("can-fail", {}))
        ckey = canon.key()
        hit = cache.get(ckey)
        if hit is not None:
            st.plans_cached += 1
            findings, order, states = hit
            mapping = dict(zip(order, canon.keys))
            by_canon = {v: k for k, v in canon.states.items()}
            state_map = {k: by_canon[v] for k, v in states.items()}
            for f in findings:
                _report(design, c, plan, _rename(f, mapping, state_map), diags)
            return
        if opts.store is not None:
            pkey = _stored_key(design, c, plan, canon, opts)
            findings = _load(opts.store, pkey, design)
            if findings is not None:
                st.plans_stored += 1
                cache[ckey] = (findings, list(canon.keys), dict(canon.states))
                for f in findings:
                    _report(design, c, plan, f, diags)
                return
    lit_dead = literal_dead_rules(plan)
    try:
        with own_context():
            findings = _Analysis(design, c, plan, assigned, opts, st, nan).run(lit_dead)
    except HasTypeError:
        return
    except _Incomplete as inc:
        _report(design, c, plan, _Finding("W0518", [], reason=inc.reason, question=inc.question, span=inc.span), diags)
        return
    if canon is not None:
        cache[canon.key()] = (findings, list(canon.keys), dict(canon.states))
        if pkey is not None:
            _save(opts.store, pkey, findings)
    for f in findings:
        _report(design, c, plan, f, diags)
