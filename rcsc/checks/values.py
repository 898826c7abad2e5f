"""Values that leave their type or their declared range, proven with z3.

The guard analysis (`rcsc.checks.guards`) takes declared ranges as
assumptions (`x: i32 in 0..10` is never 20).  This family checks the other
side of that promise: every value that a rule's job list puts into a ranged
slot - a command argument for a ranged parameter, an assignment to a ranged
local, status field or Global Memory variable - stays in the range; and the
integer arithmetic of conditions and job lists neither wraps nor divides by
zero.  Each question is asked in the context where the expression runs: the
rule's own condition true and the earlier rules of its state false, and,
for a part of an expression, the conditions under which it is evaluated at
all (the left side of an `and` true, of an `or` false, an `if` branch's
condition; `_evaluated_when`).  The witness gives the inputs.  Expressions that read a variable which an earlier
job of the same list assigns are skipped (the value they see is not an
input), and so are values computed from the controller's history, which the
analysis does not follow: an unranged local or status field, and compound
assignments (`count += 1`).  Plans whose conditions cannot be encoded are
skipped too (the guard analysis reports them, W0518).

W0524 value outside its declared range
    With the witness's inputs, the value is outside the slot's range (a
    constant argument outside it needs no solver).  The plan receiving the
    command is checked for values inside the range only, so it can then
    sit in `new` for ever.
W0525 integer overflow or division by zero
    With the witness's inputs, `+`, `-` or `*` on an integer type wraps
    around, or `/` or `%` divides by zero (which gives 0).
W0251 array index may be out of range
    With the witness's inputs, an index (`a[i]` read, or `a[i] = v`
    written) is outside 0..N-1: the read gives the element type's zero and
    the write is ignored.  A path plan whose step rule is guarded by
    `k < len(path)` (or `k >= len(path)` in an earlier rule) has none.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import z3

from rcsc.checks import cache
from rcsc.codes import CODES
from rcsc.diagnostics import Diagnostic, Label, Severity
from rcsc.front.source import Span
from rcsc.semantics import model as m
from rcsc.checks.guard_analysis import _ekey, _skey
from rcsc.checks.guards import front_end_errors, nan_params
from rcsc.checks.plans import plan_states, rule_sources
from rcsc.diagnostics import Diagnostics
from rcsc.semantics.model import Design
from rcsc.checks.smt import F, Encoder, HasTypeError, Unsupported, concrete, format_value, own_context, real_of
from rcsc.semantics.types import DURATION, FloatType, IntType, RecordType, Type

# As in `rcsc.checks.guards`: the resource limit decides (1M units, about
# 1 s on a loaded CI machine); the time-out is a safety net far above it, so
# that the findings never depend on the machine's load.
TIMEOUT_MS = 60_000
RLIMIT = 1_000_000
I64 = IntType("i64", 64, True)


def check(design: Design, diags: Diagnostics, store=None) -> None:
    """The value analysis of every plan; with `store` (a `rcsc.checks.cache`
    store), each plan's findings are read from and written to it (see
    "Results kept between runs" below)."""
    if front_end_errors(diags):
        return
    nan = nan_params(design)
    keys = _Keys(design) if store is not None else None
    for c in m.checked_controllers(design):
        cpu = design.cpus.get(c.cpu) if c.cpu else None
        period = cpu.heartbeat_ns if cpu is not None else None
        for plan in c.plans.values():
            if plan.verb not in c.verbs:
                continue
            flag = (c.name, plan.verb) in nan
            context = keys.of(c) if keys is not None else None
            if context is None:
                with own_context():
                    _Plan(design, c, plan, period, diags, flag).run()
                continue
            key = cache.digest((context, c.name, period, flag, _plan_key(plan)))
            if _replay(store, key, plan, diags):
                continue
            own = Diagnostics()
            with own_context():
                _Plan(design, c, plan, period, own, flag).run()
            _remember(store, key, plan, own)
            diags.extend(own)


# ---- results kept between runs ---------------------------------------------------------------
#
# A plan's value findings depend on the plan (its rules, conditions and
# jobs), on the declarations of the whole design (types, constants,
# functions, Global Memory, CPUs), on its controller but its plans (verbs
# and their ranges, locals, status fields, `pre`, `post`, its rate), on
# what its plans can see of its subordinates (their verbs with the
# parameters' ranges, status values and status fields), and on whether the
# plan's parameters may be NaN (which the supervisors' plans decide;
# computed every run).  The key holds all of that, spans left out, and no
# more: an edit of one controller's header leaves the keys of the plans of
# the controllers other than it and its supervisor as they were.  The
# findings are stored with their spans as positions among the plan's nodes,
# so a plan that only moved in the file (an edit above it) reads its
# findings back at the new place.

FORMAT = 2
_FIELDS: dict[type, tuple[str, ...]] = {}


def _structure(x):
    """`x` (model objects, containers, values) as nested tuples, without spans."""
    t = type(x)
    if x is None or t is bool or t is int or t is str:
        return x
    if t is float:
        return ("float", x.hex()) if x == x else ("nan",)
    if t is Span:
        return None
    if t is list or t is tuple:
        return tuple(_structure(v) for v in x)
    if t is dict:
        return ("dict",) + tuple((_structure(k), _structure(v)) for k, v in x.items())
    names = _FIELDS.get(t)
    if names is None:
        if not dataclasses.is_dataclass(x):
            raise cache.NotStorable(t.__name__)
        names = _FIELDS[t] = tuple(f.name for f in dataclasses.fields(x))
    return (t.__name__,) + tuple(_structure(getattr(x, n)) for n in names)


def globals_key(design: Design) -> str:
    """The digest of the declarations of the whole design that a plan's
    value findings depend on.  It depends only on the text outside the
    controllers and on the imported files, so an incremental re-check
    (rcsc.checks.incremental) brings the last check's in
    `Design.values_context`."""
    return cache.digest(("values", FORMAT, _structure(
        (design.gm, design.consts, design.functions, design.enums, design.records, design.cpus, design.base_tick_ns))))


class _Keys:
    """The part of a plan's key that is not the plan, per controller (see above), made once per check."""

    def __init__(self, design: Design) -> None:
        self.design = design
        self.memo: dict[str, str | None] = {}

    def of(self, c: m.Controller) -> str | None:
        """None when something in it cannot be stored (the plan is analysed without the store)."""
        if c.name not in self.memo:
            try:
                if self.design.values_context is None:
                    self.design.values_context = globals_key(self.design)
                own = tuple((f.name, getattr(c, f.name)) for f in dataclasses.fields(c) if f.name != "plans")
                subs = []
                for u in c.subordinates:
                    sub = self.design.controllers.get(u.name)
                    subs.append(None if sub is None else (sub.name, sub.verbs, sub.statuses, sub.status_fields))
                self.memo[c.name] = cache.digest((self.design.values_context, _structure(own), _structure(tuple(subs))))
            except cache.NotStorable:
                self.memo[c.name] = None
        return self.memo[c.name]


