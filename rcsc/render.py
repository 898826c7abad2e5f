"""Renderings of a run's diagnostics: human, short, JSON and SARIF.

Every renderer takes the findings of one run (a `Diagnostics` bag or a plain
list of `Diagnostic`), puts them in `Diagnostics.sorted()` order, and returns
the whole report as one string, so the command line decides where it goes.

- `render_human`: rustc-style snippets with `^` / `-` underlines, for people.
- `render_short`: one `file:line:col: severity[CODE]: message` line each, for
  editors and grep.
- `render_json`: rcsc's own stable document (sorted keys, 2-space indent).
- `render_sarif`: SARIF 2.1.0 for code-scanning services.

Positions everywhere are 1-based lines and columns counted in characters
(Unicode code points) of the source text.  An end position (`end_line`,
`end_column`, SARIF `endColumn`) is exclusive: it names the character just past
the span, so a zero-width span has its end equal to its start.
"""

from __future__ import annotations

import enum
import hashlib
import json
import math
import unicodedata
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path, PurePosixPath, PureWindowsPath
from urllib.parse import quote

from rcsc.codes import CODES, DOCS_URL, Code, help_uri
from rcsc.diagnostics import Diagnostic, Diagnostics, Severity
from rcsc.front.source import BIDI_CONTROLS, SourceFile, Span

# A tab is shown as this many spaces; carets are moved to match.
TAB_WIDTH = 4

JSON_FORMAT_VERSION = 1

SARIF_VERSION = "2.1.0"
SARIF_SCHEMA_URI = "https://json.schemastore.org/sarif-2.1.0.json"
# The tool's documentation (SARIF requires an absolute URI); each rule's helpUri
# is `codes.help_uri(code)` below it.
INFORMATION_URI: str | None = DOCS_URL
# Named and versioned as SARIF recommends, so that a future change of the
# hashed fields can use a new key instead of silently re-keying every finding.
FINGERPRINT_KEY = "rcscFinding/v1"
SRCROOT = "%SRCROOT%"


# ---------------------------------------------------------------------------
# shared helpers
# ---------------------------------------------------------------------------

def _ordered(diags: Diagnostics | Iterable[Diagnostic]) -> list[Diagnostic]:
    """The findings in the one order every rendering uses."""
    if isinstance(diags, Diagnostics):
        return diags.sorted()
    return sorted(diags, key=Diagnostic.sort_key)


def _counts(ordered: list[Diagnostic]) -> tuple[int, int]:
    errors = sum(1 for d in ordered if d.severity is Severity.ERROR)
    warnings = sum(1 for d in ordered if d.severity is Severity.WARNING)
    return errors, warnings


def _title(d: Diagnostic) -> str:
    """`error[E0100]`, or just `error` for a finding without a code."""
    return f"{d.severity.value}[{d.code}]" if d.code else d.severity.value


def _location(span: Span | None) -> dict:
    """File and 1-based start / exclusive end of a span (all None without one)."""
    if span is None:
        return {"file": None, "line": None, "column": None, "end_line": None, "end_column": None}
    end_line, end_col = span.end_line_col
    return {
        "file": span.file.path,
        "line": span.line,
        "column": span.col,
        "end_line": end_line,
        "end_column": end_col,
    }


def _plain(value: object) -> object:
    """`value` as plain JSON data, so odd `Diagnostic.data` never breaks a report.

    Dict keys become strings (sort_keys needs comparable keys), sets become
    sorted lists (for determinism), spans become locations, non-finite floats
    and anything unknown (Fraction, Decimal, ...) become their `str`.
    """
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, enum.Enum):
        return _plain(value.value)
    if isinstance(value, Span):
        return _location(value)
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (set, frozenset)):
        items = [_plain(v) for v in value]
        return sorted(items, key=lambda v: json.dumps(v, sort_keys=True))
    return str(value)


