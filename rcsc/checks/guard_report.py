"""The guard family's findings as diagnostics: messages, labels, notes, the
witness in words and in `Diagnostic.data`.
"""

from __future__ import annotations

from rcsc.semantics import model as m
from rcsc.diagnostics import Diagnostic, Diagnostics
from rcsc.semantics.model import Design
from rcsc.checks.smt import format_value, json_value
from rcsc.checks.guard_analysis import HELD_QUESTION, RLIMIT, TIMEOUT_MS, _difference, _Finding, _name_type, _next_text
from rcsc.checks.guard_replay import _replays
from rcsc.checks.plans import failure_of, held_statuses


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
        _note_replay(d, data, design, c, plan, f)
    if f.approx:
        d.with_note("approximate: " + "; ".join(f.approx))
        data["approximate"] = list(f.approx)
    d.data = data


def _note_replay(d: Diagnostic, data: dict, design: Design, c: m.Controller, plan: m.Plan, f: _Finding) -> None:
    """Replay the witness in the reference simulator; one that does not show the claim is called approximate."""
    ok = _replays(design, c, plan, f)
    if not ok:
        d.with_note("the witness is approximate: rounded to doubles, the reference evaluator does not show the claim")
    data["replayed"] = ok


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


def _held_text(design: Design, plan: m.Plan, sub: str, kind: str, by: int) -> str:
    if by < 0 and kind in ("done", "error"):
        return f"`{sub}` holds {kind.upper()} left over from an earlier command: this plan did not command it on this path"
    label = plan.rules[by].label if by >= 0 else "?"
    verb = next((j.verb for j in m.walk_stmts(plan.rules[by].jobs) if isinstance(j, m.Command) and j.sub == sub), "?") if by >= 0 else "?"
    holds = held_statuses(design, sub, verb) if kind == "run" and verb != "?" else None
    if holds is not None:
        # A continuous plan need not end: it holds what its last rule left.
        held = [x for x in holds if x != "EXEC"] + (["ERROR"] if failure_of(design, sub, verb) is not None else [])
        then = (["holds " + " or ".join(held)] if held else []) + (["stays executing"] if "EXEC" in holds or not held else [])
        return f"`{sub}` is executing `{verb}` sent by `{label}`, a continuous plan; then it " + ", or ".join(then)
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
    held_notes = [_held_text(design, plan, k[1], v[0], v[1]) for k, v in f.held.items()]
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
        _note_replay(d, data, design, c, plan, f)
        if f.approx:
            d.with_note("approximate: " + "; ".join(f.approx))
            data["approximate"] = list(f.approx)
    elif f.code == "W0541":
        ref = _first_mention(plan, f.state or "") if f.state != "new" else None
        span = rules[f.rules[0]].label_span if f.rules else ref.span if ref is not None else plan.name_span
        what = f"once in state `{f.state}` by this path, {where}" if f.path else where
        label = "cannot lead to `done` here" if f.rules else "`done` unreachable"
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
