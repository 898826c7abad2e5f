"""Held subordinate status: what a plan can see of its subordinates on each path.

A subordinate's status answers the last command it was sent and stays until
it is commanded again: EXEC while it works, then DONE or ERROR (ERROR only if
it can fail for that verb, `rcsc.checks.plans.failure_of`), held; a
`continuous` plan may instead never end, holding EXEC or an extra status it
reports (`rcsc.checks.plans.held_statuses`).  The guard
analysis (`rcsc.checks.guards`) treats a subordinate's view as an input that
can take any value in any cycle; this module follows the plan's paths
instead.  For every state it computes the *contexts* in which the plan can be
there: for each subordinate the plan's conditions read, its phase

    any      not commanded by this plan on the path (a stale status: anything)
    none     seen never commanded at all, held
    run      commanded on the path (by verb V), may still be executing
    done     seen DONE since the last command, held
    error    seen ERROR since the last command, held

and whether this plan commanded it on the path (and with which verb).  A
rule can fire in a context when its condition, the earlier rules of the
state false, and the subordinates' views allowed by their phases are
satisfiable together (the plan's own solver answers, under assumptions); the
phase after the rule is what its condition saw, then each command of its job
list starts a new `run`.  The result is a graph over (state, context) pairs,
built breadth-first from (`new`, every subordinate `any`), which the guard
analysis turns into three findings:

W0540 a state can wait forever on a held status (`stalls`)
    In a context of the state, the subordinates' statuses settle (a `run`
    ends DONE, or ERROR when it can fail) and then hold: the exists-forall
    question of W0517 with those statuses among the fixed inputs.  Asked only
    for states whose rules read a subordinate and that W0517 does not report.
W0541 `done` unreachable along the held statuses (`trapped`)
    From a (state, context) reachable from `new` the plan can still fail but
    no longer reach `done`, although the state graph has a way to `done`:
    the rules on that way need a status the subordinates cannot have there
    (a loop whose only exits are `*` error rules).
W0542 a wait on a subordinate not commanded on a path into the state (`stale`)
    A rule of a state (not `new`) tests `SUB.done`, `.executing` or an extra
    status of SUB, and on some path into the state this plan has not
    commanded SUB (the plan commands it elsewhere; W0522 covers a plan that
    never does): the wait reads a status left over from an earlier command.

Each finding carries the path from `new` (rule indexes) as its witness; the
stall's also holds the fixed inputs, and is replayed like W0517's.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import z3

from rcsc.semantics import model as m
from rcsc.checks.guard_analysis import rule_vector
from rcsc.checks.smt import neg
from rcsc.checks.plans import DONE, ERROR, failure_of, held_statuses, rule_target

MAX_CONTEXTS = 32  # per state
MAX_NODES = 2000  # per plan
WAIT_ATTRS = ("done", "status", "executing")
_VIEW_OF = {"DONE": "done"}  # a status's name -> its member of a subordinate's view


class TooMany(Exception):
    """The plan has more (state, context) pairs than the analysis follows."""


class Unknown(Exception):
    """The solver could not answer a question of this analysis."""

    def __init__(self, reason: str, question: str, span) -> None:
        super().__init__(reason)
        self.reason, self.question, self.span = reason, question, span


@dataclass(frozen=True)
class Phase:
    kind: str  # any, none, run, done, error
    verb: str | None = None  # the verb this plan last sent on the path; None: not commanded
    by: int = -1  # index of the rule that sent it


@dataclass
class Graph:
    subs: list[str]
    nodes: dict = field(default_factory=dict)  # (state, ctx) -> (parent node, rule index) or None
    order: list = field(default_factory=list)  # nodes in breadth-first order
    edges: dict = field(default_factory=dict)  # node -> set of successor nodes (or DONE / ERROR)

    def path(self, node) -> list[int]:
        out = []
        while self.nodes.get(node) is not None:
            node, r = self.nodes[node]
            out.append(r)
        return out[::-1]


def commands(rule: m.Rule) -> tuple[list[m.Command], list[m.Command]]:
    """The rule's commands: those always sent, and those sent only in some branch of an `if`."""
    top = [j for j in rule.jobs if isinstance(j, m.Command)]
    every = list(m.walk_stmts(rule.jobs))
    if len(every) == len(rule.jobs):
        return top, []  # no nested statements: every command is a top one
    nested = [j for j in every if isinstance(j, m.Command) and j not in top]
    return top, nested