# ---------------------------------------------------------------------------
# human
# ---------------------------------------------------------------------------

# ANSI SGR parameters.
_BOLD = "1"
_RED = "31"
_GREEN = "32"
_YELLOW = "33"
_BLUE = "34"
_CYAN = "36"

_SEVERITY_STYLE = {
    Severity.ERROR: (_BOLD, _RED),
    Severity.WARNING: (_BOLD, _YELLOW),
    Severity.NOTE: (_BOLD, _GREEN),
}
_GUTTER = (_BOLD, _BLUE)
_SECONDARY = (_BOLD, _BLUE)


class _Painter:
    """Wraps text in ANSI colour codes, or leaves it alone when colour is off."""

    def __init__(self, color: bool) -> None:
        self.color = color

    def __call__(self, text: str, style: tuple[str, ...] | None) -> str:
        if not self.color or not style or not text:
            return text
        return f"\x1b[{';'.join(style)}m{text}\x1b[0m"


def _char_width(ch: str) -> int:
    """Terminal columns one source character takes (after tab expansion)."""
    if ch == "\t":
        return TAB_WIDTH
    if unicodedata.combining(ch):
        return 0
    if unicodedata.east_asian_width(ch) in ("W", "F"):
        return 2
    return 1


def escape_controls(text: str) -> str:
    """`text` for a terminal or log: newlines and tabs kept, every other
    control character (C0, DEL, C1) and every bidirectional control shown as
    a visible escape (`\\x1b`, `\\u202e`), so input cannot drive the terminal
    (clear the screen, hide a line) or reorder what is shown."""
    if text.isprintable():
        # No control or format character (bidirectional controls are format
        # characters): the common case, answered in C.
        return text
    out = []
    for ch in text:
        if ch in "\n\t" or not (unicodedata.category(ch) == "Cc" or ch in BIDI_CONTROLS):
            out.append(ch)
        else:
            out.append(f"\\x{ord(ch):02x}" if ord(ch) < 0x100 else f"\\u{ord(ch):04x}")
    return "".join(out)


def _display_char(ch: str) -> str:
    if ch == "\t":
        return " " * TAB_WIDTH
    # Control characters in a broken input must not drive the terminal, nor
    # bidirectional controls reorder the line shown.
    if unicodedata.category(ch) == "Cc" or ch in BIDI_CONTROLS:
        return "\ufffd"
    return ch


def _width(text: str) -> int:
    return sum(_char_width(ch) for ch in text)


def _source_line(file: SourceFile, line: int) -> str:
    """Line `line` without its newline or the `\\r` of a CRLF file."""
    text = file.line_text(line)
    return text[:-1] if text.endswith("\r") else text


@dataclass
class _Mark:
    """One underline on one displayed line: columns are display columns, 0-based."""

    line: int
    start: int
    width: int
    primary: bool
    message: str

    @property
    def stop(self) -> int:
        return self.start + self.width


def _mark(span: Span, primary: bool, message: str) -> _Mark:
    line, col = span.line, span.col
    end_line, end_col = span.end_line_col
    text = _source_line(span.file, line)
    start = _width(text[: col - 1])
    # A span over several lines is underlined from its start to the end of its
    # first line; that is enough to find it, and keeps the snippet short.
    stop = _width(text[: end_col - 1]) if end_line == line else _width(text)
    # Zero-width spans (a missing token, the end of the file) get one caret.
    return _Mark(line, start, max(1, stop - start), primary, message)


class _Row:
    """A line of display cells, each with its own style; spaces are unstyled."""

    def __init__(self) -> None:
        self.cells: list[tuple[str, tuple[str, ...] | None]] = []

    def put(self, col: int, text: str, style: tuple[str, ...] | None) -> None:
        while len(self.cells) < col + len(text):
            self.cells.append((" ", None))
        for i, ch in enumerate(text):
            self.cells[col + i] = (ch, style)

    def render(self, paint: _Painter) -> str:
        out: list[str] = []
        run, run_style = "", None
        for ch, style in self.cells:
            if style != run_style:
                out.append(paint(run, run_style))
                run, run_style = "", style
            run += ch
        out.append(paint(run, run_style))
        return "".join(out).rstrip()


