"""How a plan commands its subordinates and reads their status back.

A subordinate's status answers the *last* command it was sent: EXEC while it
works on it, then DONE or ERROR, which stay until it is commanded again.  The
mistakes found here all come from forgetting that, and all hang or mislead a
real design.  Structural checks, per plan (no solver):

W0519 command storm
    A rule that stays in its state and commands a subordinate without testing
    that subordinate in its condition fires again in the next cycle and
    commands it again: the subordinate restarts its plan every cycle and never
    finishes.
W0520 `*` status rule before the `new` rules
    In `new`, a subordinate's status is still the answer to the previous
    command.  A `*` rule that tests it, written before the `new` rules, can
    fire on that stale status instead of the entry rule.
W0521 finishing while a subordinate still works
    A rule that ends the plan (`done`) in a state entered by commanding a
    subordinate, without testing that subordinate: the supervisor hears DONE
    while the work it delegated is still under way.
W0522 waiting on a subordinate this plan never commands
    A condition tests `SUB.done` (or another status of SUB) but no rule of the
    plan commands SUB: the status is left over from an earlier command (or
    there never was one), so the wait ends at once or never.
"""

from __future__ import annotations

from rcsc.semantics import model as m
from rcsc.checks.guards import front_end_errors
from rcsc.checks.plans import plan_states, rule_sources, rule_target
from rcsc.diagnostics import Diagnostics
from rcsc.semantics.model import Design

STATUS_ATTRS = ("done", "error", "executing", "status", "error_code")
WAIT_ATTRS = ("done", "status", "executing")


def check(design: Design, diags: Diagnostics) -> None:
    if front_end_errors(diags):
        return  # a command dropped for a bad verb or argument would only give follow-on findings
    for c in m.checked_controllers(design):
        for plan in c.plans.values():
            _check_plan(c, plan, diags)


def _commands(rule: m.Rule) -> list[m.Command]:
    return [j for j in m.walk_stmts(rule.jobs) if isinstance(j, m.Command)]


def _tested(rule: m.Rule, attrs: tuple[str, ...] = STATUS_ATTRS) -> set[str]:
    """The subordinates whose status the rule's condition tests."""
    if rule.guard is None:
        return set()
    return {x.sub for x in m.walk_expr(rule.guard) if isinstance(x, m.SubView) and x.attr in attrs}


def _check_plan(c: m.Controller, plan: m.Plan, diags: Diagnostics) -> None:
    states = plan_states(plan)
    _storms(plan, states, diags)
    _stale_star_rules(plan, diags)
    _finish_while_busy(plan, states, diags)
    _never_commanded(plan, diags)


def _storms(plan: m.Plan, states: list[str], diags: Diagnostics) -> None:
    for r in plan.rules:
        cmds = _commands(r)
        if not cmds:
            continue
        loops = [s for s in rule_sources(r, states) if rule_target(r, s) == s]
        if not loops:
            continue
        tested = _tested(r)
        for cmd in cmds:
            if cmd.sub in tested:
                continue
            where = "its state" if r.next.kind == "same" else f"state `{loops[0]}`"
            diag = diags.add("W0519", cmd.span, f"rule `{r.label}` stays in {where} and commands `{cmd.sub}` again every cycle it fires", "command storm")
            diag.with_label(r.guard_span, "nothing here waits for `" + cmd.sub + "`")
            diag.with_note(f"each new command supersedes the last: `{cmd.sub}` restarts `{cmd.verb}` every cycle and never finishes")
            diag.with_help(f"command `{cmd.sub}` once on the way into the state, or test `{cmd.sub}.done` / `{cmd.sub}.error` in this rule's condition")


def _stale_star_rules(plan: m.Plan, diags: Diagnostics) -> None:
    new_rules = [r for r in plan.rules if r.state.kind == "new"]
    for r in plan.rules:
        if r.state.kind != "any":
            continue
        later = [x for x in new_rules if x.index > r.index]
        subs = sorted(_tested(r))
        if not later or not subs:
            continue
        diag = diags.add("W0520", r.label_span, f"`*` rule `{r.label}` comes before the `new` rules and tests `{subs[0]}`", "before the entry")
        diag.with_label(later[0].label_span, "the entry rule comes after it")
        diag.with_note(f"in `new`, `{subs[0]}`'s status still answers the previous command, so `{r.label}` can fire instead of the entry")
        diag.with_help("move the `*` rule after the `new` rules, which then cover `new` first")