def _plan_key(plan: m.Plan) -> tuple:
    rules = tuple(
        (r.index, r.label, r.state.kind, r.state.name, r.next.kind, r.next.name, r.next.code,
         None if r.guard is None else _ekey(r.guard), _skey(r.jobs))
        for r in plan.rules
    )
    return (plan.verb, plan.continuous, plan.ordered, rules)


def _positions(plan: m.Plan) -> list[Span]:
    """The spans of a plan's rules and nodes, in a fixed order."""
    out: list[Span] = []
    for r in plan.rules:
        out += (r.span, r.label_span, r.guard_span)
        if r.guard is not None:
            out += [x.span for x in m.walk_expr(r.guard)]
        for s in m.walk_stmts(r.jobs):
            out.append(s.span)
            for e in m.stmt_exprs(s):
                out += [x.span for x in m.walk_expr(e)]
    return out


def _remember(store, key: str, plan: m.Plan, own: Diagnostics) -> None:
    index: dict[tuple, int] = {}
    for i, sp in enumerate(_positions(plan)):
        index.setdefault((id(sp.file), sp.start, sp.end), i)

    def where(sp: Span | None):
        if sp is None:
            return None
        return index[(id(sp.file), sp.start, sp.end)]

    try:
        data = [
            [d.code, d.severity.value, d.message, where(d.span), d.label, [[where(lab.span), lab.message] for lab in d.labels],
             list(d.notes), list(d.helps), cache.encode(d.data)]
            for d in own.items
        ]
    except (KeyError, cache.NotStorable):
        return  # a span that is not one of the plan's, or data JSON cannot hold
    store.put(key, data)


