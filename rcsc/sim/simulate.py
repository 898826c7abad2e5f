"""The reference interpreter: one executable definition of the cycle semantics.

It implements the cycle semantics of docs/language.md over the checked design model, and every
backend is compared against it byte for byte (through the trace, see
`rcsc.sim.trace`).  A `Simulator` runs the cycles of one CPU: increment the cycle
counter, apply the scenario's operator commands and environment inputs, step
each controller of the schedule that is due in this cycle (every `divider`-th
cycle, from cycle 1), then record a snapshot.  One controller step: read,
pre, new-command check, decide, post, write (see `Simulator.step`).  Several
CPUs on one time base, with the buffers that cross between them, are run by
`rcsc.sim.timebase`.

Time is measured in nanoseconds from the release of the first cycle: cycle k
of a CPU with heartbeat P is released at (k-1)*P.  Every buffer carries the
stamp of the instant its value became visible (the release instant of the
writer's step on the same CPU); `age` is the reader's release instant minus
that stamp, and a buffer nobody has written has the stamp of one base tick
before time 0.

Buffers follow the paper's triple buffering: each controller reads copies of
its command, its subordinates' status and its Global Memory at the start of
its step, works on the copies, and writes its status, its Global Memory
outputs and the commands it issued at the end.  So a controller sees the
writes of controllers scheduled before it in the same cycle, and those of
later ones in the next cycle.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rcsc.semantics import model as m
from rcsc.semantics.evaluate import Env, _arith, eval_expr, zero_value  # noqa: F401  (zero_value: re-exported)
from rcsc.semantics.types import BOOL, DURATION, EnumType, FloatType, IntType, RecordType, Type, U32

STATUS_NAMES = {m.UNINITIALIZED: "UNINITIALIZED", m.DONE: "DONE", m.EXEC: "EXEC", m.ERROR: "ERROR"}
SERIAL_MAX = U32.max


def clone(value):
    """A copy of a value: scalars are immutable, records (dicts) and arrays (lists) are copied deeply."""
    if isinstance(value, dict):
        return {k: clone(v) for k, v in value.items()}
    if isinstance(value, list):
        return [clone(v) for v in value]
    return value


def clone_status(st: "StatusBuffer") -> "StatusBuffer":
    return StatusBuffer(st.echo_serial, st.status, st.state, st.rule, st.error_code, st.stamp, st.verb, clone(st.fields))


def next_serial(serial: int) -> int:
    """The serial after `serial`: wraps past 2^32-1 to 1, never 0 ("no command yet")."""
    return 1 if serial >= SERIAL_MAX else serial + 1


@dataclass
class CommandBuffer:
    """Supervisor -> subordinate: `serial` (0 = none yet), `verb` and its arguments."""

    serial: int = 0
    verb: str = ""
    args: dict = field(default_factory=dict)


@dataclass
class StatusBuffer:
    """Subordinate -> supervisor, written every cycle."""

    echo_serial: int = 0
    status: int = m.UNINITIALIZED
    state: str = ""
    rule: str = ""
    error_code: int = 0
    stamp: int = 0  # instant (ns) the value became visible to the reader
    verb: str = ""
    fields: dict = field(default_factory=dict)


class ControllerRuntime:
    """The private state of one controller between its steps."""

    def __init__(self, c: m.Controller) -> None:
        self.c = c
        self.status = StatusBuffer(fields={n: clone(v.init) for n, v in c.status_fields.items()})
        self.locals = {n: clone(v.init) for n, v in c.locals.items()}
        self.fields = self.status.fields
        self.cmd = CommandBuffer()
        self.subs: dict[str, StatusBuffer] = {}
        self.gm: dict[str, object] = {}
        self.last_sent: dict[str, int] = {u.name: 0 for u in c.subordinates}
        self.pending: dict[str, tuple[str, dict]] = {}
        self.plan: m.Plan | None = None
        self.idle = True
        self.entry_ns = 0  # release instant of the step that entered the current state
        self.steps = 0
        self.cycle_at: int | None = None  # `cycle` fixed by a witness replay (rcsc.checks.guards)
        self.gm_uses = c.reads + c.writes


class ExternCallError(Exception):
    """A Python stand-in for an extern failed (`rcsc.sim.externs`); `step`
    says where the run was, filled in by the step that made the call."""

    step = ""


class _StepEnv(Env):
    """What an expression reads during one controller step."""

    def __init__(self, sim: "Simulator", rt: ControllerRuntime) -> None:
        self.sim = sim
        self.rt = rt

    def ref(self, e: m.Ref):
        rt = self.rt
        if e.kind == "gm":
            return rt.gm[e.name]
        if e.kind == "local":
            return rt.locals[e.name]
        if e.kind == "status":
            return rt.fields[e.name]
        if e.kind == "param":
            return rt.cmd.args[e.name]
        raise KeyError(e.name)

    def in_state(self, e: m.InState):
        return self.sim.now - self.rt.entry_ns

    def cycle(self, e: m.Cycle):
        rt = self.rt
        if rt.cycle_at is not None:
            return rt.cycle_at
        return (self.sim.cycle - 1) // rt.c.divider + 1

    def sub_view(self, e: m.SubView):
        rt = self.rt
        st = rt.subs[e.sub]
        sent = rt.last_sent[e.sub]
        current = sent != 0 and st.echo_serial == sent
        if e.attr == "done":
            return current and st.status == m.DONE
        if e.attr == "error":
            return current and st.status == m.ERROR
        if e.attr == "executing":
            return sent != 0 and not (current and st.status in (m.DONE, m.ERROR))
        if e.attr == "status":
            return current and st.status == self.sim.design.controllers[e.sub].statuses[e.value]
        if e.attr == "error_code":
            return st.error_code
        if e.attr == "age":
            return self.sim.now - st.stamp
        if e.attr == "field":
            return st.fields[e.value]
        raise KeyError(e.attr)

    def age(self, e: m.Age):
        return self.sim.now - self.sim.gm_stamp[e.name]

    def call_extern(self, e: m.Call, args: list):
        impl = self.sim.externs.get(e.func)
        if impl is None:
            return zero_value(e.type)
        try:
            return impl(*args)
        except ExternCallError as exc:
            if not exc.step:
                exc.step = f"in cycle {self.sim.cycle} of CPU {self.sim.cpu.name}, controller {self.rt.c.name}"
            raise

    def function(self, name: str) -> m.Function:
        return self.sim.design.functions[name]


class Simulator:
    """Runs one CPU cycle by cycle: the design's only CPU, or `cpu` of a multi-CPU design.

    It keeps a copy of every buffer of the design (Global Memory, command and
    status buffers); on a multi-CPU design `rcsc.sim.timebase` refreshes the
    copies of the buffers that other CPUs write.
    """

    # When a list: one line per step, `CTRL<TAB>VERB<TAB>STATE<TAB>RULE` (the
    # compiled Main Program's --step-log, docs/backends.md "Performance").
    step_log: list[str] | None = None

    def __init__(self, design: m.Design, externs: dict | None = None, cpu: m.Cpu | None = None) -> None:
        self.design = design
        if cpu is None:
            cpus = list(design.cpus.values())
            if len(cpus) != 1:
                raise ValueError("name the CPU to simulate: the design has several")
            cpu = cpus[0]
        self.cpu = cpu
        self.period_ns = cpu.heartbeat_ns
        self.externs = externs or {}
        self.cycle = 0
        never = -(design.base_tick_ns or self.period_ns)  # the stamp of a buffer nobody has written
        self.gm = {n: clone(v.init) for n, v in design.gm.items()}
        self.gm_stamp = {n: never for n in design.gm}
        self.commands = {n: CommandBuffer() for n in design.controllers}
        self.statuses = {
            n: StatusBuffer(stamp=never, fields={k: clone(v.init) for k, v in c.status_fields.items()}) for n, c in design.controllers.items()
        }
        self.runtimes = {n: ControllerRuntime(c) for n, c in design.controllers.items()}
        self.schedule = [design.controllers[u.name] for u in cpu.schedule]
        self.frozen: set[str] = set()  # controllers a scenario froze: never stepped again
        self.now = -self.period_ns  # the release instant of the current cycle, in ns

    # ---- outside world ---------------------------------------------------------

    def operator_command(self, ctrl: str, verb: str, args: dict) -> int:
        """Write a command into a top controller's command buffer; returns its serial."""
        serial = next_serial(self.commands[ctrl].serial)
        self.commands[ctrl] = CommandBuffer(serial, verb, dict(args))
        return serial

    def set_input(self, name: str, value, stamp: int | None = None) -> None:
        """An environment input; its stamp is the instant of the input (default: this release)."""
        self.gm[name] = clone(value)
        self.gm_stamp[name] = self.now if stamp is None else stamp

    # ---- the cycle -------------------------------------------------------------

    def run_cycle(self) -> None:
        """Step the controllers due in this cycle, in schedule order (call after applying inputs)."""
        for c in self.schedule:
            if (self.cycle - 1) % c.divider == 0 and c.name not in self.frozen:
                self.step(self.runtimes[c.name])

    def begin_cycle(self) -> int:
        self.cycle += 1
        self.now = (self.cycle - 1) * self.period_ns
        return self.cycle

    def step(self, rt: ControllerRuntime) -> None:
        c = rt.c
        env = _StepEnv(self, rt)
        # 1. Read: copies of the command, the subordinates' status and Global Memory.
        cmd = self.commands[c.name]
        rt.cmd = CommandBuffer(cmd.serial, cmd.verb, clone(cmd.args))
        rt.subs = {u.name: self.statuses[u.name] for u in c.subordinates}  # read-only; replaced, never mutated
        gm = self.gm  # scalars are immutable: only records (dicts) need a copy
        rt.gm = {n: (v if type(v) is not dict else clone(v)) for n, v in ((u.name, gm[u.name]) for u in rt.gm_uses)}
        rt.pending = {}
        # 2. Pre.
        self.exec_block(c.pre, rt, env)
        # 3. New command: a new serial supersedes whatever ran before.
        st = rt.status
        log = self.step_log
        began = ("new" if rt.cmd.serial != st.echo_serial else st.state) if log is not None else ""
        fired = ""
        if rt.cmd.serial != st.echo_serial:
            st.echo_serial = rt.cmd.serial
            st.status = m.EXEC
            st.state = "new"
            st.error_code = 0
            st.rule = ""
            st.verb = rt.cmd.verb
            rt.entry_ns = self.now
            rt.plan = c.plans.get(rt.cmd.verb)
            rt.idle = rt.plan is None
            if rt.plan is None:
                st.status = m.ERROR
        # 4. Decide.
        if rt.plan is not None and not rt.idle:
            rule = self.select_rule(rt.plan, st.state, env)
            if rule is not None:
                self.fire(rule, rt, env)
                fired = rule.label
        # 5. Post.
        self.exec_block(c.post, rt, env)
        # 6. Write.
        now = self.now
        st.stamp = now
        self.statuses[c.name] = clone_status(st)
        for use in c.writes:
            v = rt.gm[use.name]
            self.gm[use.name] = v if type(v) is not dict else clone(v)
            self.gm_stamp[use.name] = now
        for sub, (verb, args) in rt.pending.items():
            serial = next_serial(rt.last_sent[sub])
            rt.last_sent[sub] = serial
            self.commands[sub] = CommandBuffer(serial, verb, args)
        # 7. Measure: the simulator counts steps; time is measured by the backends.
        rt.steps += 1
        if log is not None:
            log.append(f"{c.name}\t{st.verb or ''}\t{began}\t{fired}")

    def select_rule(self, plan: m.Plan, state: str, env: Env) -> m.Rule | None:
        """The first rule whose state matches and whose condition holds, else the state's `otherwise`."""
        fallback = None
        for r in plan.rules:
            matches = r.state.kind == "any" or (r.state.kind == "new" and state == "new") or (
                r.state.kind == "named" and r.state.name == state
            )
            if not matches:
                continue
            if r.guard is None:
                if fallback is None and r.state.kind != "any":
                    fallback = r
                continue
            if eval_expr(r.guard, env):
                return r
        return fallback

    def fire(self, rule: m.Rule, rt: ControllerRuntime, env: Env) -> None:
        st = rt.status
        # A rule that fires means the plan is executing; a `report` in its jobs
        # then sets an extra status, which holds until the next rule fires.
        st.status = m.EXEC
        st.rule = rule.label
        self.exec_block(rule.jobs, rt, env)
        nxt = rule.next
        if nxt.kind == "named" and nxt.name != st.state:
            st.state = nxt.name or ""
            rt.entry_ns = self.now
        elif nxt.kind == "done":
            st.status = m.DONE
            st.state = "done"
            rt.idle = True
        elif nxt.kind == "error":
            st.status = m.ERROR
            st.error_code = nxt.code
            st.state = "error"
            rt.idle = True

    # ---- statements ------------------------------------------------------------

    def exec_block(self, stmts: list[m.Stmt], rt: ControllerRuntime, env: Env) -> None:
        for s in stmts:
            if isinstance(s, m.Assign):
                self.assign(s, rt, env)
            elif isinstance(s, m.CallStmt):
                eval_expr(s.call, env)
            elif isinstance(s, m.Command):
                args = {p.name: eval_expr(a, env) for p, a in zip(self.design.controllers[s.sub].verbs[s.verb].params, s.args)}
                rt.pending[s.sub] = (s.verb, args)
            elif isinstance(s, m.Report):
                rt.status.status = rt.c.statuses[s.status]
            elif isinstance(s, m.If):
                for cond, body in s.branches:
                    if eval_expr(cond, env):
                        self.exec_block(body, rt, env)
                        break
                else:
                    self.exec_block(s.else_body, rt, env)

    def assign(self, s: m.Assign, rt: ControllerRuntime, env: Env) -> None:
        value = eval_expr(s.value, env)
        store = {"gm": rt.gm, "local": rt.locals, "status": rt.fields}[s.target.kind]
        container, key = store, s.target.name
        for part in s.target.path:
            container[key] = clone(container[key])
            container, key = container[key], part
        if s.target.index is not None:
            i = eval_expr(s.target.index, env)
            if not (0 <= i < len(container[key])):
                return  # out of range: the write is ignored
            container[key] = clone(container[key])
            container, key = container[key], i
        if s.op != "=":
            value = _arith(s.op[0], container[key], value, s.target.type)
        container[key] = clone(value)

    # ---- observation -----------------------------------------------------------

    def status_name(self, ctrl: str, status: int) -> str:
        if status in STATUS_NAMES:
            return STATUS_NAMES[status]
        for name, number in self.design.controllers[ctrl].statuses.items():
            if number == status:
                return name
        return str(status)
