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

from rcsc.front.source import edit_between

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
    # Where the scan was when it met the controller's `{`: the end of the
    # last brace, comment or string before it.  A scan started there (at the
    # top level) reads the rest of the text exactly as the whole scan did.
    scan_from: int = 0

    def moved(self, delta: int) -> "ControllerItem":
        """The same controller `delta` characters further on."""
        return ControllerItem(self.name, self.start + delta, self.end + delta,
                              [(v, s + delta, e + delta) for v, s, e in self.bodies], self.scan_from + delta)

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


# The last text scanned (the same object), its controllers, for each of them
# the index of the same controller in the text scanned before it (or None
# when it was scanned anew; no list when the whole text was scanned), and
# that text: `digests` reuses what did not change.
_memo: list = [None, None, None, None]


def controller_items(text: str) -> list[ControllerItem] | None:
    """The controllers of `text` in order, or None when the braces do not balance."""
    if _memo[0] is text:
        return _memo[1]
    origin = None
    found = None
    if _memo[0] is not None and _memo[1] is not None:
        # A language server checks text after text, each a small edit of
        # the one before: only the controllers the edit lies in are
        # scanned again.
        again = _rescan(_memo[0], _memo[1], text)
        if again is not None:
            found, origin = again
    if found is None:
        found = _scan(text)
    _memo[:] = [text, found, origin, _memo[0] if origin is not None else None]
    return found


def _rescan(old: str, old_items: list[ControllerItem], new: str) -> tuple[list[ControllerItem], list[int | None]] | None:
    """The controllers of `new`, an edit of `old` whose controllers are
    `old_items`, found by scanning only from the last controller that opens
    before the edit to the first that closes after it; None when that
    stretch does not end as it did (the rest must then be scanned too)."""
    p, old_end, new_end = edit_between(old, new)
    delta = new_end - old_end
    # The stretch starts at the top level, at a place where the whole scan
    # stood between two of its steps: before a controller's `{`
    # (`scan_from`) or after its closing `}` (`end`), or at 0.  What the scan
    # read up to such a place depends on the text after it up to the end of
    # its line, no further (a comment runs to the end of its line, and a
    # lone `"` is a string only when its line closes it), so the place must
    # lie on a line that ends before the edit: the last such place.
    first = 0
    while first < len(old_items) and old_items[first].end <= p:
        first += 1
    first_start, kept = 0, 0
    for k in range(min(first, len(old_items) - 1), -1, -1):
        x = old_items[k]
        if k < first and _line_ends_before(old, x.end, p):
            first_start, kept = x.end, k + 1
            break
        if _line_ends_before(old, x.scan_from, p):
            first_start, kept = x.scan_from, k
            break
    first = kept
    last = first
    while last < len(old_items) and old_items[last].end < old_end:
        last += 1
    stop = old_items[last].end + delta if last < len(old_items) else None  # None: to the end
    if first_start > p or (stop is not None and stop < new_end):
        return None
    middle = _scan(new, first_start, stop)
    if middle is None:
        return None
    tail = [x.moved(delta) for x in old_items[last + 1:]]
    found = old_items[:first] + middle + tail
    origin: list[int | None] = list(range(first)) + [None] * len(middle) + list(range(last + 1, len(old_items)))
    return found, origin


def _line_ends_before(text: str, at: int, p: int) -> bool:
    """Whether the line holding offset `at` of `text` ends before offset `p`."""
    line_end = text.find("\n", at)
    return 0 <= line_end < p


# What the scan stops at: a string (to its closing quote on the line, or the
# quote alone when none), a comment (whole; an unclosed block comment to the
# end), a brace, or a `/` that is a division (passed over).  Everything
# before it is skipped in one step.
# The end of the text is a stop too (an empty one): without it, the text
# after the last stop would be skipped again from each of its characters.
_STOPS = re.compile(r'[^{}"/]*+("[^"\n]*"|"|//[^\n]*|/\*[\s\S]*?(?:\*/|\Z)|/|[{}]|\Z)')


def _scan(text: str, start: int = 0, stop: int | None = None) -> list[ControllerItem] | None:
    """The controllers of `text`, or with `stop` of `text[start:stop]`:
    read from `start` at the top level, where the whole scan stood after a
    brace, comment or string; None when the braces do not balance, or when
    the stretch does not end, at the top level, with a `}` that ends at
    `stop` (it then does not end where the whole scan would be in the same
    state again).  The text after `stop` is read as the whole scan reads it
    (a string or comment that runs past `stop` is one), so a stretch that
    succeeds finds what the whole scan finds there."""
    items: list[ControllerItem] = []
    depth = 0
    current: ControllerItem | None = None
    body: tuple[str, int, int] | None = None  # the plan being read: (verb, body start, its depth)
    last = start  # the end of the last brace, comment or string: an opener starts after it
    for mt in _STOPS.finditer(text, start):
        ch = mt.group(1)
        if stop is not None and mt.end() >= stop:
            if ch != "}" or mt.end() != stop or depth != 1:
                return None
        elif ch == "/":
            continue  # a division: not a comment
        if not ch:
            break  # the end
        if ch == "{":
            i = mt.start(1)
            if depth == 0:
                mo = _CONTROLLER.search(text, max(last, i - _LOOKBACK), i)
                if mo is not None:
                    current = ControllerItem(mo.group(1), mo.start() + (mo.group(0)[0] not in "cs"), -1, scan_from=last)
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
        if stop is not None and last == stop:
            return items
    if depth != 0 or stop is not None:
        return None
    return items


def digest(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()


_digests_memo: list = [None, None]  # the last text digested (the same object) and its digests


def digests(text: str) -> tuple[list[str], list[tuple[str, str]]] | None:
    """The digests of the text outside the controllers of
    `controller_items(text)` (`gaps`) and, for each controller, the digests
    of its outline and of its plan bodies; None when the braces do not
    balance.  Kept for the last text: a re-check compares them and then
    stores them."""
    if _digests_memo[0] is text:
        return _digests_memo[1]
    found = controller_items(text)
    out = None
    if found is not None:
        before = _digests_memo[1] if _memo[0] is text and _memo[3] is not None and _digests_memo[0] is _memo[3] else None
        origin = _memo[2] if before is not None else None
        sums = []
        for i, x in enumerate(found):
            j = origin[i] if origin is not None else None
            # A controller the last scan did not read again has the text it had.
            sums.append(before[1][j] if j is not None else (digest(x.outline(text)), digest(x.body_text(text))))  # type: ignore[index]
        out = (gaps(text, found), sums)
    _digests_memo[0], _digests_memo[1] = text, out
    return out


def gaps(text: str, controllers: list[ControllerItem]) -> list[str]:
    """The digests of the text outside the controllers (declarations, CPUs,
    imports): before each controller, and after the last one."""
    out, at = [], 0
    for c in controllers:
        out.append(digest(text[at:c.start]))
        at = c.end
    out.append(digest(text[at:]))
    return out


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
