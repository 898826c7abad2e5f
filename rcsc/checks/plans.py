"""Plan (state table) checks (paper sections 4.2 and 5.3.2).

Per plan: an entry rule for `new`; every state reachable from `new`; from
every reachable state `done` or `error` reachable unless the plan is
`continuous`; no rule after an unconditional rule of the same state; at most
one `otherwise` per state; at most one command per subordinate in a job list;
a state that waits on a subordinate must also handle that subordinate's error
when the subordinate can fail for a verb this controller sends it.
In the state graph node "new" is the entry and the nodes "<done>" and
"<error>" are the terminals.  What every plan is asked (what `new` reaches,
what reaches the terminals) is answered by `rcsc.semantics.graphs`;
networkx describes what is wrong when something is.
"""

from __future__ import annotations

from rcsc.semantics import graphs
from rcsc.semantics import model as m
from rcsc.diagnostics import Diagnostics, closest
from rcsc.semantics.model import Design

MAX_RULES = 10
DONE, ERROR = "<done>", "<error>"
WAIT_ATTRS = ("done", "status", "executing")


def plan_states(plan: m.Plan) -> list[str]:
    """`new` and the named states, in order of first appearance."""
    return ["new"] + plan.states


def rule_sources(rule: m.Rule, states: list[str]) -> list[str]:
    """The states in which `rule` is evaluated."""
    if rule.state.kind == "any":
        return list(states)
    if rule.state.kind == "new":
        return ["new"]
    return [rule.state.name or ""]


def rule_target(rule: m.Rule, source: str) -> str | None:
    k = rule.next.kind
    if k == "named":
        return rule.next.name
    if k == "same":
        return source
    if k == "done":
        return DONE
    if k == "error":
        return ERROR
    return None  # `new` as next state: reported in sema


class StateGraph:
    """Where a plan's rules lead: the successors of each state, in the order
    the rules are written (the nodes are the plan's states, then the
    terminals)."""

    __slots__ = ("succ", "_pred")

    def __init__(self, succ: dict[str, dict[str, None]]) -> None:
        self.succ = succ
        self._pred: dict[str, list[str]] | None = None

    def descendants(self, state: str) -> set[str]:
        return graphs.descendants(self.succ, state)

    def ancestors(self, state: str) -> set[str]:
        if self._pred is None:
            self._pred = graphs.reverse(self.succ)
        return graphs.descendants(self._pred, state)

    def subgraph(self, region: list[str]):
        """The `networkx.DiGraph` of the states in `region` and the edges among them."""
        return graphs.to_networkx(self.succ, set(region))


def state_graph(plan: m.Plan) -> StateGraph:
    """The plan's state graph: an edge from each state in which a rule is evaluated to where it leads."""
    states = plan_states(plan)
    succ: dict[str, dict[str, None]] = {s: {} for s in states}
    succ[DONE] = {}
    succ[ERROR] = {}
    for r in plan.rules:
        for src in rule_sources(r, states):
            dst = rule_target(r, src)
            if dst is not None:
                succ[src][dst] = None
                succ.setdefault(dst, {})
    return StateGraph(succ)


def is_always_true(e: m.Expr | None) -> bool:
    return isinstance(e, m.Const) and e.value is True


def check(design: Design, diags: Diagnostics) -> None:
    for c in m.checked_controllers(design):
        for plan in c.plans.values():
            _check_plan(design, c, plan, diags)


def _region_ends(g: StateGraph, region: list[str], sources: bool) -> list[str]:
    """The first state (in `region` order) of each source (or sink) component of `region`'s subgraph."""
    if not region:
        return []
    cond = graphs.networkx().condensation(g.subgraph(region))
    order = {s: i for i, s in enumerate(region)}
    ends = []
    for comp in cond.nodes:
        degree = cond.in_degree(comp) if sources else cond.out_degree(comp)
        if degree == 0:
            members = cond.nodes[comp]["members"]
            ends.append(min(members, key=order.__getitem__))
    return sorted(ends, key=order.__getitem__)


def _first_mention(plan: m.Plan, state: str) -> m.StateRef | None:
    for r in plan.rules:
        if r.state.kind == "named" and r.state.name == state:
            return r.state
    for r in plan.rules:
        if r.next.kind == "named" and r.next.name == state:
            return r.next
    return None


