"""Re-check after an edit inside plans or headers: only the edited controllers are parsed and checked again.

`rcsc check` keeps the findings of the last check of each design in
`.rcsc-cache/` (`rcsc.checks.replay`).  When the root file has changed
since, but only inside some controllers (the common edits: a rule, a
condition, a job; a verb, a parameter's range, a status value, a local),
this module answers without parsing or checking the other controllers
again:

1. The root text is cut into its controllers and their plan bodies without
   parsing (`rcsc.front.items`).  Every imported file must be unchanged.
   Outside the controllers, only declarations (constants, enums, records,
   Global Memory, functions, externs, verb sets) may have changed: the
   text between them (the `design` line, imports, CPUs, comments) must be
   as it was, blanks aside (`rcsc.front.declarations`), and no imported
   file may use a name whose declaration changed (the files of a design
   share their names); otherwise the design is checked in full.
2. The controllers checked again are those whose text changed, those
   whose text names what an edited declaration declares (directly or
   through another declaration), and the supervisors of those whose header
   (the outline: header, verbs, status, locals, `pre`, `post`) changed or
   that name an edited declaration, since a supervisor's plans command its
   subordinates' verbs and read their status.  What the rest of the design
   reads of a header -- level, budget, period, kind, subordinates, Global
   Memory (`controller_head`) -- must be as it was.
3. The design is parsed with the plan bodies of the other controllers read
   as blanks (holes the tokenizer skips: every offset, line and column
   stays where it was), so their plans cost nothing.  The parser must find
   exactly the plans the scan found.
4. Those controllers' plans in the model are `ElidedPlans`: the check
   families skip them (`model.checked_controllers`), and what other
   controllers' checks read of them -- whether a verb can end in ERROR
   (`plans.failure_of`) and the commands they send with arguments that
   can be NaN (`guards.commands_sent`) -- is their summary from the last
   check (`controller_summary`).  Any other read of an elided plan raises
   `PlansElided` and the design is checked in full: a check that needs more
   than the summary is never answered from a stale table.
5. The checked controllers' summaries must equal their last ones (else what
   other controllers were checked against has changed: full check).
6. The findings are the last check's findings inside the other
   controllers (moved by the length change of the edits before them) and
   this run's findings everywhere else; suppressions (`rcsc: allow`) are
   applied to the whole again.  A last finding of an unchanged controller
   that points into edited text between the controllers (a label at an
   edited declaration) has no place in the new text: full check.

In a long-lived process (the language server, `memory_stores`) the
unchanged controllers are not even parsed again: the syntax tree each one
had with its plan bodies blank is kept from one re-check to the next and
moved to where the controller now starts (`_KeptTree`), and their
semantic pass models no plans (`ast_to_model(elided_plans=...)`).

The answer is the one a full check with the same cache gives, finding for
finding (tests/test_incremental.py edits designs at random and compares).
Only `rcsc check` uses it: the result carries findings, not a model.
"""

from __future__ import annotations

import json
import os

from rcsc.checks import cache
from rcsc.checks import replay as replays
from rcsc.diagnostics import Diagnostic, Diagnostics
from rcsc.front import items as it
from rcsc.front.declarations import changed_names, declarations, mentioning, names_in
from rcsc.front.source import SourceFile, Span, normalized
from rcsc.outputs import safeio

NAMESPACE = "outline"
FORMAT = 4
# In a long-lived process only (`memory_stores`): the syntax trees of the
# unchanged controllers, kept from one re-check to the next (`_KeptTree`).
TREES = "trees"
_KEPT_DESIGNS = 8  # designs whose trees are kept (the oldest go first)
# The findings that `rcsc.checks.suppress` makes: computed again over the whole text.
_SUPPRESSION_CODES = frozenset(("W0008",))


def controller_summary(design, c) -> dict:
    """What the checks of other controllers read of `c`'s plans (JSON values)."""
    from rcsc.checks.guards import commands_sent
    from rcsc.checks.plans import failure_of, held_statuses
    from rcsc.semantics import model as m

    if m.is_elided(c):
        return c.plans.summary
    return _plain({
        "sends": [list(x) for x in commands_sent(design, c)],
        "failure": {verb: failure_of(design, c.name, verb) for verb in c.plans},
        "holds": {verb: held_statuses(design, c.name, verb) for verb in c.plans},
    })


