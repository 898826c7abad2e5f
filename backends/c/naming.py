"""Every name in the generated C: one function per kind of name, built on `rcsc.outputs.naming`.

C has one scope for the names of a translation unit (types, functions,
enumerators, variables) and macros that replace a name everywhere, also as a
struct member.  The scheme (docs/backends.md, "Names"):

* design-wide names are `<p>_` and the design's names as fragments joined by
  `__`, with fixed words (*tags*) where the kind needs them:
  `<p>_ShipDir` (a type), `<p>_ShipDir__AHEAD` (an enum member),
  `<p>_MAX_RPM` (a constant), `<p>_PR__VERB__AHEAD` (a verb number),
  `<p>_PR__cmd` (a command buffer type), `<p>_MAIN__PERIOD_NS`;
* names local to one file start with a fixed lead and `_`: `S_IDLE` (a
  state), `RULE_AHEAD__E0`, `plan_AHEAD`, and in the Main Program `ctrl_PR`,
  `type_ShipDir`...;
* struct members and parameters keep the design's name unless a header, the
  runtime or the language takes it: then it gets a trailing `_` (`EOF_`,
  `int_`), and a name that is not plain gets the wrapped form with a leading
  `_` (`_0_0Atomic` for `_Atomic`: members and parameters are not at file
  scope, where a leading `_` is reserved).

`<p>` is the design's name, or that name and `_` when a header or the
runtime uses it as a prefix (a design called `rcs`, `INT32` or `ctrl`).
Identifiers are cut at 63 characters (C99's significant length) and file
names at 120 (`rcsc.outputs.naming.shorten`); file names that differ only in case get
a hash.
"""

from __future__ import annotations

import re

from rcsc.outputs import naming as nm
from rcsc.backends.c.headers import FUNCTIONS, MACROS, OTHERS

C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto if inline int long "
    "register restrict return short signed sizeof static struct switch typedef union unsigned void volatile while "
    "_Alignas _Alignof _Atomic _Bool _Complex _Generic _Imaginary _Noreturn _Static_assert _Thread_local "
    "bool true false alignas alignof constexpr nullptr static_assert thread_local typeof typeof_unqual asm fortran".split()
)
# Fixed words inside design-wide names; a design name equal to one gets a trailing `_`.
TAGS = frozenset(
    "H VERB STATUS PERIOD_NS BUDGET_NS init step args cmd status fields state rule gm gm_stamps buffers buffers_init "
    "io io_read io_write externs ARRAY".split()
)
# Leads of the file-local names (`S_`, `RULE_`, `ctrl_`...) and the runtime's prefixes: a
# design whose name is one of them, or starts with one and `_`, gets a trailing `_`.
LEADS = frozenset(
    "ST S RULE plan cse ctrl step type members fields const params verbs status states rules statuses gm io main run "
    "rcs RCS".split()
)
# The names the Main Program's file defines beside the leads above.
MAIN_FIXED = frozenset("buf types consts gm_fields gm_from_env ctrls schedule design main io_read io_write".split())
HEADER_NAMES = MACROS | FUNCTIONS | OTHERS
IDENT_LIMIT = 63
FILE_LIMIT = 120


def _prefix(design: str) -> str:
    if not nm.is_plain(design):
        return "d__" + nm.wrap(design)
    taken = (
        design in C_KEYWORDS or design in HEADER_NAMES
        or any(design == lead or design.startswith(lead + "_") for lead in LEADS)
        or any(h.startswith(design + "_") for h in HEADER_NAMES)
    )
    return design + "_" if taken else design


