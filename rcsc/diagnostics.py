"""Diagnostics: findings collected by every stage, never raised.

A `Diagnostic` carries a stable code (see `rcsc.codes`), a severity, a short
lowercase message, the smallest span that shows the problem with a label,
secondary labelled spans, and free `note:` / `help:` lines.  Stages append to
a `Diagnostics` bag; the command line renders the bag at the end (see
`rcsc.render`).
"""

from __future__ import annotations

import difflib
import enum
from dataclasses import dataclass, field

from rcsc.front.source import Span


class Severity(enum.Enum):
    ERROR = "error"
    WARNING = "warning"
    NOTE = "note"


@dataclass(frozen=True)
class Label:
    """A secondary span with a short message (rendered with `-` underlines)."""

    span: Span
    message: str


@dataclass
class Diagnostic:
    code: str
    severity: Severity
    message: str
    span: Span | None
    label: str = ""
    labels: list[Label] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    helps: list[str] = field(default_factory=list)
    # Structured extra data (e.g. a witness of a guard finding) that the JSON
    # and SARIF renderings carry as properties.
    data: dict = field(default_factory=dict)

    def sort_key(self) -> tuple:
        if self.span is None:
            return ("", 0, 0, self.code, self.message)
        return (self.span.file.path, self.span.start, self.span.end, self.code, self.message)

    def with_note(self, note: str) -> "Diagnostic":
        self.notes.append(note)
        return self

    def with_help(self, help_: str) -> "Diagnostic":
        self.helps.append(help_)
        return self

    def guess(self, name: str, declared) -> str | None:
        """Add "did you mean" the name among `declared` closest to the unknown
        `name` (`closest`), if one is close enough; that name, or None."""
        best = closest(name, declared)
        if best is not None:
            self.helps.append(f"did you mean `{best}`?")
        return best

    def with_label(self, span: Span | None, message: str) -> "Diagnostic":
        if span is not None:
            self.labels.append(Label(plain_span(span)[0], message))
        return self


def closest(name: str, candidates) -> str | None:
    """The declared name closest to `name` (case ignored), if one is close enough."""
    cands = sorted({c for c in candidates if c and c != name})
    if not cands:
        return None
    lower = {c.lower(): c for c in cands}
    if name.lower() in lower:
        return lower[name.lower()]
    hit = difflib.get_close_matches(name.lower(), list(lower), n=1, cutoff=0.75)
    if hit:
        return lower[hit[0]]
    # A short name has too few letters for the similarity ratio: `PX` for
    # `PR`, `LWO` for `LOW`, `xo` for `x0` score 0.5 to 0.67.  One typo (a
    # letter replaced, added, dropped, or two swapped) is still a guess when
    # only one declared name is that close.
    near = [c for low, c in lower.items() if _one_typo(name.lower(), low)]
    return near[0] if len(near) == 1 else None


def _one_typo(a: str, b: str) -> bool:
    """Whether `a` and `b` differ by one letter replaced, added or dropped, or two neighbours swapped."""
    if a == b or abs(len(a) - len(b)) > 1:
        return False
    if len(a) == len(b):
        diff = [i for i in range(len(a)) if a[i] != b[i]]
        return len(diff) == 1 or (len(diff) == 2 and diff[1] == diff[0] + 1 and a[diff[0]] == b[diff[1]] and a[diff[1]] == b[diff[0]])
    short, long_ = (a, b) if len(a) < len(b) else (b, a)
    return any(long_[:i] + long_[i + 1:] == short for i in range(len(long_)))


def plain_span(span: Span) -> tuple[Span, list[Label], str]:
    """A span inside an instance of a controller type or a block (its file an
    `rcsc.front.instantiate.InstanceSource`) as the span of the text written:
    (span in the real file, labels that name the instance(s), a key that
    tells the instances apart)."""
    labels: list[Label] = []
    key = ""
    while getattr(span.file, "instance", None) is not None:
        message, where = span.file.instance
        span = Span(span.file.origin, span.start, span.end)
        where, outer, outer_key = plain_span(where)
        labels.append(Label(where, message))
        labels.extend(outer)
        key += f"/{where.start}{outer_key}"
    return span, labels, key


class Diagnostics:
    """An ordered bag of findings shared by all stages of one run."""

    def __init__(self) -> None:
        self.items: list[Diagnostic] = []
        self._seen: set[tuple] = set()
        # Findings an in-source `rcsc: allow(CODE) reason` comment covers
        # (rcsc.checks.suppress): out of the report, kept for SARIF.
        self.suppressed: list[Diagnostic] = []

    def add(
        self,
        code: str,
        span: Span | None,
        message: str,
        label: str = "",
        severity: Severity | None = None,
    ) -> Diagnostic:
        """Record a finding; the severity defaults to the code's own."""
        from rcsc.codes import CODES

        if code not in CODES:
            raise KeyError(f"internal error: diagnostic code {code} is not registered")
        sev = severity or CODES[code].severity
        labels: list[Label] = []
        instance = ""
        if span is not None:
            span, labels, instance = plain_span(span)
        diag = Diagnostic(code, sev, message, span, label, labels)
        key = (code, message, span.file.path if span else "", span.start if span else -1)
        if instance:
            key += (instance,)
        diag._key = key  # type: ignore[attr-defined]
        if key not in self._seen:
            self._seen.add(key)
            self.items.append(diag)
        return diag

    def extend(self, other: "Diagnostics") -> None:
        for d in other.items:
            key = getattr(d, "_key", None) or (d.code, d.message, d.span.file.path if d.span else "", d.span.start if d.span else -1)
            if key not in self._seen:
                self._seen.add(key)
                self.items.append(d)

    def sorted(self) -> list[Diagnostic]:
        return sorted(self.items, key=Diagnostic.sort_key)

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.items if d.severity is Severity.ERROR]

    @property
    def warnings(self) -> list[Diagnostic]:
        return [d for d in self.items if d.severity is Severity.WARNING]

    def has_errors(self) -> bool:
        return any(d.severity is Severity.ERROR for d in self.items)

    def __len__(self) -> int:
        return len(self.items)

    def __iter__(self):
        return iter(self.items)