def controller_head(c) -> list:
    """What of `c`'s header the checks of other controllers and the
    design-wide checks read, beyond its verbs and status: its level, budget,
    period, kind, subordinates and Global Memory (JSON values).  A re-check
    after an edit of a header applies only while this is as it was."""
    return [c.level, c.budget_ns, c.declared_period_ns, c.simulator, [u.name for u in c.subordinates],
            [u.name for u in c.reads], [u.name for u in c.writes]]


def _plain(value):
    """`value` as JSON gives it back (lists for tuples), so that summaries compare equal."""
    return json.loads(json.dumps(value))


# ---- remembering the outline of a full check ----------------------------------------------


def stores_in(folder: str) -> dict:
    """The stores of the cache folder `folder`, by namespace."""
    return {ns: cache.Store(folder, ns) for ns in (NAMESPACE, replays.NAMESPACE, "guards", "values")}


def memory_stores(solver_store: cache.MemoryStore) -> dict:
    """Stores in memory, for a long-lived process (the language server); the
    solver's analyses in `solver_store`, which the process keeps anyway.

    A check made with them holds the kept syntax trees of the unchanged
    controllers (`_KeptTree`), whose spans the next re-check of the same
    design moves: use a result before checking that design again (the
    language server publishes the findings at once)."""
    return {NAMESPACE: cache.MemoryStore(limit=64), replays.NAMESPACE: cache.MemoryStore(limit=64), "guards": solver_store,
            "values": solver_store, TREES: {}}


def remember(path: str, as_module: bool, folder: str | None, result, stores: dict | None = None) -> None:
    """Keep a check (`result`, a `rcsc.driver.CheckResult`) for the next run:
    its findings (`replay.remember`) and the outline of its root file, in
    `folder` or in `stores` (`memory_stores`)."""
    replays.remember(path, as_module, folder, result, into=stores[replays.NAMESPACE] if stores is not None else None)
    _remember_outline(path, as_module, folder, result, stores)


def _remember_outline(path: str, as_module: bool, folder: str | None, result, stores: dict | None) -> None:
    from rcsc.checks import hints

    design = getattr(result, "model", None)
    loaded = getattr(result, "files", None)
    if (stores is None and cache.disabled_by_environment()) or design is None or not loaded or not loaded[0].is_root:
        return
    text = loaded[0].source.text
    found = it.controller_items(text)
    sums = it.digests(text)
    if found is None or sums is None or any(f.tree is None for f in loaded):
        return
    try:
        summaries = {item.name: controller_summary(design, design.controllers[item.name]) for item in found}
    except KeyError:
        return  # a controller the scan found and the model does not hold
    decls = declarations(text, loaded[0].tree.items, found)
    value = {
        "format": FORMAT,
        "root": replays._sha(text),
        "gaps": sums[0],
        "controllers": [[x.name, x.start, x.end, osha, bsha] for x, (osha, bsha) in zip(found, sums[1])],
        "summaries": summaries,
        "heads": {x.name: controller_head(design.controllers[x.name]) for x in found},
        # Needed only by a kept unknown-name finding (`_check`).
        "scope": hints.scope_names_key(design) if any(d.code == "E0100" for d in result.diags.items) else None,
        "values_context": design.values_context,
        # What an edit of declarations outside the controllers is compared with (`_edited_declarations`).
        "declarations": None if decls is None else {"frame": decls.frame, "digests": decls.digests},
    }
    target = stores[NAMESPACE] if stores is not None else cache.Store(folder, NAMESPACE)  # type: ignore[arg-type]
    try:
        target.put(replays.key_of(path, as_module), value)
    except (ValueError, TypeError):
        return


# ---- the re-check -------------------------------------------------------------------------


class _Miss(Exception):
    """The incremental re-check does not apply: check in full (the argument says why)."""


# Why the last `recheck` did not apply (for tests and bench/incremental_fuzz.py).
last_miss = ""
# How many controllers' kept syntax trees the last `recheck` used (for tests).
last_kept = 0
# The controllers the last `recheck` checked again (for tests).
last_rechecked: frozenset[str] = frozenset()