class Held:
    """The (state, context) graph of one plan, over the guard analysis `an` (a `guard_analysis._Analysis`)."""

    def __init__(self, an) -> None:
        self.an = an
        self.subs = [k[1] for k in an.enc.inputs if k[0] == "view"]
        self.members = {s: an.enc.inputs[("view", s)].members for s in self.subs}
        self.view = {s: an.enc.inputs[("view", s)].term for s in self.subs}
        self.lit: dict[tuple[str, int], z3.BoolRef] = {}  # made when a question first pins a view
        self.fail: dict[tuple[str, str | None], bool] = {}
        self.holding: dict[tuple[str, str | None], list[str] | None] = {}
        self.models: list[list] = []  # [rule vector, view values (None: not read yet), z3 model] of each model found
        self.memo: dict = {}
        self.seen = 0  # how many of the guard analysis's models are in `models`

    def literal(self, sub: str, i: int) -> z3.BoolRef:
        """A Boolean that is `sub`'s view == member i (an assumption literal for the solver)."""
        if (sub, i) not in self.lit:
            b = z3.Bool(f"held.{sub}.{i}")
            self.an.solver.add(b == (self.view[sub] == i))
            self.lit[(sub, i)] = b
        return self.lit[(sub, i)]

    # ---- phases ----

    def can_fail(self, sub: str, verb: str | None) -> bool:
        key = (sub, verb)
        if key not in self.fail:
            self.fail[key] = verb is None or failure_of(self.an.design, sub, verb) is not None
        return self.fail[key]

    def values(self, sub: str, kind: str, verb: str | None) -> frozenset[int]:
        """The view values (member indexes) a phase allows now."""
        mem = self.members[sub]
        if kind == "any":
            return frozenset(range(len(mem)))
        if kind in ("none", "done", "error"):
            return frozenset([mem.index(kind)])
        out = {mem.index("executing"), mem.index("done")} | set(range(4, len(mem)))
        if self.can_fail(sub, verb):
            out.add(mem.index("error"))
        return frozenset(out)

    def settled(self, sub: str, p: Phase) -> frozenset[int] | None:
        """The values a phase ends in and then holds while nothing commands the subordinate (None: any, varying)."""
        mem = self.members[sub]
        if p.kind == "any":
            return None
        if p.kind != "run":
            return frozenset([mem.index(p.kind)])
        holds = self.holds(sub, p.verb)
        # A continuous plan need not end: it holds the status its last rule
        # reported.  One that stays executing (a regulator, a stub) is still
        # at work, so EXEC is not a status the plan could wait on for ever.
        out = {mem.index("done")} if holds is None else {mem.index(_VIEW_OF.get(x, x)) for x in holds if x != "EXEC"}
        if self.can_fail(sub, p.verb):
            out.add(mem.index("error"))
        return frozenset(out)

    def holds(self, sub: str, verb: str | None) -> list[str] | None:
        key = (sub, verb)
        if key not in self.holding:
            self.holding[key] = None if verb is None else held_statuses(self.an.design, sub, verb)
        return self.holding[key]

    @staticmethod
    def cls(members: tuple[str, ...], i: int) -> str:
        name = members[i]
        return name if name in ("none", "done", "error") else "run"

    # ---- questions ----

    def pull(self) -> None:
        """Take in the guard analysis's models found since the last call (views not read yet)."""
        an = self.an
        while self.seen < len(an.vectors):
            v = an.vectors[self.seen]
            self.seen += 1
            self.models.append([v.vec, None, v.model])

    def views_of(self, entry: list) -> dict:
        """The subordinates' views in one model of `models` ([rule vector, views or None, z3 model])."""
        if entry[1] is None:
            model = entry[2]
            entry[1] = {s: model.eval(self.view[s], model_completion=True).as_long() for s in self.subs}
            entry[2] = None
        return entry[1]

    def sat(self, lits: dict[int, bool], allowed: dict[str, frozenset[int]], what: str, span) -> dict | None:
        """The subordinates' views of an input where `lits` hold and each view is allowed (None: there is none)."""
        key = (tuple(sorted(lits.items())), tuple(sorted(allowed.items())))
        if key in self.memo:
            return self.memo[key]
        an = self.an
        if not allowed and key[0] in an.unsat:  # the guard analysis asked this already
            an.st.reused += 1
            return None
        # The guard analysis's own models first, then this analysis's; a
        # model's views are read only when its rule vector matches.
        self.pull()
        for entry in self.models:
            vec = entry[0]
            if all(vec[i] == b for i, b in lits.items()):
                views = self.views_of(entry)
                if all(views[s] in vals for s, vals in allowed.items()):
                    an.st.reused += 1
                    self.memo[key] = views
                    return views
        assumptions = an.lits(lits)
        for s, vals in allowed.items():
            for i in range(len(self.members[s])):
                if i not in vals:
                    assumptions.append(neg(self.literal(s, i)))
        an.st.queries += 1
        r = an.solver.check(*assumptions)
        if r == z3.unknown:
            raise Unknown(an.solver.reason_unknown() or "unknown", what, span)
        found = None
        if r == z3.sat:
            model = an.solver.model()
            vec = rule_vector(model, an.p)
            found = {s: model.eval(self.view[s], model_completion=True).as_long() for s in self.subs}
            self.models.append([vec, found, None])
        self.memo[key] = found
        return found

    # ---- the graph ----

    def build(self) -> Graph:
        an = self.an
        g = Graph(self.subs)
        start = ("new", tuple(Phase("any") for _ in self.subs))
        g.nodes[start] = None
        queue = deque([start])
        per_state: dict[str, int] = {}
        while queue:
            node = queue.popleft()
            g.order.append(node)
            state, ctx = node
            succ = g.edges.setdefault(node, set())
            for r, lits in self._candidates(state):
                for post in self._fire(r, lits, state, ctx):
                    for ctx2 in self._jobs(r, post):
                        tgt = rule_target(r, state)
                        if tgt is None:
                            continue
                        if tgt in (DONE, ERROR):
                            succ.add(tgt)
                            continue
                        nxt = (tgt, ctx2)
                        succ.add(nxt)
                        if nxt not in g.nodes:
                            per_state[tgt] = per_state.get(tgt, 0) + 1
                            if per_state[tgt] > MAX_CONTEXTS or len(g.nodes) >= MAX_NODES:
                                raise TooMany()
                            g.nodes[nxt] = (node, r.index)
                            queue.append(nxt)
        return g

    def _candidates(self, state: str):
        """The rules that can be tried in `state`, each with the literals under which it fires."""
        an = self.an
        rules = an.rules_in.get(state)
        if rules is None:
            return
        for r in rules:
            before = [x.index for x in rules if x.index < r.index]
            lits = {i: False for i in before}
            lits[r.index] = True
            yield r, lits
        other = an.otherwise.get(state)
        if other is not None:
            yield other, {x.index: False for x in rules}

    def _fire(self, r: m.Rule, lits: dict[int, bool], state: str, ctx: tuple) -> list[tuple]:
        """The context right after `r` fires in (state, ctx), before its jobs ([] if it cannot fire).

        Whether it can fire is asked of the solver with the views of the
        subordinates that hold a status (DONE, ERROR, none) pinned; a
        subordinate still executing may show any status but `none` (and
        `error` only when it can fail), which the solver is not asked about
        beyond a condition that requires `SUB.error`.  What the rule's own
        condition requires (`SUB.done and ...`) is then held; otherwise a
        phase stays as it was, which allows more (never fewer) behaviours
        afterwards.  A stale subordinate (not commanded by this plan) stays
        `any`.
        """
        an = self.an
        read = set()
        for i in lits:
            if i in an.encs:
                read.update(k[1] for k in an.encs[i].inputs if k[0] == "view")
        pinned = {}
        for s, p in zip(self.subs, ctx):
            if s in read and p.kind in ("none", "done", "error"):
                pinned[s] = self.values(s, p.kind, p.verb)
        required = _required(r.guard)
        for s, p in zip(self.subs, ctx):
            if p.kind == "run" and required.get(s) == "error" and not self.can_fail(s, p.verb):
                return []
        # Conditions that the held views decide need no question.
        named = {s: self.members[s][next(iter(v))] for s, v in pinned.items()}
        ask = dict(lits)
        for i, want in lits.items():
            t = truth(an.plan.rules[i].guard, named)
            if t is not None:
                if t != want:
                    return []
                del ask[i]
        still = set()
        for i in ask:
            if i in an.encs:
                still.update(k[1] for k in an.encs[i].inputs if k[0] == "view")
        pinned = {s: v for s, v in pinned.items() if s in still}
        what = f"whether `{r.label}` can fire in state `{state}` with the subordinates' held status"
        if ask and self.sat(ask, pinned, what, r.label_span) is None:
            return []
        out = list(ctx)
        for j, (s, p) in enumerate(zip(self.subs, ctx)):
            if p.kind == "run" and s in required:
                out[j] = Phase(required[s], p.verb, p.by)
        return [tuple(out)]

    def _jobs(self, r: m.Rule, ctx: tuple) -> list[tuple]:
        top, nested = commands(r)
        base = list(ctx)
        for cmd in top:
            if cmd.sub in self.subs:
                base[self.subs.index(cmd.sub)] = Phase("run", cmd.verb, r.index)
        outs = [tuple(base)]
        for cmd in nested:
            if cmd.sub in self.subs:
                j = self.subs.index(cmd.sub)
                more = []
                for o in outs:
                    x = list(o)
                    x[j] = Phase("run", cmd.verb, r.index)
                    more.append(tuple(x))
                outs = list(dict.fromkeys(outs + more))
        return outs

    # ---- findings ----

    def trapped(self, g: Graph, structural_done: set[str]):
        """The nodes (breadth-first) that can still fail but no longer reach `done`."""
        can_done: set = set()
        can_fail: set = set()
        rev: dict = {}
        for n, succ in g.edges.items():
            for t in succ:
                rev.setdefault(t, set()).add(n)
        # A node where nothing can fire is a stall (W0540, W0517), reported
        # as such: taken here as if its missing rule led to `done`.
        stalls = [n for n, succ in g.edges.items() if not succ]
        for target, found in ((DONE, can_done), (ERROR, can_fail)):
            stack = list(rev.get(target, ())) + (stalls if target == DONE else [])
            while stack:
                n = stack.pop()
                if n in found:
                    continue
                found.add(n)
                stack.extend(rev.get(n, ()))
        return [n for n in g.order if n not in can_done and n in can_fail and n[0] in structural_done]

    def stale_waits(self, g: Graph, commanded: set[str]):
        """(view, rule, node) of each subordinate first waited on without a command on the path."""
        an = self.an
        out: dict[str, tuple] = {}
        for node in g.order:
            state, ctx = node
            if state == "new":
                continue
            for r in an.rules_in.get(state, []):
                for view in m.walk_expr(r.guard):
                    if not isinstance(view, m.SubView) or view.attr not in WAIT_ATTRS:
                        continue
                    if view.sub in out or view.sub not in commanded or view.sub not in self.subs:
                        continue
                    if ctx[self.subs.index(view.sub)].verb is None:
                        out[view.sub] = (view, r, node)
        return list(out.values())


