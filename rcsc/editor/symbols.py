"""What each name of a design means, for editors (`rcsc lsp`): definitions,
hover text and the outline of a file, read from the syntax trees.

The index is built from the parsed files of one design (its root and every
import), so it works even when the design does not pass its checks.  A name
is looked up where it is used: inside a controller its own verbs, plans,
locals and status fields come first, then the design's global names; in
`X.Y`, `X` decides (a controller's verb or status field, an enum's member);
in a rule's state or next-state position, a state of that plan (defined by
the first rule that names it).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from rcsc.front import ast
from rcsc.front.source import SourceFile, Span

_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
CODE_RE = re.compile(r"[EW]\d{4}")


@dataclass
class Symbol:
    name: str
    kind: str  # const, gm, fn, extern, enum, member, record, verb-set, controller, verb, plan, local, status, cpu, state, rule
    span: Span  # the name where it is declared
    decl: Span  # the whole declaration
    detail: str  # one-line signature for hover
    children: list["Symbol"] = field(default_factory=list)
    doc: str = ""  # its `///` doc comment


def _squash(text: str) -> str:
    return " ".join(text.split())


def _signature(node: ast.Node, stop: str | None = None) -> str:
    text = node.span.text
    if stop and stop in text:
        text = text[: text.index(stop)]
    return _squash(text)


@dataclass
class Index:
    globals: dict[str, Symbol] = field(default_factory=dict)
    controllers: dict[str, Symbol] = field(default_factory=dict)
    members: dict[str, dict[str, Symbol]] = field(default_factory=dict)  # controller or enum -> its names
    top: dict[str, list[Symbol]] = field(default_factory=dict)  # file path -> outline
    plans: list[tuple[str, ast.Plan, Symbol]] = field(default_factory=list)  # (controller, plan, symbol)

    def add_global(self, sym: Symbol, path: str) -> None:
        self.globals.setdefault(sym.name, sym)
        self.top.setdefault(path, []).append(sym)


def build(files: list[ast.File]) -> Index:
    """The index of the syntax trees of one design's files."""
    idx = Index()
    verb_sets: dict[str, list[ast.Verb]] = {}
    for tree in files:
        path = tree.span.file.path
        idx.top.setdefault(path, [])
        for item in tree.items:
            if isinstance(item, ast.Const):
                idx.add_global(Symbol(item.name.name, "const", item.name.span, item.span, _signature(item)), path)
            elif isinstance(item, ast.GmVar):
                idx.add_global(Symbol(item.name.name, "gm", item.name.span, item.span, _signature(item)), path)
            elif isinstance(item, ast.Function):
                idx.add_global(Symbol(item.name.name, "fn", item.name.span, item.span, _signature(item, "=")), path)
            elif isinstance(item, ast.Extern):
                idx.add_global(Symbol(item.name.name, "extern", item.name.span, item.span, _signature(item)), path)
            elif isinstance(item, ast.Enum):
                sym = Symbol(item.name.name, "enum", item.name.span, item.span, f"enum {item.name.name}")
                members = {}
                for m in item.members:
                    child = Symbol(m.name, "member", m.span, m.span, f"{item.name.name}.{m.name}")
                    members[m.name] = child
                    sym.children.append(child)
                idx.members[item.name.name] = members
                idx.add_global(sym, path)
            elif isinstance(item, ast.Record):
                sym = Symbol(item.name.name, "record", item.name.span, item.span, _signature(item, "{") + " { "
                             + ", ".join(_squash(f.span.text) for f in item.fields) + " }")
                idx.add_global(sym, path)
            elif isinstance(item, ast.VerbSet):
                verb_sets[item.name.name] = item.verbs
                sym = Symbol(item.name.name, "verb-set", item.name.span, item.span, f"verbs {item.name.name}")
                for v in item.verbs:
                    sym.children.append(Symbol(v.name.name, "verb", v.name.span, v.span, _signature(v)))
                idx.add_global(sym, path)
            elif isinstance(item, ast.Cpu):
                idx.add_global(Symbol(item.name.name, "cpu", item.name.span, item.span, f"cpu {item.name.name}"), path)
            elif isinstance(item, ast.Controller):
                sym = _controller(item, idx)
                idx.controllers[item.name.name] = sym
                idx.add_global(sym, path)
            elif isinstance(item, ast.ControllerType):  # its instances share its members
                sym = _controller(item.body, idx)
                sym.detail = "controller type " + sym.detail[len("controller "):]
                idx.add_global(sym, path)
            elif isinstance(item, ast.ControllerInstance):
                sym = Symbol(item.name.name, "controller", item.name.span, item.span, _squash(item.span.text))
                idx.controllers[item.name.name] = sym
                idx.add_global(sym, path)
    for tree in files:
        for item in tree.items:
            if isinstance(item, ast.ControllerInstance):
                idx.members[item.name.name] = idx.members.get(item.type_name.name, {})
    # Verbs a controller takes through `verbs SET` belong to it too.
    for tree in files:
        for item in tree.items:
            if isinstance(item, ast.ControllerType):
                item = item.body
            if isinstance(item, ast.Controller):
                members = idx.members[item.name.name]
                for set_name in item.verb_sets:
                    for v in verb_sets.get(set_name.name, []):
                        members.setdefault(v.name.name, Symbol(v.name.name, "verb", v.name.span, v.span, _signature(v)))
    _attach_docs(files, idx)
    # An instance without a doc comment of its own shows its type's, as the
    # model (and so `rcsc doc` and the generated code) gives it.
    types = {item.name.name: item for tree in files for item in tree.items if isinstance(item, ast.ControllerType)}
    for tree in files:
        for item in tree.items:
            t = types.get(item.type_name.name) if isinstance(item, ast.ControllerInstance) else None
            if t is not None and item.doc is None and t.doc is not None and item.name.name in idx.controllers:
                idx.controllers[item.name.name].doc = t.doc.text
    return idx