def recheck(path: str, as_module: bool, folder: str | None, stores: dict | None = None, overlay: dict[str, str] | None = None):
    """The findings of `path` after an edit inside the plans of some of its
    controllers (a `rcsc.driver.CheckResult` whose model has the unchanged
    controllers' plans elided), or None when the design must be checked in
    full (`last_miss` says why)."""
    if os.environ.get("RCSC_INCREMENTAL") == "0" or (stores is None and cache.disabled_by_environment()):
        return None
    import gc

    # As in `rcsc.driver.check_path`: no cyclic collection during the run.
    was_enabled = gc.isenabled()
    gc.disable()
    global last_miss, last_kept, last_rechecked
    last_miss, last_kept, last_rechecked = "", 0, frozenset()
    try:
        return _recheck(path, as_module, stores if stores is not None else stores_in(folder), overlay or {})  # type: ignore[arg-type]
    except _Miss as miss:
        last_miss = str(miss.args[0]) if miss.args else "?"
        return None
    finally:
        gc.freeze()
        if was_enabled:
            gc.enable()


def _recheck(path: str, as_module: bool, stores: dict, overlay: dict[str, str]):
    key = replays.key_of(path, as_module)
    outline = stores[NAMESPACE].get(key)
    last = stores[replays.NAMESPACE].get(key)
    if not isinstance(outline, dict) or not isinstance(last, dict) or outline.get("format") != FORMAT:
        raise _Miss("no stored outline")

    def read(where: str) -> str | None:
        text = overlay.get(where)
        return text if text is not None else replays._read_text(where)

    try:
        files = last["files"]
        if files[0][2] != outline["root"]:
            raise _Miss("findings and outline of different checks")
        imported = []
        for _, where, sha in files[1:]:
            text = read(where)
            if text is None or replays._sha(normalized(text)) != sha:
                raise _Miss("an imported file changed")
            imported.append(text)
        old_items = [(str(n), int(s), int(e), str(o), str(b)) for n, s, e, o, b in outline["controllers"]]
        summaries = outline["summaries"]
        values_context = outline.get("values_context")
        if values_context is not None and not isinstance(values_context, str):
            raise ValueError
    except (KeyError, TypeError, ValueError, IndexError):
        raise _Miss("a corrupt entry") from None
    raw = overlay.get(os.path.realpath(path))
    if raw is None:
        try:
            raw = safeio.read_input(path).decode("utf-8")
        except (OSError, ValueError, safeio.InputError):
            raise _Miss("the root file cannot be read") from None
    text = normalized(raw)
    if replays._sha(text) == outline["root"]:
        raise _Miss("the root file is unchanged")
    new_items = it.controller_items(text)
    sums = it.digests(text)
    if new_items is None or sums is None:
        raise _Miss("the text outside the controllers changed")
    if [x.name for x in new_items] != [n for n, *_ in old_items]:
        raise _Miss("controllers added, removed or renamed")
    # The pieces of text outside the controllers (before each, and after the
    # last) that the edit changed; in them, the names whose declarations it
    # changed.
    gaps = _edited_gaps(outline, sums[0])
    declared = _edited_declarations(path, text, new_items, outline, imported) if gaps else set()
    changed: set[str] = set()
    headers: set[str] = set()
    outlines: dict[str, str] = {}
    for x, (name, _, _, osha, bsha), (new_osha, new_bsha) in zip(new_items, old_items, sums[1]):
        if new_osha != osha:
            headers.add(name)
        outlines[name] = new_osha
        if new_bsha != bsha:
            changed.add(name)
    if declared:
        # A controller that names what an edited declaration declares is
        # checked again, as if its header had changed (the declaration can
        # be the type of a verb's parameter or of a status field, which its
        # supervisor reads).
        headers |= mentioning(text, new_items, declared)
    if not changed and not headers and not gaps:
        raise _Miss("no controller changed")
    heads = outline.get("heads")
    if not isinstance(heads, dict) or any(x.name not in summaries or x.name not in heads for x in new_items):
        raise _Miss("a corrupt entry")
    # An edited header (verbs, their parameters, status, locals, `pre`,
    # `post`) is read by the controller's own checks and by its
    # supervisor's plans (the commands they send it, the status and fields
    # they read of it): the supervisor is checked again too.  What the rest
    # of the design reads of a header (level, budget, period, subordinates,
    # Global Memory) must be as it was: checked once it is modelled.
    supervisors = {name for name, head in heads.items() if isinstance(head, list) and len(head) == 7
                   and isinstance(head[4], list) and any(sub in headers for sub in head[4])}
    rechecked = changed | headers | supervisors
    global last_rechecked
    last_rechecked = frozenset(rechecked)
    elided = [x for x in new_items if x.name not in rechecked]
    # The text before each controller (where its doc comment is).
    before = {x.name: sums[0][i] for i, x in enumerate(new_items)}
    kept = _kept_trees(stores, key, elided, outlines, before)
    # The parser reads the edited controllers whole, the other controllers
    # with their plan bodies as blanks, and nothing of those whose tree is
    # kept: those are holes in the text, which it reads as blanks.
    holes = [r for x in elided for r in ([(x.start, x.end)] if x.name in kept else [(s, e) for _, s, e in x.bodies])]
    return _check(path, as_module, stores, overlay, text, holes, new_items, old_items, elided, rechecked, summaries, last,
                  None if gaps else values_context, kept, outlines, before, {name: heads[name] for name in headers},
                  outline.get("scope"), gaps)


