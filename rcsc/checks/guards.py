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
"""

from __future__ import annotations

import math
import os
import re
import time
from dataclasses import dataclass, field, fields
from types import SimpleNamespace

import z3

from rcsc.semantics import model as m
from rcsc.checks.plans import literal_dead_rules, plan_states, rule_sources
from rcsc.diagnostics import Diagnostic, Diagnostics, Severity
from rcsc.semantics.model import Design
from rcsc.checks.smt import (
    APPROX_ARITH,
    F,
    Encoder,
    Encoding,
    HasTypeError,
    Unsupported,
    concrete,
    format_value,
    json_value,
)
from rcsc.front.source import Span
from rcsc.checks.smt import _and as _z3_and
from rcsc.checks.smt import _rational as _rational_of
from rcsc.checks.smt import to_f64
from rcsc.checks.smt import neg, real_of
from rcsc.checks.smt import own_context
from rcsc.semantics.types import DURATION, ArrayType, EnumType, FloatType, RecordType, Type

# The budget of one solver query.  The resource limit is deterministic (the
# same answer on every machine; 2M units take about 0.8 s on a 2024 laptop,
# up to 2.5 s on a loaded 2-core CI machine).  The wall-clock time-out is
# only a safety net for a query whose work z3 does not count: it must never
# be what stops an ordinary query, or the findings would depend on the
# machine's load (a question decided on a quiet machine, W0518 on a busy
# one).  So it is far above what the resource limit allows.
TIMEOUT_MS = 60_000
RLIMIT = 2_000_000


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


HELD_QUESTION = "the subordinates' held status along the plan's paths"


class _Incomplete(Exception):
    def __init__(self, reason: str, question: str, span: Span | None) -> None:
        super().__init__(reason)
        self.reason = reason
        self.question = question
        self.span = span


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


def _new_solver(opts: Options) -> z3.Solver:
    s = z3.Solver()
    s.set("timeout", int(opts.timeout_ms))
    if opts.rlimit:
        s.set("rlimit", int(opts.rlimit))
    return s


def front_end_errors(diags: Diagnostics) -> bool:
    """Whether names or types failed (E00xx-E02xx): the model then holds placeholders
    (error types, values replaced by 0) that would only give follow-on findings."""
    return any(d.severity is Severity.ERROR and d.code[1:3] in ("00", "01", "02") for d in diags)


# ---- plan structure --------------------------------------------------------------------


def _assigned_in_pre_post(c: m.Controller) -> set[tuple[str, str]]:
    out = set()
    for s in m.walk_stmts(c.pre + c.post):
        if isinstance(s, m.Assign):
            out.add((s.target.kind, s.target.name))
    return out


def _is_fixed(key: tuple, c: m.Controller, assigned: set[tuple[str, str]]) -> bool:
    """Whether an input keeps its value while the plan waits in a state (no rule fires)."""
    kind = key[0]
    if kind == "param":
        return True
    if kind in ("local", "status"):
        return (kind, key[1]) not in assigned
    if kind == "gm":
        return any(u.name == key[1] for u in c.writes) and ("gm", key[1]) not in assigned
    return False


def _vkey(v):
    if isinstance(v, dict):
        return tuple(sorted((k, _vkey(x)) for k, x in v.items()))
    if isinstance(v, list):
        return ("[]",) + tuple(_vkey(x) for x in v)
    if isinstance(v, float) and math.isnan(v):
        return ("nan",)
    return (type(v).__name__, v)


def _ekey(e: m.Expr):
    """A structural key of an expression: equal for equal expressions, whatever their spans."""
    t = type(e)
    if t is m.Const:
        return ("c", str(e.type), _vkey(e.value))
    if t is m.Ref:
        return ("r", e.kind, e.name)
    if t is m.InState:
        return ("t",)
    if t is m.Cycle:
        return ("cycle",)
    if t is m.SubView:
        return ("s", e.sub, e.attr, e.value)
    if t is m.Age:
        return ("age", e.name)
    if t is m.Field:
        return ("f", _ekey(e.obj), e.name)
    if t is m.Call:
        return ("call", e.kind, e.func, tuple(_ekey(a) for a in e.args))
    if t is m.Unary:
        return ("u", e.op, str(e.type), _ekey(e.operand))
    if t is m.Binary:
        return ("b", e.op, str(e.type), _ekey(e.left), _ekey(e.right))
    if t is m.IfExpr:
        return ("if", _ekey(e.cond), _ekey(e.then), _ekey(e.else_))
    if t is m.Index:
        return ("[]", _ekey(e.obj), _ekey(e.index))
    if t is m.ArrayLit:
        return ("[,]", str(e.type), tuple(_ekey(x) for x in e.items))
    return ("?", t.__name__, id(e))  # unknown: equal only to itself


def _skey(jobs: list[m.Stmt]) -> tuple:
    """A structural key of a job list: equal for equal jobs, whatever their spans."""
    out = []
    for s in jobs:
        t = type(s)
        if t is m.Assign:
            index = None if s.target.index is None else _ekey(s.target.index)
            out.append(("=", s.target.kind, s.target.name, tuple(s.target.path), index, s.op, _ekey(s.value)))
        elif t is m.CallStmt:
            out.append(("call", _ekey(s.call)))
        elif t is m.Command:
            out.append(("cmd", s.sub, s.verb, tuple(_ekey(a) for a in s.args)))
        elif t is m.Report:
            out.append(("report", s.status))
        elif t is m.If:
            out.append(("if", tuple((_ekey(c), _skey(b)) for c, b in s.branches), _skey(s.else_body)))
        else:
            out.append(("?", t.__name__, id(s)))
    return tuple(out)


def _target(rule: m.Rule, state: str) -> tuple:
    k = rule.next.kind
    if k == "same" or (k == "named" and rule.next.name == state):
        return ("state", state)
    if k == "named":
        return ("state", rule.next.name)
    if k == "error":
        return ("error", rule.next.code)
    return (k,)


def _outcome(rule: m.Rule, state: str) -> tuple:
    return (_target(rule, state), _skey(rule.jobs))


def _next_text(rule: m.Rule) -> str:
    return str(rule.next)


def _difference(a: m.Rule, b: m.Rule, state: str) -> str:
    """What two rules do differently: next state, jobs, or both."""
    parts = []
    if _target(a, state) != _target(b, state):
        parts.append(f"the next state ({_next_text(a)} / {_next_text(b)})")
    if _skey(a.jobs) != _skey(b.jobs):
        parts.append(f"their jobs ({_jobs_text(a)} / {_jobs_text(b)})")
    return " and ".join(parts) or "their outcome"


def _jobs_text(rule: m.Rule) -> str:
    if not rule.jobs:
        return "none"
    spans = [j.span for j in rule.jobs]
    return spans[0].to(spans[-1]).text if spans[0].file is spans[-1].file else "..."


# ---- the per-plan analysis -----------------------------------------------------------------


@dataclass
class _Finding:
    """A finding in terms of rule indexes, states and input keys (so it can be cached)."""

    code: str
    rules: list[int]  # the rule(s) it is about, the main one first
    state: str | None = None
    witness: dict = field(default_factory=dict)  # input key -> value
    externs: list = field(default_factory=list)  # (func, [arg values], value, [arg types], result type)
    fires: int | None = None  # rule index that fires at the witness (-1: none)
    covering: list[int] = field(default_factory=list)
    hidden: list[int] = field(default_factory=list)
    sample: dict = field(default_factory=dict)
    reason: str = ""
    question: str = ""
    approx: list[str] = field(default_factory=list)
    path: list[int] = field(default_factory=list)  # rule indexes from `new` (held-status findings)
    held: dict = field(default_factory=dict)  # ("view", sub) -> [phase, index of the rule that last commanded it or -1]
    span: Span | None = None


def rule_vector(model, p: dict) -> dict[int, bool]:
    """Which rules' conditions hold in `model` (`p`: rule index -> its Boolean).

    The same as `z3.is_true(model.eval(b, model_completion=True))` for each,
    through z3's C API directly: for a Boolean constant the evaluation gives
    z3's own `true` or `false`, so no term is made, kept or freed (the
    solver's later answers, which can depend on the terms made before them,
    are the same), only the Python wrappers are saved.
    """
    ctx = model.ctx.ref()
    mod = model.model
    r = (z3.Ast * 1)()
    out = {}
    for i, b in p.items():
        if not z3.Z3_model_eval(ctx, mod, b.as_ast(), True, r):
            raise z3.Z3Exception("failed to evaluate expression in the model")
        out[i] = z3.Z3_get_bool_value(ctx, r[0]) == z3.Z3_L_TRUE
    return out


class _Sat:
    def __init__(self, model, vec) -> None:
        self.model = model
        self.vec = vec


class _Unsat:
    def __init__(self, core: list[tuple[int, bool]]) -> None:
        self.core = core


class _Analysis:
    def __init__(self, design: Design, c: m.Controller, plan: m.Plan, assigned, opts: Options, st: Stats, nan: bool = True) -> None:
        self.design, self.c, self.plan, self.opts, self.st = design, c, plan, opts, st
        self.assigned = assigned
        verb = c.verbs.get(plan.verb)
        self.period = c.period_ns or None
        self.enc = Encoder(design, c, verb, self.period, nan_params=nan)
        self.guarded = [r for r in plan.rules if r.guard is not None]
        self.encs: dict[int, Encoding] = {}
        for r in self.guarded:
            try:
                self.encs[r.index] = self.enc.guard(r.guard)  # type: ignore[arg-type]
            except HasTypeError:
                raise
            except Unsupported as exc:
                raise _Incomplete(f"cannot encode the condition ({exc})", f"the condition of `{r.label}`", r.guard_span)
        self.p = {i: z3.Bool(f"rule.{i}") for i in self.encs}
        # A solver of its own per plan (not one shared in push/pop scopes):
        # then a plan's answers and witnesses do not depend on which plans
        # were analysed before it (about 10% slower).
        self.solver = _new_solver(opts)
        for i, e in self.encs.items():
            self.solver.add(self.p[i] == e.term)
        for inp in self.enc.inputs.values():
            self.solver.add(inp.constraint)
        for s in self.enc.side:
            self.solver.add(s)
        self.vectors: list[_Sat] = []
        self.jobkeys: dict[int, tuple] = {}
        self.unsat: set[tuple] = set()  # the questions answered unsat (as sorted literals)
        # `done` and `error` as current states are E0510: never evaluated.
        self.states = [s for s in plan_states(plan) if s not in ("done", "error")]
        self.rules_in: dict[str, list[m.Rule]] = {}
        self.otherwise: dict[str, m.Rule] = {}
        for s in self.states:
            self.rules_in[s] = [r for r in self.guarded if s in rule_sources(r, self.states)]
        for r in plan.rules:
            if r.otherwise and r.state.kind != "any":
                key = r.state.name if r.state.kind == "named" else "new"
                self.otherwise.setdefault(key or "", r)

    def jobkey(self, r: m.Rule) -> tuple:
        """`_skey(r.jobs)`, made once per rule (the pairs of step 4 compare each rule with every later one)."""
        k = self.jobkeys.get(r.index)
        if k is None:
            k = self.jobkeys[r.index] = _skey(r.jobs)
        return k

    def sources(self, r: m.Rule) -> list[str]:
        return [s for s in rule_sources(r, self.states) if s in self.rules_in]

    # ---- questions ----

    def query(self, lits: dict[int, bool], question: str, span: Span | None):
        for v in self.vectors:
            if all(v.vec[i] == b for i, b in lits.items()):
                self.st.reused += 1
                return v
        assumptions = [self.p[i] if b else neg(self.p[i]) for i, b in lits.items()]
        self.st.queries += 1
        r = self.solver.check(*assumptions)
        if r == z3.sat:
            model = self.solver.model()
            vec = rule_vector(model, self.p)
            res = _Sat(model, vec)
            self.vectors.append(res)
            return res
        if r == z3.unsat:
            self.unsat.add(tuple(sorted(lits.items())))
            ids = {a.get_id(): (i, b) for a, (i, b) in zip(assumptions, lits.items())}
            core = [ids[a.get_id()] for a in self.solver.unsat_core() if a.get_id() in ids]
            return _Unsat(core)
        raise _Incomplete(self.solver.reason_unknown() or "unknown", question, span)

    def minimal_core(self, lits: dict[int, bool], core: list[tuple[int, bool]], keep: int | None = None) -> list[int]:
        """The rules of an unsat core, without those that are not needed (deletion-based; for findings only)."""
        need = [i for i, _ in core if i != keep]
        for i in list(need):
            trial = {j: lits[j] for j in need if j != i}
            if keep is not None:
                trial[keep] = lits[keep]
            self.st.queries += 1
            if self.solver.check(*self.lits(trial)) == z3.unsat:
                need.remove(i)
        return need

    # ---- witness ----

    def inputs_of(self, idxs) -> list[tuple]:
        keys: dict[tuple, None] = {}
        for i in idxs:
            for k in self.encs[i].inputs:
                keys.setdefault(k, None)
        return list(keys)

    def lits(self, lits: dict[int, bool]) -> list:
        return [self.p[i] if b else neg(self.p[i]) for i, b in lits.items()]

    def witness(self, model, idxs, hard: list | None = None):
        """The values of the inputs of rules `idxs`, made readable first (see `polish`); and the model."""
        if hard is not None:
            model = self.polish(self.solver, hard, self.inputs_of(idxs), model)
        values = {}
        for k in self.inputs_of(idxs):
            inp = self.enc.inputs[k]
            values[k] = concrete(model, inp.term, inp.type, inp.members)
        externs = []
        seen = set()
        for i in idxs:
            for call in self.encs[i].calls:
                args = [concrete(model, a, t) for a, t in zip(call.args, call.arg_types)]
                value = concrete(model, call.result, call.ret)
                key = (call.func, repr(args))
                if key not in seen:
                    seen.add(key)
                    externs.append((call.func, args, value, call.arg_types, call.ret))
        return values, externs, model

    def polish(self, solver: z3.Solver, hard: list, keys: list[tuple], model):
        """A model of `hard` whose input values are simple: initial values, 0, small magnitudes, round numbers.

        A heuristic with a few extra queries per finding (never per question):
        each input in turn is pinned to the first simple value that keeps
        `hard` satisfiable, else to its current value.
        """
        solver.push()
        try:
            for h in hard:
                solver.add(h)
            for k in keys:
                inp = self.enc.inputs[k]
                model = self._simplest(solver, inp, model)
                for cst in inp.consts:
                    solver.add(cst == model.eval(cst, model_completion=True))
        finally:
            solver.pop()
        return model

    def _try(self, solver: z3.Solver, cond) -> object:
        self.st.queries += 1
        if solver.check(cond) == z3.sat:
            return solver.model()
        return None

    def _simplest(self, solver: z3.Solver, inp, model):
        t = inp.term
        pref = _preferred(self.design, self.c, inp.key)
        if inp.type is None:  # a view: keep what the solver chose
            return model
        if z3.is_bool(t) if not isinstance(t, F) else False:
            cands = [t == bool(pref)] if pref is not None else [z3.Not(t)]
            for cnd in cands:
                got = self._try(solver, cnd)
                if got is not None:
                    return got
            return model
        if isinstance(inp.type, EnumType):
            if pref is not None:
                got = self._try(solver, t == inp.type.members.index(pref))
                if got is not None:
                    return got
            return model
        if isinstance(t, F):
            cands = []
            if isinstance(pref, float) and math.isfinite(pref):
                cands.append(_and_not_nan(t, real_of(pref)))
            cands.append(_and_not_nan(t, real_of(0.0)))
            for cnd in cands:
                got = self._try(solver, cnd)
                if got is not None:
                    return got
            if z3.is_true(model.eval(t.nan, model_completion=True)):
                got = self._try(solver, z3.Not(t.nan))
                if got is None:
                    return model
                model = got
            v = to_f64(_rational_of(model.eval(t.r, model_completion=True)))
            for digits in (0, 1, 2, 3):
                r = round(v, digits)
                if r == v:
                    return model
                got = self._try(solver, _and_not_nan(t, real_of(float(r))))
                if got is not None:
                    return got
            return model
        # integers and durations: the initial value, 0, else the smallest magnitude
        cands = [t == pref] if isinstance(pref, int) and not isinstance(pref, bool) and pref != 0 else []
        cands.append(t == 0)
        for cnd in cands:
            got = self._try(solver, cnd)
            if got is not None:
                return got
        mag = z3.If(t < 0, -t, t)
        hi = model.eval(mag, model_completion=True).as_long()
        lo = 0
        if hi <= 10:
            return model
        while lo < hi:
            mid = (lo + hi) // 2
            got = self._try(solver, mag <= mid)
            if got is not None:
                model, hi = got, got.eval(mag, model_completion=True).as_long()
            else:
                lo = mid + 1
        return model

    def approx(self, idxs) -> list[str]:
        out: dict[str, None] = {}
        for i in idxs:
            e = self.encs[i]
            if e.f64_arith:
                out.setdefault(APPROX_ARITH, None)
            for a in sorted(e.approx):
                out.setdefault(a, None)
        return list(out)

    # ---- the analysis ----

    def run(self, lit_dead: dict[int, m.Rule]) -> list[_Finding]:
        out: list[_Finding] = []
        # Rules in no analysed state (`done` as a current state, E0510) and the
        # literal dead rules (E0506 from the plans family) are not analysed.
        skip = set(lit_dead) | {r.index for r in self.guarded if not self.sources(r)}
        # 1. Rules that can never fire: their condition is never true (E0513),
        # or earlier rules hide them in every state (E0506).  A rule that can
        # fire somewhere (the common case) needs no question of its own.
        live: dict[tuple[int, str], bool] = {}
        for r in self.guarded:
            if r.index in skip:
                continue
            covering: dict[int, None] = {}
            example = None
            never = False
            for s in self.sources(r):
                before = [x.index for x in self.rules_in[s] if x.index < r.index]
                lits = {i: False for i in before}
                lits[r.index] = True
                res = self.query(lits, f"whether `{r.label}` can fire in state `{s}`", r.label_span)
                live[(r.index, s)] = isinstance(res, _Sat)
                if isinstance(res, _Sat):
                    break
                cover = self.minimal_core(lits, res.core, keep=r.index)
                if not cover:  # unsat without any earlier rule: the condition itself
                    never = True
                    break
                for i in cover:
                    covering.setdefault(i, None)
                if example is None:
                    example = (s, before)
            if never:
                out.append(_Finding("E0513", [r.index], approx=self.approx([r.index])))
                skip.add(r.index)
                continue
            if any(live.get((r.index, s)) for s in self.sources(r)):
                continue
            f = _Finding("E0506", [r.index], covering=sorted(covering))
            if example is not None:
                s, before = example
                # The witness shows one of the rules the note names firing:
                # the earlier rules the note does not name are kept false
                # (else the witness could show a third rule firing first).
                ask = {r.index: True} | {i: False for i in before if i not in covering}
                res = self.query(ask, f"an example for `{r.label}`", r.label_span)
                if not isinstance(res, _Sat):
                    ask = {r.index: True}
                    res = self.query(ask, f"an example for `{r.label}`", r.label_span)
                if isinstance(res, _Sat):
                    upto = [x.index for x in self.rules_in[s] if x.index <= r.index]
                    f.witness, f.externs, model = self.witness(res.model, upto, self.lits(ask))
                    f.state = s
                    f.fires = next((i for i in before if z3.is_true(model.eval(self.p[i], model_completion=True))), None)
            f.approx = self.approx([r.index] + f.covering)
            out.append(f)
            skip.add(r.index)
        # 2. Per state: a dead `otherwise`, or inputs for which nothing fires.
        for s in self.states:
            rules = self.rules_in[s]
            idxs = [x.index for x in rules]
            other = self.otherwise.get(s)
            if other is not None:
                if other.index in lit_dead or not rules:
                    continue
                res = self.query({i: False for i in idxs}, f"whether `otherwise` of `{s}` can fire", other.label_span)
                if isinstance(res, _Unsat):
                    cover = self.minimal_core({i: False for i in idxs}, res.core)
                    out.append(_Finding("E0506", [other.index], state=s, covering=sorted(cover), approx=self.approx(idxs)))
                continue
            if not rules:
                continue
            if s == "new":
                res = self.query({i: False for i in idxs}, "whether a rule of `new` always fires", rules[0].label_span)
                if isinstance(res, _Sat):
                    w, ex, _ = self.witness(res.model, idxs, self.lits({i: False for i in idxs}))
                    out.append(_Finding("E0516", idxs, state=s, witness=w, externs=ex, fires=-1, approx=self.approx(idxs)))
            elif not self.plan.continuous:  # a continuous plan holds its state until superseded
                f = self.forever(s, rules)
                if f is not None:
                    out.append(f)
        # 3. Tautologies that hide later rules.
        for r in self.guarded:
            if r.index in skip or (isinstance(r.guard, m.Const) and r.guard.value is True):
                continue
            hidden: dict[int, None] = {}
            for s in self.sources(r):
                for x in self.rules_in[s]:
                    if x.index > r.index:
                        hidden.setdefault(x.index, None)
                o = self.otherwise.get(s)
                if o is not None:
                    hidden.setdefault(o.index, None)
            if not hidden:
                continue
            res = self.query({r.index: False}, f"whether the condition of `{r.label}` can be false", r.guard_span)
            if isinstance(res, _Unsat):
                out.append(_Finding("W0514", [r.index], hidden=sorted(hidden), approx=self.approx([r.index])))
        # 4. Pairs of rules that can both be true with different outcomes.
        if not self.plan.ordered:
            reported: set[tuple[int, int]] = set()
            for s in self.states:
                rules = [x for x in self.rules_in[s] if x.index not in skip]
                for a, ri in enumerate(rules):
                    if ri.next.kind == "error":
                        continue
                    for rj in rules[a + 1:]:
                        pair = (ri.index, rj.index)
                        if pair in reported or (_target(ri, s) == _target(rj, s) and self.jobkey(ri) == self.jobkey(rj)):
                            continue
                        if not self._live(rj, s, live):
                            continue
                        if s == "new" and ri.state.kind == "new" and rj.state.kind == "any":
                            # A `*` rule after the `new` rules (the fault-rule
                            # idiom) fires in `new` only where the `new` rules
                            # leave a gap: that gap is E0516 (once), not an
                            # overlap per `*` rule.
                            continue
                        before = [x.index for x in self.rules_in[s] if x.index < ri.index]
                        lits = {i: False for i in before}
                        lits[ri.index] = True
                        lits[rj.index] = True
                        res = self.query(lits, f"whether `{ri.label}` and `{rj.label}` can both be true in `{s}`", rj.label_span)
                        if isinstance(res, _Sat):
                            reported.add(pair)
                            upto = [x.index for x in self.rules_in[s] if x.index <= rj.index]
                            w, ex, _ = self.witness(res.model, upto, self.lits(lits))
                            out.append(_Finding("W0515", [rj.index, ri.index], state=s, witness=w, externs=ex, fires=ri.index, approx=self.approx(upto)))
        out.extend(self.held(out))
        return out

    # ---- held subordinate status (rcsc.checks.held) ----

    def held(self, found: list[_Finding]) -> list[_Finding]:
        """W0540, W0541 and W0542: the plan's paths with each subordinate's status held until it is commanded again."""
        from rcsc.checks import held as hd

        if not any(k[0] == "view" for k in self.enc.inputs):
            return []
        h = hd.Held(self)
        try:
            g = h.build()
            out: list[_Finding] = []
            by_state: dict[str, list] = {}
            for node in g.order:
                by_state.setdefault(node[0], []).append(node)
            # W0540: stalls on a held status, where W0517 finds none.
            stalled = {f.state for f in found if f.code == "W0517"}
            if not self.plan.continuous:
                for s in self.states:
                    rules = self.rules_in[s]
                    if s == "new" or s in stalled or s in self.otherwise or s not in by_state:
                        continue
                    if not any(x.state.kind == "named" for x in rules):
                        continue  # only `*` rules: a misspelt next state (E0502), not a wait
                    read = [k for k in self.inputs_of([x.index for x in rules]) if k[0] == "view"]
                    if not read:
                        continue
                    # A subordinate's ERROR that the state never tests is E0505's finding.
                    tests_error = {
                        x.sub for x in self.rules_in[s] for x in m.walk_expr(x.guard) if isinstance(x, m.SubView) and x.attr in ("error", "error_code")  # type: ignore[arg-type]
                    }
                    asked: set = set()
                    for node in by_state[s]:
                        ctx = node[1]
                        views = {}
                        for k in read:
                            p = ctx[h.subs.index(k[1])]
                            if p.verb is None:
                                continue  # a stale status: W0542's finding, varying here
                            vals = h.settled(k[1], p)
                            if vals is not None and k[1] not in tests_error:
                                vals = vals - {h.members[k[1]].index("error")}
                            if vals:
                                views[k] = vals
                        key = tuple(sorted(views.items()))
                        if not views or key in asked:
                            continue
                        asked.add(key)
                        f = self._held_stall(s, rules, views, h)
                        if f is not None:
                            f.path = g.path(node)
                            f.held = {k: [ctx[h.subs.index(k[1])].kind, ctx[h.subs.index(k[1])].by] for k in views}
                            out.append(f)
                            break
            # W0541: `done` unreachable along the held statuses.
            if not self.plan.continuous:
                import networkx as nx

                from rcsc.checks.plans import DONE as _DONE
                from rcsc.checks.plans import state_graph

                done_states = nx.ancestors(state_graph(self.plan), _DONE)
                trapped = h.trapped(g, done_states)
                # Shown where a rule to `done` is written but cannot fire (else the first such node).
                exits = {
                    n: [x.index for x in self.rules_in.get(n[0], []) + ([self.otherwise[n[0]]] if n[0] in self.otherwise else []) if x.next.kind == "done"]
                    for n in trapped
                }
                node = next((n for n in trapped if exits[n]), trapped[0] if trapped else None)
                if node is not None:
                    state, ctx = node
                    held = {("view", sub): [p.kind, p.by] for sub, p in zip(h.subs, ctx) if p.kind in ("none", "done", "error")}
                    out.append(_Finding("W0541", exits[node], state=state, path=g.path(node), held=held))
            # W0542: a wait on a subordinate not commanded on a path into the state.
            commanded = {cmd.sub for r in self.plan.rules for cmd in m.walk_stmts(r.jobs) if isinstance(cmd, m.Command)}
            for view, r, node in h.stale_waits(g, commanded):
                p = node[1][h.subs.index(view.sub)]
                out.append(_Finding("W0542", [r.index], state=node[0], path=g.path(node), held={("view", view.sub): [p.kind, p.by]}))
            return out
        except hd.TooMany:
            return [_Finding("W0518", [], reason="more paths than the held-status analysis follows", question=HELD_QUESTION)]
        except hd.Unknown as exc:
            return [_Finding("W0518", [], reason=exc.reason, question=f"{HELD_QUESTION} ({exc.question})")]

    def _live(self, r: m.Rule, s: str, live: dict) -> bool:
        if (r.index, s) in live:
            return live[(r.index, s)]
        before = [x.index for x in self.rules_in[s] if x.index < r.index]
        lits = {i: False for i in before}
        lits[r.index] = True
        res = self.query(lits, f"whether `{r.label}` can fire in state `{s}`", r.label_span)
        live[(r.index, s)] = isinstance(res, _Sat)
        return live[(r.index, s)]

    def _held_stall(self, s: str, rules: list[m.Rule], views: dict, h) -> _Finding | None:
        """W0540 for one set of held views: a stall, asked cheaply where the views decide it.

        For each combination of held values, the rules are simplified with
        the views in place: when the rules left read no fixed input, the
        state waits forever exactly when none of them can be true (one
        ordinary question); otherwise the exists-forall question is asked.
        """
        from rcsc.checks import held as hd

        keys = list(views)
        # The combinations of held values, without those in which a rule
        # certainly fires (decided on the partial combination already).
        combos: list[tuple] = []
        stack: list[tuple] = [()]
        while stack:
            part = stack.pop()
            named = {k[1]: h.members[k[1]][v] for k, v in zip(keys, part)}
            if any(hd.truth(x.guard, named) is True for x in rules):
                continue
            if len(part) == len(keys):
                combos.append(part)
                if len(combos) > 64:
                    return self.forever(s, rules, views)
                continue
            stack.extend(part + (v,) for v in sorted(views[keys[len(part)]], reverse=True))
        for combo in combos:
            remaining = []
            certain = False
            named = {k[1]: h.members[k[1]][v] for k, v in zip(keys, combo)}
            for x in rules:
                t = hd.truth(x.guard, named)
                if t is True:
                    certain = True  # this rule (or an earlier one) fires whatever the rest
                    break
                if t is None:
                    remaining.append(x.index)
            if certain:
                continue
            one = {k: {v} for k, v in zip(keys, combo)}
            fixed = [k for i in remaining for k in self.encs[i].inputs if k[0] != "view" and _is_fixed(k, self.c, self.assigned)]
            if remaining and not fixed:
                pinned = {k[1]: v for k, v in zip(keys, combo)}
                if any(any(e[0].get(i) for i in remaining) and all(h.views_of(e)[x] == v for x, v in pinned.items()) for e in h.models):
                    self.st.reused += 1
                    continue
                self.solver.push()
                try:
                    self.solver.add(z3.Or(*[self.p[i] for i in remaining]))
                    for k, v in zip(keys, combo):
                        self.solver.add(self.enc.inputs[k].term == v)
                    self.st.queries += 1
                    r = self.solver.check()
                finally:
                    self.solver.pop()
                if r == z3.sat:
                    continue  # some input fires a rule, and nothing fixed can keep it from doing so
                if r != z3.unsat:
                    raise _Incomplete(self.solver.reason_unknown() or "unknown", f"whether state `{s}` can wait forever with the subordinates' held status", rules[0].label_span)
            f = self.forever(s, rules, one)
            if f is not None:
                return f
        return None

    def _duration_cap(self, key: tuple) -> list:
        """A fixed duration without a declared range is at most the longest time in state.

        `in_state` counts whole heartbeats in 64-bit nanoseconds, so it stops
        short of 2^63 ns (292 years).  A wait `in_state >= cmd.t` ends for every
        duration it can count; a longer one is not a design's wait but the
        limit of the counter, so it is not a witness of waiting for ever.
        """
        inp = self.enc.inputs[key]
        if inp.type != DURATION or len(key) != 2:
            return []
        var = _var_of(self.design, self.c, self.plan, key[0], key[1])
        if var is None or var.range is not None:
            return []
        period = self.period or 1
        return [inp.term <= (2**63 - 1) // period * period]

    def forever(self, s: str, rules: list[m.Rule], views: dict | None = None) -> _Finding | None:
        """Exists fixed inputs such that for all other inputs no rule of `s` fires.

        `views` (W0540): subordinates' views that are fixed too, each to one
        of a set of values (member indexes): the statuses they hold.
        """
        idxs = [x.index for x in rules]
        keys = self.inputs_of(idxs)
        views = views or {}
        fixed = [k for k in keys if _is_fixed(k, self.c, self.assigned) or k in views]
        if not fixed:
            return None  # then only conditions that are never true can stall it (E0513)
        varying = [k for k in keys if k not in fixed]
        body = z3.And(*[z3.Not(self.encs[i].term) for i in idxs]) if idxs else z3.BoolVal(True)
        side = list(self.enc.side)
        # Unknown functions (externs, non-linear f64) are not chosen by the
        # adversary: their results count as inputs that vary.
        apps = _uninterpreted_apps([body] + side)
        fresh = [z3.Const(f"free.{n}", a.sort()) for n, a in enumerate(apps)]
        pairs = list(zip(apps, fresh))
        if pairs:
            body = z3.substitute(body, *pairs)
            side = [z3.substitute(x, *pairs) for x in side]
        vconsts = [cst for k in varying for cst in self.enc.inputs[k].consts] + fresh
        vcons = z3.And(*([self.enc.inputs[k].constraint for k in varying] + side)) if (varying or side) else z3.BoolVal(True)
        formula = z3.Implies(vcons, body)
        if vconsts:
            formula = z3.ForAll(vconsts, formula)
        solver = _new_solver(self.opts)
        try:
            for k in fixed:
                solver.add(self.enc.inputs[k].constraint)
                solver.add(*self._duration_cap(k))
                if k in views:
                    solver.add(z3.Or(*[self.enc.inputs[k].term == i for i in sorted(views[k])]))
            solver.add(formula)
            self.st.queries += 1
            self.st.forall_queries += 1
            r = solver.check()
            if r == z3.unsat:
                return None
            if r != z3.sat:
                what = "with the subordinates' held status" if views else ""
                raise _Incomplete(solver.reason_unknown() or "unknown", f"whether state `{s}` can wait forever{what}", rules[0].label_span)
            model = self.polish(solver, [], fixed, solver.model())
        finally:
            del solver
        values = {k: concrete(model, self.enc.inputs[k].term, self.enc.inputs[k].type, self.enc.inputs[k].members) for k in fixed}
        f = _Finding("W0540" if views else "W0517", idxs, state=s, witness=values, fires=-1, approx=self.approx(idxs))
        # One full input of that kind, for the replay.
        self.solver.push()
        try:
            for k in fixed:
                for cst in self.enc.inputs[k].consts:
                    self.solver.add(cst == model.eval(cst, model_completion=True))
            self.st.queries += 1
            r2 = self.solver.check(*[z3.Not(self.p[i]) for i in idxs])
            if r2 == z3.sat:
                f.sample, f.externs, _ = self.witness(self.solver.model(), idxs, self.lits({i: False for i in idxs}))
        finally:
            self.solver.pop()
        return f


def _and_not_nan(t: F, r):
    return _z3_and(z3.Not(t.nan), t.r == r)


def _preferred(design: Design, c: m.Controller, key: tuple):
    """The value a witness shows for an input when it can: the variable's initial value."""
    kind = key[0]
    var = None
    if kind == "gm":
        var = design.gm.get(key[1])
    elif kind == "local":
        var = c.locals.get(key[1])
    elif kind == "status":
        var = c.status_fields.get(key[1])
    elif kind == "subfield":
        sub = design.controllers.get(key[1])
        var = sub.status_fields.get(key[2]) if sub else None
        key = key[1:]
    if var is None or var.init is None:
        return None
    value = var.init
    for p in key[2:]:
        if not isinstance(value, dict):
            return None
        value = value.get(p)
    return value