def _underline_rows(marks: list[_Mark], severity_style: tuple[str, ...]) -> list[_Row]:
    """The rows under one source line: underlines, then hanging label messages.

    As rustc does, the rightmost label is written after its underline when no
    other underline overlaps it; every other label hangs below its own
    underline on a `|` so that the messages never collide.
    """
    marks = sorted(marks, key=lambda m: (m.start, m.primary))

    def style(m: _Mark) -> tuple[str, ...]:
        return severity_style if m.primary else _SECONDARY

    first = _Row()
    # Secondary underlines first so that the primary one wins where they overlap.
    for m in sorted(marks, key=lambda m: m.primary):
        first.put(m.start, ("^" if m.primary else "-") * m.width, style(m))

    last = max(marks, key=lambda m: (m.start, m.primary))
    others = [m for m in marks if m is not last]
    inline = bool(last.message) and all(o.stop <= last.start for o in others)
    if inline:
        first.put(len(first.cells) + 1, last.message, style(last))
    hanging = [m for m in marks if m.message and not (inline and m is last)]
    rows = [first]
    if not hanging:
        return rows
    connector = _Row()
    for m in hanging:
        connector.put(m.start, "|", style(m))
    rows.append(connector)
    for m in reversed(hanging):
        row = _Row()
        for pending in hanging:
            if pending.start < m.start:
                row.put(pending.start, "|", style(pending))
        row.put(m.start, m.message, style(m))
        rows.append(row)
    return rows


def _group_marks(d: Diagnostic) -> list[tuple[SourceFile, Span, dict[int, list[_Mark]]]]:
    """Marks grouped by file (primary span's file first), then by line.

    Each group also carries the span its `-->` line points at.
    """
    spans: list[tuple[Span, bool, str]] = []
    if d.span is not None:
        spans.append((d.span, True, escape_controls(d.label)))
    spans.extend((label.span, False, escape_controls(label.message)) for label in d.labels)
    groups: list[tuple[SourceFile, Span, dict[int, list[_Mark]]]] = []
    for span, primary, message in spans:
        group = next((g for g in groups if g[0] is span.file), None)
        if group is None:
            group = (span.file, span, {})
            groups.append(group)
        mark = _mark(span, primary, message)
        group[2].setdefault(mark.line, []).append(mark)
    return groups


def _shown_lines(lines: list[int]) -> list[int | None]:
    """Annotated line numbers in order, with a lone skipped line filled in and
    longer gaps shown as `...` (None)."""
    shown: list[int | None] = []
    for line in sorted(lines):
        prev = shown[-1] if shown else None
        if prev is not None:
            if line - prev == 2:
                shown.append(prev + 1)
            elif line - prev > 2:
                shown.append(None)
        shown.append(line)
    return shown