def _edited_declarations(path: str, text: str, new_items: list, outline: dict, imported: list[str]) -> set[str]:
    """The names whose declarations outside the controllers an edit changed
    (changed, added or removed, and those of the declarations that name
    them: `rcsc.front.declarations`).  Misses when anything else outside
    the controllers changed (the `design` line, an import, a CPU, a
    comment), and when an imported file (`imported`, their texts) names
    one: the names of a design are shared by all its files, so a function
    or a controller of an imported file can use a constant of the root."""
    from rcsc.front.rdparse import Fallback, parse_fast

    stored = outline.get("declarations")
    if not isinstance(stored, dict) or not isinstance(stored.get("frame"), str) or not isinstance(stored.get("digests"), dict):
        raise _Miss("the text outside the controllers changed")
    if not all(isinstance(k, str) and " " in k and isinstance(v, str) for k, v in stored["digests"].items()):
        raise _Miss("a corrupt entry")
    # The controllers are holes: only the text outside them is parsed.
    try:
        tree, found = parse_fast(SourceFile(path, text), [(x.start, x.end) for x in new_items])
    except Fallback:
        raise _Miss("a syntax error") from None
    if tree is None or found.has_errors():
        raise _Miss("a syntax error")
    now = declarations(text, tree.items, new_items)
    if now is None or now.frame != stored["frame"]:
        raise _Miss("the text outside the controllers changed")
    names = changed_names(stored["digests"], now)
    if not names:
        raise _Miss("the text outside the controllers changed")
    if not now.frame_words.isdisjoint(names):
        # A CPU (or an import) names what changed: its schedule or rate may
        # depend on it.
        raise _Miss("the text outside the controllers changed")
    if any(not names_in(other).isdisjoint(names) for other in imported):
        raise _Miss("an imported file names an edited declaration")
    return names


def _edited_gaps(outline: dict, now: list[str]) -> set[int]:
    """The pieces of text outside the controllers (before each, and after
    the last: by index) that an edit changed (`now`: their digests in the
    new text, `items.gaps`)."""
    old = outline.get("gaps")
    if not isinstance(old, list) or len(old) != len(now):
        raise _Miss("a corrupt entry")
    return {i for i, (a, b) in enumerate(zip(old, now)) if a != b}


# ---- syntax trees kept between re-checks (a long-lived process) -----------------------------