def _uninterpreted_apps(terms) -> list:
    """Applications of uninterpreted functions (arity > 0) and extern constants in `terms`."""
    seen: set[int] = set()
    out = []
    stack = list(terms)
    while stack:
        t = stack.pop()
        if t.get_id() in seen:
            continue
        seen.add(t.get_id())
        if z3.is_app(t):
            d = t.decl()
            if d.kind() == z3.Z3_OP_UNINTERPRETED and (t.num_args() > 0 or d.name().startswith("extern.")):
                out.append(t)
                continue
            stack.extend(t.children())
        elif z3.is_quantifier(t):
            stack.append(t.body())
    out.sort(key=lambda t: t.get_id())
    return out


# ---- cache: plans of the same shape --------------------------------------------------------


class _Canon:
    """A canonical text of a plan's analysis problem, with its inputs numbered in order of use."""

    def __init__(self, design: Design, c: m.Controller, plan: m.Plan, assigned, period, nan: bool = True, fails: dict | None = None) -> None:
        self.design, self.c = design, c
        self.fails = {} if fails is None else fails  # (sub, verb) -> can it fail (shared by a run)
        self.keys: dict[tuple, int] = {}
        self.parts: list = [plan.ordered, period, nan]
        verb = c.verbs.get(plan.verb)
        self.params = {p.name: p for p in verb.params} if verb else {}
        self.assigned = assigned
        self.fns: set[str] = set()
        states = {"new": "new"}
        for r in plan.rules:
            for ref in (r.state, r.next):
                if ref.kind == "named" and ref.name not in states:
                    states[ref.name] = f"s{len(states)}"  # type: ignore[index]
        self.states = states
        jobs: dict = {}
        for r in plan.rules:
            nxt = r.next
            ntext = states.get(nxt.name or "", "") if nxt.kind == "named" else (nxt.kind, nxt.code)
            jk = _skey(r.jobs)
            jobs.setdefault(jk, len(jobs))
            st = states.get(r.state.name or "", "") if r.state.kind == "named" else r.state.kind
            self.parts.append(("rule", st, ntext, jobs[jk], None if r.guard is None else self.expr(r.guard), self.commands(r)))

    def commands(self, r: m.Rule) -> tuple:
        """The rule's commands as the held-status analysis sees them: which subordinate, always or in an `if`, can it fail."""
        if not r.jobs:
            return ()
        from rcsc.checks.held import commands
        from rcsc.checks.plans import failure_of

        top, nested = commands(r)
        out = []
        controllers = self.design.controllers
        for n, cmd in enumerate(top + nested):
            if cmd.sub not in controllers:
                continue
            key = (cmd.sub, cmd.verb)
            if key not in self.fails:
                self.fails[key] = failure_of(self.design, cmd.sub, cmd.verb) is not None
            # `nested` holds no command equal to one of `top` (`held.commands`).
            out.append((self.key_of(("view", cmd.sub)), n >= len(top), self.fails[key]))
        return tuple(out)

    def key_of(self, key: tuple) -> int:
        if key not in self.keys:
            self.keys[key] = len(self.keys)
            self.parts.append(("input", len(self.keys) - 1) + self.describe(key))
        return self.keys[key]

    def describe(self, key: tuple) -> tuple:
        kind = key[0]
        fixed = _is_fixed(key, self.c, self.assigned)
        if kind == "view":
            return ("view", tuple(self.design.controllers[key[1]].statuses))
        if kind in ("error_code", "age", "in_state", "cycle"):
            return (kind,)
        var = None
        if kind == "gm":
            var = self.design.gm.get(key[1])
        elif kind == "local":
            var = self.c.locals.get(key[1])
        elif kind == "status":
            var = self.c.status_fields.get(key[1])
        elif kind == "param":
            var = self.params.get(key[1])
        elif kind == "subfield":
            var = self.design.controllers[key[1]].status_fields.get(key[2])
        if var is None:
            return (kind, "?")
        rng = (var.range.lo, var.range.hi) if var.range is not None else None
        tail = key[3:] if kind == "subfield" else key[2:]
        return (kind == "param", fixed, str(var.type), rng, tail)

    def expr(self, e: m.Expr, in_fn: bool = False):
        t = type(e)
        # The common kinds first (the text is computed for every plan, cached or not).
        if t is m.Binary:
            return ("b", e.op, str(e.type), str(e.left.type), self.expr(e.left), self.expr(e.right))
        if t is m.Ref:
            if e.kind == "arg":
                return ("arg", e.name)
            return ("v", self.key_of((e.kind, e.name)), ())
        if t is m.Const:
            return ("c", str(e.type), _vkey(e.value))
        if t is m.InState:
            return ("v", self.key_of(("in_state",)))
        if t is m.Cycle:
            return ("v", self.key_of(("cycle",)))
        if t is m.SubView:
            if e.attr in ("done", "error", "executing", "status"):
                return ("view", self.key_of(("view", e.sub)), e.attr, e.value)
            if e.attr == "field":
                return ("v", self.key_of(("subfield", e.sub, e.value)))
            return ("v", self.key_of((e.attr, e.sub)))
        if t is m.Age:
            return ("v", self.key_of(("gm_age", e.name)))
        if t is m.Field:
            return ("f", self.expr(e.obj), e.name)
        if t is m.Call:
            if e.kind == "fn":
                self.fns.add(e.func)
            return ("call", e.kind, e.func, str(e.type), tuple(self.expr(a) for a in e.args))
        if t is m.Unary:
            return ("u", e.op, str(e.type), self.expr(e.operand))
        if t is m.IfExpr:
            return ("if", str(e.type), self.expr(e.cond), self.expr(e.then), self.expr(e.else_))
        return ("?", t.__name__)

    def key(self) -> tuple:
        # The values a witness prefers for the inputs (`_preferred`: their
        # initial values) belong to the shape: two plans that differ only
        # there would otherwise share one witness, and which one depended on
        # which plan was analysed first (a check without the cache against a
        # re-check of one controller).
        preferred = tuple(_vkey(_preferred(self.design, self.c, k)) for k in self.keys)
        return (*self.parts, preferred)


