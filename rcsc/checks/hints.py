""""Did you mean" helps for typos, added after every stage has run.

A misspelt name is the most common mistake and the most confusing one to
read about: `levl_m` is "not found", a verb `GOO` is "not accepted".  This
pass looks at the findings about unknown names (E0100, E0103, E0104, E0105)
whose candidates the model knows and at syntax errors where an
operator of another language was written (`&&`, `||`, `!`, `else if`), and
adds a help naming the closest declared name or the rcs spelling.  It only
adds helps; it never changes a finding's code, span or message.  (The
findings whose guess also stands in for the name, so that no follow-on
findings are reported, guess where they are made: `Diagnostic.guess`.)
"""

from __future__ import annotations

import re

from rcsc.diagnostics import Diagnostic, Diagnostics, closest
from rcsc.semantics.model import Design

_QUOTED = re.compile(r"`([^`]*)`")


def _scope_names(design: Design) -> set[str]:
    names: set[str] = set(design.consts) | set(design.gm) | set(design.functions) | set(design.enums) | set(design.records)
    for c in design.controllers.values():
        names |= set(c.locals) | set(c.status_fields) | {u.name for u in c.subordinates}
        for v in c.verbs.values():
            names |= {p.name for p in v.params}
    return names


def scope_names_key(design: Design) -> str:
    """A digest of the names an unknown name's "did you mean" can suggest
    (E0100): every controller's locals, status fields, subordinates and
    verb parameters among them, so an edit of any header can change the
    help of a finding in another controller (rcsc.checks.incremental)."""
    import hashlib

    return hashlib.sha256("\n".join(sorted(_scope_names(design))).encode()).hexdigest()


def _controller_at(design: Design, d: Diagnostic):
    if d.span is None:
        return None
    for c in design.controllers.values():
        # An instance of a controller type spans its type's text (in a view of the file).
        if getattr(c.span.file, "origin", c.span.file) is d.span.file and c.span.start <= d.span.start < c.span.end:
            return c
    return None


def _candidates(design: Design, d: Diagnostic) -> list[str]:
    quoted = _QUOTED.findall(d.message)
    if d.code == "E0100" and d.message.startswith("no Global Memory variable"):
        return list(design.gm)
    if d.code == "E0100":
        names = _scope_names(design)
        # E0100 also says that a declared name is out of reach (not in the
        # `reads`, used outside a plan): another name is no fix for that.
        return [] if d.span.text in names else sorted(names)
    if d.code == "E0104":
        return list(design.controllers)
    if d.code == "E0105" and quoted:
        sub = design.controllers.get(quoted[0])
        return list(sub.verbs) if sub else []
    if d.code == "E0103" and len(quoted) >= 2:
        owner = quoted[0]
        if d.message.startswith("enum") and owner in design.enums:
            return list(getattr(design.enums[owner], "members", []))
        if d.message.startswith("record") and owner in design.records:
            return [f for f, _ in getattr(design.records[owner], "fields", [])]
        if d.message.startswith("subordinate") and owner in design.controllers:
            sub = design.controllers[owner]
            return ["done", "error", "executing", "error_code", "age"] + list(sub.statuses) + list(sub.status_fields)
        if d.message.startswith("verb"):
            c = _controller_at(design, d)
            v = c.verbs.get(owner) if c else None
            return [p.name for p in v.params] if v else []
    return []


# Operators of C-like languages and the rcs spelling (section 6 of docs/language.md).
_FOREIGN = (
    ("&&", "`and`"),
    ("||", "`or`"),
)


def _syntax_hint(d: Diagnostic) -> str | None:
    if d.span is None:
        return None
    text = d.span.file.text
    at = d.span.start
    for op, word in _FOREIGN:
        for start in (at, at - 1):
            if start >= 0 and text.startswith(op, start):
                return f"rcs writes {word} for `{op}`"
    if text.startswith("!", at) and not text.startswith("!=", at):
        return "rcs writes `not` for `!`"
    before = text[max(0, at - 40):at].rstrip()
    if text.startswith("if", at) and before.endswith("else"):
        return "rcs writes `elif` for `else if`"
    if text.startswith((".", "["), at) and text[:at].rstrip().endswith("]") and any("`=`" in n for n in d.notes):
        return "in an assignment the index comes last (`a[i] = v`, `r.xs[i] = v`): assign the whole element (`a[i] = P(...)`)"
    if re.match(r"elif\b", text[at:]) and _in_if_expression(text, at):
        return "an `if` expression chains with `else if` (`if a then x else if b then y else z`); `elif` is for `if` statements"
    return None


def _in_if_expression(text: str, at: int) -> bool:
    """Whether `at` follows a `then` of the statement, condition or argument it is in."""
    start = max(text.rfind(c, 0, at) for c in ";{}|")
    return re.search(r"\bthen\b", text[start + 1:at]) is not None


def add_hints(diags: Diagnostics, design: Design | None) -> None:
    """Add "did you mean" helps to the findings about unknown names and foreign operators."""
    for d in diags.items:
        if d.code in ("E0001", "E0002"):
            hint = _syntax_hint(d)
            if hint is not None:
                # The reference parser made the finding, so it is loaded already;
                # imported here, a check of valid files never loads it (lark).
                from rcsc.front.lark_parse import RULE_END_HELP

                # The foreign spelling is the mistake: a forgotten `;` is not.
                d.helps = [hint] + [h for h in d.helps if h != RULE_END_HELP]
            continue
        if design is None or d.code not in ("E0100", "E0103", "E0104", "E0105") or d.span is None:
            continue
        name = d.span.text
        if not name.isidentifier():
            continue
        if d.code == "E0100" and d.message.startswith("cannot find") and d.helps:
            continue  # the finding already says what the name is (an enum member, a next state, ...)
        candidates = _candidates(design, d)
        if name in candidates:
            continue  # the name exists (not in `reads`, or another controller's): another name would be a wrong guess
        best = closest(name, candidates)
        if best is not None:
            d.helps.insert(0, f"did you mean `{best}`?")