class _KeptTree:
    """The syntax tree of one controller as the parser built it from the
    controller's text with its plan bodies blank, and every span in it.

    Such a tree depends only on the controller's outline, on the length of
    each plan body and on the doc comment before it (in the text outside
    the controllers): when all are as they were (`key`), the tree is the
    one the parser would build again, but at another offset if the text
    before the controller changed length.  Moving it there means adding
    that difference to each of its spans, which is much cheaper than
    parsing the controller again (a 200-controller design re-parses 3,400
    verbs and their parameters otherwise).  The spans are moved in place:
    the tree belongs to the last check only, which the next one replaces.
    """

    __slots__ = ("key", "start", "tree", "spans")

    def __init__(self, key: tuple, start: int, tree, spans: list[Span]) -> None:
        self.key = key
        self.start = start
        self.tree = tree
        self.spans = spans

    def move_to(self, root: SourceFile, start: int) -> None:
        delta = start - self.start
        for span in self.spans:
            span.file = root
            if delta:
                span.start += delta
                span.end += delta
        self.start = start


def _tree_key(x: it.ControllerItem, outline_sha: str, before_sha: str) -> tuple:
    # The text between the last controller and this one belongs to the key
    # too: a doc comment written before the controller since its tree was
    # kept (checked in full then) documents the controller, which a kept
    # tree would not know.  Only that text: an edit of a declaration
    # elsewhere keeps the tree.
    return (before_sha, outline_sha, tuple(e - s for _, s, e in x.bodies))


def _kept_trees(stores: dict, key: str, elided: list, outlines: dict[str, str], before: dict[str, str]) -> dict[str, _KeptTree]:
    """The kept trees of the elided controllers `elided` that are still
    their trees (same outline, same plan body lengths, same text between
    the controller before and this one)."""
    designs = stores.get(TREES)
    found = designs.get(key) if designs is not None else None
    if not found:
        return {}
    out = {}
    for x in elided:
        k = found.get(x.name)
        if k is not None and k.key == _tree_key(x, outlines[x.name], before[x.name]):
            out[x.name] = k
    return out


def _spans_of(node) -> list[Span]:
    """Every span in the syntax tree `node`, each once (a span object can be shared by nodes)."""
    from rcsc.front import ast

    out: list[Span] = []
    seen: set[int] = set()
    stack = [node]
    slots_of: dict[type, tuple[str, ...]] = {}
    while stack:
        x = stack.pop()
        if isinstance(x, Span):
            if id(x) not in seen:
                seen.add(id(x))
                out.append(x)
        elif isinstance(x, (list, tuple)):
            stack.extend(x)
        elif isinstance(x, ast._Slots):
            names = slots_of.get(type(x))
            if names is None:
                names = slots_of[type(x)] = tuple(n for k in type(x).__mro__ for n in getattr(k, "__slots__", ()))
            for n in names:
                v = getattr(x, n, None)
                if v is not None and not isinstance(v, (str, int, float)):
                    stack.append(v)
    return out


def _keep_trees(stores: dict, key: str, trees: dict, elided: list, kept: dict[str, _KeptTree], outlines: dict[str, str],
                before: dict[str, str]) -> None:
    designs = stores.get(TREES)
    if designs is None:
        return
    found = designs.pop(key, {})
    for x in elided:
        if x.name not in kept and x.name in trees:
            tree = trees[x.name]
            if tree.doc is None:  # a doc comment lies before the controller: blanking it would orphan it
                found[x.name] = _KeptTree(_tree_key(x, outlines[x.name], before[x.name]), x.start, tree, _spans_of(tree))
    designs[key] = found
    while len(designs) > _KEPT_DESIGNS:
        del designs[next(iter(designs))]