def _check_plan(design: Design, c: m.Controller, plan: m.Plan, diags: Diagnostics) -> None:
    rules = plan.rules
    if len(rules) > MAX_RULES:
        diags.add("W0311", plan.name_span, f"plan `{plan.verb}` of `{c.name}` has {len(rules)} rules", f"more than {MAX_RULES} rules").with_help(
            "split the task: give part of it to a subordinate as its own command"
        )
    if not any(r.state.kind in ("new", "any") for r in rules):
        diags.add("E0511", plan.name_span, f"plan `{plan.verb}` has no rule for `new`", "never leaves `new`").with_help(
            "add an entry rule: `E0: true | new -> S1 | ...;`"
        )
        return

    states = plan_states(plan)
    g = state_graph(plan)
    reachable = g.descendants("new") | {"new"}
    # Report the causes, not their consequences: of the unreachable states,
    # those that no other unreachable state leads to (sources of the
    # unreachable region); of the states that cannot finish, those whose way
    # out leads only among themselves (sinks of the trapped region).
    unreachable = [s for s in plan.states if s not in reachable and s not in ("done", "error")]
    for s in _region_ends(g, unreachable, sources=True):
        ref = _first_mention(plan, s)
        if ref is not None:
            diag = diags.add("E0502", ref.span, f"state `{s}` of plan `{plan.verb}` is unreachable from `new`", "unreachable state")
            diag.with_note("no rule leads here from the entry state")
            own = {r.state.name for r in plan.rules if r.state.kind == "named"}
            orphan = closest(s, [x for x in plan.states if x in reachable and x not in own])
            typo = closest(s, [x for x in plan.states if x in reachable] + ["done"])
            if orphan is not None:
                diag.with_help(f"a rule leads to `{orphan}`, which has no rules of its own: did you mean `{s}` there? A misspelt next state makes a new state")
            elif typo is not None:
                diag.with_help(f"did you mean `{typo}`? A misspelt state name makes a new state")
            after = sorted(g.descendants(s) & set(unreachable))
            if after:
                diag.with_note("so are the states it leads to: " + ", ".join(f"`{x}`" for x in after))
    if not plan.continuous:
        ends = g.ancestors(DONE) | g.ancestors(ERROR)
        trapped = [s for s in states if s in reachable and s not in ends]
        for s in _region_ends(g, trapped, sources=False):
            ref = _first_mention(plan, s) if s != "new" else None
            span = ref.span if ref is not None else plan.name_span
            diag = diags.add("E0503", span, f"from state `{s}` plan `{plan.verb}` can never finish", "no way to `done` or `error`")
            before = sorted(x for x in trapped if x != s and s in g.descendants(x))
            if before:
                diag.with_note("states that lead here cannot finish either: " + ", ".join(f"`{x}`" for x in before))
            diag.with_help(f"add a rule that leads to `done` or `error(...)`, or declare `plan {plan.verb} continuous`")
        _check_fail_only(plan, g, reachable, ends, diags)

    _check_shadowing(plan, states, diags)
    _check_otherwise(plan, diags)
    _check_commands(plan, diags)
    _check_error_handling(design, c, plan, states, reachable, diags)


def _check_fail_only(plan: m.Plan, g: StateGraph, reachable: set[str], ends: set[str], diags: Diagnostics) -> None:
    """W0526: a loop of states whose only ways out fail, in a plan that can succeed."""
    succeed = g.ancestors(DONE)
    fail_only = [s for s in plan_states(plan) if s in reachable and s in ends and s not in succeed]
    if not fail_only or "new" in fail_only:
        # A plan that always fails (an ABORT) is a design choice, not a loop.
        return
    for comp in graphs.networkx().strongly_connected_components(g.subgraph(fail_only)):
        if len(comp) < 2:
            continue
        first = min(comp, key=fail_only.index)
        ref = _first_mention(plan, first)
        span = ref.span if ref is not None else plan.name_span
        names = ", ".join(f"`{x}`" for x in sorted(comp, key=fail_only.index))
        diag = diags.add("W0526", span, f"the loop {names} of plan `{plan.verb}` can only be left through `error(...)`", "only fails")
        diag.with_note("no rule of the loop leads towards `done`: once entered, the command can only fail")
        diag.with_help("add the rule that leaves the loop on success, or correct a misspelt next state")