# ---- reporting -------------------------------------------------------------------------


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


# ---- the on-disk cache -----------------------------------------------------------------------
#
# The in-memory cache above shares one analysis between plans of the same
# shape.  The on-disk one (rcsc.checks.cache) is keyed more narrowly, so that a
# stored result is exactly what analysing the plan again would give: the
# plan's shape, the real names of its inputs, states, controller and verb,
# the values a witness prefers (initial values), the definitions of every
# type and function of the design, and the solver budget.


def _stored_key(design: Design, c: m.Controller, plan: m.Plan, canon: _Canon, opts: Options) -> str:
    from rcsc.checks.cache import digest

    preferred = tuple((k, _vkey(_preferred(design, c, k))) for k in canon.keys)
    return digest(
        (
            "guards",
            opts.timeout_ms,
            opts.rlimit,
            c.name,
            plan.verb,
            plan.continuous,
            canon.key(),
            tuple(canon.keys),
            tuple(canon.states.items()),
            preferred,
            _definitions_key(design),
        )
    )


# The design whose definitions were digested last (a weak reference: the
# memo must not keep a checked design alive) and the digest: the same for
# every plan of a check.
_definitions_memo: list = [None, ""]


def _definitions_key(design: Design) -> str:
    """A digest of the definitions of every type and function of `design`."""
    from rcsc.checks.cache import digest

    import weakref

    if _definitions_memo[0] is not None and _definitions_memo[0]() is design:
        return _definitions_memo[1]
    types = (
        tuple((n, tuple(t.members)) for n, t in sorted(design.enums.items())),
        tuple((n, tuple((fn, str(ft), _range_key(t.field_range(fn))) for fn, ft in t.fields)) for n, t in sorted(design.records.items())),
    )
    fns = tuple(
        (
            f.name,
            f.extern,
            str(f.ret),
            tuple((p.name, str(p.type), p.range and (p.range.lo, p.range.hi)) for p in f.params),
            None if f.body is None else _ekey(f.body),
        )
        for _, f in sorted(design.functions.items())
    )
    key = digest(("definitions", types, fns))
    _definitions_memo[:] = [weakref.ref(design), key]
    return key