def _check(path, as_module, stores, overlay, text, holes, new_items, old_items, elided, changed, summaries, last, values_context,
           kept, outlines, before, heads, scope, gaps):
    from rcsc.checks import check_model, guards, hints, suppress
    from rcsc.checks.hints import add_hints
    from rcsc.front import ast
    from rcsc.front.loader import path_to_files
    from rcsc.semantics import model as m
    from rcsc.semantics.sema import ast_to_model

    diags = Diagnostics()
    loaded = path_to_files(path, diags, as_module, {**overlay, os.path.realpath(path): text}, root_holes=holes)
    if any(f.tree is None for f in loaded) or not loaded[0].is_root:
        raise _Miss("a syntax error")
    if any(isinstance(x, (ast.ControllerType, ast.ControllerInstance)) for f in loaded for x in f.tree.items):
        # The plans of a controller type are the plans of all its
        # instances, checked as the instances' (and the value analysis
        # cannot keep their findings between runs): not re-checked in part.
        raise _Miss("controller types")
    root = loaded[0].source
    trees = {x.name.name: x for x in loaded[0].tree.items if isinstance(x, ast.Controller)}
    if kept:
        if any(name in trees for name in kept):
            raise _Miss("the parser found a controller where the text was blank")
        for x in new_items:
            if x.name in kept:
                kept[x.name].move_to(root, x.start)
                trees[x.name] = kept[x.name].tree
        loaded[0].tree.items = sorted([*loaded[0].tree.items, *(k.tree for k in kept.values())], key=lambda n: n.span.start)
        global last_kept
        last_kept = len(kept)
    # The parser must have found the plans the scan found, in every controller.
    for x in new_items:
        c = trees.get(x.name)
        if c is None or (c.span.start, c.span.end) != (x.start, x.end):
            raise _Miss("the parser found other controllers than the scan")
        if [(p.name.name, p.span.end - 1) for p in c.plans] != [(v, e) for v, _, e in x.bodies]:
            raise _Miss("the parser found other plans than the scan")
    _keep_trees(stores, replays.key_of(path, as_module), trees, elided, kept, outlines, before)
    elided_names = {x.name for x in elided}
    try:
        design = ast_to_model(loaded, diags, elided_plans={name: summaries[name] for name in elided_names})
    except m.PlansElided:
        raise _Miss("the semantic pass read an elided plan") from None
    # When the text outside the controllers and the imports are as they
    # were, so are the declarations the value analysis digests (else it
    # digests them again: None).
    design.values_context = values_context
    if any(not m.is_elided(design.controllers[name]) for name in elided_names):
        raise _Miss("the semantic pass modelled an elided controller's plans")
    if any(_plain(controller_head(design.controllers[name])) != head for name, head in heads.items()):
        raise _Miss("a controller's level, budget, period, subordinates or Global Memory changed")

    # Every finding belongs either to an unchanged controller (the last
    # check's, moved to where that controller is now) or to the rest (this
    # run's).  This run's findings that belong to an unchanged controller
    # come from its blanked plans and are dropped.
    ranges = [(x.start, x.end) for x in elided]

    def in_elided(span: Span | None) -> bool:
        return span is not None and span.file is root and any(lo <= span.start < hi for lo, hi in ranges)

    def owned(d: Diagnostic) -> bool:
        """Whether `d` is about an unchanged controller: where it points, or
        for a finding in shared text (a function, a block type, another
        file), the instance it names or the controller of its data."""
        if d.span is not None and d.span.file is root and not _in_gap(d.span.start, new_items):
            return in_elided(d.span)
        return any(in_elided(lab.span) for lab in d.labels) or d.data.get("controller") in elided_names

    shift = _shifts(old_items, new_items, elided_names, gaps)
    kept = [d for d in _moved(last, root, shift, loaded, elided_names) if d is not None and owned(d)]
    if any(getattr(d, "_edited", False) for d in kept):
        raise _Miss("a finding with a label in an edited controller")
    # The "did you mean" of an unknown name (E0100) is chosen among names
    # declared in every controller's header: after an edit of a header, a
    # kept one holds only while those names are as they were.
    if (heads or gaps) and any(d.code == "E0100" for d in kept) and hints.scope_names_key(design) != scope:
        raise _Miss("the names a hint can suggest changed")
    diags.items = [d for d in diags.items if not owned(d)] + kept
    diags._seen = {getattr(d, "_key", None) or (d.code, d.message, d.span.file.path if d.span else "", d.span.start if d.span else -1)
                   for d in diags.items}
    cached = set(map(id, kept))
    # The solver-based families skip the whole design when names or types
    # failed anywhere (`guards.front_end_errors`): the kept findings hold
    # only if that is as it was.
    was = any(str(x[1]) == "error" and str(x[0])[1:3] in ("00", "01", "02") for x in last["items"])
    if guards.front_end_errors(diags) != was:
        raise _Miss("errors of names or types came or went")

    def same_summaries() -> None:
        # Asked before the solver families run: a miss then leaves no z3
        # terms behind to change the witnesses of the full check that follows.
        for name in changed:
            if controller_summary(design, design.controllers[name]) != summaries[name]:
                raise _Miss("an edited controller's summary changed")

    try:
        check_model(design, diags, guards.Options(store=stores["guards"]), stores["values"], before_solver=same_summaries)
    except m.PlansElided:
        raise _Miss("a check read an elided plan") from None
    diags.items = [d for d in diags.items if id(d) in cached or not owned(d)]
    fresh = Diagnostics()
    fresh.items = [d for d in diags.items if id(d) not in cached]
    add_hints(fresh, design)
    suppress.apply([f.source for f in loaded], diags, report_unused=not diags.has_errors())
    from rcsc.driver import CheckResult

    return CheckResult(diags, design, loaded, partial=True)


