"""Source files and spans.

A `Span` is a half-open byte range [start, end) in one `SourceFile`, the
smallest piece of text a diagnostic points at.  Line and column numbers are
1-based and computed on demand from the file's line table, so spans stay cheap
to create in large designs.
"""

from __future__ import annotations

import bisect
import itertools
import re
from dataclasses import dataclass, field

_LONE_CR = re.compile("\r(?!\n)")

# Characters that reorder how the text around them is displayed (Unicode
# bidirectional embeddings, overrides, isolates and marks).  In a comment or a
# string they can make a design read differently from what it means ("trojan
# source", CVE-2021-42574): the parser refuses them wherever they stand
# (E0008) and the diagnostics never print them.
BIDI_CONTROLS = frozenset("\u061c\u200e\u200f\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069")


def normalized(text: str) -> str:
    """The text as a `SourceFile` holds it.  A byte-order mark is not part of
    the text (editors do not count it in columns), and a lone CR (classic
    Mac line ends) ends a line like LF does; replacing it by LF keeps every
    offset where it was."""
    if text.startswith("\ufeff"):
        text = text[1:]
    if "\r" in text:
        text = _LONE_CR.sub("\n", text)
    return text


def edit_between(old: str, new: str) -> tuple[int, int, int]:
    """(p, old_end, new_end): `old[p:old_end]` became `new[p:new_end]`, the
    text before and after the same (the longest common prefix, then the
    longest common suffix of what remains).  Compared a block at a time, in
    C: a millisecond for megabytes."""
    n = min(len(old), len(new))
    step = 1 << 14
    p = 0
    while p < n and old[p:p + step] == new[p:p + step]:
        p += step
    p = min(p, n)
    hi = min(p + step, n)
    while p < hi:  # old[:p] == new[:p] and they differ before hi (or hi == n)
        mid = (p + hi + 1) // 2
        if old[p:mid] == new[p:mid]:
            p = mid
        else:
            hi = mid - 1
    limit = n - p  # the suffix must not overlap the prefix
    s = 0
    lo, ln = len(old), len(new)
    while s < limit:
        k = min(step, limit - s)
        if old[lo - s - k:lo - s] != new[ln - s - k:ln - s]:
            break
        s += k
    else:
        return p, lo - s, ln - s
    hi = min(s + step, limit)
    while s < hi:
        mid = (s + hi + 1) // 2
        if old[lo - mid:lo - s] == new[ln - mid:ln - s]:
            s = mid
        else:
            hi = mid - 1
    return p, lo - s, ln - s


# The last large text whose line table was made, and the table.  A language
# server or the check daemon reads text after text, each an edit of the one
# before: the new table is the old one with the lines of the edit made
# again and those after it moved (a few milliseconds instead of twenty for
# 5 MB).
_last_lines: list = [None, None]
_REUSE_ABOVE = 1 << 16  # characters; below, a table is made in well under a millisecond
_KNOWN_LINES = 1024  # lines found by counting (`SourceFile._probe`) before the table is made


def _line_starts_of(text: str) -> list[int]:
    old, old_starts = _last_lines
    if old is not None and old is not text and len(text) > _REUSE_ABOVE:
        p, old_end, new_end = edit_between(old, text)
        if (old_end - p) + (new_end - p) < len(text) // 4:
            before = bisect.bisect_right(old_starts, p)  # lines that start at or before the edit: as they were
            after = bisect.bisect_right(old_starts, old_end)  # lines that start after it: moved
            delta = new_end - old_end
            middle = []  # the lines that start in the edit: after each of its line breaks
            at = text.find("\n", p, new_end)
            while at >= 0:
                middle.append(at + 1)
                at = text.find("\n", at + 1, new_end)
            starts = old_starts[:before] + middle + (old_starts[after:] if delta == 0 else list(map(delta.__add__, old_starts[after:])))
            _last_lines[:] = [text, starts]
            return starts
    lengths = map(len, text.split("\n")[:-1])
    starts = [0, *itertools.accumulate(map((1).__add__, lengths))]  # from the line lengths, in C
    if len(text) > _REUSE_ABOVE:
        _last_lines[:] = [text, starts]
    return starts