def _range_key(rng) -> tuple | None:
    return None if rng is None else (_vkey(rng.lo), _vkey(rng.hi))


def _load(store, key: str, design: Design) -> list[_Finding] | None:
    from rcsc.checks.cache import decode

    data = store.get(key)
    if not isinstance(data, list):
        return None
    types = {**design.enums, **design.records}
    names = {fl.name for fl in fields(_Finding)}
    try:
        out = []
        for item in data:
            values = decode(item, types)
            if not isinstance(values, dict) or set(values) != names - {"span"}:
                return None
            out.append(_Finding(**values))
        return out
    except (KeyError, ValueError, TypeError, OverflowError):
        return None


def _save(store, key: str, findings: list[_Finding]) -> None:
    from rcsc.checks.cache import NotStorable, encode

    if any(f.span is not None for f in findings):
        return  # spans belong to this run's source files
    try:
        data = [encode({fl.name: getattr(f, fl.name) for fl in fields(_Finding) if fl.name != "span"}) for f in findings]
    except NotStorable:
        return
    store.put(key, data)


def _rename_key(key: tuple, mapping: dict[tuple, tuple]) -> tuple:
    for n in (3, 2, 1):
        base = key[:n]
        if base in mapping:
            return mapping[base] + key[n:]
    return key


