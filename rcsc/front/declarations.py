"""The top-level declarations of a root file, as a re-check after an edit compares them.

An incremental re-check (`rcsc.checks.incremental`) checks again only the
controllers an edit touched.  An edit outside the controllers used to mean a
full check; when it changes only declarations -- a constant, an enum, a
record, a Global Memory variable, a function, an extern, a verb set -- the
controllers it can touch are those whose text names what changed, directly
or through another declaration that names it.  This module says, for one
text and its syntax tree (the controllers may be holes in it):

- the digest of each such declaration's text, by kind and name;
- the names each declaration's text holds (its words: more than the names
  it uses, never fewer);
- the digest of the frame: the text outside the controllers and those
  declarations (the `design` line, imports, CPUs, comments, doc comments),
  blank lines and indentation aside.  A re-check after an edit of the frame
  is a full check;
- which controllers' texts hold one of a set of names (`mentioning`), and
  which names another file uses (`names_in`: an imported file can use the
  root's names too).

Names are found as words of the text, comments and strings included, and a
name is found inside a longer word too (`MAX` in `MAX_COUNT`): a controller
that does not use a changed name may be checked again, one that uses it is
never missed.
"""

from __future__ import annotations

import bisect
import re
from dataclasses import dataclass

from rcsc.front.items import ControllerItem, digest

# The syntax tree classes of the declarations an edit may change without a
# full check (`rcsc.front.ast`).
KINDS = frozenset(("Const", "Enum", "Record", "GmVar", "Function", "Extern", "VerbSet"))
_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


@dataclass
class Declarations:
    frame: str  # digest of the text outside the controllers and the declarations
    frame_words: frozenset[str]  # the names that text holds
    digests: dict[str, str]  # "Kind name" -> digest of the declaration's text
    words: dict[str, frozenset[str]]  # "Kind name" -> the names its text holds


def declarations(text: str, items: list, controllers: list[ControllerItem]) -> Declarations | None:
    """The declarations among the top-level syntax tree `items` of `text`;
    None when two have the same kind and name (an error the full check reports)."""
    found = [x for x in items if type(x).__name__ in KINDS]
    digests: dict[str, str] = {}
    words: dict[str, frozenset[str]] = {}
    for x in found:
        key = f"{type(x).__name__} {x.name.name}"
        if key in digests:
            return None
        body = text[x.span.start:x.span.end]
        digests[key] = digest(body)
        words[key] = frozenset(_WORD.findall(body))
    # The frame: the text between the cuts, blanks aside, in groups by the
    # controllers between them (a comment that moves past a controller
    # changes it: it may be that controller's doc comment now).
    cuts = sorted([(c.start, c.end, True) for c in controllers] + [(x.span.start, x.span.end, False) for x in found])
    groups: list[list[str]] = [[]]
    at = 0
    for start, end, is_controller in cuts:
        if start > at:
            groups[-1].append(text[at:start].strip())
        if is_controller:
            groups.append([])
        at = max(at, end)
    groups[-1].append(text[at:].strip())
    frame = "\x01".join("\x00".join(p for p in group if p) for group in groups)
    return Declarations(digest(frame), frozenset(_WORD.findall(frame)), digests, words)


def name_of(key: str) -> str:
    """The declared name of a "Kind name" key."""
    return key.split(" ", 1)[1]


def changed_names(old: dict[str, str], new: Declarations) -> set[str]:
    """The names declared differently in `new` than in `old` (digests by
    "Kind name"): changed, added or removed, and then every declaration
    whose text names one of those, until none is added."""
    names = {name_of(k) for k in set(old) ^ set(new.digests)}
    names |= {name_of(k) for k, d in new.digests.items() if k in old and old[k] != d}
    grew = True
    while grew:
        grew = False
        for key, words in new.words.items():
            name = name_of(key)
            if name not in names and not words.isdisjoint(names):
                names.add(name)
                grew = True
    return names


def mentioning(text: str, controllers: list[ControllerItem], names: set[str]) -> set[str]:
    """The controllers whose text holds one of `names` (as a word or inside one)."""
    starts = [c.start for c in controllers]
    out: set[str] = set()
    for name in sorted(names):
        at = text.find(name)
        while at >= 0:
            k = bisect.bisect_right(starts, at) - 1
            if k >= 0 and at < controllers[k].end:
                out.add(controllers[k].name)
                at = text.find(name, controllers[k].end)  # the rest of this controller says nothing more
            else:
                at = text.find(name, at + 1)
    return out


def names_in(text: str) -> frozenset[str]:
    """The names a text uses: its name tokens, as the parser reads them
    (not the words of its comments and strings)."""
    from rcsc.front.lexer import NAME_START, tokenize

    return frozenset(tok for tok in tokenize(text)[0] if tok[:1] in NAME_START)

