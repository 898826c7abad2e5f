"""The controllers of a source text and their plan bodies, found without parsing.

An incremental re-check (`rcsc.checks.incremental`) needs to know, before it
parses anything, which controllers an edit touched and whether it touched
only the inside of their plans.  This module finds, with one scan of the
text for braces, comments and strings (a few milliseconds per megabyte),
every top-level `controller NAME ... { ... }` and, inside it, every
`plan NAME [modifiers] { ... }` body.

It is a guess that the parser confirms: the re-check compares the plan
spans the parser produced with the bodies found here and falls back to a
full check when they differ, so an unusual text (a syntax error, a brace
in an odd place) costs time, never a wrong answer.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass, field

# The scan looks only at the characters that matter: braces, and `"` and `/`
# (strings and comments are skipped whole: a brace in them is not one).  At
# each `{` the text since the last brace says what it opens: at the top
# level `controller|simulator NAME` with its attributes (`level 2 budget
# 100 us`), inside a controller `plan NAME` with its modifiers.  Anything
# else written there (a comment between the name and the brace) is not
# recognised, and the controller is then part of the rest of the text
# (checked in full).
_SPECIAL = re.compile(r'[{}"/]')
_W = r"[ \t\r\n]"
_NAME = r"[A-Za-z_][A-Za-z0-9_]*"
_ATTR = rf"{_W}+(?:level|budget|period){_W}+[0-9][0-9A-Za-z_.+\-]*(?:{_W}*(?:us|ms|s)\b)?"
_CONTROLLER = re.compile(rf"(?:^|[^A-Za-z0-9_])(?:controller|simulator){_W}+({_NAME})(?:{_ATTR})*{_W}*\Z")
_PLAN = re.compile(rf"(?:^|[^A-Za-z0-9_])plan{_W}+({_NAME})(?:{_W}+(?:continuous|ordered)\b)*{_W}*\Z")
# How far back from a `{` its opener can start (a long attribute list is not a design).
_LOOKBACK = 200


@dataclass
class ControllerItem:
    """One top-level controller: [start, end) of its text and the [start, end) of each plan body (inside the braces)."""

    name: str
    start: int
    end: int
    bodies: list[tuple[str, int, int]] = field(default_factory=list)  # (verb, start, end)

    def outline(self, text: str) -> str:
        """The controller's text without its plan bodies: what other controllers can see of it."""
        parts, at = [], self.start
        for _, s, e in self.bodies:
            parts.append(text[at:s])
            at = e
        parts.append(text[at:self.end])
        return "\x00".join(parts)

    def body_text(self, text: str) -> str:
        return "\x00".join(text[s:e] for _, s, e in self.bodies)


_memo: list = [None, None]  # the last text scanned (the same object) and its result


def controller_items(text: str) -> list[ControllerItem] | None:
    """The controllers of `text` in order, or None when the braces do not balance."""
    if _memo[0] is text:
        return _memo[1]
    found = _scan(text)
    _memo[0], _memo[1] = text, found
    return found


# What the scan stops at: a string (to its closing quote on the line, or the
# quote alone when none), a comment (whole; an unclosed block comment to the
# end), a brace, or a `/` that is a division (passed over).  Everything
# before it is skipped in one step.
# The end of the text is a stop too (an empty one): without it, the text
# after the last stop would be skipped again from each of its characters.
_STOPS = re.compile(r'[^{}"/]*+("[^"\n]*"|"|//[^\n]*|/\*[\s\S]*?(?:\*/|\Z)|/|[{}]|\Z)')


def _scan(text: str) -> list[ControllerItem] | None:
    items: list[ControllerItem] = []
    depth = 0
    current: ControllerItem | None = None
    body: tuple[str, int, int] | None = None  # the plan being read: (verb, body start, its depth)
    last = 0  # the end of the last brace, comment or string: an opener starts after it
    for mt in _STOPS.finditer(text):
        ch = mt.group(1)
        if ch == "/":
            continue  # a division: not a comment
        if not ch:
            break  # the end
        if ch == "{":
            i = mt.start(1)
            if depth == 0:
                mo = _CONTROLLER.search(text, max(last, i - _LOOKBACK), i)
                if mo is not None:
                    current = ControllerItem(mo.group(1), mo.start() + (mo.group(0)[0] not in "cs"), -1)
            elif depth == 1 and current is not None and body is None:
                mo = _PLAN.search(text, max(last, i - _LOOKBACK), i)
                if mo is not None:
                    body = (mo.group(1), i + 1, depth + 1)
            depth += 1
        elif ch == "}":
            i = mt.start(1)
            depth -= 1
            if depth < 0:
                return None
            if body is not None and depth == body[2] - 1:
                assert current is not None
                current.bodies.append((body[0], body[1], i))
                body = None
            if depth == 0 and current is not None:
                current.end = i + 1
                items.append(current)
                current = None
        last = mt.end()
    if depth != 0:
        return None
    return items


def digest(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()


_digests_memo: list = [None, None]  # the last text digested (the same object) and its digests


def digests(text: str) -> tuple[str, list[tuple[str, str]]] | None:
    """The digest of the rest of `text` (`rest_of`) and, for each controller
    of `controller_items(text)`, the digests of its outline and of its plan
    bodies; None when the braces do not balance.  Kept for the last text: a
    re-check compares them and then stores them."""
    if _digests_memo[0] is text:
        return _digests_memo[1]
    found = controller_items(text)
    out = None if found is None else (digest(rest_of(text, found)), [(digest(x.outline(text)), digest(x.body_text(text))) for x in found])
    _digests_memo[0], _digests_memo[1] = text, out
    return out


def rest_of(text: str, items: list[ControllerItem]) -> str:
    """The text outside every controller (declarations, CPUs, imports), items cut out."""
    parts, at = [], 0
    for it in items:
        parts.append(text[at:it.start])
        at = it.end
    parts.append(text[at:])
    return "\x00".join(parts)


def blank(text: str, spans: list[tuple[int, int]]) -> str:
    """`text` with each [start, end) of `spans` (sorted, disjoint) replaced by
    blanks, its line breaks kept: every offset, line and column stays where
    it was."""
    parts, at = [], 0
    for s, e in spans:
        parts.append(text[at:s])
        parts.append("\n".join(" " * len(line) for line in text[s:e].split("\n")))
        at = e
    parts.append(text[at:])
    return "".join(parts)