def literal_dead_rules(plan: m.Plan, states: list[str] | None = None) -> dict[int, m.Rule]:
    """Rules after a literally unconditional (`true`) rule in each of their states.

    Maps the dead rule's index to the first `true` rule that hides it.  E0506
    reports these here, without a solver; the guard analysis
    (`rcsc.checks.guards`) finds the rest and skips these.
    """
    states = plan_states(plan) if states is None else states
    covered: dict[str, m.Rule] = {}  # state -> first unconditional rule covering it
    dead: dict[int, m.Rule] = {}
    for r in plan.rules:
        sources = rule_sources(r, states)
        dead_by = [covered[s] for s in sources if s in covered]
        if sources and len(dead_by) == len(sources):
            dead[r.index] = dead_by[0]
        if is_always_true(r.guard):
            for s in sources:
                covered.setdefault(s, r)
    return dead


def _check_shadowing(plan: m.Plan, states: list[str], diags: Diagnostics) -> None:
    dead = literal_dead_rules(plan, states)
    for r in plan.rules:
        if r.index in dead:
            first = dead[r.index]
            what = "`otherwise`" if r.otherwise else f"rule `{r.label}`"
            diag = diags.add("E0506", r.label_span, f"{what} can never fire", "dead rule")
            diag.with_label(first.guard_span, f"`{first.label}` always matches first")
            diag.with_note("the first rule whose state and condition match fires; an unconditional rule hides the rules after it")


def _check_otherwise(plan: m.Plan, diags: Diagnostics) -> None:
    seen: dict[str, m.Rule] = {}
    for r in plan.rules:
        if not r.otherwise or r.state.kind == "any":
            continue
        key = r.state.name if r.state.kind == "named" else "new"
        if key in seen:
            diag = diags.add("E0509", r.guard_span, f"state `{key}` already has an `otherwise` rule", "second `otherwise`")
            diag.with_label(seen[key].guard_span, "first `otherwise`")
        else:
            seen[key] = r


def _check_commands(plan: m.Plan, diags: Diagnostics) -> None:
    for r in plan.rules:
        issued: dict[str, m.Command] = {}
        for job in r.jobs:
            if isinstance(job, m.Command):
                if job.sub in issued:
                    diag = diags.add("E0504", job.span, f"second command to `{job.sub}` in rule `{r.label}`", "second command")
                    diag.with_label(issued[job.sub].span, "first command")
                    diag.with_note("commands are not queued: the second would supersede the first in the same cycle")
                else:
                    issued[job.sub] = job


def _subs_in(e: m.Expr | None, attrs: tuple[str, ...]) -> list[m.SubView]:
    if e is None:
        return []
    return [x for x in m.walk_expr(e) if isinstance(x, m.SubView) and x.attr in attrs]


def _error_codes(plan: m.Plan) -> list[int]:
    """The codes of the plan's `-> error(code)` rules, in table order, each once."""
    return list(dict.fromkeys(r.next.code for r in plan.rules if r.next.kind == "error"))


def verbs_sent(c: m.Controller, sub: str) -> dict[str, m.Command]:
    """The verbs that `c`'s plans send to `sub`, each with its first command."""
    out: dict[str, m.Command] = {}
    for plan in c.plans.values():
        for r in plan.rules:
            for job in m.walk_stmts(r.jobs):
                if isinstance(job, m.Command) and job.sub == sub:
                    out.setdefault(job.verb, job)
    return out


def failure_of(design: Design, sub: str, verb: str) -> str | None:
    """Why `sub` can end `verb` in ERROR (a short phrase), or None if it cannot.

    A subordinate can fail when its plan for the verb has an `error(...)`
    rule or reports ERROR, when it is a `simulator` (a plant model that a
    deployment build can replace by the real plant), and when the design has
    no plan for the verb (its behaviour is not known here).
    """
    c = design.controllers.get(sub)
    if c is None:
        return "it is not declared in this design"
    if c.simulator:
        return f"`{sub}` is a simulator, which a deployment replaces by the plant"
    if m.is_elided(c):
        # An incremental re-check keeps this answer for each verb of the
        # controllers it does not parse again (`rcsc.checks.incremental`).
        return c.plans.summary["failure"].get(verb, f"`{sub}` has no plan for `{verb}`")  # type: ignore[attr-defined]
    plan = c.plans.get(verb)
    if plan is None:
        return f"`{sub}` has no plan for `{verb}`"
    for r in plan.rules:
        if r.next.kind == "error":
            return f"rule `{r.label}` of `{sub}.{verb}` ends in `error({r.next.code})`"
        for job in m.walk_stmts(r.jobs):
            if isinstance(job, m.Report) and job.status == "ERROR":
                return f"rule `{r.label}` of `{sub}.{verb}` reports ERROR"
    return None