def _required(e: m.Expr | None) -> dict[str, str]:
    """The subordinates whose class (done, error, run) a condition's top-level conjuncts require."""
    out: dict[str, str] = {}
    stack = [e] if e is not None else []
    while stack:
        x = stack.pop()
        if isinstance(x, m.Binary) and x.op == "and":
            stack += [x.left, x.right]
        elif isinstance(x, m.SubView):
            if x.attr in ("done", "error"):
                out[x.sub] = x.attr
            elif x.attr == "status" and x.value not in ("done", "error", "none"):
                out[x.sub] = "run"
    return out


def truth(e: m.Expr | None, views: dict[str, str]):
    """The value of a condition when the subordinates' views are `views` (sub -> member): True, False, or None (it depends on more)."""
    if e is None:
        return None
    if isinstance(e, m.Const) and isinstance(e.value, bool):
        return e.value
    if isinstance(e, m.SubView) and e.sub in views and e.attr in ("done", "error", "executing", "status"):
        v = views[e.sub]
        if e.attr == "executing":
            return v not in ("none", "done", "error")
        return v == (e.value if e.attr == "status" else e.attr)
    if isinstance(e, m.Unary) and e.op == "not":
        t = truth(e.operand, views)
        return None if t is None else not t
    if isinstance(e, m.Binary) and e.op in ("and", "or"):
        a, b = truth(e.left, views), truth(e.right, views)
        if e.op == "and":
            if a is False or b is False:
                return False
            return True if a is True and b is True else None
        if a is True or b is True:
            return True
        return False if a is False and b is False else None
    return None
