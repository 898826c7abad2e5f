"""Parsing: source text to AST (`text_to_ast`).

The reference grammar lives in `grammar/rcs.lark` (shipped as
`rcsc.grammar`).  Lark builds a parse tree with positions; a Transformer
turns it into `rcsc.front.ast` nodes whose spans cover exactly the text they came
from.  A syntax error becomes one diagnostic (E0001/E0002) with the expected
tokens spelled out the way an engineer reads them.

The Lark side (`rcsc.front.lark_parse`) is imported only when a file
needs it: a check of valid files never loads Lark.

`text_to_ast` first tries the fast hand-written parser (`rcsc.front.rdparse`),
which builds the same tree without a parse tree in between, and uses Lark
only for a file the fast parser leaves to it (a syntax error, very deep
nesting, bidirectional-text controls).  `RCSC_PARSER=lark` in the
environment, or `text_to_ast_lark`, uses Lark for every file.
"""


from __future__ import annotations

import os
import re
import unicodedata
from fractions import Fraction

from rcsc.front import ast
from rcsc.diagnostics import Diagnostics
from rcsc.front.source import BIDI_CONTROLS, SourceFile, Span

UNIT_NANOS = {"us": 1_000, "ms": 1_000_000, "s": 1_000_000_000}

# Expressions and `if` blocks nested deeper than this are refused (E0007)
# rather than handed to the recursive passes after the parser, the way rustc
# has a recursion limit.  Real control code stays far below it.
MAX_NESTING = 128


def _depth(x) -> int:
    return getattr(x, "depth", 1) if x is not None else 0


def nest(parser, node, children):
    """Record `node`'s nesting depth; report the first node past MAX_NESTING (E0007).

    Both parsers call it (`parser` has `diags` and a `too_deep` flag), so the
    limit and its finding are one rule.
    """
    depth = 1 + max((_depth(c) for c in children), default=0)
    node.depth = depth
    if depth > MAX_NESTING and not parser.too_deep:
        parser.too_deep = True
        parser.diags.add("E0007", node.span, f"nested more than {MAX_NESTING} levels deep", "too deep here").with_help(
            "split it: compute parts in locals, or move them into functions"
        )
    return node



# ---- literals in bounded time ------------------------------------------------------------
#
# Python's int() refuses more than 4,300 digits and Fraction("1e100000000")
# computes a 100-million-digit power of ten.  No fixed-width type holds more
# than 20 decimal digits and no duration more than ~9.2e18 ns, so literals
# beyond these bounds are replaced by a value that is just as out of range
# (the type checker reports E0207 for it) without ever computing them.

TOO_LARGE = 1 << 200  # beyond every type: reported as out of range
_MAX_DIGITS = 80  # more significant digits than any literal that fits can have
_MAX_EXPONENT = 400  # |exponent| beyond which a nonzero value is out of range or below 1 ns


def literal_int(text: str) -> int:
    """The value of an INT token (decimal or 0x hex, `_` separators), in bounded time."""
    text = text.replace("_", "")
    hexa = text.lower().startswith("0x")
    digits = (text[2:] if hexa else text).lstrip("0")
    if len(digits) > _MAX_DIGITS:
        return TOO_LARGE
    return int(digits or "0", 16 if hexa else 10)


def literal_fraction(text: str) -> Fraction:
    """The exact value of an INT or FLOAT token, in bounded time and size.

    A nonzero value with a huge exponent is replaced by TOO_LARGE (positive
    exponents) or by 1/TOO_LARGE (negative ones: finer than any unit), which
    the callers report as out of range or as not a whole nanosecond.
    """
    text = text.replace("_", "")
    if text.lower().startswith("0x"):
        return Fraction(literal_int(text))
    mantissa, _, exponent = text.lower().partition("e")
    whole, _, frac = mantissa.partition(".")
    if not (whole + frac).strip("0"):
        return Fraction(0)
    exp = int(exponent) if exponent and len(exponent.lstrip("+-0")) <= 6 else (0 if not exponent else (1 if "-" not in exponent else -1) * 10**7)
    digits = (whole + frac).lstrip("0")
    scale = exp - len(frac)
    significant = digits.rstrip("0")
    scale += len(digits) - len(significant)  # value = significant * 10**scale
    if len(significant) + scale > _MAX_EXPONENT:
        return Fraction(TOO_LARGE)
    if scale < -4 * _MAX_EXPONENT or len(significant) > 4 * _MAX_EXPONENT:
        # Then scale < -9 (the line above), and a last digit that is not 0
        # that far below the point is finer than a nanosecond in any unit.
        return Fraction(1, TOO_LARGE)
    return Fraction(int(significant)) * Fraction(10) ** scale


# Characters that reorder text on screen.  A file holding one goes to the
# reference parser, so that however the language treats them is decided in
# one place (the grammar).
_BIDI_CONTROLS = re.compile("[\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069]")


def text_to_ast(source: SourceFile, diags: Diagnostics, holes: list[tuple[int, int]] | None = None) -> ast.File | None:
    """Parse one file.  Returns None (with a diagnostic) on a syntax error.

    `holes` (the incremental re-check's unchanged controllers and plan
    bodies) are read as blanks without being looked at; the file is then
    parsed by the fast parser only, and None without a diagnostic means that
    it could not (the caller checks the design in full)."""
    text = source.text
    # `isascii` answers at once (a string knows its widest character); the
    # search reads the whole text (14 ms for 5 MB).
    if os.environ.get("RCSC_PARSER") != "lark" and (text.isascii() or not _BIDI_CONTROLS.search(text)):
        from rcsc.front.rdparse import Fallback, parse_fast

        try:
            tree, found = parse_fast(source, holes)
        except Fallback:
            pass
        else:
            diags.extend(found)
            return tree
    if holes:
        return None
    return text_to_ast_lark(source, diags)


def text_to_ast_lark(source: SourceFile, diags: Diagnostics) -> ast.File | None:
    """Parse one file with the reference (Lark) parser (`rcsc.front.lark_parse`)."""
    from rcsc.front.lark_parse import text_to_ast_lark as parse

    return parse(source, diags)


def check_bidi(source: SourceFile, diags: Diagnostics) -> None:
    """E0008 for each bidirectional control character of `source`, comments and strings included."""
    for pos, ch in enumerate(source.text):
        if ch in BIDI_CONTROLS:
            name = unicodedata.name(ch, "BIDIRECTIONAL CONTROL")
            diag = diags.add("E0008", Span(source, pos, pos + 1), f"bidirectional control character U+{ord(ch):04X} ({name})",
                             "changes how the text around it is displayed")
            diag.with_note("what an editor shows here may differ from what rcsc reads (\"trojan source\")")
            diag.with_help("delete the character; the language needs no text direction marks")