@dataclass(eq=False)
class SourceFile:
    """One file of a design: its display path and its text."""

    path: str
    text: str
    _starts: list[int] | None = field(default=None, init=False, repr=False)
    # Before the table is made: the lines found by counting (`_probe`), as
    # sorted (offset of the line's start, line) pairs, and the characters
    # counted so far.
    _known: list[tuple[int, int]] | None = field(default=None, init=False, repr=False)
    _counted: int = field(default=0, init=False, repr=False)

    def __post_init__(self) -> None:
        self.text = normalized(self.text)

    @property
    def _line_starts(self) -> list[int]:
        """The offset of each line's first character.  Made on first use: a
        check that reports nothing in a file (a replayed check, most files of
        a large design) never needs the lines of its hundreds of thousands
        of lines."""
        starts = self._starts
        if starts is None:
            starts = self._starts = _line_starts_of(self.text)
        return starts

    @_line_starts.setter
    def _line_starts(self, starts: list[int]) -> None:
        self._starts = starts

    def line_col(self, offset: int) -> tuple[int, int]:
        """1-based (line, column) of a character offset."""
        offset = max(0, min(offset, len(self.text)))
        if self._starts is None and len(self.text) > _REUSE_ABOVE:
            found = self._probe(offset)
            if found is not None:
                return found
        line = bisect.bisect_right(self._line_starts, offset) - 1
        return line + 1, offset - self._line_starts[line] + 1

    def _probe(self, offset: int) -> tuple[int, int] | None:
        """(line, column) of `offset` without the line table: the line breaks
        are counted from the nearest line known before it.

        A check that reports a few findings in a large file (a re-check
        after an edit: a handful, in 5 MB) needs a few lines, and counting
        up to them costs a fraction of the table's 12 ms.  Once as many
        characters are counted as the file holds, the table is cheaper and
        is made instead (None): the counting never costs more than the table.
        So is it after `_KNOWN_LINES` lines, which are kept in a sorted list.
        """
        known = self._known
        if known is None:
            known = self._known = [(0, 1)]
        at = bisect.bisect_right(known, (offset, 1 << 62)) - 1
        base, line = known[at]
        if self._counted + (offset - base) > len(self.text) or len(known) > _KNOWN_LINES:
            return None
        self._counted += offset - base
        text = self.text
        breaks = text.count("\n", base, offset)
        if breaks:
            line += breaks
            base = text.rfind("\n", base, offset) + 1
            known.insert(at + 1, (base, line))
        return line, offset - base + 1

    def _known_start(self, line: int) -> int | None:
        """The start of `line` if `_probe` found it (the lines of the findings shown)."""
        known = self._known or []
        # Each known line is a different line, so their numbers increase with their starts.
        at = bisect.bisect_left(known, line, key=lambda k: k[1])
        return known[at][0] if at < len(known) and known[at][1] == line else None

    def line_text(self, line: int) -> str:
        """The text of 1-based line `line`, without its newline."""
        start = self._known_start(line) if self._starts is None else None
        if start is None:
            if line < 1 or line > len(self._line_starts):
                return ""
            start = self._line_starts[line - 1]
        end = self.text.find("\n", start)
        return self.text[start:] if end < 0 else self.text[start:end]

    @property
    def line_count(self) -> int:
        return len(self._line_starts)

    def offset(self, line: int, col: int = 1) -> int:
        """The character offset of 1-based (line, column), clamped into the
        file: for positions other tools report (TOML, Python)."""
        starts = self._line_starts
        start = starts[max(1, min(line, len(starts))) - 1]
        return min(start + max(col, 1) - 1, len(self.text))


class Span:
    """A half-open character range [start, end) of a source file.

    Treated as immutable, with one exception: a language server's re-check
    moves the spans of the syntax trees it keeps between re-checks to
    their new offsets (`rcsc.checks.incremental._KeptTree`).  A plain class with slots rather than a frozen
    dataclass: a large design has millions of spans, and a frozen
    dataclass's constructor is several times slower and its instances
    larger.
    """

    __slots__ = ("file", "start", "end")

    def __init__(self, file: SourceFile, start: int, end: int) -> None:
        self.file = file
        self.start = start
        self.end = end

    @property
    def line(self) -> int:
        return self.file.line_col(self.start)[0]

    @property
    def col(self) -> int:
        return self.file.line_col(self.start)[1]

    @property
    def end_line_col(self) -> tuple[int, int]:
        return self.file.line_col(max(self.start, self.end))

    @property
    def text(self) -> str:
        return self.file.text[self.start:self.end]

    def to(self, other: "Span") -> "Span":
        """The span covering both `self` and `other` (same file)."""
        return Span(self.file, min(self.start, other.start), max(self.end, other.end))

    def __repr__(self) -> str:
        return f"Span({self.file.path}:{self.line}:{self.col})"

    def __hash__(self) -> int:  # SourceFile compares by identity
        return hash((id(self.file), self.start, self.end))

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, Span)
            and other.file is self.file
            and other.start == self.start
            and other.end == self.end
        )


def skip_trivia(text: str, i: int) -> int:
    """The index of the first character at or after `i` that is not blank or comment."""
    while i < len(text):
        if text[i].isspace():
            i += 1
        elif text.startswith("//", i):
            j = text.find("\n", i)
            i = len(text) if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            i = len(text) if j < 0 else j + 2
        else:
            break
    return i
