"""Plans of the same shape share one guard analysis: the canonical text of a
plan's analysis problem (`_Canon`), and the results kept on disk between runs.

Many plans of a large design ask the solver the same questions under other
names (a controller per axis, a plan per mode).  `_Canon` writes a plan's
problem with its inputs numbered in order of use and its states renamed, so
that two such plans get one key; the second takes the first's findings,
renamed.  The on-disk store (`rcsc.checks.cache`) is keyed more narrowly
(the real names too), so that a stored result is exactly what analysing the
plan again would give.
"""

from __future__ import annotations

from dataclasses import fields
from typing import TYPE_CHECKING

from rcsc.semantics import model as m
from rcsc.semantics.model import Design
from rcsc.checks.guard_analysis import _ekey, _Finding, _is_fixed, _preferred, _skey, _vkey

if TYPE_CHECKING:
    from rcsc.checks.guards import Options


# ---- cache: plans of the same shape --------------------------------------------------------


class _Canon:
    """A canonical text of a plan's analysis problem, with its inputs numbered in order of use."""

    def __init__(self, design: Design, c: m.Controller, plan: m.Plan, assigned, period, nan: bool = True, fails: dict | None = None) -> None:
        self.design, self.c = design, c
        self.fails = {} if fails is None else fails  # (sub, verb) -> can it fail (shared by a run)
        self.keys: dict[tuple, int] = {}
        self.parts: list = [plan.ordered, period, nan]
        verb = c.verbs.get(plan.verb)
        self.params = {p.name: p for p in verb.params} if verb else {}
        self.assigned = assigned
        self.fns: set[str] = set()
        states = {"new": "new"}
        for r in plan.rules:
            for ref in (r.state, r.next):
                if ref.kind == "named" and ref.name not in states:
                    states[ref.name] = f"s{len(states)}"  # type: ignore[index]
        self.states = states
        jobs: dict = {}
        for r in plan.rules:
            nxt = r.next
            ntext = states.get(nxt.name or "", "") if nxt.kind == "named" else (nxt.kind, nxt.code)
            jk = _skey(r.jobs)
            jobs.setdefault(jk, len(jobs))
            st = states.get(r.state.name or "", "") if r.state.kind == "named" else r.state.kind
            self.parts.append(("rule", st, ntext, jobs[jk], None if r.guard is None else self.expr(r.guard), self.commands(r)))

    def commands(self, r: m.Rule) -> tuple:
        """The rule's commands as the held-status analysis sees them: which subordinate, always or in an `if`, can it fail."""
        if not r.jobs:
            return ()
        from rcsc.checks.held import commands
        from rcsc.checks.plans import failure_of

        top, nested = commands(r)
        out = []
        controllers = self.design.controllers
        for n, cmd in enumerate(top + nested):
            if cmd.sub not in controllers:
                continue
            key = (cmd.sub, cmd.verb)
            if key not in self.fails:
                self.fails[key] = failure_of(self.design, cmd.sub, cmd.verb) is not None
            # `nested` holds no command equal to one of `top` (`held.commands`).
            out.append((self.key_of(("view", cmd.sub)), n >= len(top), self.fails[key]))
        return tuple(out)

    def key_of(self, key: tuple) -> int:
        if key not in self.keys:
            self.keys[key] = len(self.keys)
            self.parts.append(("input", len(self.keys) - 1) + self.describe(key))
        return self.keys[key]

    def describe(self, key: tuple) -> tuple:
        kind = key[0]
        fixed = _is_fixed(key, self.c, self.assigned)
        if kind == "view":
            return ("view", tuple(self.design.controllers[key[1]].statuses))
        if kind in ("error_code", "age", "in_state", "cycle"):
            return (kind,)
        var = None
        if kind == "gm":
            var = self.design.gm.get(key[1])
        elif kind == "local":
            var = self.c.locals.get(key[1])
        elif kind == "status":
            var = self.c.status_fields.get(key[1])
        elif kind == "param":
            var = self.params.get(key[1])
        elif kind == "subfield":
            var = self.design.controllers[key[1]].status_fields.get(key[2])
        if var is None:
            return (kind, "?")
        rng = (var.range.lo, var.range.hi) if var.range is not None else None
        tail = key[3:] if kind == "subfield" else key[2:]
        return (kind == "param", fixed, str(var.type), rng, tail)

    def expr(self, e: m.Expr, in_fn: bool = False):
        t = type(e)
        # The common kinds first (the text is computed for every plan, cached or not).
        if t is m.Binary:
            return ("b", e.op, str(e.type), str(e.left.type), self.expr(e.left), self.expr(e.right))
        if t is m.Ref:
            if e.kind == "arg":
                return ("arg", e.name)
            return ("v", self.key_of((e.kind, e.name)), ())
        if t is m.Const:
            return ("c", str(e.type), _vkey(e.value))
        if t is m.InState:
            return ("v", self.key_of(("in_state",)))
        if t is m.Cycle:
            return ("v", self.key_of(("cycle",)))
        if t is m.SubView:
            if e.attr in ("done", "error", "executing", "status"):
                return ("view", self.key_of(("view", e.sub)), e.attr, e.value)
            if e.attr == "field":
                return ("v", self.key_of(("subfield", e.sub, e.value)))
            return ("v", self.key_of((e.attr, e.sub)))
        if t is m.Age:
            return ("v", self.key_of(("gm_age", e.name)))
        if t is m.Field:
            return ("f", self.expr(e.obj), e.name)
        if t is m.Call:
            if e.kind == "fn":
                self.fns.add(e.func)
            return ("call", e.kind, e.func, str(e.type), tuple(self.expr(a) for a in e.args))
        if t is m.Unary:
            return ("u", e.op, str(e.type), self.expr(e.operand))
        if t is m.IfExpr:
            return ("if", str(e.type), self.expr(e.cond), self.expr(e.then), self.expr(e.else_))
        return ("?", t.__name__)

    def key(self) -> tuple:
        # The values a witness prefers for the inputs (`_preferred`: their
        # initial values) belong to the shape: two plans that differ only
        # there would otherwise share one witness, and which one depended on
        # which plan was analysed first (a check without the cache against a
        # re-check of one controller).
        preferred = tuple(_vkey(_preferred(self.design, self.c, k)) for k in self.keys)
        return (*self.parts, preferred)


