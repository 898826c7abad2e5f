"""The formatter (`rcsc fmt`): one canonical layout, every comment kept.

What it changes, and nothing else:

- line ends become LF, a byte-order mark goes, the file ends in one newline;
- trailing blanks go; tabs in indentation become spaces; runs of blank lines
  shrink to one, and the file starts with no blank line;
- each block's lines are indented four spaces per `{` level; a line that
  continues a statement keeps its extra indentation relative to its block;
- the rules of each plan are laid out as the state tables of the RCS papers,
  in aligned columns: `LABEL: event | state -> next | job list;`.  A rule
  whose job list goes on over several lines keeps its line breaks, with the
  continuation lines aligned under the job list; a rule with a line break
  elsewhere, or with a comment inside it, is left as written (its columns
  just do not count for the table).

It works on the text and a map of where the comments and strings are, never
on a parse tree, so that comments stay exactly where they were; the tests
parse every file before and after and require equal syntax trees, and require
`format(format(x)) == format(x)`.  Text that does not parse is not formatted
(`rcsc fmt` reports the syntax errors instead).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

INDENT = 4

_RULE_START = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\s*:(?!:)")
# A plan's head, `plan NAME [continuous] [ordered] {`, in a controller's body
# (depth 1): a line that only starts with the word (a local or constant named
# `plan` continuing an expression, `plan or ready;`) is not one.
_PLAN_HEAD = re.compile(r"\s*plan\s+[A-Za-z_]\w*(?:\s+(?:continuous|ordered))*\s*(?:\{|$)")


def _code_mask(text: str) -> list[bool]:
    """For every character: True when it is code, False inside a comment or string."""
    mask = [True] * len(text)
    i, n = 0, len(text)
    while i < n:
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
        elif text[i] == '"':
            j = i + 1
            while j < n and text[j] not in '"\n':
                j += 1
            if j < n and text[j] == '"':
                j += 1
        else:
            i += 1
            continue
        for k in range(i, j):
            mask[k] = False
        i = j
    return mask


@dataclass
class _Line:
    start: int  # offset of the line in the (normalised) text
    text: str  # without the newline
    code: list[bool]
    in_comment: bool  # the line starts inside a block comment
    ends_in_comment: bool = False  # its newline is inside a block comment

    @property
    def stripped(self) -> str:
        return self.text.strip()

    def code_chars(self) -> str:
        """The line with comments and strings blanked (same length)."""
        return "".join(c if m else " " for c, m in zip(self.text, self.code))


def _lines(text: str) -> list[_Line]:
    mask = _code_mask(text)
    out = []
    pos = 0
    for raw in text.split("\n"):
        # Only a block comment covers a newline, so a line whose preceding
        # newline is not code starts inside one.
        end = pos + len(raw)
        out.append(_Line(pos, raw, mask[pos:end], pos > 0 and not mask[pos - 1], end < len(text) and not mask[end]))
        pos += len(raw) + 1
    return out


def format_text(text: str) -> str:
    """`text` in the canonical layout (the input must parse)."""
    if text.startswith("\ufeff"):
        text = text[1:]
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    lines = _lines(text)
    out: list[str] = []
    depth = 0
    # For each open block: the indentation its first line had in the input
    # (None until that line is seen) and whether it is a plan.
    blocks: list[list] = [[0, False]]
    i = 0
    blank = 0
    pending_plan = False
    while i < len(lines):
        line = lines[i]
        if line.in_comment:
            # Inside a block comment every character is kept, up to where it ends.
            out.append(line.text if line.ends_in_comment else line.text.rstrip())
            i += 1
            continue
        stripped = line.text.lstrip() if line.ends_in_comment else line.text.strip()
        if not stripped:
            blank += 1
            i += 1
            continue
        if blank and out:
            out.append("")
        blank = 0
        code = line.code_chars()
        leading_close = len(code.strip()) > 0 and code.strip()[0] == "}"
        d = depth - 1 if leading_close else depth
        d = max(d, 0)
        block = blocks[min(d, len(blocks) - 1)]
        orig = _indent_width(line.text)
        if block[0] is None:
            block[0] = orig
        extra = max(0, orig - block[0]) if not leading_close else 0
        indent = " " * (INDENT * d + extra)
        if blocks[-1][1] and d == len(blocks) - 1 and _RULE_START.match(stripped) and not leading_close:
            j, rows = _collect_rules(lines, i, len(blocks) - 1, blocks[-1])
            out.extend(rows)
            # A rule's line may close the plan (`R1: ... | S -> done; }`): its
            # braces count as any line's do.
            for ruled in lines[i:j]:
                depth, pending_plan = _braces(ruled.code_chars(), depth, blocks, pending_plan)
            i = j
            continue
        out.append(indent + stripped if line.ends_in_comment else (indent + stripped).rstrip())
        if depth == 1 and _PLAN_HEAD.match(code):
            pending_plan = True
        depth, pending_plan = _braces(code, depth, blocks, pending_plan)
        i += 1
    while out and not out[-1]:
        out.pop()
    return "\n".join(out) + "\n" if out else ""


def _braces(code: str, depth: int, blocks: list[list], pending_plan: bool) -> tuple[int, bool]:
    """The depth after the braces of `code`, opening and closing `blocks` (a `{`
    after a plan's head opens a plan); returns the depth and `pending_plan`."""
    for ch in code:
        if ch == "{":
            depth += 1
            blocks.append([None, pending_plan])
            pending_plan = False
        elif ch == "}":
            depth = max(0, depth - 1)
            if len(blocks) > 1:
                blocks.pop()
    return depth, pending_plan


def _indent_width(text: str) -> int:
    width = 0
    for ch in text:
        if ch == " ":
            width += 1
        elif ch == "\t":
            width += INDENT
        else:
            break
    return width


@dataclass
class _Rule:
    cells: list[str] | None  # label+guard, state, next, jobs (None: no job bar)
    has_jobs_bar: bool
    tail: str  # what follows the `;` on its line (a comment, with its gap)
    continuation: list[str]  # further lines of the job list
    verbatim: list[_Line] | None  # the rule's lines when it is left as written


def _collect_rules(lines: list[_Line], i: int, d: int, block: list) -> tuple[int, list[str]]:
    """Format the run of rules (and the comments and blank lines between
    them) that starts at line `i` of a plan at depth `d`; returns the index of
    the first line after the run and the formatted lines."""
    items: list[object] = []  # _Rule, or a str (a comment line, "" for a blank)
    while i < len(lines):
        line = lines[i]
        stripped = line.text.strip()
        code = line.code_chars().strip()
        if not stripped:
            items.append("")
            i += 1
            continue
        if line.in_comment or (not code):
            items.append(line)
            i += 1
            continue
        if not _RULE_START.match(stripped):
            break
        j = i
        while j < len(lines) and ";" not in lines[j].code_chars():
            j += 1
        j = min(j, len(lines) - 1)
        items.append(_parse_rule(lines[i:j + 1], d, block))
        i = j + 1
        if "}" in lines[j].code_chars():
            break  # the plan ends on this rule's line: what follows is outside it
    # Trailing blank lines belong to what follows: give them back.
    while items and items[-1] == "":
        items.pop()
        i -= 1
    rules = [r for r in items if isinstance(r, _Rule) and r.cells is not None]
    widths = [max((len(r.cells[k]) for r in rules), default=0) for k in range(3)]
    any_jobs = [r for r in rules if r.has_jobs_bar]
    next_width = max((len(r.cells[2]) for r in any_jobs), default=0)
    indent = " " * (INDENT * d)
    out: list[str] = []
    blank = False
    for item in items:
        if item == "":
            blank = True
            continue
        if blank and out:
            out.append("")
        blank = False
        if isinstance(item, _Line):
            extra = max(0, _indent_width(item.text) - (block[0] or 0))
            out.append(item.text.rstrip() if item.in_comment else (indent + " " * extra + item.text.strip()).rstrip())
            continue
        assert isinstance(item, _Rule)
        if item.cells is None:
            assert item.verbatim is not None
            first = item.verbatim[0]
            out.append(_keep_end(first, indent + first.text.lstrip()))
            delta = len(indent) - _indent_width(first.text)
            for more in item.verbatim[1:]:
                if more.in_comment:  # inside a block comment: as written
                    out.append(_keep_end(more, more.text))
                else:
                    out.append(_keep_end(more, " " * max(0, _indent_width(more.text) + delta) + more.text.lstrip()))
            continue
        head, state, nxt, jobs = item.cells
        row = f"{indent}{head:<{widths[0]}} | {state:<{widths[1]}} -> "
        if item.has_jobs_bar:
            row += f"{nxt:<{next_width}} |"
            if jobs:
                column = len(row) + 1
                row += " " + jobs
                out.append(row + ("" if item.continuation else ";") + ("" if item.continuation else item.tail))
                for k, more in enumerate(item.continuation):
                    last = k == len(item.continuation) - 1
                    out.append(" " * column + more + (";" + item.tail if last else ""))
                continue
            out.append(row + ";" + item.tail)
        else:
            out.append(row + nxt + ";" + item.tail)
    return i, out


def _keep_end(line: _Line, text: str) -> str:
    """`text` without trailing blanks, unless the line ends inside a block
    comment (a comment keeps every character)."""
    return text if line.ends_in_comment else text.rstrip()


def _split_top(text: str, code: str, sep: str) -> list[int]:
    """Offsets of `sep` in `text` outside parentheses, comments and strings."""
    found, depth = [], 0
    k = 0
    while k < len(text):
        ch = code[k]
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        elif depth == 0 and code.startswith(sep, k):
            found.append(k)
            k += len(sep)
            continue
        k += 1
    return found


def _squash(text: str) -> str:
    return " ".join(text.split())


def _parse_rule(rule_lines: list[_Line], d: int, block: list) -> _Rule:
    verbatim = _Rule(None, False, "", [], list(rule_lines))
    first = rule_lines[0]
    code = first.code_chars()
    semi_line = rule_lines[-1]
    semi_code = semi_line.code_chars()
    semi = semi_code.find(";")
    if semi < 0:
        return verbatim  # not a rule after all: left as written
    tail_text = semi_line.text[semi + 1:]
    tail = "" if not tail_text.strip() else (" " * max(1, _indent_width(tail_text)) + tail_text.strip())
    if tail.strip() and not tail.strip().startswith("//"):
        return verbatim  # more code after the `;`: keep the line as it is
    # A comment inside the rule (before its `;`) keeps it as written.
    for ln in rule_lines:
        stop = semi if ln is semi_line else len(ln.text)
        if not all(ln.code[:stop]):
            return verbatim
    body_code = code if len(rule_lines) > 1 else semi_code[:semi]
    body = first.text if len(rule_lines) > 1 else first.text[:semi]
    bars = _split_top(body, body_code, "|")
    arrows = _split_top(body, body_code, "->")
    if not bars or not arrows or arrows[0] < bars[0]:
        return verbatim
    head = body[:bars[0]]
    label, _, guard = head.partition(":")
    state = body[bars[0] + 1:arrows[0]]
    rest_start = arrows[0] + 2
    has_jobs = len(bars) > 1 and bars[1] > arrows[0]
    if len(rule_lines) > 1 and not has_jobs:
        return verbatim  # a line break before the job list
    nxt = body[rest_start:bars[1]] if has_jobs else body[rest_start:]
    jobs = body[bars[1] + 1:] if has_jobs else ""
    if len(bars) > 2:
        return verbatim
    continuation: list[str] = []
    if len(rule_lines) > 1:
        if not jobs.strip() or not jobs.rstrip().endswith(","):
            return verbatim
        for k, ln in enumerate(rule_lines[1:]):
            part = ln.text[:semi] if ln is semi_line else ln.text
            if ln is not semi_line and not part.rstrip().endswith(","):
                return verbatim
            continuation.append(_squash(part))
    cells = [f"{label.strip()}: {_squash(guard)}", _squash(state), _squash(nxt), _squash(jobs)]
    return _Rule(cells, has_jobs, tail, continuation, None)


def format_source(path: str, text: str):
    """(formatted text, diagnostics): the text is None when `text` does not
    parse (the diagnostics say why) or, as a safety net, when the formatted
    text would not parse to the same syntax tree."""
    from rcsc.diagnostics import Diagnostics
    from rcsc.front.parse import text_to_ast
    from rcsc.front.source import SourceFile

    diags = Diagnostics()
    before = text_to_ast(SourceFile(path, text), diags)
    if before is None:
        return None, diags
    formatted = format_text(text)
    after = text_to_ast(SourceFile(path, formatted), Diagnostics())
    if after is None or shape(after) != shape(before):
        raise AssertionError(f"internal error: formatting {path} would change its meaning; the file is left alone")
    return formatted, diags


def shape(node: object) -> object:
    """A syntax tree without its spans, to compare two parses of one design."""
    import dataclasses

    from rcsc.front.source import Span

    if isinstance(node, Span):
        return None
    if dataclasses.is_dataclass(node) and not isinstance(node, type):
        return (type(node).__name__,) + tuple(
            shape(getattr(node, f.name)) for f in dataclasses.fields(node) if f.name != "span"
        )
    if isinstance(node, (list, tuple)):
        return tuple(shape(v) for v in node)
    if isinstance(node, dict):
        return tuple(sorted((k, shape(v)) for k, v in node.items()))
    return node
