"""Scenarios: operator commands, environment inputs and expectations (`text_to_scenario`).

A scenario file says what happens from outside a design: commands to the top
controller at given cycles (a command to a controller that has a supervisor
is refused: chain of command, paper section 3.7), values of `from env`
Global Memory variables, the number of cycles, and expectations checked on
the state at the end of a cycle.  Its expressions use the design language's
grammar and type checker, with an observer's view of the design: Global
Memory variables by name and each controller's status buffer as
`CTRL.status`, `CTRL.state`, `CTRL.rule`, `CTRL.done`, `CTRL.error`,
`CTRL.executing`, `CTRL.AT_GOAL` (extra status values), `CTRL.error_code`
and `CTRL.FIELD`.  See docs/scenarios.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources

from lark import Lark

from rcsc.front import ast
from rcsc.semantics import model as m
from rcsc.diagnostics import Diagnostics
from rcsc.front.lark_parse import _ToAst, parse_with
from rcsc.front.source import SourceFile, Span
from rcsc.semantics.typecheck import Checker, Globals, Scope
from rcsc.semantics.types import BOOL, ERROR, I32, ErrorType, Type
from lark import v_args


@lru_cache(maxsize=1)
def _parser() -> Lark:
    pkg = resources.files("rcsc.grammar")
    head = pkg.joinpath("scenario.lark").read_text(encoding="utf-8")
    design = pkg.joinpath("rcs.lark").read_text(encoding="utf-8")
    exprs = design[design.index("// ---- expressions") :]
    from rcsc.front.grammar_cache import lark_cache

    text = head + "\n" + exprs
    return Lark(text, parser="lalr", propagate_positions=True, maybe_placeholders=True, cache=lark_cache("scenario", text))


# The longest scenario: 2^32-1 cycles (over a year at 10 ms).  A longer count is
# a typo, and it would keep `rcsc sim` busy for ever.
MAX_CYCLES = 2**32 - 1

@dataclass
class Command:
    cycle: int
    ctrl: str
    verb: str
    args: dict
    span: Span
    cycle_span: Span | None = None


@dataclass
class Input:
    cycle: int
    var: str
    value: object
    span: Span
    cycle_span: Span | None = None


@dataclass
class Fault:
    """`at N: stop CPU` (kind "stop") or `at N: freeze CTRL` (kind "freeze")."""

    cycle: int
    kind: str
    name: str
    span: Span
    cycle_span: Span | None = None


@dataclass
class Expectation:
    kind: str  # at | within | always | final
    lo: int
    hi: int
    cond: m.Expr
    span: Span  # the whole `expect` line
    text: str  # the condition as written


@dataclass
class Scenario:
    name: str
    path: str
    cycles: int
    commands: list[Command] = field(default_factory=list)
    inputs: list[Input] = field(default_factory=list)
    expects: list[Expectation] = field(default_factory=list)
    faults: list[Fault] = field(default_factory=list)


@dataclass
class Observed(m.Expr):
    """An observer's reading of a controller's published status buffer.

    attr: status | state | rule | verb (compared with `value`), done | error |
    executing (status is DONE / ERROR / EXEC or an extra value), extra (status
    equals the extra value `value`), error_code, echo, field (`value`).
    """

    ctrl: str
    attr: str
    value: str | None = None


class _ScenarioAst(_ToAst):
    @v_args(meta=True)
    def start(self, meta, children):
        return [c for c in children if c is not None]

    @v_args(meta=True)
    def scenario_name(self, meta, children):
        return ("name", self.span(meta), str(children[0])[1:-1])

    @v_args(meta=True)
    def scenario_cycles(self, meta, children):
        return ("cycles", self.span(meta), self._int(children[0]), self.tspan(children[0]))

    @v_args(meta=True)
    def scenario_command(self, meta, children):
        cycle, ctrl, verb, args = children
        return ("command", self.span(meta), self._int(cycle), self.tspan(cycle), self.ident(ctrl), self.ident(verb), args or [])

    @v_args(meta=True)
    def scenario_input(self, meta, children):
        cycle, var, value = children
        return ("input", self.span(meta), self._int(cycle), self.tspan(cycle), self.ident(var), value)

    @v_args(meta=True)
    def scenario_stop(self, meta, children):
        return ("fault", self.span(meta), self._int(children[0]), self.tspan(children[0]), "stop", self.ident(children[1]))

    @v_args(meta=True)
    def scenario_freeze(self, meta, children):
        return ("fault", self.span(meta), self._int(children[0]), self.tspan(children[0]), "freeze", self.ident(children[1]))

    @v_args(meta=True)
    def scenario_expect(self, meta, children):
        when, cond = children
        return ("expect", self.span(meta), when, cond)

    @v_args(meta=True)
    def when_at(self, meta, children):
        n = self._int(children[0])
        return ("at", n, n, self.span(meta))

    @v_args(meta=True)
    def when_within(self, meta, children):
        return ("within", self._int(children[0]), self._int(children[1]), self.span(meta))

    @v_args(meta=True)
    def when_final(self, meta, children):
        return ("final", 0, 0, self.span(meta))

    @v_args(meta=True)
    def when_always(self, meta, children):
        return ("always", 0, 0, self.span(meta))


def globals_of(design: m.Design) -> Globals:
    """The design-wide names, as the type checker wants them."""
    from rcsc.semantics.types import BUILTIN_TYPES

    g = Globals()
    g.types.update(BUILTIN_TYPES)
    g.types.update(design.enums)
    g.types.update(design.records)
    g.consts.update(design.consts)
    g.gm.update(design.gm)
    g.functions.update(design.functions)
    g.controllers.update(design.controllers)
    return g


_SYMBOL_ATTRS = {"status", "state", "rule", "verb"}


class _ObserverChecker(Checker):
    """Types scenario expectations: GM by name, controllers through their status buffers."""

    def __init__(self, design: m.Design, g: Globals, diags: Diagnostics) -> None:
        super().__init__(Scope(g), diags)
        self.design = design

    def e_Name(self, node: ast.Name, expected: Type | None) -> m.Expr:
        if node.name in self.design.gm:
            return m.Ref(node.span, self.design.gm[node.name].type, "gm", node.name)
        return super().e_Name(node, expected)

    def _unknown_name(self, node: ast.Node, n: str) -> m.Expr:
        before = len(self.d.items)
        out = super()._unknown_name(node, n)
        for d in self.d.items[before:]:
            if d.code == "E0100" and not d.helps:
                d.guess(n, [*self.design.gm, *self.g.consts, *self.g.functions, *self.design.controllers])
        return out

    def e_Binary(self, node: ast.Binary, expected: Type | None) -> m.Expr:
        if node.op in ("==", "!="):
            for a, b in ((node.left, node.right), (node.right, node.left)):
                sym = self._symbol_compare(a, b, node)
                if sym is not None:
                    return sym if node.op == "==" else m.Unary(node.span, BOOL, "not", sym)
        return super().e_Binary(node, expected)

    def _symbol_compare(self, a: ast.Expr, b: ast.Expr, node: ast.Binary) -> m.Expr | None:
        """`PR.state == S1`, `PR.status == DONE`, `PR.rule == E3`, `PR.verb == AHEAD`."""
        if not (isinstance(a, ast.Attr) and isinstance(a.obj, ast.Name) and a.attr.name in _SYMBOL_ATTRS and isinstance(b, ast.Name)):
            return None
        ctrl = self.design.controllers.get(a.obj.name)
        if ctrl is None and a.obj.name not in self.design.gm and a.obj.name not in self.g.consts:
            # `TBB.state == SPOOLING`: the controller is unknown, so the
            # state cannot be looked up; it is not also "not found".
            self.d.add("E0100", a.obj.span, f"cannot find `{a.obj.name}` in this scope", "not found").guess(
                a.obj.name, self.design.controllers)
            return m.Const(node.span, ERROR, False)
        if ctrl is None or a.obj.name in self.design.gm:
            return None
        attr, sym = a.attr.name, b.name
        known: list[str]
        if attr == "state":
            known = ["new", "done", "error"] + sorted({s for p in ctrl.plans.values() for s in p.states})
        elif attr == "status":
            known = ["UNINITIALIZED", "DONE", "EXEC", "ERROR"] + list(ctrl.statuses)
        elif attr == "rule":
            known = sorted({r.label for p in ctrl.plans.values() for r in p.rules})
        else:
            known = list(ctrl.verbs)
        if sym not in known:
            what = {"state": "state", "status": "status value", "rule": "rule label", "verb": "verb"}[attr]
            self.d.add("E0703", b.span, f"`{ctrl.name}` has no {what} `{sym}`", f"unknown {what}").with_note(
                f"{what}s of `{ctrl.name}`: " + (", ".join(known) if known else "none")
            ).guess(sym, known)
            return m.Const(node.span, ERROR, False)
        return Observed(node.span, BOOL, ctrl.name, attr, sym)

    def e_Call(self, node: ast.Call, expected: Type | None) -> m.Expr:
        fn = self.g.functions.get(getattr(node.func, "name", ""))
        if fn is not None and fn.extern:
            self.d.add("E0211", node.func.span, f"extern function `{fn.name}` cannot be called in an expectation", "extern call").with_note(
                "an expectation observes the run, after the cycle, on what the trace shows: it calls none of the design's code"
            )
            return m.Const(node.span, ERROR, False)
        return super().e_Call(node, expected)

    def e_Attr(self, node: ast.Attr, expected: Type | None) -> m.Expr:
        if isinstance(node.obj, ast.Name) and node.obj.name in self.design.controllers and node.obj.name not in self.design.gm:
            ctrl = self.design.controllers[node.obj.name]
            attr = node.attr.name
            fixed: dict[str, Type] = {"done": BOOL, "error": BOOL, "executing": BOOL, "error_code": I32, "echo": I32}
            if attr in fixed:
                return Observed(node.span, fixed[attr], ctrl.name, attr)
            if attr in ctrl.statuses:
                return Observed(node.span, BOOL, ctrl.name, "extra", attr)
            if attr in ctrl.status_fields:
                return Observed(node.span, ctrl.status_fields[attr].type, ctrl.name, "field", attr)
            if attr in _SYMBOL_ATTRS:
                self.d.add("E0200", node.span, f"`{ctrl.name}.{attr}` can only be compared with `==` or `!=` to a name", "compare me").with_help(
                    f"write e.g. `{ctrl.name}.{attr} == NAME`"
                )
                return m.Const(node.span, ERROR, False)
            diag = self.d.add("E0103", node.attr.span, f"`{ctrl.name}` has no status `{attr}`", "unknown status")
            diag.with_note(
                "available: status, state, rule, verb, done, error, executing, error_code, echo"
                + "".join(", " + x for x in list(ctrl.statuses) + list(ctrl.status_fields))
            )
            diag.guess(attr, [*fixed, *_SYMBOL_ATTRS, *ctrl.statuses, *ctrl.status_fields])
            return m.Const(node.span, ERROR, False)
        return super().e_Attr(node, expected)


def text_to_scenario(source: SourceFile, design: m.Design, diags: Diagnostics) -> Scenario | None:
    """Parse and check one scenario against a checked design."""
    # Counted before parsing: a finding of the parser that still yields items
    # (a duration finer than 1 ns, E0210) must also stop the scenario.
    start = len(diags.errors)
    items = parse_with(_parser(), _ScenarioAst, source, diags)
    if items is None:
        return None
    g = globals_of(design)
    const_checker = Checker(Scope(g, const_only=True), diags)
    observer = _ObserverChecker(design, g, diags)
    name = source.path.rsplit("/", 1)[-1].removesuffix(".scn")
    cycles: int | None = None
    cycles_span: Span | None = None
    named: Span | None = None
    sc = Scenario(name, source.path, 0)
    windows: list[tuple[int, int, Span]] = []  # the cycles `at N` / `within A..B` of the expectations
    for item in items:
        kind = item[0]
        if kind == "name":
            if named is not None:
                diags.add("E0704", item[1], "the scenario is named more than once", "repeated").with_label(named, "first named here")
            named = item[1]
            sc.name = item[2]
        elif kind == "cycles":
            if cycles is not None:
                diags.add("E0704", item[1], "`cycles` is given more than once", "repeated")
            cycles, cycles_span = item[2], item[3]
        elif kind == "command":
            _, span, cycle, cspan, ctrl, verb, args = item
            cmd = _command(design, const_checker, diags, span, cycle, cspan, ctrl, verb, args)
            if cmd is not None:
                cmd.cycle_span = cspan
                sc.commands.append(cmd)
        elif kind == "input":
            _, span, cycle, cspan, var, value = item
            inp = _input(design, const_checker, diags, span, cycle, cspan, var, value)
            if inp is not None:
                inp.cycle_span = cspan
                sc.inputs.append(inp)
        elif kind == "fault":
            _, span, cycle, cspan, what, target = item
            fault = _fault(design, diags, span, cycle, what, target)
            if fault is not None:
                fault.cycle_span = cspan
                sc.faults.append(fault)
        elif kind == "expect":
            _, span, (when, lo, hi, wspan), cond = item
            e = observer.condition(cond)
            if when == "within" and lo > hi:
                diags.add("E0702", wspan, f"empty window: {lo} is after {hi}", "empty window")
            if when in ("at", "within"):
                windows.append((lo, hi, wspan))
            sc.expects.append(Expectation(when, lo, hi, e, span, cond.span.text))
    if cycles is None:
        diags.add("E0704", Span(source, 0, 0), "the scenario does not say how many cycles to run", "no `cycles`").with_help(
            "add a line such as `cycles 200`"
        )
        return None
    if cycles <= 0:
        diags.add("E0702", cycles_span, "a scenario runs at least one cycle", "zero cycles")
        return None
    if cycles > MAX_CYCLES:
        diags.add("E0702", cycles_span, f"a scenario runs at most {MAX_CYCLES} cycles", "too many cycles").with_note(
            "the simulator and the compiled Main Programs count cycles in 32 bits of scenario time"
        )
        return None
    sc.cycles = cycles
    for when_cycle, span in [(c.cycle, c.cycle_span or c.span) for c in sc.commands] + [(i.cycle, i.cycle_span or i.span) for i in sc.inputs] + [
        (f.cycle, f.cycle_span or f.span) for f in sc.faults
    ] + [(hi, wspan) for _, hi, wspan in windows] + [(lo, wspan) for lo, _, wspan in windows]:
        if not 1 <= when_cycle <= cycles:
            diags.add("E0702", span, f"cycle {when_cycle} is outside the scenario's cycles 1..{cycles}", "outside the run")
    _one_per_cycle(sc, diags)
    if len(diags.errors) > start:
        return None
    sc.commands.sort(key=lambda c: c.cycle)
    sc.inputs.sort(key=lambda i: i.cycle)
    sc.faults.sort(key=lambda f: f.cycle)
    return sc


def _one_per_cycle(sc: Scenario, diags: Diagnostics) -> None:
    """W0706: a second command to one controller, or a second value for one
    input, at the same cycle (the first would be overwritten unseen)."""
    first: dict[tuple, Span] = {}
    for key, span, what in [((c.cycle, "cmd", c.ctrl), c.span, f"`{c.ctrl}` gets a second command") for c in sc.commands] + [
        ((i.cycle, "in", i.var), i.span, f"`{i.var}` gets a second value") for i in sc.inputs
    ]:
        if key in first:
            diag = diags.add("W0706", span, f"{what} at cycle {key[0]}", "overwrites the first")
            diag.with_label(first[key], "the first, without effect")
            diag.with_help("give each its own cycle, or remove the one not meant")
            continue
        first[key] = span


def _fault(design: m.Design, diags: Diagnostics, span: Span, cycle: int, what: str, target: ast.Ident) -> Fault | None:
    """`stop` names a CPU, `freeze` a controller; a name that is the other kind gets a hint."""
    table, other, noun = (design.cpus, design.controllers, "CPU") if what == "stop" else (design.controllers, design.cpus, "controller")
    if target.name in table:
        return Fault(cycle, what, target.name, span)
    diag = diags.add("E0705", target.span, f"`{what}` needs a {noun}; the design has no {noun} named `{target.name}`", f"not a {noun}")
    if target.name in other:
        diag.with_help(f"`{target.name}` is a {'controller' if what == 'stop' else 'CPU'}: write `{'freeze' if what == 'stop' else 'stop'} {target.name}`")
    else:
        diag.with_note(f"{noun}s: " + ", ".join(table)).guess(target.name, table)
    return None


def _command(design, checker, diags, span, cycle, cspan, ctrl: ast.Ident, verb: ast.Ident, args) -> Command | None:
    c = design.controllers.get(ctrl.name)
    if c is None:
        diags.add("E0104", ctrl.span, f"no controller named `{ctrl.name}`", "unknown controller").guess(ctrl.name, design.controllers)
        return None
    if c.supervisor is not None:
        diags.add("E0700", ctrl.span, f"`{c.name}` takes commands only from its supervisor `{c.supervisor}`", "not the top").with_note(
            "operator commands enter at the top of the hierarchy (chain of command, paper section 3.7)"
        )
        return None
    v = c.verbs.get(verb.name)
    if v is None:
        diags.add("E0105", verb.span, f"`{c.name}` does not accept the verb `{verb.name}`", "unknown verb").with_note(
            f"`{c.name}` accepts: " + (", ".join(c.verbs) if c.verbs else "no verbs")
        ).guess(verb.name, c.verbs)
        return None
    checker.s.const_only = True
    # A wrong number of arguments is shown on the command, not the whole line.
    call = Span(ctrl.span.file, ctrl.span.start, span.end)
    values = checker.match_args([(p.name, p.type) for p in v.params], args, ast.Node(call), f"`{c.name}.{v.name}`")
    if values is None:
        return None
    out = {}
    for p, e in zip(v.params, values):
        if isinstance(e.type, ErrorType):
            return None
        value = _constant_value(checker, e)
        if value is None:
            diags.add("E0204", e.span, "a command argument in a scenario must be a constant", "not constant")
            return None
        if not _in_range(diags, e.span, p, value.value) or not _fields_in_range(diags, e, p.name, p.type, value.value):
            return None
        out[p.name] = value.value
    return Command(cycle, c.name, v.name, out, span)


def _in_range(diags, span, p: m.Var, value) -> bool:
    """An operator command carries a number inside its parameter's declared range (E0206).

    The guard analysis assumes both: a ranged parameter inside its range,
    and an f64 parameter of an operator command never NaN.
    """
    if isinstance(value, float) and math.isnan(value):
        diags.add("E0206", span, f"`{p.name}` would be NaN", "not a number").with_note(
            "operator commands carry numbers; the checker assumes a command parameter is never NaN unless a supervisor computes it"
        )
        return False
    rng = p.range
    if rng is not None and isinstance(value, (int, float)) and not isinstance(value, bool) and not (rng.lo <= value <= rng.hi):
        from rcsc.checks.smt import format_value

        shown = [format_value(v, p.type) for v in (value, rng.lo, rng.hi)]
        diags.add("E0206", span, f"`{p.name}` = {shown[0]} is outside its declared range {shown[1]}..{shown[2]}", "out of range").with_note(
            "the plan is checked for values inside the range only"
        )
        return False
    return True


def _fields_in_range(diags, e: m.Expr, name: str, t, value) -> bool:
    """Each field of a record argument inside its declared field range, and never NaN (E0206)."""
    from rcsc.semantics.types import RecordType

    if not isinstance(t, RecordType) or not isinstance(value, dict):
        return True
    ok = True
    built = isinstance(e, m.Call) and e.kind == "record"
    for i, (fname, ftype) in enumerate(t.fields):
        if fname not in value:
            continue
        arg = e.args[i] if built and i < len(e.args) else e
        slot = m.Var(f"{name}.{fname}", ftype, arg.span, range=t.field_range(fname))
        if not _in_range(diags, arg.span, slot, value[fname]) or not _fields_in_range(diags, arg, slot.name, ftype, value[fname]):
            ok = False
    return ok


def _constant_value(checker: Checker, e: m.Expr) -> m.Const | None:
    """The folded value of `e`; records are built by evaluating their constructor."""
    from rcsc.semantics.evaluate import NotConstant, eval_expr
    from rcsc.semantics.typecheck import FoldEnv

    e = checker.fold(e)
    if isinstance(e, m.Const):
        return e
    try:
        return m.Const(e.span, e.type, eval_expr(e, FoldEnv(checker.g)))
    except (NotConstant, TypeError, KeyError, ValueError, ArithmeticError, RecursionError):
        return None


def _input(design, checker, diags, span, cycle, cspan, var: ast.Ident, value: ast.Expr) -> Input | None:
    g = design.gm.get(var.name)
    if g is None:
        diags.add("E0100", var.span, f"no Global Memory variable named `{var.name}`", "unknown variable").guess(
            var.name, [n for n, v in design.gm.items() if v.from_env])
        return None
    if not g.from_env:
        diags.add("E0701", var.span, f"`{var.name}` is written by a controller, not by the environment", "not `from env`").with_help(
            f"only variables declared `gm {var.name}: ... from env` take scenario inputs"
        )
        return None
    c = checker.constant(value, g.type, "an input value")
    if c is None:
        return None
    rng = g.range
    v = c.value
    if rng is not None and isinstance(v, (int, float)) and not isinstance(v, bool) and not (rng.lo <= v <= rng.hi):
        # Allowed (a drill may feed a sensor's impossible value), but the
        # checks assumed the range: say what was not checked.
        from rcsc.checks.smt import format_value

        shown = [format_value(x, g.type) for x in (v, rng.lo, rng.hi)]
        diags.add("W0707", value.span, f"`{var.name}` = {shown[0]} is outside its declared range {shown[1]}..{shown[2]}",
                  "outside the checked range").with_note(
            f"the design was checked for `{var.name}` in {shown[1]}..{shown[2]} only: what it does with this value was not"
        ).with_help("to drill an out-of-range input, widen the variable's declared range so that the checks cover it")
    return Input(cycle, var.name, c.value, span)