def _replay(store, key: str, plan: m.Plan, diags: Diagnostics) -> bool:
    data = store.get(key)
    if not isinstance(data, list):
        return False
    spans = _positions(plan)
    try:
        found = []
        for code, sev, message, at, label, labels, notes, helps, extra in data:
            d = Diagnostic(code, Severity(sev), message, None if at is None else spans[at], label)
            d.labels = [Label(None if a is None else spans[a], msg) for a, msg in labels]
            d.notes, d.helps = list(notes), list(helps)
            d.data = cache.decode(extra, {})
            if code not in CODES or not isinstance(d.data, dict):
                return False
            found.append(d)
    except (KeyError, ValueError, TypeError, IndexError):
        return False
    own = Diagnostics()
    own.items = found
    diags.extend(own)
    return True


def _assigned_names(s: m.Stmt) -> set[tuple[str, str]]:
    return {(s.target.kind, s.target.name)} if isinstance(s, m.Assign) else set()


def _reads(e: m.Expr) -> set[tuple[str, str]]:
    return {(x.kind, x.name) for x in m.walk_expr(e) if isinstance(x, m.Ref)}


def _int_type(t: Type) -> IntType | None:
    if isinstance(t, IntType):
        return t
    if t == DURATION:
        return I64
    return None


def _array_size(design: Design, c: m.Controller, lv: m.LValue) -> int | None:
    """The length of the array whose element the indexed assignment `lv` writes."""
    var = {"gm": design.gm, "local": c.locals, "status": c.status_fields}[lv.kind].get(lv.name)
    t = var.type if var is not None else None
    for part in lv.path:
        t = t.field_type(part) if isinstance(t, RecordType) else None
    return getattr(t, "size", None)


_ARITH = frozenset(("+", "-", "*", "/", "%"))
_NOTHING: tuple = ((), (), ())


def _parts(e: m.Expr) -> tuple[Sequence[m.Binary], Sequence[m.Index], Sequence[m.Call]]:
    """The nodes of `e` that the value questions are about, in walk order: integer
    arithmetic (W0525), indexes that are not constants (W0251) and records built
    (W0524 on a ranged field).  One walk for the three checks: most expressions
    have none of them, and are then done with after this walk."""
    arith = index = records = None
    for x in m.walk_expr(e):
        if isinstance(x, m.Binary):
            if x.op in _ARITH and _int_type(x.type) is not None:
                (arith := arith if arith is not None else []).append(x)
        elif isinstance(x, m.Index):
            if not isinstance(x.index, m.Const):
                (index := index if index is not None else []).append(x)
        elif isinstance(x, m.Call):
            if x.kind == "record" and isinstance(x.type, RecordType):
                (records := records if records is not None else []).append(x)
    if arith is None and index is None and records is None:
        return _NOTHING
    return arith or [], index or [], records or []


def _evaluated_when(root: m.Expr, node: m.Expr) -> list[tuple[m.Expr, bool]] | None:
    """The conditions (each with the value it must have) under which `node` is
    evaluated within `root`: `and` evaluates its right side only when its left
    side is true, `or` only when it is false, `if` one branch (docs/language.md,
    "Order of evaluation").  None when `node` is not in `root`."""
    parent: dict[int, m.Expr] = {}
    for x in m.walk_expr(root):
        for child in m.expr_children(x):
            parent[id(child)] = x
    conds: list[tuple[m.Expr, bool]] = []
    at = node
    while at is not root:
        up = parent.get(id(at))
        if up is None:
            return None
        if isinstance(up, m.Binary) and up.op in ("and", "or") and at is up.right:
            conds.append((up.left, up.op == "and"))
        elif isinstance(up, m.IfExpr) and at is not up.cond:
            conds.append((up.cond, at is up.then))
        at = up
    return conds[::-1]


