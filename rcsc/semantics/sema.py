"""Semantic analysis: the loaded files' ASTs to the checked design model (`ast_to_model`).

It runs in passes so that declaration order never matters: (1) collect every
top-level name, (2) resolve types, (3) constants, functions' signatures,
verb sets and Global Memory, (4) controller interfaces (verbs, statuses,
fields, locals), (5) bodies: function bodies, pre/post blocks and plans, and
(6) CPUs.  Problems are collected as diagnostics; the model is always built
(with placeholders where something was wrong) so that the structural checks
can still run and report their own findings in the same run.
"""

from __future__ import annotations

from rcsc.front import ast
from rcsc.semantics import model as m
from rcsc.diagnostics import Diagnostic, Diagnostics, closest
from rcsc.front.instantiate import expand
from rcsc.front.loader import LoadedFile
from rcsc.front.source import Span
from rcsc.semantics import graphs
from rcsc.semantics.typecheck import BUILTIN_FUNCS, CONVERSIONS, MATH_FUNCS, Checker, Globals, Scope
from rcsc.semantics.types import BUILTIN_TYPES, DURATION, ERROR, I32, EnumType, ErrorType, RecordType, Type, array_of

_RESERVED = set(BUILTIN_TYPES) | set(BUILTIN_FUNCS) | set(MATH_FUNCS) | CONVERSIONS | {"cmd", "in_state", "seconds", "cycle"}
# The names a design cannot declare (E0101), for tools that generate designs.
RESERVED_NAMES = frozenset(_RESERVED)


# What `NAME.attr` reads instead of a status field or value called `attr`
# (W0101): a supervisor's view of its subordinate (docs/language.md §9.4)
# and a scenario's view of a controller (docs/scenarios.md) look these up
# before the status fields, so such a field is never seen there...
_SUPERVISOR_AND_SCENARIO = "its supervisor or a scenario"
_BUILT_IN_VIEW: dict[str, tuple[str, str]] = {
    "done": (_SUPERVISOR_AND_SCENARIO, "whether its plan has finished"),
    "error": (_SUPERVISOR_AND_SCENARIO, "whether its plan has failed"),
    "executing": (_SUPERVISOR_AND_SCENARIO, "whether a plan is executing"),
    "error_code": (_SUPERVISOR_AND_SCENARIO, "the code of its last `error(...)`"),
    "age": ("its supervisor", "the age of the status the supervisor reads"),
    "echo": ("a scenario", "the serial number of the last command it took"),
}
# ... and a scenario reads these as the field, except in a comparison with a
# name (`X.state == S1`), which compares the built-in: one name, two meanings.
_SCENARIO_SYMBOLS: dict[str, str] = {
    "status": "its status value", "state": "its plan's current state", "rule": "the rule that fired last", "verb": "the verb it executes",
}


def _doc(node) -> str:
    """The text of the doc comment of an AST node, or ""."""
    doc = getattr(node, "doc", None)
    return doc.text if doc is not None else ""