# ---- the on-disk cache -----------------------------------------------------------------------
#
# The in-memory cache above shares one analysis between plans of the same
# shape.  The on-disk one (rcsc.checks.cache) is keyed more narrowly, so that a
# stored result is exactly what analysing the plan again would give: the
# plan's shape, the real names of its inputs, states, controller and verb,
# the values a witness prefers (initial values), the definitions of every
# type and function of the design, and the solver budget.


def _stored_key(design: Design, c: m.Controller, plan: m.Plan, canon: _Canon, opts: Options) -> str:
    from rcsc.checks.cache import digest

    preferred = tuple((k, _vkey(_preferred(design, c, k))) for k in canon.keys)
    return digest(
        (
            "guards",
            opts.timeout_ms,
            opts.rlimit,
            c.name,
            plan.verb,
            plan.continuous,
            canon.key(),
            tuple(canon.keys),
            tuple(canon.states.items()),
            preferred,
            _definitions_key(design),
        )
    )


# The design whose definitions were digested last (a weak reference: the
# memo must not keep a checked design alive) and the digest: the same for
# every plan of a check.
_definitions_memo: list = [None, ""]


def _definitions_key(design: Design) -> str:
    """A digest of the definitions of every type and function of `design`."""
    from rcsc.checks.cache import digest

    import weakref

    if _definitions_memo[0] is not None and _definitions_memo[0]() is design:
        return _definitions_memo[1]
    types = (
        tuple((n, tuple(t.members)) for n, t in sorted(design.enums.items())),
        tuple((n, tuple((fn, str(ft), _range_key(t.field_range(fn))) for fn, ft in t.fields)) for n, t in sorted(design.records.items())),
    )
    fns = tuple(
        (
            f.name,
            f.extern,
            str(f.ret),
            tuple((p.name, str(p.type), p.range and (p.range.lo, p.range.hi)) for p in f.params),
            None if f.body is None else _ekey(f.body),
        )
        for _, f in sorted(design.functions.items())
    )
    key = digest(("definitions", types, fns))
    _definitions_memo[:] = [weakref.ref(design), key]
    return key


def _range_key(rng) -> tuple | None:
    return None if rng is None else (_vkey(rng.lo), _vkey(rng.hi))


def _load(store, key: str, design: Design) -> list[_Finding] | None:
    from rcsc.checks.cache import decode

    data = store.get(key)
    if not isinstance(data, list):
        return None
    types = {**design.enums, **design.records}
    names = {fl.name for fl in fields(_Finding)}
    try:
        out = []
        for item in data:
            values = decode(item, types)
            if not isinstance(values, dict) or set(values) != names - {"span"}:
                return None
            out.append(_Finding(**values))
        return out
    except (KeyError, ValueError, TypeError, OverflowError):
        return None


def _save(store, key: str, findings: list[_Finding]) -> None:
    from rcsc.checks.cache import NotStorable, encode

    if any(f.span is not None for f in findings):
        return  # spans belong to this run's source files
    try:
        data = [encode({fl.name: getattr(f, fl.name) for fl in fields(_Finding) if fl.name != "span"}) for f in findings]
    except NotStorable:
        return
    store.put(key, data)


def _rename_key(key: tuple, mapping: dict[tuple, tuple]) -> tuple:
    for n in (3, 2, 1):
        base = key[:n]
        if base in mapping:
            return mapping[base] + key[n:]
    return key


def _rename(f: _Finding, mapping: dict, states: dict) -> _Finding:
    """A cached plan's finding in the names of a plan of the same shape."""
    g = _Finding(**{fl.name: getattr(f, fl.name) for fl in fields(_Finding)})
    g.state = states.get(f.state, f.state) if f.state is not None else None
    g.witness = {_rename_key(k, mapping): v for k, v in f.witness.items()}
    g.sample = {_rename_key(k, mapping): v for k, v in f.sample.items()}
    g.held = {_rename_key(k, mapping): v for k, v in f.held.items()}
    return g