def _attach_docs(files: list[ast.File], idx: Index) -> None:
    """Give each symbol the doc comment of the declaration it stands for."""
    from rcsc.front.doccomment import DOCUMENTED, _children

    docs: dict[tuple[str, int], str] = {}

    def collect(node) -> None:
        if isinstance(node, DOCUMENTED) and node.doc is not None:
            docs[(node.span.file.path, node.span.start)] = node.doc.text
        for child in _children(node):
            collect(child)

    for tree in files:
        for item in tree.items:
            collect(item)
    if not docs:
        return
    seen: set[int] = set()

    def give(sym: Symbol) -> None:
        if id(sym) in seen:
            return
        seen.add(id(sym))
        sym.doc = docs.get((sym.decl.file.path, sym.decl.start), "")
        for child in sym.children:
            give(child)

    for syms in idx.top.values():
        for sym in syms:
            give(sym)
    for members in idx.members.values():
        for sym in members.values():
            give(sym)


def _controller(c: ast.Controller, idx: Index) -> Symbol:
    head = f"controller {c.name.name}"
    if c.level:
        head += f" level {c.level[0][0]}"
    if c.budget:
        head += f" budget {c.budget[0].text}"
    sym = Symbol(c.name.name, "controller", c.name.span, c.span, head)
    members: dict[str, Symbol] = {}
    for v in c.verbs:
        members[v.name.name] = Symbol(v.name.name, "verb", v.name.span, v.span, _signature(v))
        sym.children.append(members[v.name.name])
    for kind, decls in (("status", c.status_fields), ("local", c.locals)):
        for dcl in decls:
            members.setdefault(dcl.name.name, Symbol(dcl.name.name, kind, dcl.name.span, dcl.span, f"{kind} {_squash(dcl.span.text)}"))
            sym.children.append(members[dcl.name.name])
    for plan in c.plans:
        psym = Symbol(plan.name.name, "plan", plan.name.span, plan.span, f"plan {plan.name.name} of {c.name.name}")
        for rule in plan.rules:
            psym.children.append(Symbol(rule.label.name, "rule", rule.label.span, rule.span, _squash(rule.span.text)))
        sym.children.append(psym)
        idx.plans.append((c.name.name, plan, psym))
        members.setdefault(f"plan {plan.name.name}", psym)
    idx.members[c.name.name] = members
    return sym


# ---------------------------------------------------------------------------
# lookup at a position
# ---------------------------------------------------------------------------

def word_at(source: SourceFile, offset: int) -> tuple[str, int, int, str | None] | None:
    """The identifier at `offset` (name, start, end) and the name before a
    `.` in front of it, if any."""
    text = source.text
    for m in _WORD.finditer(text, max(0, text.rfind("\n", 0, offset) + 1)):
        if m.start() > offset:
            break
        if m.start() <= offset <= m.end():
            prefix = None
            if m.start() > 0 and text[m.start() - 1] == ".":
                k = j = m.start() - 1
                while j > 0 and (text[j - 1].isalnum() or text[j - 1] == "_"):
                    j -= 1
                prefix = text[j:k] or None
            return m.group(0), m.start(), m.end(), prefix
    return None


def _enclosing(idx: Index, path: str, offset: int) -> tuple[str | None, ast.Plan | None]:
    controller = None
    for name, sym in idx.controllers.items():
        if sym.decl.file.path == path and sym.decl.start <= offset < sym.decl.end:
            controller = name
    plan = None
    for cname, p, _ in idx.plans:
        if cname == controller and p.span.file.path == path and p.span.start <= offset < p.span.end:
            plan = p
    return controller, plan


def _state_symbol(plan: ast.Plan, name: str) -> Symbol | None:
    for rule in plan.rules:
        if rule.next.kind == "named" and rule.next.name == name:
            return Symbol(name, "state", rule.next.span, rule.span, f"state {name} of plan {plan.name.name} (entered by rule {rule.label.name})")
    for rule in plan.rules:
        if rule.state.kind == "named" and rule.state.name == name:
            return Symbol(name, "state", rule.state.span, rule.span, f"state {name} of plan {plan.name.name}")
    return None


def lookup(idx: Index, source: SourceFile, offset: int) -> Symbol | None:
    """The symbol the identifier at `offset` of `source` refers to, or None."""
    found = word_at(source, offset)
    if found is None:
        return None
    word, start, _end, prefix = found
    controller, plan = _enclosing(idx, source.path, offset)
    if prefix is not None:
        if prefix in idx.members and word in idx.members[prefix]:
            return idx.members[prefix][word]
        if prefix == "cmd" and plan is not None and controller is not None:
            verb = idx.members.get(controller, {}).get(plan.name.name)
            return verb
        return None
    for _, _, psym in idx.plans:  # a plan's own name (a verb's name elsewhere)
        if psym.span.file.path == source.path and psym.span.start == start:
            return psym
    if plan is not None:
        for rule in plan.rules:
            in_state = rule.state.span.start <= start < rule.state.span.end
            in_next = rule.next.span.start <= start < rule.next.span.end and rule.next.kind == "named"
            if in_state or in_next:
                return _state_symbol(plan, word)
    if controller is not None:
        own = idx.members.get(controller, {})
        if word in own:
            return own[word]
    if word in idx.globals:
        return idx.globals[word]
    return None


def hover_text(sym: Symbol) -> str:
    text = f"```rcs\n{sym.detail}\n```\n({sym.kind})"
    return text + "\n\n" + sym.doc if sym.doc else text