class _Sema:
    def __init__(self, files: list[LoadedFile], diags: Diagnostics) -> None:
        self.files = files
        self.d = diags
        self.g = Globals()
        self.g.types.update(BUILTIN_TYPES)
        self.g.resolve_const = self._resolve_const_lazily
        self.g.resolve_fn = self._fn_body
        self.fn_busy: set[str] = set()
        self.dropped_schedule: set[str] = set()  # scheduled by a CPU defined a second time
        self.ambiguous_types: set[str] = set()  # records and enums defined twice
        self.release_plans = False
        self.elided_plans: dict[str, dict] = {}
        self.decls: dict[str, ast.Node] = {}
        self.const_ast: dict[str, ast.Const] = {}
        self.const_busy: set[str] = set()
        self.verbsets: dict[str, ast.VerbSet] = {}
        self.record_ast: dict[str, ast.Record] = {}
        self.record_busy: set[str] = set()

    # ---- pass 1: names ---------------------------------------------------------

    def collect(self) -> None:
        for f, items in zip(self.files, expand(self.files, self.d)):
            if f.tree is None:
                continue
            for item in items:
                name = getattr(item, "name", None)
                if not isinstance(name, ast.Ident):
                    continue
                if name.name in _RESERVED:
                    self.d.add("E0101", name.span, f"`{name.name}` is a built-in name and cannot be redefined", "built-in name")
                    continue
                prev = self.decls.get(name.name)
                if prev is not None:
                    again, first = name, prev.name  # type: ignore[attr-defined]
                    if again.span.file.path.startswith("<stdlib>/") and not first.span.file.path.startswith("<stdlib>/"):
                        # Blame the design's own declaration, not the standard library's.
                        again, first = first, again
                    diag = self.d.add("E0101", again.span, f"`{name.name}` is defined more than once", "defined again here")
                    diag.with_label(first.span, "first defined here")
                    if isinstance(item, (ast.Record, ast.Enum)):
                        # Which of the two a use means is anyone's guess: the
                        # type reads as unknown, silently, wherever it is used.
                        self.ambiguous_types.add(name.name)
                        diag.with_note(f"the uses of `{name.name}` are not checked until one of the two is renamed")
                    if isinstance(item, ast.Cpu):
                        # A CPU defined twice (most often a copy not renamed):
                        # what the dropped one schedules is not "never run".
                        self.dropped_schedule.update(n.name for lst in item.schedule for n in lst.names)
                    continue
                self.decls[name.name] = item

    # ---- pass 2: types ---------------------------------------------------------

    def types(self) -> None:
        for name, item in self.decls.items():
            if isinstance(item, ast.Enum):
                members: list[str] = []
                for mem in item.members:
                    if mem.name in members:
                        self.d.add("E0101", mem.span, f"enum member `{mem.name}` is defined more than once", "repeated member")
                    else:
                        members.append(mem.name)
                if not members:
                    self.d.add("E0101", item.name.span, f"enum `{name}` has no members", "empty enum")
                self.g.types[name] = EnumType(name, tuple(members), item.span)
            elif isinstance(item, ast.Record):
                self.record_ast[name] = item
        # An array length in a record field may name a constant (`[f64; N]`):
        # constants resolve lazily from here on.
        for name, item in self.decls.items():
            if isinstance(item, ast.Const):
                self.const_ast[name] = item
        # Before any record resolves: a field of a type defined twice is as
        # unknown as the type (`h.k.x` with `k: Knot`).
        for name in self.ambiguous_types:
            self.g.types[name] = ERROR
        for name in self.record_ast:
            self._record(name)

    def _record(self, name: str) -> Type:
        if name in self.g.types:
            return self.g.types[name]
        item = self.record_ast[name]
        if name in self.record_busy:
            self.d.add("E0102", item.name.span, f"record `{name}` contains itself", "recursive record")
            return ERROR
        self.record_busy.add(name)
        fields: list[tuple[str, Type]] = []
        for f in item.fields:
            if any(f.name.name == n for n, _ in fields):
                self.d.add("E0101", f.name.span, f"field `{f.name.name}` is defined more than once", "repeated field")
                continue
            fields.append((f.name.name, self.type_ref(f.type)))
        self.record_busy.discard(name)
        t = RecordType(name, tuple(fields), item.span)
        self.g.types[name] = t
        return t

    def type_ref(self, ref: ast.TypeRef) -> Type:
        if ref.elem is not None and ref.size is not None:
            return self.array_type(ref)
        n = ref.name.name
        if n in self.g.types:
            return self.g.types[n]
        if n in self.record_ast:
            return self._record(n)
        diag = self.d.add("E0102", ref.name.span, f"unknown type `{n}`", "not a type")
        diag.with_note("types: bool, i32, i64, u32, f64, duration, and declared enums and records")
        diag.guess(n, [*self.g.types, *self.record_ast])
        return ERROR

    def array_type(self, ref: ast.TypeRef) -> Type:
        """`[T; N]`: N a positive integer literal or integer constant."""
        assert ref.elem is not None and ref.size is not None
        elem = self.type_ref(ref.elem)
        if ref.elem.lo is not None:
            self.d.add("E0254", ref.elem.span, "an array element cannot have a declared range", "range on an element").with_help(
                "declare the range on a local that holds the element, or check the values in the plan"
            )
        checker = Checker(Scope(self.g, const_only=True), self.d)
        size = checker.array_length(ref.size, "an array length")
        if size is None or isinstance(elem, ErrorType):
            return ERROR
        return array_of(elem, size)

    def range_of(self, ref: ast.TypeRef, t: Type, checker: Checker) -> m.Range | None:
        if ref.lo is None or ref.hi is None:
            return None
        if not t.is_numeric and t != DURATION:
            if not isinstance(t, ErrorType):
                self.d.add("E0206", ref.span, f"a range needs a numeric type or `duration`, not `{t}`", "not numeric")
            return None
        lo = checker.constant(ref.lo, t, "a range bound")
        hi = checker.constant(ref.hi, t, "a range bound")
        if lo is None or hi is None:
            return None
        if lo.value > hi.value:  # type: ignore[operator]
            self.d.add("E0206", ref.lo.span.to(ref.hi.span), "empty range: the lower bound is above the upper bound", "empty range")
            return None
        return m.Range(lo.value, hi.value)  # type: ignore[arg-type]

    def check_in_range(self, value, rng: m.Range | None, span: Span, t: Type | None = None) -> None:
        if isinstance(t, RecordType) and isinstance(value, dict):
            for fname, ftype in t.fields:
                if fname in value:
                    self.check_in_range(value[fname], t.field_range(fname), span, ftype)
            return
        if rng is None or not isinstance(value, (int, float)) or isinstance(value, bool):
            return
        if not (rng.lo <= value <= rng.hi):
            self.d.add("E0206", span, f"value {value} is outside the declared range {rng.lo}..{rng.hi}", "out of range")

    # ---- pass 3: constants, functions, verb sets, Global Memory -----------------

    def _resolve_const_lazily(self, name: str) -> bool:
        if name in self.g.consts:
            return True
        item = self.const_ast.get(name)
        if item is None:
            return False
        if name in self.const_busy:
            self.d.add("E0204", item.name.span, f"constant `{name}` depends on itself", "circular constant")
            return True  # a known constant without a value yet: its uses become ERROR, not E0100
        self.const_busy.add(name)
        self._const(item)
        self.const_busy.discard(name)
        return name in self.g.consts

    def _const(self, item: ast.Const) -> None:
        t = self.type_ref(item.type)
        checker = Checker(Scope(self.g, const_only=True), self.d)
        value = checker.constant(item.value, t, "a constant's value") if not isinstance(t, ErrorType) else None
        if value is None:
            self.g.consts[item.name.name] = m.ConstDef(item.name.name, ERROR, 0, item.span)
            return
        self.check_in_range(value.value, self.range_of(item.type, t, checker), item.value.span, t)
        self.g.consts[item.name.name] = m.ConstDef(item.name.name, t, value.value, item.span, doc=_doc(item))

    def globals_(self) -> None:
        # Function signatures first: constants may call pure functions.  A
        # parameter range that needs a constant resolves it lazily.
        const_checker = Checker(Scope(self.g, const_only=True), self.d)
        self.g.variables = {name: "a Global Memory variable" for name, item in self.decls.items() if isinstance(item, ast.GmVar)}
        for name, item in self.decls.items():
            if isinstance(item, ast.Const):
                self.const_ast[name] = item
        for name, item in self.decls.items():
            if isinstance(item, (ast.Function, ast.Extern)):
                params = self.params(item.params, const_checker)
                fn = m.Function(name, params, self.type_ref(item.ret), item.span, extern=isinstance(item, ast.Extern), doc=_doc(item))
                if isinstance(item, ast.Extern):
                    fn.budget_ns = item.budget.nanos
                fn.module = item.span.file.path
                self.g.functions[name] = fn
        for name in self.const_ast:
            self._resolve_const_lazily(name)
        # Record field ranges, now that the constants that may bound them are known.
        for name, item in self.record_ast.items():
            rt = self.g.types.get(name)
            if not isinstance(rt, RecordType):
                continue
            for f in item.fields:
                ft = rt.field_type(f.name.name)
                if ft is not None and f.type.lo is not None:
                    rng = self.range_of(f.type, ft, const_checker)
                    if rng is not None:
                        rt.ranges[f.name.name] = rng
        for cname, const in self.g.consts.items():  # record constants were folded before their field ranges were known
            if isinstance(const.type, RecordType) and cname in self.const_ast:
                self.check_in_range(const.value, None, self.const_ast[cname].value.span, const.type)
        for name, item in self.decls.items():
            if isinstance(item, ast.VerbSet):
                self.verbsets[name] = item
                for i, v in enumerate(item.verbs):
                    if any(v.name.name == w.name.name for w in item.verbs[:i]):
                        self.d.add("E0101", v.name.span, f"verb `{v.name.name}` is declared more than once in verb set `{name}`", "repeated verb")
            elif isinstance(item, ast.GmVar):
                t = self.type_ref(item.type)
                var = m.Var(name, t, item.span, from_env=item.from_env, to_env=item.to_env, doc=_doc(item))
                var.range = self.range_of(item.type, t, const_checker)
                if item.init is None:
                    self.d.add("E0402", item.name.span, f"Global Memory variable `{name}` has no initial value", "no initial value").with_help(
                        f"give it one: `gm {name}: {t} = ...`"
                    )
                elif not isinstance(t, ErrorType):
                    value = const_checker.constant(item.init, t, "an initial value")
                    if value is not None:
                        var.init = value.value
                        self.check_in_range(value.value, var.range, item.init.span, t)
                self.g.gm[name] = var

    def params(self, params: list[ast.Param], checker: Checker) -> list[m.Var]:
        out: list[m.Var] = []
        for p in params:
            if any(q.name == p.name.name for q in out):
                self.d.add("E0101", p.name.span, f"parameter `{p.name.name}` is defined more than once", "repeated parameter")
                # Keep the slot (typed ERROR) so that calls with the written
                # number of arguments do not also get E0201.
                out.append(m.Var(p.name.name, ERROR, p.span))
                continue
            t = self.type_ref(p.type)
            out.append(m.Var(p.name.name, t, p.span, range=self.range_of(p.type, t, checker), doc=_doc(p)))
        return out

    # ---- pass 4: controller interfaces ------------------------------------------

    def interfaces(self) -> None:
        for name, item in self.decls.items():
            if isinstance(item, ast.Controller):
                self.g.controllers[name] = self.interface(item)

    def interface(self, item: ast.Controller) -> m.Controller:
        name = item.name.name
        self.g.poisoned.update(item.poisoned)
        level, level_span = self._single(item.level, item, "level", lambda v: v[0], lambda v: v[1])
        budget, budget_span = self._single(item.budget, item, "budget", lambda v: v.nanos, lambda v: v.span)
        c = m.Controller(name, item.span, item.name.span, item.simulator, level or 0, budget or 0, doc=_doc(item))
        if item.placeholder:
            c.placeholder = True
            self.g.poisoned.add(name)
        c.level_span, c.budget_span = level_span, budget_span
        # `period` is optional (default: every cycle of its CPU); the timing
        # check relates it to the CPU's heartbeat once the controller is placed.
        for extra in item.period[1:]:
            self.d.add("E0209", extra.span, "`period` is given more than once", "repeated `period`")
        if item.period:
            c.declared_period_ns, c.period_span = item.period[0].nanos, item.period[0].span
        c.subordinates = self._names(item.subordinates, "subordinate")
        c.reads = self._names(item.reads, "read")
        c.writes = self._names(item.writes, "write")
        for names in (c.reads, c.writes):
            for i, use in enumerate(names):
                if use.name in self.g.gm:
                    continue
                diag = self.d.add("E0100", use.span, f"no Global Memory variable named `{use.name}`", "not declared")
                diag.with_help(f"declare it: `gm {use.name}: TYPE = VALUE`")
                # Its uses are not reported again (an instance's body uses the
                # name its argument gave); the name it likely means stands in.
                self.g.poisoned.add(use.name)
                names[i] = _meant(use, self.g.gm, names) or use
        checker = Checker(Scope(self.g, const_only=True), self.d)
        for param, arg in item.param_args:  # a controller type's parameters are constants
            pt = self.type_ref(param.type)
            if not isinstance(pt, ErrorType):
                value = checker.constant(arg, pt, f"the argument of `{param.name.name}`")
                if value is not None:
                    self.check_in_range(value.value, self.range_of(param.type, pt, checker), arg.span, pt)
        verbs = list(item.verbs)
        set_refs = list(item.verb_sets)
        for v in item.verbs:
            n = v.name.name
            if not v.params and n in self.verbsets and not any(p.name.name == n for p in item.plans):
                # `verb Lifecycle` for `verbs Lifecycle`: one finding, and the
                # set's verbs stand in (their plans are not each E0501).
                self.d.add("E0106", v.name.span, f"`{n}` is a verb set, not a verb", "a verb set").with_help(
                    f"take its verbs with `verbs {n}`")
                verbs.remove(v)
                set_refs.append(v.name)
        uses: list[Span | None] = [None] * len(verbs)
        used_sets: set[str] = set()
        for ref in set_refs:
            vs = self.verbsets.get(ref.name)
            if vs is None:
                diag = self.d.add("E0106", ref.span, f"no verb set named `{ref.name}`", "unknown verb set")
                best = diag.guess(ref.name, self.verbsets)
                if best is None:
                    continue
                # The meant set stands in, so its verbs' plans are not each
                # "for a verb the controller does not declare".
                ref, vs = ast.Ident(ref.span, best), self.verbsets[best]
            if ref.name in used_sets:  # one finding for the line, not one per verb
                self.d.add("E0101", ref.span, f"verb set `{ref.name}` is used more than once in `{name}`", "repeated `verbs`")
                continue
            used_sets.add(ref.name)
            for v in vs.verbs:
                if not any(v.name.name == w.name.name for w in vs.verbs[: vs.verbs.index(v)]):  # repeats: reported once, at the verb set
                    verbs.append(v)
                    uses.append(ref.span)
        for v, use in zip(verbs, uses):
            if v.name.name in c.verbs:
                self.d.add("E0101", use or v.name.span, f"verb `{v.name.name}` is declared more than once in `{name}`", "repeated verb")
                continue
            verb = m.Verb(v.name.name, self.params(v.params, checker), v.span, doc=_doc(v))
            verb.use_span = use or v.name.span
            c.verbs[v.name.name] = verb
        number = m.FIRST_EXTRA_STATUS
        for nl in item.reports:
            for ident in nl.names:
                if ident.name in c.statuses or ident.name in ("DONE", "EXEC", "ERROR", "UNINITIALIZED"):
                    self.d.add("E0101", ident.span, f"status value `{ident.name}` is defined more than once", "repeated status value")
                    continue
                self._shadowed_status(name, ident, "status value")
                c.statuses[ident.name] = number
                c.status_spans[ident.name] = ident.span
                number += 1
        design_variables = self.g.variables
        self.g.variables = design_variables | {d.name.name: f"a local of `{name}`" for d in item.locals} | {
            d.name.name: f"a status field of `{name}`" for d in item.status_fields}
        for decl, table, what in [(d, c.status_fields, "status field") for d in item.status_fields] + [
            (d, c.locals, "local") for d in item.locals
        ]:
            n = decl.name.name
            if n in ("cmd", "in_state"):
                self.d.add("E0101", decl.name.span, f"`{n}` is a built-in name and cannot be redefined", "built-in name")
                continue
            if n in c.status_fields or n in c.locals:
                self.d.add("E0101", decl.name.span, f"`{n}` is defined more than once in `{name}`", f"repeated {what}")
                continue
            gm_use = next((u for u in c.reads + c.writes if u.name == n), None)
            if gm_use is not None:
                # Inside the controller the bare name would be the field or
                # the local: the Global Memory variable would silently never
                # be read or written.
                access = "writes" if any(u is gm_use for u in c.writes) else "reads"
                self.d.add("E0101", decl.name.span, f"`{n}` is both a {what} of `{name}` and a Global Memory variable it {access}",
                           f"{what} named like a Global Memory variable").with_label(gm_use.span, f"`{access}` names it here").with_note(
                    f"inside `{name}`, `{n}` would name the {what}, never the Global Memory variable").with_help(
                    f"rename the {what}")
                continue
            if table is c.status_fields and n in c.statuses:
                # `C.homed` would name both; readers take the status value.
                self.d.add("E0101", decl.name.span, f"`{n}` is both a status value (`reports {n}`) and a status field of `{name}`",
                           "repeated status name").with_label(c.status_spans[n], "the status value").with_note(
                    f"`{name}.{n}` names either; a supervisor and a scenario would read the status value, never the field")
            elif table is c.status_fields:
                self._shadowed_status(name, decl.name, "status field")
            t = self.type_ref(decl.type)
            var = m.Var(n, t, decl.span, range=self.range_of(decl.type, t, checker), doc=_doc(decl))
            if not isinstance(t, ErrorType):
                value = checker.constant(decl.init, t, "an initial value")
                if value is not None:
                    var.init = value.value
                    self.check_in_range(value.value, var.range, decl.init.span, t)
            table[n] = var
        self.g.variables = design_variables
        return c

    def _shadowed_status(self, controller: str, ident: ast.Ident, what: str) -> None:
        """W0101 for a status field or an extra status value that its readers
        cannot see: `SUB.done` is the built-in, whatever `SUB` declares."""
        n = ident.name
        rename = f"give it a name of its own, such as `{n}_value`" if what == "status field" else f"give it a name of its own, such as `{n.upper()}`"
        if n in _BUILT_IN_VIEW:
            who, means = _BUILT_IN_VIEW[n]
            self.d.add("W0101", ident.span, f"{what} `{n}` cannot be read by {who}", "named like a built-in status").with_note(
                f"`{controller}.{n}` reads {means}, not this {what}").with_help(rename)
        elif n in _SCENARIO_SYMBOLS:
            self.d.add("W0101", ident.span, f"{what} `{n}` has the name of a scenario's built-in `{controller}.{n}`",
                       "named like a built-in status").with_note(
                f"a scenario reads `{controller}.{n}` as this {what}, but `{controller}.{n} == NAME` compares {_SCENARIO_SYMBOLS[n]}"
            ).with_help(rename)

    def _single(self, values, item: ast.Controller, what: str, get, span_of):
        if not values and item.placeholder:  # an instance that could not be made: reported
            return None, None
        if not values:
            diag = self.d.add("E0209", item.name.span, f"controller `{item.name.name}` has no `{what}`", f"no `{what}`").with_help(
                f"write it in the header: `controller {item.name.name} level {1 if not item.subordinates else 2} budget 1 ms {{`"
            )
            if what == "level":
                diag.with_note("there is no default: the hierarchy check compares levels (a controller without subordinates is "
                               "level 1, a supervisor is above its highest subordinate), and a guessed level would hide a wrong hierarchy")
            else:
                diag.with_note("there is no default: the timing check adds the budgets of each CPU cycle to prove that the schedule "
                               "fits the heartbeat, and a guessed budget would make that proof meaningless; start with an upper "
                               "bound and refine it with `rcsc budget`")
            return None, None
        for extra in values[1:]:
            self.d.add("E0209", span_of(extra), f"`{what}` is given more than once", f"repeated `{what}`")
        return get(values[0]), span_of(values[0])

    def _names(self, lists: list[ast.NameList], what: str) -> list[m.NameUse]:
        out: list[m.NameUse] = []
        for nl in lists:
            for ident in nl.names:
                if any(u.name == ident.name for u in out):
                    self.d.add("E0101", ident.span, f"`{ident.name}` is listed more than once", f"repeated {what}")
                    continue
                out.append(m.NameUse(ident.name, ident.span))
        return out

    # ---- pass 5: bodies ---------------------------------------------------------

    def _fn_body(self, name: str) -> None:
        """Type-check a function's body (once), on demand or in declaration order."""
        fn = self.g.functions.get(name)
        item = self.decls.get(name)
        if fn is None or fn.body is not None or not isinstance(item, ast.Function) or name in self.fn_busy:
            return  # a recursive call leaves the body unchecked until the first call returns
        self.fn_busy.add(name)
        scope = Scope(self.g, fn_params={p.name: p for p in fn.params}, pure=True)
        fn.body = Checker(scope, self.d).expect(item.body, fn.ret, f"the result of `{name}`")
        self.fn_busy.discard(name)

    def bodies(self) -> None:
        for name, item in self.decls.items():
            if isinstance(item, ast.Function):
                self._fn_body(name)
        self._recursion()
        for name, item in self.decls.items():
            if isinstance(item, ast.Controller):
                self.controller_body(self.g.controllers[name], item)

    def _recursion(self) -> None:
        calls: dict[str, dict[str, None]] = {}
        for fn in self.g.functions.values():
            calls.setdefault(fn.name, {})
            if fn.body is None:
                continue
            for e in m.walk_expr(fn.body):
                if isinstance(e, m.Call) and e.kind == "fn":
                    calls[fn.name][e.func] = None
        for cycle in graphs.cycles(calls):
            first = min(cycle)
            fn = self.g.functions[first]
            item = self.decls[first]
            path = " -> ".join(cycle[cycle.index(first):] + cycle[: cycle.index(first)] + [first])
            self.d.add("E0205", item.name.span, f"function `{first}` is recursive", "calls itself").with_note(  # type: ignore[attr-defined]
                f"call cycle: {path}"
            )
            fn.body = m.Const(fn.span, ERROR, 0)  # never evaluate it
        # Recursive functions are cut off above, so folding and simulation stay finite.

    def controller_body(self, c: m.Controller, item: ast.Controller) -> None:
        scope = Scope(self.g, controller=c)
        checker = Checker(scope, self.d)
        for _, block in item.pre:
            c.pre.extend(checker.stmts(block))
        for _, block in item.post:
            c.post.extend(checker.stmts(block))
        summary = self.elided_plans.get(c.name)
        if summary is not None:
            # Its plans are the last check's (their findings too); what
            # other controllers' checks need of them is the summary.
            c.plans = m.ElidedPlans(summary)
            return
        orphans: list[tuple[str, Diagnostic]] = []  # plans for undeclared verbs
        for plan in item.plans:
            verb_name = plan.name.name
            if verb_name in c.plans:
                diag = self.d.add("E0512", plan.name.span, f"`{c.name}` has two plans for `{verb_name}`", "second plan")
                diag.with_label(c.plans[verb_name].name_span, "first plan")
                continue
            verb = c.verbs.get(verb_name)
            if verb is None:
                diag = self.d.add("E0501", plan.name.span, f"plan `{verb_name}` is for a verb `{c.name}` does not declare", "no such verb")
                orphans.append((verb_name, diag))
                verb = m.Verb(verb_name, [], plan.name.span)
            c.plans[verb_name] = self.plan(c, verb, plan)
        if self.release_plans:
            # The plans are most of a large design's syntax tree: letting them
            # go as soon as they are converted keeps the tree and the model
            # from being in memory whole at the same time.
            item.plans = []
        # A misspelt plan name (`plan ALL_STPO`) is one finding: the verb it
        # most likely means, among those without a plan, is not also "without
        # a plan" (E0500).
        meant: set[str] = set()
        for verb_name, diag in orphans:
            best = diag.guess(verb_name, [v for v in c.verbs if v not in c.plans and v not in meant])
            if best is not None:
                meant.add(best)
            diag.with_help(f"declare it: `verb {verb_name}`")
        for v in c.verbs.values():
            if v.name not in c.plans and v.name not in meant:
                diag = self.d.add("E0500", v.use_span, f"verb `{v.name}` of `{c.name}` has no plan", "no plan for this verb")
                diag.with_help(f"add `plan {v.name} {{ ... }}` to `{c.name}`")

    def plan(self, c: m.Controller, verb: m.Verb, plan: ast.Plan) -> m.Plan:
        scope = Scope(self.g, controller=c, verb=verb, in_plan=True)
        checker = Checker(scope, self.d)
        const_checker = Checker(Scope(self.g, const_only=True), self.d)
        rules: list[m.Rule] = []
        labels: dict[str, Span] = {}
        for i, r in enumerate(plan.rules):
            if r.label.name in labels:
                diag = self.d.add("E0508", r.label.span, f"rule label `{r.label.name}` is used twice in plan `{verb.name}`", "repeated label")
                diag.with_label(labels[r.label.name], "first used here")
            else:
                labels[r.label.name] = r.label.span
            state = m.StateRef(r.state.kind, r.state.name, r.state.span)
            if state.kind == "named" and state.name in ("done", "error"):
                self.d.add("E0510", r.state.span, f"`{state.name}` is terminal and cannot be a current state", "terminal state").with_note(
                    "after `done` or `error` the plan is idle until the next command"
                )
            if r.guard is None and state.kind == "any":
                self.d.add("E0510", r.state.span, "`otherwise` needs a concrete state, not `*`", "`*` here").with_help(
                    "use a rule with condition `true` for a catch-all in every state"
                )
            guard = checker.condition(r.guard) if r.guard is not None else None
            nxt = m.StateRef(r.next.kind, r.next.name, r.next.span)
            if nxt.kind == "new":
                self.d.add("E0510", r.next.span, "`new` cannot be a next state", "entry state").with_note(
                    "only a new command enters `new`"
                )
            if nxt.kind == "error" and r.next.code is not None:
                found = len(self.d.items)
                code = const_checker.constant(r.next.code, I32, "an error code")
                for d in self.d.items[found:]:
                    if d.code == "E0204":  # the idiom of docs/language.md 9.6
                        d.with_help("`error(CODE)` takes a constant; to pass a code up, copy it (`SUB.error_code`) into a status field in the same rule")
                nxt.code = int(code.value) if code is not None and isinstance(code.value, int) else 0
            jobs = checker.stmts(r.jobs)
            rules.append(m.Rule(i, r.label.name, r.span, r.label.span, state, guard, r.guard_span, nxt, jobs, doc=_doc(r)))
        ordered = any(mod.name == "ordered" for mod in plan.modifiers)
        return m.Plan(verb.name, plan.span, plan.name.span, plan.continuous, rules, ordered, doc=_doc(plan))

    # ---- pass 6: CPUs -----------------------------------------------------------

    def cpus(self) -> dict[str, m.Cpu]:
        out: dict[str, m.Cpu] = {}
        for name, item in self.decls.items():
            if not isinstance(item, ast.Cpu):
                continue
            hb = item.heartbeat[0] if item.heartbeat else None
            if hb is None:
                self.d.add("E0209", item.name.span, f"cpu `{name}` has no `heartbeat`", "no heartbeat").with_help(
                    "add `heartbeat 30 ms` (the cycle period)"
                )
            elif hb.nanos <= 0:
                self.d.add("E0209", hb.span, "the heartbeat must be longer than zero", "zero period")
            for extra in item.heartbeat[1:]:
                self.d.add("E0209", extra.span, "`heartbeat` is given more than once", "repeated `heartbeat`")
            for extra in item.overhead[1:]:
                self.d.add("E0209", extra.span, "`overhead` is given more than once", "repeated `overhead`")
            for extra in item.schedule[1:]:
                self.d.add("E0209", extra.span, "`schedule` is given more than once", "second schedule").with_help(
                    "list every controller of the CPU in one `schedule`, in execution order"
                )
            if not item.schedule:
                self.d.add("E0209", item.name.span, f"cpu `{name}` has no `schedule`", "no schedule")
            schedule: list[m.NameUse] = []
            for nl in item.schedule:  # a repeat in one CPU is E0604, as across CPUs
                for ident in nl.names:
                    first = next((u for u in schedule if u.name == ident.name), None)
                    if first is not None:
                        diag = self.d.add("E0604", ident.span, f"`{ident.name}` is scheduled more than once", "scheduled again")
                        diag.with_label(first.span, f"first scheduled on `{name}`")
                        continue
                    schedule.append(m.NameUse(ident.name, ident.span))
            for i, use in enumerate(schedule):
                if use.name not in self.g.controllers:
                    self.d.add("E0104", use.span, f"no controller named `{use.name}`", "unknown controller")
                    schedule[i] = _meant(use, self.g.controllers, schedule) or use
            schedule = [u for u in schedule if u.name in self.g.controllers]
            cpu = m.Cpu(name, item.span, item.name.span, hb.nanos if hb else 0, item.overhead[0].nanos if item.overhead else 0, schedule, doc=_doc(item))
            cpu.heartbeat_span = hb.span if hb else None
            out[name] = cpu
        return out