def held_statuses(design: Design, sub: str, verb: str) -> list[str] | None:
    """What `sub` can hold for ever once it runs `verb`: None when its plan for
    the verb is not `continuous` (it ends in DONE, or ERROR: section 12 of
    docs/language.md); for a continuous plan, which may never end, the status
    each rule into a state of its own leaves behind (`EXEC`, or the extra
    status it reports, which holds until the next rule fires), and `DONE` if a
    rule ends the plan.  ERROR is `failure_of`'s."""
    c = design.controllers.get(sub)
    if c is None:
        return None
    if m.is_elided(c):
        return c.plans.summary["holds"].get(verb)  # type: ignore[attr-defined]
    plan = c.plans.get(verb)
    if plan is None or not plan.continuous:
        return None
    out: set[str] = set()
    for r in plan.rules:
        if r.next.kind == "done":
            out.add("DONE")
        elif r.next.kind in ("named", "same"):
            reports = [j.status for j in r.jobs if isinstance(j, m.Report)]
            nested = [j.status for j in m.walk_stmts(r.jobs) if isinstance(j, m.Report) and j not in r.jobs]
            out.update(x for x in reports + nested if x != "ERROR")
            if not reports:
                out.add("EXEC")  # no report on some way through the jobs: the rule left EXEC
    return sorted(out)


def _check_error_handling(design: Design, c: m.Controller, plan: m.Plan, states: list[str], reachable: set[str],
                          diags: Diagnostics) -> None:
    """E0505, once per plan and subordinate that can fail, at its first wait
    in a reachable state (an unreachable one is E0502, often a misspelt name:
    its waits are not reported besides)."""
    handled: dict[str, set[str]] = {s: set() for s in states}
    for r in plan.rules:
        for view in _subs_in(r.guard, ("error", "error_code")):
            for s in rule_sources(r, states):
                handled[s].add(view.sub)
    waits: dict[str, list[tuple[m.SubView, list[str]]]] = {}
    for r in plan.rules:
        for view in _subs_in(r.guard, WAIT_ATTRS):
            missing = [s for s in rule_sources(r, states) if s in reachable and view.sub not in handled[s]]
            if missing:
                waits.setdefault(view.sub, []).append((view, missing))
    codes = _error_codes(plan) or _error_codes_of(c)
    for sub, found in waits.items():
        why = [(verb, failure_of(design, sub, verb)) for verb in verbs_sent(c, sub)]
        why = [(verb, w) for verb, w in why if w is not None]
        if not why:
            continue  # nothing this controller sends `sub` can end in ERROR
        view, _ = found[0]
        missing = list(dict.fromkeys(s for _, ms in found for s in ms))
        where = f"state `{missing[0]}`" if len(missing) == 1 else "states " + ", ".join(f"`{s}`" for s in missing)
        verbs = ("wait", "test") if len(missing) > 1 else ("waits", "tests")
        diag = diags.add("E0505", view.span, f"{where} {verbs[0]} on `{sub}` but never {verbs[1]} `{sub}.error`", "waits here")
        for other, _ in found[1:]:
            diag.with_label(other.span, "waits here too")
        verb, w = why[0]
        diag.with_note(f"`{sub}.{verb}` can fail: {w}")
        diag.with_note(f"if `{sub}` fails, plan `{plan.verb}` of `{c.name}` waits forever")
        code = codes[0] if codes else 1
        diag.with_help(f"add a rule such as `E9: {sub}.error | * -> error({code});` right after the `new` rules")


def _error_codes_of(c: m.Controller) -> list[int]:
    return [code for plan in c.plans.values() for code in _error_codes(plan)]