def _rename(f: _Finding, mapping: dict, states: dict) -> _Finding:
    """A cached plan's finding in the names of a plan of the same shape."""
    g = _Finding(**{fl.name: getattr(f, fl.name) for fl in fields(_Finding)})
    g.state = states.get(f.state, f.state) if f.state is not None else None
    g.witness = {_rename_key(k, mapping): v for k, v in f.witness.items()}
    g.sample = {_rename_key(k, mapping): v for k, v in f.sample.items()}
    g.held = {_rename_key(k, mapping): v for k, v in f.held.items()}
    return g


def _reason_text(reason: str) -> str:
    if reason in ("canceled", "timeout") or "resource limit" in reason:
        return f"it ran out of its budget (a resource limit of {RLIMIT:,} units or {TIMEOUT_MS / 1000:g} s per question by default; solver: {reason})"
    return reason


def _labels(plan: m.Plan, idxs) -> str:
    names = [f"`{plan.rules[i].label}`" for i in idxs]
    if len(names) <= 1:
        return "".join(names)
    return ", ".join(names[:-1]) + " and " + names[-1]


def _report(design: Design, c: m.Controller, plan: m.Plan, f: _Finding, diags: Diagnostics) -> None:
    rules = plan.rules
    where = f"plan `{plan.verb}` of `{c.name}`"
    data: dict = {"controller": c.name, "plan": plan.verb}
    d: Diagnostic
    if f.code == "W0518":
        span = f.span or plan.name_span
        d = diags.add("W0518", span, f"guard analysis of {where} is incomplete", "not analysed")
        d.with_note(f"the solver could not decide {f.question}: {_reason_text(f.reason)}")
        if f.question.startswith(HELD_QUESTION):
            d.with_note("the held-status findings of this plan (W0540, W0541, W0542) were not computed")
        else:
            d.with_note("the rest of this plan's conditions were not analysed")
        d.with_help("simplify the condition, or move arithmetic into `pre` (a local the rule compares)")
        data["reason"] = f.reason
        d.data = data
        return
    if f.code in ("W0540", "W0541", "W0542"):
        _report_held(design, c, plan, f, diags, data)
        return
    main = rules[f.rules[0]]
    data["rules"] = [rules[i].label for i in f.rules]
    if f.state is not None:
        data["state"] = f.state
    if f.code == "E0513":
        d = diags.add("E0513", main.guard_span, f"the condition of rule `{main.label}` is never true", "always false")
        d.with_note(f"so `{main.label}` can never fire, wherever it stands in the table")
        d.with_help("correct the condition, or remove the rule")
    elif f.code == "W0514":
        d = diags.add("W0514", main.guard_span, f"the condition of rule `{main.label}` is always true", "always true")
        d.with_note(f"it hides {_labels(plan, f.hidden)} after it" + (", which can never fire" if f.hidden else ""))
        d.with_help("write `true` if that is meant, or correct the condition")
        data["hidden"] = [rules[i].label for i in f.hidden]
    elif f.code == "E0506":
        what = "`otherwise`" if main.otherwise else f"rule `{main.label}`"
        d = diags.add("E0506", main.label_span, f"{what} can never fire", "dead rule")
        for i in f.covering:
            d.with_label(rules[i].guard_span, f"`{rules[i].label}`")
        if main.otherwise:
            d.with_note(f"in state `{f.state}` the rules {_labels(plan, f.covering)} together match every input")
        else:
            d.with_note(f"whenever its condition holds, an earlier rule matches: {_labels(plan, f.covering)}")
        data["covered_by"] = [rules[i].label for i in f.covering]
    elif f.code == "E0516":
        own = [i for i in f.rules if rules[i].state.kind == "new"]
        main = rules[own[0]] if own else main
        d = diags.add("E0516", main.label_span, f"a new `{plan.verb}` command can leave every rule of `new` false", "no rule fires")
        for i in f.rules:
            if rules[i] is not main:
                d.with_label(rules[i].label_span, "also false")
        d.with_note(f"then the command is accepted (status EXEC) and {where} stays in `new`")
        d.with_help("add a rule for the missing case, or an `otherwise` rule for `new`")
    elif f.code == "W0517":
        d = diags.add("W0517", main.label_span, f"state `{f.state}` of {where} can wait forever", "no rule can fire")
        d.with_note("no rule of the state can fire, whatever the inputs that change while it waits (subordinates, sensors, time in state)")
        d.with_help(f"add a rule for this case, an `otherwise` for `{f.state}`, or a time-out (`in_state >= ...`)")
    elif f.code == "W0515":
        first = rules[f.fires]  # type: ignore[index]
        d = diags.add("W0515", main.label_span, f"rules `{first.label}` and `{main.label}` can both be true in state `{f.state}`", "also true")
        d.with_label(first.label_span, f"`{first.label}` fires first")
        d.with_note(f"`{first.label}` (-> {_next_text(first)}) fires and `{main.label}` (-> {_next_text(main)}) does not: the order of the table decides")
        d.with_note(f"they differ in {_difference(first, main, f.state or '')}")
        d.with_help("if neither should win for this input (an off-by-one, a missing `and not ...`), make the conditions exclusive")
        d.with_help(
            f"if `{first.label}` must win (a priority), say so here with `// rcsc: allow(W0515) why` on `{main.label}`'s line; "
            f"`plan {plan.verb} ordered` declares every overlap of the table intended and hides real ones too"
        )
    else:  # pragma: no cover
        raise KeyError(f.code)
    if f.witness:
        text, wjson = _witness_text(design, c, plan, f.witness)
        ext_text, ext_json = _externs_text(f.externs)
        if f.code == "W0517":
            d.with_note(f"witness: {text}" + " (fixed while the plan waits)")
        elif f.code == "E0506":
            fired = rules[f.fires].label if f.fires is not None else "an earlier rule"
            d.with_note(f"witness: {text}{ext_text}: `{main.label}`'s condition holds but `{fired}` fires")
            data["fires"] = fired
        else:
            d.with_note(f"witness: {text}{ext_text}")
        data["witness"] = wjson
        if ext_json:
            data["externs"] = ext_json
        if f.sample:
            data["sample"] = _witness_text(design, c, plan, f.sample)[1]
        if f.code in ("E0516", "W0517"):
            data["fires"] = None
        elif f.code == "W0515":
            data["fires"] = rules[f.fires].label  # type: ignore[index]
        ok = _replays(design, c, plan, f)
        if not ok:
            d.with_note("the witness is approximate: rounded to doubles, the reference evaluator does not show the claim")
        data["replayed"] = ok
    if f.approx:
        d.with_note("approximate: " + "; ".join(f.approx))
        data["approximate"] = list(f.approx)
    d.data = data