class CNames:
    """The names of one design's C code."""

    def __init__(self, design: str, controllers: list[str] = (), cpus: list[str] = ()) -> None:  # type: ignore[assignment]
        self.design = design
        self.p = nm.shorten(_prefix(design), 24)
        self._member_reserved = nm.Reserved(C_KEYWORDS | MACROS | OTHERS, [r"(rcs|RCS)_", re.escape(self.p) + "_"])
        stems = {c: self._stem(self.p + "_" + self.frag(c)) for c in controllers}
        stems.update({("cpu", c): self._stem("main_" + self.frag(c)) for c in cpus})
        unique = nm.casefold_unique(stems.values())
        self._stems = {k: unique[v] for k, v in stems.items()}

    # ---- building blocks ---------------------------------------------------------------

    def frag(self, name: str) -> str:
        return nm.fragment(name, lambda n: n in TAGS)

    def _g(self, *parts: str) -> str:
        """A design-wide name: `<p>_` and the parts joined by `__` (parts are fragments or tags)."""
        return nm.shorten(self.p + "_" + nm.SEP.join(parts), IDENT_LIMIT)

    @staticmethod
    def _stem(text: str) -> str:
        return nm.shorten(text, FILE_LIMIT)

    def local(self, lead: str, *names: str) -> str:
        """A file-local name: a fixed lead, `_` and the design's names joined by `__`."""
        return nm.shorten(lead + "_" + nm.SEP.join(self.frag(n) for n in names), IDENT_LIMIT)

    # ---- design-wide names ------------------------------------------------------------

    def type(self, name: str) -> str:
        return self._g(self.frag(name))

    def _type_key(self, t) -> str:
        """A type as name parts: a built-in's name, a declared type's fragment,
        `ARRAY__<element>__<length>` for an array (ARRAY is a tag: no design name)."""
        elem = getattr(t, "elem", None)
        if elem is not None:
            return nm.SEP.join(("ARRAY", self._type_key(elem), str(t.size)))
        return t.name if t.name in ("bool", "i32", "i64", "u32", "f64", "duration") else self.frag(t.name)

    def array_type(self, t) -> str:
        """The struct that holds an array type's elements (`v`)."""
        return self._g(self._type_key(t))

    def array_fn(self, t, op: str) -> str:
        """An array type's helper: `get` (element or zero), `sum`, `min_of`, `max_of`."""
        return self._g(self._type_key(t), op)

    def enum_member(self, enum: str, member: str) -> str:
        return self._g(self.frag(enum), self.frag(member))

    def const(self, name: str) -> str:
        return self._g(self.frag(name))

    def function(self, name: str) -> str:
        return self._g(self.frag(name))

    def ctrl_type(self, ctrl: str) -> str:
        return self._g(self.frag(ctrl))

    def ctrl_part(self, ctrl: str, tag: str) -> str:
        """`init`, `step` (functions), `args`, `cmd`, `status`, `fields` (types), `state`,
        `rule` (enum tags), `BUDGET_NS`, `H` (macros) of a controller."""
        assert tag in TAGS, tag
        return self._g(self.frag(ctrl), tag)

    def verb(self, ctrl: str, verb: str) -> str:
        return self._g(self.frag(ctrl), "VERB", self.frag(verb))

    def status(self, ctrl: str, status: str) -> str:
        return self._g(self.frag(ctrl), "STATUS", self.frag(status))

    def verb_args(self, ctrl: str, verb: str) -> str:
        return self._g(self.frag(ctrl), self.frag(verb), "args")

    def period(self, cpu: str) -> str:
        return self._g(self.frag(cpu), "PERIOD_NS")

    def fixed(self, *tags: str) -> str:
        """`gm`, `buffers`, `buffers_init`, `io_read`, `io_write`, `H`, (`externs`, `H`), (`io`, `H`)."""
        assert all(t in TAGS for t in tags), tags
        return self._g(*tags)

    # ---- members, parameters and file-local names -------------------------------------------

    def member(self, name: str) -> str:
        """A struct member or a function parameter."""
        # A name that is not plain, or that starts like a design-wide name
        # (`<p>_`, which a trailing `_` would not keep apart from a reserved
        # fragment's `<p>_X_`), gets `_` and its wrapped form: no design-wide
        # name starts with `_0`.
        if not nm.is_plain(name) or name.startswith(self.p + "_"):
            return nm.shorten("_" + nm.wrap(name), IDENT_LIMIT)
        return nm.shorten(name + "_" if name in self._member_reserved else name, IDENT_LIMIT)

    def buffer_member(self, ctrl: str, tag: str) -> str:
        """The members of `<p>_buffers`: `gm`, and `<C>__cmd`, `<C>__status` per controller.
        A wrapped fragment starts with a digit, which no C identifier may: it
        gets `_` first (a member is not at file scope, where `_0` would be
        reserved; no other member of the struct starts with `_`)."""
        frag = self.frag(ctrl)
        return nm.shorten(("_" if frag[:1].isdigit() else "") + frag + nm.SEP + tag, IDENT_LIMIT)

    def state(self, name: str) -> str:
        fixed = {"": "ST_NONE", "new": "ST_NEW", "done": "ST_DONE", "error": "ST_ERROR"}
        return fixed[name] if name in fixed else self.local("S", name)

    def rule(self, verb: str, label: str) -> str:
        return self.local("RULE", verb, label)

    def plan_fn(self, verb: str) -> str:
        return self.local("plan", verb)

    # ---- files --------------------------------------------------------------------------

    def ctrl_stem(self, ctrl: str) -> str:
        return self._stems[ctrl]

    def main_stem(self, cpu: str) -> str:
        return self._stems[("cpu", cpu)]

    def binary(self, cpu: str) -> str:
        return self._stem(self.p + "_" + self.frag(cpu))