def _render_one(d: Diagnostic, paint: _Painter) -> list[str]:
    severity_style = _SEVERITY_STYLE.get(d.severity, (_BOLD,))
    # What a finding says can quote the input (a name, an import path):
    # escaped, so that it cannot drive the terminal.
    out = [paint(_title(d), severity_style) + paint(f": {escape_controls(d.message)}", (_BOLD,))]

    groups = _group_marks(d)
    shown = [(file, span, _shown_lines(list(marks)), marks) for file, span, marks in groups]
    numbers = [n for _, _, lines, _ in shown for n in lines if n is not None]
    width = len(str(max(numbers))) if numbers else 1
    pad = " " * width
    empty_gutter = pad + " " + paint("|", _GUTTER)

    for index, (file, span, lines, marks) in enumerate(shown):
        if index > 0:
            out.append(empty_gutter)
        out.append(pad + paint("-->", _GUTTER) + f" {escape_controls(file.path)}:{span.line}:{span.col}")
        out.append(empty_gutter)
        for line in lines:
            if line is None:
                out.append(paint("...", _GUTTER))
                continue
            text = "".join(_display_char(ch) for ch in _source_line(file, line))
            out.append((paint(f"{line:>{width}} |", _GUTTER) + " " + text).rstrip())
            if line in marks:
                for row in _underline_rows(marks[line], severity_style):
                    out.append((empty_gutter + " " + row.render(paint)).rstrip())

    extras = [("note", n) for n in d.notes] + [("help", h) for h in d.helps]
    if extras:
        out.append(empty_gutter)
        for kind, text in extras:
            head = f"= {kind}: "
            # Continuation lines of a long note line up under its first word.
            body = escape_controls(text).replace("\n", "\n" + pad + " " + " " * len(head))
            out.append(pad + " " + paint("=", _GUTTER) + paint(f" {kind}", (_BOLD,)) + f": {body}")
    return out


def _summary(errors: int, warnings: int, paint: _Painter) -> str:
    def plural(n: int, word: str) -> str:
        return f"{n} {word}" if n == 1 else f"{n} {word}s"

    parts = [plural(n, w) for n, w in ((errors, "error"), (warnings, "warning")) if n]
    severity = Severity.ERROR if errors else Severity.WARNING
    return paint(severity.value, _SEVERITY_STYLE[severity]) + paint(
        f": {' and '.join(parts)} emitted", (_BOLD,)
    )


def render_human(diags: Diagnostics | Iterable[Diagnostic], color: bool, summary: bool = True) -> str:
    """rustc-style report; ANSI colour only when `color` is true; the closing
    `N errors emitted` line only with `summary`."""
    paint = _Painter(color)
    ordered = _ordered(diags)
    out: list[str] = []
    for d in ordered:
        out.extend(_render_one(d, paint))
        out.append("")
    errors, warnings = _counts(ordered)
    if (errors or warnings) and summary:
        out.append(_summary(errors, warnings, paint))
    return "\n".join(out) + "\n" if out else ""


# ---------------------------------------------------------------------------
# short
# ---------------------------------------------------------------------------

def render_short(diags: Diagnostics | Iterable[Diagnostic]) -> str:
    """One `file:line:col: severity[CODE]: message` line per finding."""
    lines = []
    for d in _ordered(diags):
        where = f"{escape_controls(d.span.file.path)}:{d.span.line}:{d.span.col}" if d.span else "rcsc"
        # One finding is one line, whatever its message holds.
        message = escape_controls(" ".join(d.message.splitlines()))
        lines.append(f"{where}: {_title(d)}: {message}")
    return "".join(line + "\n" for line in lines)


# ---------------------------------------------------------------------------
# GitHub Actions
# ---------------------------------------------------------------------------

_GITHUB_COMMAND = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.NOTE: "notice"}


def _github_data(text: str) -> str:
    """A workflow command's message: `%`, CR and LF escaped (in that order)."""
    return text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def _github_property(text: str) -> str:
    """A workflow command's property value: also `:` and `,`, which end it."""
    return _github_data(text).replace(":", "%3A").replace(",", "%2C")


def render_github(diags: Diagnostics | Iterable[Diagnostic]) -> str:
    """One GitHub Actions workflow command per finding (`::error file=...::message`),
    which the Actions runner turns into an annotation on the line."""
    lines = []
    for d in _ordered(diags):
        props = []
        if d.span is not None:
            end_line, end_col = d.span.end_line_col
            props.append(f"file={_github_property(d.span.file.path)}")
            props.append(f"line={d.span.line}")
            props.append(f"col={d.span.col}")
            props.append(f"endLine={end_line}")
            if end_line == d.span.line:
                props.append(f"endColumn={end_col}")
        title = f"{d.code} {CODES[d.code].title}" if d.code in CODES else "rcsc"
        props.append(f"title={_github_property(title)}")
        message = d.message + "".join(f"\nnote: {n}" for n in d.notes) + "".join(f"\nhelp: {h}" for h in d.helps)
        lines.append(f"::{_GITHUB_COMMAND.get(d.severity, 'notice')} {','.join(props)}::{escape_controls(_github_data(message))}")
    return "".join(line + "\n" for line in lines)