def path_states(plan: m.Plan, path: list[int]) -> list[tuple[m.Rule, str, str]]:
    """The steps of a path from `new`: (rule, state it fires in, state it leads to)."""
    from rcsc.checks.plans import rule_target

    out, cur = [], "new"
    for i in path:
        r = plan.rules[i]
        nxt = rule_target(r, cur) or cur
        out.append((r, cur, nxt))
        cur = nxt
    return out


def _path_text(plan: m.Plan, path: list[int]) -> str:
    if not path:
        return "the entry"
    return ", ".join(f"`{r.label}` ({a} -> {b})" for r, a, b in path_states(plan, path))


_HELD_TEXT = {
    "any": "`{sub}` was not commanded by this plan on this path (a stale status)",
    "none": "`{sub}` has never been commanded",
    "run": "`{sub}` is executing `{verb}` sent by `{by}`; then its DONE or ERROR holds",
    "done": "`{sub}` holds DONE (last commanded by `{by}`): nothing commands it again",
    "error": "`{sub}` holds ERROR (last commanded by `{by}`): nothing commands it again",
}


def _held_text(plan: m.Plan, sub: str, kind: str, by: int) -> str:
    if by < 0 and kind in ("done", "error"):
        return f"`{sub}` holds {kind.upper()} left over from an earlier command: this plan did not command it on this path"
    label = plan.rules[by].label if by >= 0 else "?"
    verb = next((j.verb for j in m.walk_stmts(plan.rules[by].jobs) if isinstance(j, m.Command) and j.sub == sub), "?") if by >= 0 else "?"
    return _HELD_TEXT[kind].format(sub=sub, by=label, verb=verb)