def _shifts(old_items, new_items, elided_names, gaps: set[int]) -> list[tuple[int, int, int, str]]:
    """The old root text in pieces (old start, old end, offset to add to move
    it to the new text, kind): "gap" (text between controllers, unchanged),
    "elided" (an unchanged controller), "edited" (a controller checked
    again: its offsets mean nothing now) or "edited gap" (text between
    controllers where declarations were edited: likewise)."""
    out: list[tuple[int, int, int, str]] = []
    at, delta = 0, 0
    for i, ((name, s, e, _, _), x) in enumerate(zip(old_items, new_items)):
        out.append((at, s, delta, "edited gap" if i in gaps else "gap"))
        delta = x.start - s
        out.append((s, e, delta, "elided" if name in elided_names else "edited"))
        delta = x.end - e
        at = e
    out.append((at, 1 << 62, delta, "edited gap" if len(old_items) in gaps else "gap"))
    return out


def _in_gap(at: int, new_items) -> bool:
    """Whether offset `at` of the new text is outside every controller."""
    return not any(x.start <= at < x.end for x in new_items)


def _moved(last: dict, root: SourceFile, shift, loaded, elided_names) -> list[Diagnostic | None]:
    """The last check's findings (before suppression: `suppress.apply`
    decides again), every span moved to the new text; a finding that points
    into an edited controller is None, one with a label there is marked
    `_edited` (its label has no place in the new text).  A finding that
    points into edited text between the controllers is this run's to make
    again (None), unless it belongs to an unchanged controller (its data
    names one, or a label points into one): then the design is checked in
    full."""
    by_where = {replays.where_of(f): f.source for f in loaded}

    def piece(s: int):
        for p in shift:
            if p[0] <= s < p[1]:
                return p
        raise _Miss("a finding outside the text pieces")

    edited: list[bool] = []
    in_elided: list[bool] = []

    def span(data):
        if data is None:
            return None
        i, s, e = int(data[0]), int(data[1]), int(data[2])
        if i != 0:
            src = by_where.get(last["files"][i][1])
            if src is None:
                raise _Miss("a finding in a file this run did not read")
            return Span(src, s, e)
        _, _, d, kind = piece(s)
        if kind in ("edited", "edited gap"):
            edited.append(True)
            return None
        if kind == "elided":
            in_elided.append(True)
        return Span(root, s + d, e + d)

    out: list[Diagnostic | None] = []
    try:
        for data in list(last["items"]) + list(last["suppressed"]):
            if data[0] in _SUPPRESSION_CODES:
                continue
            where = piece(int(data[3][1]))[3] if data[3] is not None and int(data[3][0]) == 0 else None
            if where == "edited":
                out.append(None)
                continue
            edited.clear()
            in_elided.clear()
            d = replays.decode(data, span)
            if where == "edited gap":
                if in_elided or d.data.get("controller") in elided_names:
                    raise _Miss("a finding of an unchanged controller in edited declarations")
                out.append(None)
                continue
            d._edited = bool(edited)  # type: ignore[attr-defined]
            d.data.pop("suppression", None)
            out.append(d)
    except (KeyError, ValueError, TypeError, IndexError):
        raise _Miss("a corrupt entry") from None
    return out