# ---------------------------------------------------------------------------
# JSON
# ---------------------------------------------------------------------------

def _diagnostic_json(d: Diagnostic) -> dict:
    return {
        "code": d.code,
        "severity": d.severity.value,
        "message": d.message,
        **_location(d.span),
        "label": d.label,
        "labels": [{**_location(label.span), "message": label.message} for label in d.labels],
        "notes": list(d.notes),
        "helps": list(d.helps),
        "data": _plain(d.data),
    }


def render_json(diags: Diagnostics | Iterable[Diagnostic], tool_version: str) -> str:
    """rcsc's own JSON report: deterministic, sorted keys, 2-space indent."""
    ordered = _ordered(diags)
    errors, warnings = _counts(ordered)
    doc = {
        "version": JSON_FORMAT_VERSION,
        "tool": {"name": "rcsc", "version": tool_version},
        "diagnostics": [_diagnostic_json(d) for d in ordered],
        "summary": {"errors": errors, "warnings": warnings},
    }
    # ASCII escapes keep the report writable to any stdout encoding.
    return json.dumps(doc, indent=2, sort_keys=True, ensure_ascii=True) + "\n"


# ---------------------------------------------------------------------------
# SARIF
# ---------------------------------------------------------------------------

_SARIF_LEVEL = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.NOTE: "note"}


def _camel(title: str) -> str:
    """`state unreachable from \\`new\\`` -> `StateUnreachableFromNew`."""
    words = "".join(ch if ch.isalnum() else " " for ch in title).split()
    return "".join(w[0].upper() + w[1:] for w in words)


def _sarif_rule(code: Code) -> dict:
    explanation = code.explanation.strip()
    return {
        "id": code.code,
        "name": _camel(code.title),
        "shortDescription": {"text": code.title},
        "fullDescription": {"text": explanation},
        "help": {
            "text": f"{explanation}\n\nrun `rcsc explain {code.code}` to read this in a terminal.",
            "markdown": f"**{code.code}: {code.title}**\n\n{explanation}",
        },
        "helpUri": help_uri(code.code),
        "defaultConfiguration": {"level": _SARIF_LEVEL[code.severity]},
    }


def _artifact_location(path: str) -> dict:
    """A path as SARIF wants it: a file URI when absolute, otherwise a relative
    URI (POSIX separators, percent-encoded) against %SRCROOT%."""
    windows = PureWindowsPath(path)
    if windows.drive and windows.is_absolute():
        return {"uri": windows.as_uri()}
    posix = path.replace("\\", "/")
    if posix.startswith("/"):
        return {"uri": PurePosixPath(posix).as_uri()}
    return {"uri": quote(str(PurePosixPath(posix)), safe="/"), "uriBaseId": SRCROOT}


def _root_uri(root: str) -> str:
    """An absolute directory URI ending in `/`, as originalUriBaseIds requires."""
    uri = root if "://" in root or root.startswith("file:") else Path(root).resolve().as_uri()
    return uri if uri.endswith("/") else uri + "/"


def _physical_location(span: Span) -> dict:
    end_line, end_col = span.end_line_col
    return {
        "artifactLocation": _artifact_location(span.file.path),
        "region": {
            "startLine": span.line,
            "startColumn": span.col,
            "endLine": end_line,
            "endColumn": end_col,
        },
    }


def _sarif_message(d: Diagnostic) -> str:
    lines = [d.message]
    lines += [f"note: {n}" for n in d.notes]
    lines += [f"help: {h}" for h in d.helps]
    return "\n".join(lines)