class _Plan:
    def __init__(self, design: Design, c: m.Controller, plan: m.Plan, period, diags: Diagnostics, nan: bool) -> None:
        self.design, self.c, self.plan, self.diags = design, c, plan, diags
        self.verb = c.verbs.get(plan.verb)
        self.enc = Encoder(design, c, self.verb, period, nan_params=nan)
        self.terms: dict[int, object] = {}
        self.reported: set[tuple] = set()
        self.solver: z3.Solver | None = None  # made on the first question

    def term(self, r: m.Rule):
        """The encoded condition of `r`, made when a question first needs it."""
        if r.index not in self.terms:
            self.terms[r.index] = self.enc.guard(r.guard).term  # type: ignore[arg-type]
        return self.terms[r.index]

    def run(self) -> None:
        states = [s for s in plan_states(self.plan) if s not in ("done", "error")]
        # The rules of each state, in order (`rule_sources` gives a state once).
        rules_in: dict[str, list[m.Rule]] = {s: [] for s in states}
        sources_of: dict[int, list[str]] = {}
        for r in self.plan.rules:
            sources = sources_of[r.index] = [s for s in rule_sources(r, states) if s in rules_in]
            for s in sources:
                rules_in[s].append(r)
        for r in self.plan.rules:
            sources = sources_of[r.index]
            if not sources:
                continue

            # Most rules ask nothing: the contexts (which encode the earlier
            # rules' conditions) are made only when a question needs them.
            def contexts(r=r, sources=sources) -> list[list]:
                out = []
                self.where = []
                for s in sources:
                    before = [x for x in rules_in[s] if x.index < r.index and x.guard is not None]
                    if r.otherwise:
                        before = [x for x in rules_in[s] if x.guard is not None]
                    out.append([z3.Not(self.term(x)) for x in before])
                    self.where.append((s, before))
                return out

            def fired(r=r, contexts=contexts) -> list[list]:
                own = [self.term(r)] if r.guard is not None else []
                return [ctx + own for ctx in contexts()]

            if r.guard is not None:
                arith, index, _ = _parts(r.guard)
                if arith:
                    self._expr_checks(r.guard, arith, contexts, r)
                if index:
                    self._index_checks(r.guard, index, contexts, r)
            assigned: set[tuple[str, str]] = set()
            for job in r.jobs:
                # The job's expressions that read nothing an earlier job of
                # the rule assigned (`assigned` does not change below until
                # the job is done, so this is asked once per expression).
                exprs = [(e, _parts(e)) for e in m.stmt_exprs(job) if not (assigned and _reads(e) & assigned)]
                for e, (arith, index, _) in exprs:
                    if arith:
                        self._expr_checks(e, arith, fired, r)
                    if index:
                        self._index_checks(e, index, fired, r)
                if (isinstance(job, m.Assign) and job.target.index is not None and not isinstance(job.target.index, m.Const)
                        and not (assigned and _reads(job.target.index) & assigned)):
                    size = _array_size(self.design, self.c, job.target)
                    if size is not None:
                        self._index_check(job.target.index, size, job.target.index.span, [job.target.index], fired, r, True)
                if isinstance(job, m.Command):
                    self._command(job, fired, r, assigned)
                elif isinstance(job, m.Assign):
                    self._assign(job, fired, r, assigned)
                for e, (_, _, records) in exprs:
                    if records:
                        self._records(records, fired, r, assigned)
                assigned |= _assigned_names(job)

    # ---- questions ----

    def _ask(self, make_contexts, bad, span=None, question: str = "") -> z3.ModelRef | None:
        """A model of `bad` in one of the contexts; an undecided question is W0518, never a pass."""
        try:
            contexts = make_contexts()
        except (Unsupported, HasTypeError):
            return None  # a condition the guard analysis cannot encode either (W0518 there)
        if self.solver is None:
            self.solver = z3.Solver()
            self.solver.set("timeout", TIMEOUT_MS)
            self.solver.set("rlimit", RLIMIT)
            self.added = 0
        s = self.solver
        # Inputs met since the last question (encoding makes them lazily).
        inputs = list(self.enc.inputs.values())
        for inp in inputs[self.added:]:
            s.add(inp.constraint)
        self.added = len(inputs)
        for n, ctx in enumerate(contexts):
            s.push()
            try:
                s.add(*self.enc.side)
                s.add(*ctx)
                s.add(bad)
                res = s.check()
                model = s.model() if res == z3.sat else None
            finally:
                s.pop()
            if model is not None:
                self.hit = n  # the context (state) of the model: `self.where[n]`
                return model
            if res != z3.unsat and span is not None and (span.start, "unknown") not in self.reported:
                self.reported.add((span.start, "unknown"))
                d = self.diags.add("W0518", span, f"value analysis of plan `{self.plan.verb}` of `{self.c.name}` is incomplete", "not decided")
                d.with_note(f"the solver could not decide {question}: {s.reason_unknown() or 'unknown'}")
                d.with_help("simplify the expression, or bound its operands with a declared range")
        return None

    def _encode(self, e: m.Expr):
        try:
            return self.enc.expr(e, None)
        except (Unsupported, HasTypeError):
            return None

    def _witness(self, model, exprs: list[m.Expr], r: m.Rule) -> tuple[str, dict]:
        """The inputs of `exprs` and of the earlier rules of the state where the model was found (so it replays)."""
        keys: dict[tuple, None] = {}
        exprs = exprs + [x.guard for x in self.where[self.hit][1] if x.guard is not None]
        self.enc._used = {}
        for e in exprs:
            self._encode(e)
        for k in self.enc._used:
            keys.setdefault(k, None)
        parts, out = [], {}
        for k in keys:
            inp = self.enc.inputs[k]
            value = concrete(model, inp.term, inp.type, inp.members)
            text = value if inp.type is None else format_value(value, inp.type)
            parts.append(f"{inp.name} = {text}")
            out[inp.name] = value if not isinstance(value, float) or value == value else "NaN"
        return ", ".join(parts), out

    def _reached(self, root: m.Expr, node: m.Expr):
        """A z3 condition under which `node` is evaluated within `root` (a
        condition that cannot be encoded is left out: the question is then
        asked more widely, never less)."""
        conds = []
        for cond, value in _evaluated_when(root, node) or []:
            term = self._encode(cond)
            if term is not None and z3.is_bool(term):
                conds.append(term if value else z3.Not(term))
        return z3.And(*conds) if conds else z3.BoolVal(True)

    def _index_checks(self, e: m.Expr, indexes: Sequence[m.Index], contexts: list[list], r: m.Rule) -> None:
        """W0251 for each index that is not a constant (`_parts`) of the expression `e`."""
        for x in indexes:
            size = x.obj.type.size  # type: ignore[attr-defined]
            # The witness shows the index's inputs and those of the conditions that let it be read.
            shown = [cond for cond, _ in _evaluated_when(e, x) or []]
            self._index_check(x.index, size, x.index.span, shown, contexts, r, False, self._reached(e, x))

    def _index_check(self, index: m.Expr, size: int, span: Span, exprs: list[m.Expr], contexts: list[list], r: m.Rule, writing: bool,
                     reached=None) -> None:
        """W0251: can `index` be outside 0..size-1 where rule `r` runs?"""
        if (span.start, "index") in self.reported:
            return
        lo, hi = self._interval(index)
        if 0 <= lo and hi < size:
            return  # the declared ranges keep it inside
        i = self._encode(index)
        if i is None or isinstance(i, F):
            return
        bad = z3.Or(i < 0, i >= size)
        model = self._ask(contexts, bad if reached is None else z3.And(reached, bad), span, f"whether an index in rule `{r.label}` is out of range")
        if model is None:
            return
        self.reported.add((span.start, "index"))
        text, data = self._witness(model, exprs + [index] + ([r.guard] if r.guard is not None else []), r)
        value = concrete(model, i, index.type)
        effect = "the write is ignored" if writing else "the read gives the element type's zero value"
        d = self.diags.add("W0251", span, f"the index in rule `{r.label}` may be {value}, outside the array of {size} elements", "may be out of range")
        d.with_note(f"witness: {text}")
        d.with_note(f"valid indices are 0..{size - 1}; out of range {effect}")
        d.with_help(f"bound the index in the rule's condition (`k < {size}`, or an earlier rule `k >= len(...)`), or declare its range")
        d.data = {"controller": self.c.name, "plan": self.plan.verb, "rules": [r.label], "witness": data, "state": self.where[self.hit][0],
                  "size": size}

    def _expr_checks(self, e: m.Expr, arith: Sequence[m.Binary], contexts: list[list], r: m.Rule) -> None:
        """W0525 for each integer operation (`_parts`) of the expression `e`."""
        # The witness shows the inputs of all of `e`: encoding it first brings
        # their declared ranges into the question (inputs are made lazily), so
        # that none is shown outside its range.
        self._encode(e)
        for x in arith:
            it = _int_type(x.type)
            if it is None or (x.span.start, x.op) in self.reported or self._history(x):
                continue  # (an unranged local or status field holds what earlier cycles made of it: not judged)
            a, b = self._encode(x.left), self._encode(x.right)
            if a is None or b is None or isinstance(a, F) or isinstance(b, F):
                continue
            if x.op in ("/", "%"):
                bad, what = b == 0, "divides by zero (the result is 0)"
            else:
                # Operands whose declared ranges keep the result in the type
                # need no question (a product of two variables is non-linear,
                # hard for the solver even when the answer is obvious).
                lo, hi = self._interval(x)
                if it.min <= lo and hi <= it.max:
                    continue
                val = a + b if x.op == "+" else a - b if x.op == "-" else a * b
                bad, what = z3.Or(val > it.max, val < it.min), f"wraps around the range of `{x.type}`"
            model = self._ask(contexts, z3.And(self._reached(e, x), bad), x.span, f"whether `{x.op}` in rule `{r.label}` {what}")
            if model is None:
                continue
            self.reported.add((x.span.start, x.op))
            text, data = self._witness(model, [e] + ([r.guard] if r.guard is not None else []), r)
            d = self.diags.add("W0525", x.span, f"`{x.op}` in rule `{r.label}` {what}", "overflow" if x.op not in ("/", "%") else "division by zero")
            d.with_note(f"witness: {text}")
            d.with_help("bound the operands (a declared range, a test in the condition), or use a wider type")
            d.data = {"controller": self.c.name, "plan": self.plan.verb, "rules": [r.label], "witness": data, "state": self.where[self.hit][0], "op": x.op}

    def _interval(self, e: m.Expr) -> tuple[int, int]:
        """Bounds of an integer expression from declared ranges, without wrapping."""
        it = _int_type(e.type) or I64
        full = (it.min, it.max)
        if isinstance(e, m.Const) and isinstance(e.value, int) and not isinstance(e.value, bool):
            return e.value, e.value
        if isinstance(e, m.Ref):
            var = None
            if e.kind == "gm":
                var = self.design.gm.get(e.name)
            elif e.kind == "local":
                var = self.c.locals.get(e.name)
            elif e.kind == "status":
                var = self.c.status_fields.get(e.name)
            elif e.kind == "param" and self.verb is not None:
                var = self.verb.param(e.name)
            if var is not None and var.range is not None:
                return int(var.range.lo), int(var.range.hi)
            return full
        if isinstance(e, m.Binary) and e.op in ("+", "-", "*"):
            (a, b), (c, d) = self._interval(e.left), self._interval(e.right)
            if e.op == "+":
                return a + c, b + d
            if e.op == "-":
                return a - d, b - c
            products = (a * c, a * d, b * c, b * d)
            return min(products), max(products)
        return full

    def _in_range(self, value, rng: m.Range, t: Type):
        if isinstance(value, F):
            return z3.Or(value.nan, value.r < real_of(float(rng.lo)), value.r > real_of(float(rng.hi)))
        return z3.Or(value < int(rng.lo), value > int(rng.hi))

    def _history(self, e: m.Expr) -> bool:
        """Whether `e` reads an unranged local or status field.

        Their values are what earlier cycles computed, which the analysis
        does not follow (it would take any value of the type): a range
        finding on them would mostly be a false alarm.
        """
        for x in m.walk_expr(e):
            if isinstance(x, m.Ref) and x.kind in ("local", "status"):
                var = (self.c.locals if x.kind == "local" else self.c.status_fields).get(x.name)
                if var is None or var.range is None:
                    return True
        return False

    def _declared(self, e: m.Expr) -> m.Range | None:
        """The declared range of a plain reference (a ranged parameter, local, ...)."""
        if not isinstance(e, m.Ref):
            return None
        table = {"gm": self.design.gm, "local": self.c.locals, "status": self.c.status_fields}.get(e.kind)
        if table is not None:
            var = table.get(e.name)
        elif e.kind == "param" and self.verb is not None:
            var = self.verb.param(e.name)
        else:
            var = None
        return var.range if var is not None else None

    def _slot(self, e: m.Expr, rng: m.Range | None, t: Type, what: str, contexts, r: m.Rule, assigned) -> None:
        if rng is None or (assigned and _reads(e) & assigned) or (e.span.start, "range") in self.reported or self._history(e):
            return
        own = self._declared(e)
        if own is not None and rng.lo <= own.lo and own.hi <= rng.hi:
            return  # a value whose own declared range fits needs no question
        if isinstance(e, m.Const):
            v = e.value
            if isinstance(v, (int, float)) and not isinstance(v, bool) and rng.lo <= v <= rng.hi:
                return
            model, text, data, state = None, f"the value is {format_value(v, t)}", {}, None
            nan = False
        else:
            value = self._encode(e)
            if value is None or not (isinstance(value, F) or isinstance(t, IntType) or t == DURATION):
                return
            model = self._ask(contexts, self._in_range(value, rng, t), e.span, f"whether {what} stays in its range")
            if model is None:
                return
            text, data = self._witness(model, [e] + ([r.guard] if r.guard is not None else []), r)
            text = "witness: " + text
            state = self.where[self.hit][0]
            nan = isinstance(value, F) and z3.is_true(model.eval(value.nan, model_completion=True))
        self.reported.add((e.span.start, "range"))
        lo, hi = format_value(rng.lo, t), format_value(rng.hi, t)
        d = self.diags.add("W0524", e.span, f"{what} can be outside its declared range {lo}..{hi}", "out of range")
        d.with_note(text)
        if nan:
            # `clamp` (and `min`/`max`) hand a NaN on, so "clamp it" would not help.
            d.with_note("the value is NaN here: no range holds a NaN, and `clamp`, `min` and `max` pass one on")
            d.with_help("test the value in the rule's condition (`in_range(x, lo, hi)` is false for NaN), or give the slot another value when it is NaN")
        else:
            d.with_help("keep the value in the range (clamp it, or test it in the rule's condition), or widen the range")
        d.data = {"controller": self.c.name, "plan": self.plan.verb, "rules": [r.label], "witness": data, "range": [rng.lo, rng.hi]}
        if state is not None:
            d.data["state"] = state

    def _assign_field(self, job: m.Assign, contexts, r: m.Rule, assigned) -> None:
        """`var.field = value` into a ranged record field."""
        t = job.target
        var = {"gm": self.design.gm, "local": self.c.locals, "status": self.c.status_fields}.get(t.kind, {}).get(t.name)
        if var is None or job.op != "=":
            return
        slot = _field_slot(var.type, list(t.path))
        if slot is None:
            return
        rec, fname = slot
        rng = rec.field_range(fname)
        ftype = rec.field_type(fname)
        if rng is None or ftype is None:
            return
        self._slot(job.value, rng, ftype, "`" + ".".join([t.name] + list(t.path)) + "`", contexts, r, assigned)

    def _command(self, cmd: m.Command, contexts, r: m.Rule, assigned) -> None:
        sub = self.design.controllers.get(cmd.sub)
        verb = sub.verbs.get(cmd.verb) if sub else None
        if verb is None:
            return
        for p, arg in zip(verb.params, cmd.args):
            self._slot(arg, p.range, p.type, f"argument `{p.name}` of `{cmd.sub}.{cmd.verb}`", contexts, r, assigned)

    def _records(self, records: Sequence[m.Call], contexts, r: m.Rule, assigned) -> None:
        """Each argument of a record built (`Spec(rpm = x)`, `_parts`) that goes into a ranged field."""
        for x in records:
            for (fname, ftype), arg in zip(x.type.fields, x.args):  # type: ignore[attr-defined]
                self._slot(arg, x.type.field_range(fname), ftype, f"field `{fname}` of `{x.type.name}`", contexts, r, assigned)  # type: ignore[attr-defined]

    def _assign(self, job: m.Assign, contexts, r: m.Rule, assigned) -> None:
        if job.target.path:
            self._assign_field(job, contexts, r, assigned)
            return
        t = job.target
        var = {"gm": self.design.gm, "local": self.c.locals, "status": self.c.status_fields}.get(t.kind, {}).get(t.name)
        if var is None or var.range is None:
            return
        if job.op != "=":
            # `count += 1` stays in range or not according to how often it
            # ran before: history, which the analysis does not follow.
            return
        self._slot(job.value, var.range, var.type, f"`{t.name}`", contexts, r, assigned)


def _field_slot(t: Type, path) -> tuple[RecordType, str] | None:
    """The record type and field name that an assignment to `var.a.b` writes."""
    for p in path[:-1]:
        if not isinstance(t, RecordType):
            return None
        t = t.field_type(p)  # type: ignore[assignment]
    if not isinstance(t, RecordType) or not path:
        return None
    return t, path[-1]