def _report_held(design: Design, c: m.Controller, plan: m.Plan, f: _Finding, diags: Diagnostics, data: dict) -> None:
    """W0540, W0541 and W0542 (`_Analysis.held`): the witness is a path from `new` and the statuses held at its end."""
    from rcsc.checks.plans import _first_mention

    rules = plan.rules
    where = f"plan `{plan.verb}` of `{c.name}`"
    data["state"] = f.state
    data["path"] = [rules[i].label for i in f.path]
    data["held"] = {k[1]: v[0] for k, v in f.held.items()}
    data["commanded_by"] = {k[1]: (rules[v[1]].label if v[1] >= 0 else None) for k, v in f.held.items()}
    held_notes = [_held_text(plan, k[1], v[0], v[1]) for k, v in f.held.items()]
    if f.code == "W0540":
        own = [i for i in f.rules if rules[i].state.kind == "named"]
        main = rules[(own or f.rules)[0]]
        data["rules"] = [rules[i].label for i in f.rules]
        d = diags.add("W0540", main.label_span, f"state `{f.state}` of {where} can wait forever on a subordinate's held status", "no rule can fire")
        d.with_note(f"path: {_path_text(plan, f.path)}")
        for n in held_notes:
            d.with_note(n)
        text, wjson = _witness_text(design, c, plan, f.witness)
        d.with_note(f"witness: {text} (held while the plan waits): no rule of `{f.state}` can fire")
        d.with_help("command the subordinate on the way into the state, add a rule for the status it holds, or a time-out (`in_state >= ...`)")
        data["witness"] = wjson
        data["fires"] = None
        if f.sample:
            data["sample"] = _witness_text(design, c, plan, f.sample)[1]
        ok = _replays(design, c, plan, f)
        if not ok:
            d.with_note("the witness is approximate: rounded to doubles, the reference evaluator does not show the claim")
        data["replayed"] = ok
        if f.approx:
            d.with_note("approximate: " + "; ".join(f.approx))
            data["approximate"] = list(f.approx)
    elif f.code == "W0541":
        ref = _first_mention(plan, f.state or "") if f.state != "new" else None
        span = rules[f.rules[0]].label_span if f.rules else ref.span if ref is not None else plan.name_span
        what = f"once in state `{f.state}` by this path, {where}" if f.path else where
        label = f"cannot lead to `done` here" if f.rules else "`done` unreachable"
        d = diags.add("W0541", span, f"{what} can only fail", label)
        data["rules"] = [rules[i].label for i in f.rules]
        d.with_note(f"path: {_path_text(plan, f.path)}")
        for n in held_notes:
            d.with_note(n)
        d.with_note("the rules on the way to `done` need a status the subordinates cannot report until they are commanded again: only `error(...)` exits remain")
        d.with_help("command the subordinate again before waiting on a new status, or test the status it holds")
    else:  # W0542
        r = rules[f.rules[0]]
        sub = next(iter(f.held))[1]
        view = next(x for x in m.walk_expr(r.guard) if isinstance(x, m.SubView) and x.sub == sub and x.attr in ("done", "status", "executing"))  # type: ignore[arg-type]
        data["rules"] = [r.label]
        d = diags.add("W0542", view.span, f"state `{f.state}` of {where} waits on `{sub}`, which this plan has not commanded on every way in", "stale status")
        d.with_note(f"path: {_path_text(plan, f.path)}: no rule on it commands `{sub}`")
        d.with_note(f"`{sub}`'s status still answers an earlier command (or none): the wait ends at once on a stale DONE, or never")
        d.with_help(f"command `{sub}` on every way into `{f.state}`, or wait on it only where it was commanded")
    d.data = data


def _witness_text(design: Design, c: m.Controller, plan: m.Plan, values: dict) -> tuple[str, dict]:
    parts, out = [], {}
    for key, value in values.items():
        name, t = _name_type(design, c, plan, key)
        parts.append(f"{name} = {format_value(value, t)}")
        out[name] = json_value(value, t)
    return ", ".join(parts), out


def _externs_text(externs: list) -> tuple[str, list]:
    if not externs:
        return "", []
    parts, out = [], []
    for func, args, value, arg_types, ret in externs:
        call = f"{func}({', '.join(format_value(a, t) for a, t in zip(args, arg_types))})"
        parts.append(f"{call} = {format_value(value, ret)}")
        out.append({"function": func, "args": [json_value(a, t) for a, t in zip(args, arg_types)], "value": json_value(value, ret)})
    return ", with " + ", ".join(parts), out


def _name_type(design: Design, c: m.Controller, plan: m.Plan, key: tuple) -> tuple[str, Type | None]:
    kind = key[0]
    if kind == "in_state":
        return "in_state", DURATION
    if kind == "cycle":
        from rcsc.semantics.types import I64

        return "cycle", I64
    if kind == "view":
        return key[1], None
    if kind == "error_code":
        from rcsc.semantics.types import I32

        return f"{key[1]}.error_code", I32
    if kind == "age":
        return f"{key[1]}.age", DURATION
    if kind == "gm_age":
        return f"age({key[1]})", DURATION
    if kind == "subfield":
        var = design.controllers[key[1]].status_fields[key[2]]
        return _path_name(key[1:]), _leaf_type(var.type, key[3:])
    var = _var_of(design, c, plan, kind, key[1])
    prefix = "cmd." if kind == "param" else ""
    return prefix + _path_name(key[1:]), _leaf_type(var.type, key[2:]) if var else None


