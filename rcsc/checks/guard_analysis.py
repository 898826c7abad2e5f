"""The per-plan analysis of the guard family: the questions asked of z3 about one plan.

`rcsc.checks.guards` (the family) runs one `_Analysis` per plan shape; this
module holds it, the solver's budget, the findings it returns
(`_Finding`, before they are reported), the keys that describe a plan's
structure (the same-shape cache and the value analysis share them) and the
names and types of the analysis' inputs (the report and the replay of a
witness need them too).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import z3

from rcsc.semantics import model as m
from rcsc.checks.plans import plan_states, rule_sources
from rcsc.semantics.model import Design
from rcsc.checks.smt import APPROX_ARITH, F, Encoder, Encoding, HasTypeError, Unsupported, concrete, neg, real_of, to_f64
from rcsc.checks.smt import _and as _z3_and
from rcsc.checks.smt import _rational as _rational_of
from rcsc.front.source import Span
from rcsc.semantics.types import DURATION, ArrayType, EnumType, RecordType, Type

if TYPE_CHECKING:
    from rcsc.checks.guards import Options, Stats


# The budget of one solver query.  The resource limit is deterministic (the
# same answer on every machine; 2M units take about 0.8 s on a 2024 laptop,
# up to 2.5 s on a loaded 2-core CI machine).  The wall-clock time-out is
# only a safety net for a query whose work z3 does not count: it must never
# be what stops an ordinary query, or the findings would depend on the
# machine's load (a question decided on a quiet machine, W0518 on a busy
# one).  So it is far above what the resource limit allows.
TIMEOUT_MS = 60_000
RLIMIT = 2_000_000


HELD_QUESTION = "the subordinates' held status along the plan's paths"


class _Incomplete(Exception):
    def __init__(self, reason: str, question: str, span: Span | None) -> None:
        super().__init__(reason)
        self.reason = reason
        self.question = question
        self.span = span


def _new_solver(opts: Options) -> z3.Solver:
    s = z3.Solver()
    s.set("timeout", int(opts.timeout_ms))
    if opts.rlimit:
        s.set("rlimit", int(opts.rlimit))
    return s


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
                from rcsc.checks.plans import DONE as _DONE
                from rcsc.checks.plans import state_graph

                done_states = state_graph(self.plan).ancestors(_DONE)
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
