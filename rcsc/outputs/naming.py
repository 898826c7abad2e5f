"""The language-neutral core of the targets' naming schemes.

A design name (`[A-Za-z_][A-Za-z0-9_]*`) becomes part of many generated
names: alone (a type, a constant), joined with other names (an enum member is
the enum's name and the member's), with fixed words (a controller's
`cmd` buffer) or behind a fixed lead (`S_` + a state).  Every target builds
its names from the functions here, so that two different things can never
get the same name, whatever the design calls them.

A *fragment* is the form of one design name inside a generated name:

* a *plain* name (it starts with a letter, has no `__` and does not end with
  `_`) is its own fragment: `MAX_AHEAD_RPM` stays `MAX_AHEAD_RPM`;
* a plain name that the target reserves (a keyword, a name of its headers or
  runtime, one of the fixed words below) gets a trailing `_`: `int` -> `int_`;
* any other name is *wrapped*: `0`, then the name with every `_` written
  `_0`: `_` -> `0_0`, `a__b` -> `0a_0_0b`, `x_` -> `0x_0`.

So a fragment never contains `__`, never starts with `_`, and the three
kinds are told apart by their first and last characters (letter ... letter
or digit; letter ... `_`; `0`).  Names are joined with `__` (`Mode__IDLE`),
which therefore always marks a boundary: `Ea_B` + `C` is `Ea_B__C` and `Ea` +
`B_C` is `Ea__B_C`.  A fixed word in a joined name (a *tag*: `VERB`, `cmd`)
is reserved, so no fragment equals one.  A run of underscores in a generated
name is 1 (inside a fragment), 2 (a boundary) or 3 (a reserved fragment's `_`
and a boundary).

Names longer than the target's limit are cut: the first characters, `____`
(a run of four, which no name of the scheme contains) and 8 hex digits of the
SHA-256 of the whole name.  The same rule, with the hash of the name, tells
apart file names that differ only in case (`casefold_unique`).
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Callable, Iterable

_PLAIN = re.compile(r"[A-Za-z](?:[A-Za-z0-9]|_(?!_))*(?<!_)\Z")
SEP = "__"
CUT = "____"


def is_plain(name: str) -> bool:
    """Starts with a letter, has no `__`, does not end with `_`."""
    return bool(_PLAIN.match(name))


def wrap(name: str) -> str:
    """The wrapped form of a name that is not plain (starts with `0`)."""
    return "0" + name.replace("_", "_0")


def fragment(name: str, reserved: Callable[[str], bool]) -> str:
    """The fragment of a design name; `reserved(name)` says whether a plain name is taken."""
    if not is_plain(name):
        return wrap(name)
    return name + "_" if reserved(name) else name


def digest(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:8]


def shorten(name: str, limit: int) -> str:
    """`name` if it fits in `limit` characters, else its first characters, `____` and a hash of it."""
    if len(name) <= limit:
        return name
    head = name[: limit - len(CUT) - 8].rstrip("_")
    return f"{head}{CUT}{digest(name)}"


def casefold_unique(stems: Iterable[str]) -> dict[str, str]:
    """File stems that stay apart on a file system that ignores case.

    A stem that another differs from only in case gets `____` and a hash of
    itself; the others are kept.
    """
    stems = list(stems)
    groups: dict[str, list[str]] = {}
    for s in stems:
        groups.setdefault(s.casefold(), []).append(s)
    return {s: (f"{s}{CUT}{digest(s)}" if len(groups[s.casefold()]) > 1 else s) for s in stems}


class Reserved:
    """A target's reserved names: exact names, and patterns (regular expressions)."""

    def __init__(self, names: Iterable[str] = (), patterns: Iterable[str] = ()) -> None:
        self.names = frozenset(names)
        self.patterns = [re.compile(p) for p in patterns]

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and (name in self.names or any(p.match(name) for p in self.patterns))

    def __or__(self, other: "Reserved") -> "Reserved":
        out = Reserved(self.names | other.names)
        out.patterns = self.patterns + other.patterns
        return out