def _path_name(path: tuple) -> str:
    """`w.xs[2].x` from ("w", "xs", 2, "x"): an int in a key is an array index."""
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def _path_parts(name: str) -> tuple:
    """The inverse of `_path_name`."""
    return tuple(int(i) if i else f for f, i in re.findall(r"([^.\[\]]+)|\[(\d+)\]", name))


def _var_of(design: Design, c: m.Controller, plan: m.Plan, kind: str, name: str) -> m.Var | None:
    if kind == "gm":
        return design.gm.get(name)
    if kind == "local":
        return c.locals.get(name)
    if kind == "status":
        return c.status_fields.get(name)
    if kind == "param":
        verb = c.verbs.get(plan.verb)
        return verb.param(name) if verb else None
    return None


def _leaf_type(t: Type, path: tuple) -> Type:
    for p in path:
        if isinstance(p, int):
            assert isinstance(t, ArrayType)
            t = t.elem
            continue
        assert isinstance(t, RecordType)
        t = t.field_type(p)  # type: ignore[assignment]
    return t


# ---- replay: the witness in the reference simulator ------------------------------------------


def witness_keys(design: Design, controller: str, plan_verb: str, witness: dict) -> dict[tuple, object]:
    """Parse a JSON witness (`Diagnostic.data["witness"]`) back into input keys and simulator values."""
    c = design.controllers[controller]
    plan = c.plans[plan_verb]
    subs = {u.name for u in c.subordinates}
    out = {}
    for name, value in witness.items():
        parts = _path_parts(name)
        if name == "in_state":
            key = ("in_state",)
        elif name == "cycle":
            key = ("cycle",)
        elif name.startswith("age(") and name.endswith(")"):
            key = ("gm_age", name[4:-1])
        elif parts[0] == "cmd":
            key = ("param",) + parts[1:]
        elif parts[0] in subs:
            if len(parts) == 1:
                key = ("view", parts[0])
            elif parts[1] in ("error_code", "age"):
                key = (parts[1], parts[0])
            else:
                key = ("subfield",) + parts
        elif parts[0] in c.locals:
            key = ("local",) + parts
        elif parts[0] in c.status_fields:
            key = ("status",) + parts
        else:
            key = ("gm",) + parts
        _, t = _name_type(design, c, plan, key)
        out[key] = _from_json(value, t)
    return out


def _from_json(value, t: Type | None):
    if isinstance(t, EnumType) and isinstance(value, str):
        return value.split(".", 1)[1] if "." in value else value
    if isinstance(t, FloatType):
        if isinstance(value, str):
            return {"NaN": math.nan, "inf": math.inf, "-inf": -math.inf}[value]
        return float(value)
    return value


def extern_table(externs: list) -> dict:
    """Extern implementations that return the witness's values (for a Simulator's `externs`)."""
    table: dict[str, list] = {}
    for item in externs:
        if isinstance(item, dict):  # from Diagnostic.data["externs"] (JSON values)
            func, args, value = item["function"], item["args"], item["value"]
        else:
            func, args, value = item[:3]
        table.setdefault(func, []).append((args, value))

    def make(entries):
        def impl(*args):
            for a, v in entries:
                if _same(list(args), a):
                    return v
            return entries[0][1]

        return impl

    return {f: make(e) for f, e in table.items()}


def _same(a, b) -> bool:
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def apply_witness(sim, controller: str, plan: m.Plan, state: str, values: dict[tuple, object]):
    """Put `sim`'s runtime of `controller` into `state` of `plan` with the witness's inputs.

    `sim` is a `rcsc.sim.simulate.Simulator` (or anything with its `design`,
    `cycle`, `now`, `period_ns` and `externs`).  Returns the `_StepEnv` to pass to
    `Simulator.select_rule(plan, state, env)`.  Inputs the witness does not
    name keep their initial values.
    """
    from rcsc.sim.simulate import CommandBuffer, ControllerRuntime, StatusBuffer, _StepEnv, clone, zero_value

    design = sim.design
    c = design.controllers[controller]
    runtimes = getattr(sim, "runtimes", None)
    rt = runtimes[controller] if runtimes is not None else ControllerRuntime(c)
    rt.plan, rt.idle = plan, False
    rt.status.state = state
    rt.gm = {u.name: clone(design.gm[u.name].init) for u in rt.gm_uses if u.name in design.gm}
    verb = c.verbs[plan.verb]
    rt.cmd = CommandBuffer(1, plan.verb, {p.name: zero_value(p.type) for p in verb.params})
    rt.status.echo_serial = 1
    rt.subs = {}
    for u in c.subordinates:
        sc = design.controllers[u.name]
        rt.subs[u.name] = StatusBuffer(fields={k: clone(v.init) for k, v in sc.status_fields.items()})
        rt.last_sent[u.name] = 0
    in_state, ages = 0, {}
    for key, value in values.items():
        kind = key[0]
        if kind == "in_state":
            in_state = int(value)  # type: ignore[call-overload]
        elif kind == "cycle":
            rt.cycle_at = int(value)  # type: ignore[call-overload]
        elif kind == "age":
            ages[("sub", key[1])] = int(value)  # type: ignore[call-overload]
        elif kind == "gm_age":
            ages[("gm", key[1])] = int(value)  # type: ignore[call-overload]
        elif kind == "view":
            st = rt.subs[key[1]]
            if value == "none":
                rt.last_sent[key[1]] = 0
            else:
                rt.last_sent[key[1]] = 2
                st.echo_serial = 1 if value == "executing" else 2
                st.status = {"executing": m.EXEC, "done": m.DONE, "error": m.ERROR}.get(
                    value, design.controllers[key[1]].statuses.get(value, m.EXEC)  # type: ignore[arg-type]
                )
        elif kind == "error_code":
            rt.subs[key[1]].error_code = int(value)  # type: ignore[call-overload]
        elif kind == "subfield":
            _store(rt.subs[key[1]].fields, key[2:], value)
        elif kind == "param":
            _store(rt.cmd.args, key[1:], value)
        elif kind == "local":
            _store(rt.locals, key[1:], value)
        elif kind == "status":
            _store(rt.fields, key[1:], value)
        elif kind == "gm":
            _store(rt.gm, key[1:], value)
    # Durations are in ns: the step happens late enough for every age and
    # `in_state` of the witness (all whole periods, so the instants are real).
    sim.now = max([in_state] + list(ages.values()))
    period = getattr(sim, "period_ns", 0) or 1
    sim.cycle = 1 + sim.now // period
    rt.entry_ns = sim.now - in_state
    # Stamps the witness does not name: never written (one base tick before 0).
    never = -(design.base_tick_ns or period)
    gm_stamp = sim.gm_stamp = {n: never for n in design.gm}
    for (what, name), age in ages.items():
        if what == "sub":
            rt.subs[name].stamp = sim.now - age
        else:
            gm_stamp[name] = sim.now - age
    return _StepEnv(sim, rt)


def _store(container: dict, path: tuple, value) -> None:
    for p in path[:-1]:
        container = container[p]
    container[path[-1]] = value


def _replays(design: Design, c: m.Controller, plan: m.Plan, f: _Finding) -> bool:
    """Whether the reference simulator's rule selection shows the finding at its witness."""
    from rcsc.semantics.evaluate import eval_expr
    from rcsc.sim.simulate import Simulator

    values = f.sample if f.code in ("W0517", "W0540") else f.witness
    if f.state is None or not values and f.code != "W0517":
        return True
    cpu = design.cpus.get(c.cpu) if c.cpu else None
    sim = SimpleNamespace(design=design, cycle=0, now=0, period_ns=cpu.heartbeat_ns if cpu else 1, externs=extern_table(f.externs))
    try:
        env = apply_witness(sim, c.name, plan, f.state, values)
        fired = Simulator.select_rule(None, plan, f.state, env)  # type: ignore[arg-type]
        if f.code in ("E0516", "W0517", "W0540"):
            return fired is None
        main = plan.rules[f.rules[0]]
        if f.fires is None or fired is None or fired.index != f.fires:
            return False
        return bool(eval_expr(main.guard, env)) if main.guard is not None else True
    except Exception:  # noqa: BLE001 - a witness that cannot be replayed is approximate, not a crash
        return False
