"""A guard finding's witness in the reference simulator.

`Diagnostic.data["witness"]` holds the inputs that show a finding.  These
functions read it back into input keys and simulator values and set them in
a simulator; `_replays` asks the simulator's own rule selection whether the
finding shows at those inputs (the rule that fires, or none), and the report
calls a witness that does not replay approximate.  The tests replay every
witness of every example the same way.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

from rcsc.semantics import model as m
from rcsc.semantics.model import Design
from rcsc.semantics.types import EnumType, FloatType, Type
from rcsc.checks.guard_analysis import _Finding, _name_type, _path_parts


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
