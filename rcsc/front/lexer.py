"""The fast front end's tokenizer: source text to a flat list of tokens.

One regular expression splits the whole file at once.  Blanks and comments
are skipped as the prefix of every match; each token is kept as its text
(`"plan"`, `"->"`, `"12.5"`) plus its start offset, in two parallel lists,
so the parser in `rcsc.front.rdparse` compares strings and never builds token
objects.  Words are not sorted into keywords here: the language reserves a
keyword only where the grammar expects it (as Lark's contextual lexer does
for `grammar/rcs.lark`), so the parser decides.

The terminal patterns are those of `grammar/rcs.lark`, in the order Lark
tries them (floats before integers, two-character operators before
one-character ones).  Any other character becomes a token of its own that no
rule accepts, so the parser hands such a file to the reference parser, which
reports it.
"""

from __future__ import annotations

import re
import sys

# Blanks and comments as in the grammar (`WS`, `COMMENT`, `BLOCK_COMMENT`);
# `\s` would also accept vertical tabs and Unicode spaces, which the
# grammar does not.
# The quantifiers are possessive (`*+`): once blanks and comments are
# skipped, the engine must not back into them and read a `/` or a blank as
# a token.  Blanks first and comments as the exception: most trivia is one
# run of blanks, which this order matches without trying the comment
# alternatives at every character (a fifth faster on large designs than
# an atomic group of the three alternatives).
_TRIVIA = r"(?:[ \t\f\r\n]*+(?:(?://[^\n]*+|/\*[\s\S]*?\*/)[ \t\f\r\n]*+)*+)"

_TOKEN = re.compile(
    "(" + _TRIVIA + ")("
    r"[0-9][0-9_]*\.[0-9][0-9_]*(?:[eE][+-]?[0-9]+)?|[0-9][0-9_]*[eE][+-]?[0-9]+"  # FLOAT
    r"|0x[0-9A-Fa-f][0-9A-Fa-f_]*|[0-9][0-9_]*"  # INT
    r"|[A-Za-z_][A-Za-z0-9_]*"  # NAME (and every keyword)
    r'|"[^"\n]*"'  # STRING
    r"|->|\.\.|[=!<>+\-*]="  # two-character operators
    r"|[\s\S]"  # one character: punctuation, or something no rule accepts
    r"|\Z"  # nothing but trivia up to the end: an empty token, dropped below
    ")"
)

# The end-of-file token: a blank, which no real token can be.
EOF = " "

NAME_START = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz_")
DIGITS = frozenset("0123456789")


def segments(length: int, holes: list[tuple[int, int]] | None) -> list[tuple[int, int]]:
    """[start, end) of the text of `length` characters outside `holes`
    (sorted, disjoint [start, end) ranges)."""
    out, at = [], 0
    for s, e in holes or ():
        if s > at:
            out.append((at, s))
        at = max(at, e)
    out.append((at, length))
    return out


def tokenize(text: str, holes: list[tuple[int, int]] | None = None) -> tuple[list[str], list[int], list[int]]:
    """The tokens of `text`, their start and their end offsets, ending with
    EOF at len(text).

    Token texts are interned: a design repeats the same few hundred names
    and keywords, and the AST keeps one copy of each instead of one per use.

    `holes` are ranges read as blanks without being looked at (the
    incremental re-check's unchanged controllers, `rcsc.checks.incremental`):
    the tokens are those of the text with the holes blanked, a hole must not
    start or end inside a token, a comment or a string.
    """
    toks: list[str] = []
    starts: list[int] = []
    ends: list[int] = []
    append_tok, append_start, append_end = toks.append, starts.append, ends.append
    intern = sys.intern
    for lo, hi in segments(len(text), holes):
        pos = lo
        for trivia, tok in _TOKEN.findall(text, lo, hi):
            if not tok:  # the end
                break
            pos += len(trivia)
            append_tok(intern(tok))
            append_start(pos)
            pos += len(tok)
            append_end(pos)
    # Every match starts where the previous one ended (a token can be any
    # character, and the end matches too), so the offsets above are exact.
    append_tok(EOF)
    append_start(len(text))
    append_end(len(text))
    return toks, starts, ends


def is_float(tok: str) -> bool:
    """Whether a token that starts with a digit is a FLOAT (else an INT)."""
    return not tok.startswith("0x") and ("." in tok or "e" in tok or "E" in tok)
