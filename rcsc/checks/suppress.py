"""Per-finding suppression in the source: `// rcsc: allow(CODE) reason`.

A designer who has judged a warning and decided that the design is right says
so where the finding is, with the reason, so that the next reader sees both:

    E3: in_state >= 60 s | FILLING -> error(1);  // rcsc: allow(W0515) the time-out wins on purpose

The comment covers the findings whose primary span starts on its own line,
or, when the comment stands alone on its line, on the next line that is not
a comment.  Several codes may be listed: `allow(W0515, W0517)`.  Only
warnings can be allowed (an error makes the design invalid whatever the
reason), the reason is required, and a comment that allows nothing is
reported: all three are W0008.

Suppressed findings leave the report (and the exit code) but are kept in
`Diagnostics.suppressed`, each with its reason in `data["suppression"]`;
the SARIF rendering lists them as results with an in-source suppression.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from rcsc.codes import CODES
from rcsc.diagnostics import Diagnostic, Diagnostics, Severity
from rcsc.front.source import SourceFile, Span

_ALLOW = re.compile(r"//\s*rcsc:\s*allow\s*\(([^)]*)\)?(.*)$")
_CODE = re.compile(r"^[EW]\d{4}$")


@dataclass
class Allow:
    span: Span  # the comment
    codes: list[str]
    reason: str
    line: int  # the line whose findings it covers
    used: bool = False


def _covered_line(file: SourceFile, line: int, standalone: bool) -> int:
    if not standalone:
        return line
    n = line + 1
    while n <= file.line_count:
        text = file.line_text(n).strip()
        if text and not text.startswith("//"):
            return n
        n += 1
    return line


def find_allows(file: SourceFile, diags: Diagnostics) -> list[Allow]:
    """The well-formed `allow` comments of one file; malformed ones are W0008."""
    out = []
    if "rcsc:" not in file.text:
        return out
    for line in range(1, file.line_count + 1):
        text = file.line_text(line)
        mt = _ALLOW.search(text)
        if mt is None:
            continue
        start = file._line_starts[line - 1] + mt.start()
        span = Span(file, start, start + len(mt.group(0)))
        codes = [c.strip() for c in mt.group(1).split(",") if c.strip()]
        reason = mt.group(2).strip()
        bad = [c for c in codes if not _CODE.match(c) or c not in CODES]
        if not codes or bad or ")" not in mt.group(0):
            what = "no closing `)`" if ")" not in mt.group(0) else (f"unknown code `{bad[0]}`" if bad else "no code")
            diags.add("W0008", span, f"malformed `rcsc: allow(...)`: {what}", "not a suppression").with_help(
                "write `// rcsc: allow(W0515) why the design is right`"
            )
            continue
        errors = [c for c in codes if CODES[c].severity is Severity.ERROR]
        if errors:
            diags.add("W0008", span, f"`{errors[0]}` is an error and cannot be allowed", "not a suppression").with_note(
                "only warnings can be allowed: an error makes the design invalid whatever the reason"
            )
            continue
        if not reason:
            diags.add("W0008", span, "a suppression needs a reason", "no reason").with_help(
                f"say why the design is right: `// rcsc: allow({', '.join(codes)}) the time-out wins on purpose`"
            )
            continue
        standalone = text[: mt.start()].strip() == ""
        out.append(Allow(span, codes, reason, _covered_line(file, line, standalone)))
    return out


def apply(files: list[SourceFile], diags: Diagnostics, report_unused: bool) -> None:
    """Move the findings that an `allow` comment covers to `diags.suppressed`."""
    allows: dict[tuple[int, int], list[Allow]] = {}
    for f in files:
        for a in find_allows(f, diags):
            allows.setdefault((id(f), a.line), []).append(a)
    if not allows:
        return
    kept: list[Diagnostic] = []
    for d in diags.items:
        hit = None
        if d.span is not None and d.severity is Severity.WARNING:
            for a in allows.get((id(d.span.file), d.span.line), []):
                if d.code in a.codes:
                    hit = a
                    break
        if hit is None:
            kept.append(d)
            continue
        hit.used = True
        d.data = dict(d.data)
        d.data["suppression"] = {"reason": hit.reason, "line": hit.span.line}
        diags.suppressed.append(d)
    diags.items[:] = kept
    if report_unused:
        for group in allows.values():
            for a in group:
                if not a.used:
                    diags.add("W0008", a.span, f"`allow({', '.join(a.codes)})` allows nothing here", "unused suppression").with_note(
                        f"no {' or '.join(a.codes)} finding starts on line {a.line}"
                    ).with_help("remove the comment, or move it to the line of the finding")