def _meant(use: m.NameUse, declared, listed: list[m.NameUse]) -> m.NameUse | None:
    """The declared name that an unknown one in a header list (`subordinates`,
    `reads`, `writes`, `schedule`) most likely misspells, standing at its
    place, or None.

    The unknown name is reported once (with this guess as its "did you
    mean", `rcsc.checks.hints`); the checks then go on as if the guess had
    been written, so the uses of the meant name are not each reported as
    "not a subordinate", "not in the `reads`" or "not in any schedule".  A
    guess the list already holds is no guess: the list stays short of it.
    """
    best = closest(use.name, declared)
    if best is None or any(u.name == best for u in listed):
        return None
    return m.NameUse(best, use.span)


def ast_to_model(files: list[LoadedFile], diags: Diagnostics, release_plans: bool = False,
                 elided_plans: dict[str, dict] | None = None) -> m.Design:
    """Resolve and type-check the loaded files into one design model.

    With `release_plans`, each controller's plans are removed from its syntax
    tree once converted (`rcsc check` needs only the model afterwards).
    `elided_plans` (an incremental re-check, `rcsc.checks.incremental`) maps
    controllers whose plans are not modelled to the summary that stands for
    them (`model.ElidedPlans`)."""
    root = next((f for f in files if f.is_root), files[0])
    name = root.tree.name.name if root.tree is not None and root.tree.name is not None else "design"
    s = _Sema(files, diags)
    s.release_plans = release_plans
    s.elided_plans = elided_plans or {}
    s.collect()
    s.types()
    s.globals_()
    s.interfaces()
    for name_, item in s.decls.items():  # subordinates that are not controllers
        if isinstance(item, ast.Controller):
            subs = s.g.controllers[name_].subordinates
            for i, use in enumerate(subs):
                if use.name not in s.g.controllers:
                    s.d.add("E0104", use.span, f"no controller named `{use.name}`", "unknown controller")
                    meant = _meant(use, (n for n in s.g.controllers if n != name_), subs)
                    if meant is None:
                        s.g.poisoned.add(use.name)
                    else:
                        subs[i] = meant
    for c in s.g.controllers.values():
        c.subordinates = [u for u in c.subordinates if u.name in s.g.controllers]
    s.bodies()
    head = root.tree.name.span if root.tree is not None and root.tree.name is not None else Span(root.source, 0, 0)
    design = m.Design(name, head)
    design.is_module = root.tree is not None and root.tree.kind != "design"
    design.dropped_schedule = set(s.dropped_schedule)
    design.enums = {k: t for k, t in s.g.types.items() if isinstance(t, EnumType)}
    design.records = {k: t for k, t in s.g.types.items() if isinstance(t, RecordType)}
    design.consts = dict(s.g.consts)
    design.gm = dict(s.g.gm)
    design.functions = dict(s.g.functions)
    design.controllers = dict(s.g.controllers)
    design.cpus = s.cpus()
    design.files = [f.source.path for f in files]
    # The scope's resolvers are methods of the pass: a cycle (pass -> scope
    # -> method -> pass) that would keep the pass, the syntax trees and the
    # model alive until a garbage collection, which a long-lived process
    # (the language server, the check daemon) runs rarely or never.
    s.g.resolve_const = s.g.resolve_fn = None
    return design
