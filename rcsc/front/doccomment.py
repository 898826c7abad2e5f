"""Doc comments: `///` lines directly before an item, kept in the AST.

A doc comment is a run of line comments that start with exactly three
slashes (`////` is an ordinary comment, as in Rust), with nothing but blanks
between them and the item that follows.  The grammar keeps treating them as
comments (`COMMENT` in grammar/rcs.lark), so both parsers build the same tree
and this one pass, run by both, attaches the text to the node it documents:
controllers, plans, rules, verbs and verb sets, Global Memory variables,
status fields and locals, record fields, functions, externs, constants,
enums, records and CPUs; also controller types (the text documents the
template, and so every instance without a doc comment of its own), controller
instances, function blocks and their inputs, states and outputs.

The text is the lines without their `///` and one following blank, joined
with newlines.  It is shown by `rcsc doc` and the language server, and the
backends copy it into comments through their sanitisers (never verbatim).
A `///` run that documents nothing (before `pre`, inside a block, at the end
of the file) is reported (W0240).
"""

from __future__ import annotations

import re

from rcsc.diagnostics import Diagnostics
from rcsc.front import ast
from rcsc.front.lexer import _TOKEN, segments
from rcsc.front.source import SourceFile, Span

_PIECE = re.compile(r"[ \t\f\r\n]+|//[^\n]*|/\*[\s\S]*?\*/")
_DOC = re.compile(r"///(?!/)")

# The nodes that can carry a doc comment.
DOCUMENTED = (ast.Const, ast.Enum, ast.Record, ast.Param, ast.GmVar, ast.Function, ast.Extern, ast.Verb, ast.VerbSet,
              ast.Rule, ast.Plan, ast.Decl, ast.Controller, ast.Cpu, ast.ControllerType, ast.ControllerInstance, ast.BlockType,
              ast.BlockMember)


def doc_runs(text: str, holes: list[tuple[int, int]] | None = None) -> dict[int, ast.DocComment]:
    """Each `///` run of `text` outside `holes` (see `rcsc.front.lexer.tokenize`),
    keyed by the offset of the token that follows it."""
    out: dict[int, ast.DocComment] = {}
    if "///" not in text:
        return out
    for lo, hi in segments(len(text), holes):
        _doc_runs(text, lo, hi, out)
    return out


def _doc_runs(text: str, lo: int, hi: int, out: dict) -> None:
    pos = lo
    for trivia, tok in _TOKEN.findall(text, lo, hi):
        start = pos
        pos += len(trivia) + len(tok)
        if "///" not in trivia:
            continue
        lines: list[str] = []
        first = last = None
        at = start
        for piece in _PIECE.findall(trivia):
            p_start = at
            at += len(piece)
            if _DOC.match(piece):
                body = piece[3:]
                lines.append(body[1:] if body.startswith(" ") else body)
                first = p_start if first is None else first
                last = at
            elif piece.startswith("/"):  # another comment ends the run
                lines, first, last = [], None, None
        if lines:
            assert first is not None and last is not None
            out[start + len(trivia)] = (first, last, "\n".join(line.rstrip() for line in lines))  # type: ignore[assignment]


def attach(tree: ast.File | None, source: SourceFile, diags: Diagnostics, holes: list[tuple[int, int]] | None = None) -> None:
    """Attach the doc comments of `source` (outside `holes`) to the nodes of `tree`; W0240 for the others."""
    if tree is None:
        return
    runs = doc_runs(source.text, holes)
    if not runs:
        return
    used: set[int] = set()

    def visit(node) -> None:
        if isinstance(node, DOCUMENTED):
            run = runs.get(node.span.start)
            if run is not None:
                first, last, text = run  # type: ignore[misc]
                node.doc = ast.DocComment(Span(source, first, last), text)
                used.add(node.span.start)
        for child in _children(node):
            visit(child)

    for item in tree.items:
        visit(item)
    for key in sorted(set(runs) - used):
        first, last, _ = runs[key]  # type: ignore[misc]
        diags.add("W0240", Span(source, first, last), "doc comment documents nothing", "not directly before an item").with_help(
            "put it right before a declaration (controller, plan, rule, verb, variable, function, ...), or write `//` for a plain comment"
        )


def _children(node) -> list:
    if isinstance(node, ast.Controller):
        return [*node.verbs, *node.status_fields, *node.locals, *node.plans]
    if isinstance(node, ast.ControllerType):
        # The template starts where the type does, so it takes the type's doc
        # comment too and hands it to the instances, which copy the template.
        return [node.body]
    if isinstance(node, ast.BlockType):
        return list(node.members)
    if isinstance(node, ast.Plan):
        return list(node.rules)
    if isinstance(node, ast.VerbSet):
        return list(node.verbs)
    if isinstance(node, ast.Record):
        return list(node.fields)
    return []