def _finish_while_busy(plan: m.Plan, states: list[str], diags: Diagnostics) -> None:
    # The subordinates commanded on every way into each state (and by the
    # rule itself, for a rule that commands and finishes at once).
    entering: dict[str, dict[str, m.Command]] = {}
    for r in plan.rules:
        for s in rule_sources(r, states):
            t = rule_target(r, s)
            if t is None or t == s:
                continue
            for cmd in _commands(r):
                entering.setdefault(t, {}).setdefault(cmd.sub, cmd)
    for r in plan.rules:
        if r.next.kind == "error":
            _error_leaves_running(r, states, entering, diags)
        if r.next.kind != "done":
            continue
        tested = _tested(r)
        busy: dict[str, m.Command] = {}
        for s in rule_sources(r, states):
            for sub, cmd in entering.get(s, {}).items():
                busy.setdefault(sub, cmd)
        for cmd in _commands(r):
            busy.setdefault(cmd.sub, cmd)
        for sub, cmd in busy.items():
            if sub in tested:
                continue
            diag = diags.add("W0521", r.label_span, f"rule `{r.label}` reports done without testing `{sub}`, which may still be executing", "done too early")
            diag.with_label(cmd.span, f"`{sub}` commanded here")
            diag.with_note(f"the supervisor hears DONE while `{sub}.{cmd.verb}` can still be under way")
            diag.with_help(f"wait for it: add `{sub}.done` to the condition (and handle `{sub}.error`)")


def _error_leaves_running(r: m.Rule, states: list[str], entering: dict[str, dict[str, m.Command]], diags: Diagnostics) -> None:
    """W0527: an error exit that neither tests nor stops a subordinate commanded on the way in.

    Only exits whose condition tests no subordinate (a time-out, a sensor
    fault): a rule reacting to one subordinate's failure while another
    finishes its part is how parallel INIT plans are written.  A watchdog on
    a subordinate's `age` reacts to that subordinate's failure too.
    """
    tested = _tested(r, tuple(STATUS_ATTRS) + ("age",))
    if tested:
        return
    stopped = {cmd.sub for cmd in _commands(r)}
    busy: dict[str, tuple[str, m.Command]] = {}
    for s in rule_sources(r, states):
        for sub, cmd in entering.get(s, {}).items():
            busy.setdefault(sub, (s, cmd))
    running = [(sub, s, cmd) for sub, (s, cmd) in busy.items() if sub not in stopped]
    if not running:
        return
    names = ", ".join(f"`{sub}`" for sub, _, _ in running)
    first_state = running[0][1]
    where = f" in state `{first_state}`" if r.state.kind == "any" else ""
    diag = diags.add("W0527", r.label_span, f"rule `{r.label}` fails the plan{where} while {names} may still be executing", "leaves it running")
    for sub, _, cmd in running:
        diag.with_label(cmd.span, f"`{sub}` commanded here")
    diag.with_note("the supervisor hears ERROR while the delegated work goes on, unsupervised")
    diag.with_help(f"stop it in the same rule (e.g. `{running[0][0]}.HALT()`), or test it in the condition")


def _never_commanded(plan: m.Plan, diags: Diagnostics) -> None:
    commanded = {cmd.sub for r in plan.rules for cmd in _commands(r)}
    reported: set[str] = set()
    for r in plan.rules:
        if r.guard is None:
            continue
        for view in m.walk_expr(r.guard):
            if not isinstance(view, m.SubView) or view.attr not in WAIT_ATTRS:
                continue
            if view.sub in commanded or view.sub in reported:
                continue
            reported.add(view.sub)
            diag = diags.add("W0522", view.span, f"plan `{plan.verb}` waits on `{view.sub}` but never commands it", "never commanded")
            diag.with_note(f"`{view.sub}`'s status answers an earlier command (or none): the wait ends at once on a stale DONE, or never")
            diag.with_help(f"command `{view.sub}` in this plan before waiting on it")