def _fingerprint(d: Diagnostic, occurrence: int) -> str:
    """A hash that survives edits which only move a finding to another line.

    It covers code, file and message, plus the ordinal of the finding among
    identical ones so that two equal findings in one file stay distinct.
    """
    path = d.span.file.path.replace("\\", "/") if d.span else ""
    key = "\0".join([d.code, path, d.message, str(occurrence)])
    return hashlib.sha256(key.encode("utf-8")).hexdigest()[:32]


def _sarif_properties(data: dict) -> dict:
    props = _plain(data)
    assert isinstance(props, dict)
    # `tags` is the one property-bag key SARIF constrains (unique strings).
    tags = props.get("tags")
    if tags is not None and not (
        isinstance(tags, list) and all(isinstance(t, str) for t in tags) and len(set(tags)) == len(tags)
    ):
        props["data.tags"] = props.pop("tags")
    return props


def _sarif_result(d: Diagnostic, rule_index: dict[str, int], occurrence: int) -> dict:
    result: dict = {"ruleId": d.code}
    if d.code in rule_index:
        result["ruleIndex"] = rule_index[d.code]
    result["level"] = _SARIF_LEVEL[d.severity]
    result["message"] = {"text": _sarif_message(d)}
    if d.span is not None:
        location: dict = {"physicalLocation": _physical_location(d.span)}
        if d.label:
            location["message"] = {"text": d.label}
        result["locations"] = [location]
    if d.labels:
        result["relatedLocations"] = [
            {"id": i, "physicalLocation": _physical_location(label.span), "message": {"text": label.message}}
            for i, label in enumerate(d.labels, start=1)
        ]
    result["partialFingerprints"] = {FINGERPRINT_KEY: _fingerprint(d, occurrence)}
    if d.data:
        result["properties"] = _sarif_properties(d.data)
    return result


def render_sarif(
    diags: Diagnostics | Iterable[Diagnostic], tool_version: str, root_uri: str | None = None
) -> str:
    """A SARIF 2.1.0 log of one run; every known code is published as a rule.

    `root_uri` (a directory path or URI), when given, tells consumers what the
    relative artifact URIs are relative to (%SRCROOT%).
    """
    codes = sorted(CODES)
    rule_index = {code: i for i, code in enumerate(codes)}
    driver: dict = {"name": "rcsc", "version": tool_version}
    if INFORMATION_URI:
        driver["informationUri"] = INFORMATION_URI
    driver["rules"] = [_sarif_rule(CODES[code]) for code in codes]

    results = []
    seen: Counter[tuple] = Counter()
    for d in _ordered(diags):
        identity = (d.code, d.span.file.path if d.span else "", d.message)
        results.append(_sarif_result(d, rule_index, seen[identity]))
        seen[identity] += 1
    # Findings that an in-source `rcsc: allow(CODE) reason` covers: listed
    # with the suppression and its justification, as SARIF viewers expect.
    for d in _ordered(getattr(diags, "suppressed", [])):
        identity = (d.code, d.span.file.path if d.span else "", d.message)
        result = _sarif_result(d, rule_index, seen[identity])
        seen[identity] += 1
        reason = d.data.get("suppression", {}).get("reason", "")
        result["suppressions"] = [{"kind": "inSource", "justification": reason}]
        results.append(result)

    run: dict = {"tool": {"driver": driver}}
    if root_uri:
        run["originalUriBaseIds"] = {SRCROOT: {"uri": _root_uri(root_uri)}}
    # Our columns count code points, not SARIF's default UTF-16 code units.
    run["columnKind"] = "unicodeCodePoints"
    run["results"] = results
    log = {"$schema": SARIF_SCHEMA_URI, "version": SARIF_VERSION, "runs": [run]}
    return json.dumps(log, indent=2, ensure_ascii=True) + "\n"
