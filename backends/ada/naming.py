"""Every name in the generated Ada: one function per kind of name, on `rcsc.outputs.naming`.

Ada differs from C and Rust in three ways that shape the scheme
(docs/backends.md, "Names"):

* identifiers are case-insensitive: `Foo` and `foo` are one name;
* an identifier starts with a letter, has no `__` and does not end with `_`,
  so the shared core's `__` join and its wrapped form (`0x_0`) are not Ada;
* every Ada identifier is a *plain* name, so a scheme that kept all plain
  names as written would have no room left for joined names.

So a design name's Ada *fragment* is the name as written when it is
*simple*: plain, not reserved here (Ada's reserved words, the runtime's and
the templates' own names, compared ignoring case), with no `_0` in it, and
no other name of the design equal to it when case is ignored.  Any other
name is written `X0` and the hexadecimal digits of its bytes (`_` ->
`X05f`, `foo` beside `Foo` -> `X0666f6f`), which has no `_` and records the
case.  Joined names join fragments and fixed words (tags) with `_0_`, which
no fragment contains, so the parts of a joined name are always found again;
the kinds of design-wide names are told apart by a leading tag (`T_0_`
a type, `K_0_` a constant, `F_0_` a function, `M_0_` an enum member...).
Names longer than 120 characters are cut: their first characters, `_0z`
and 8 hex digits of the SHA-256 of the whole name.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Iterable

from rcsc.outputs import naming as nm

ADA_KEYWORDS = frozenset(
    "abort abs abstract accept access aliased all and array at begin body case constant declare delay delta digits "
    "do else elsif end entry exception exit for function generic goto if in interface is limited loop mod new not "
    "null of or others out overriding package pragma private procedure protected raise range record rem renames "
    "requeue return reverse select separate some subtype synchronized tagged task terminate then type until use "
    "when while with xor".split()
)
# Names of Standard, Interfaces and the generated code's own words (tags, fixed
# objects and types, parameters): a design name equal to one (ignoring case)
# is written in hex, so it never hides or meets them.
FIXED = frozenset(
    "Standard System Interfaces Ada GNAT Boolean True False Integer Natural Positive Float Long_Float Character "
    "String Duration Integer_8 Integer_16 Integer_32 Integer_64 Unsigned_8 Unsigned_16 Unsigned_32 Unsigned_64 "
    "F64 Buf Buffers Gm Gm_Record Gm_Stamp Gm_Stamps Head Status_Head Command_Head Loc Locals Sent Send Sent_Record "
    "Send_Record Plan Entry_Cycle Steps Cycle State Args Cmd Status Verb Fields Period Init Step Types Functions "
    "Externs Ctrl Unused Ignore Self T K F M V S R St St_None St_New St_Done St_Error Cmd_Buffer Status_Buffer "
    "Budget_Ns Value Result".split()
)
RESERVED = frozenset(x.casefold() for x in ADA_KEYWORDS | FIXED)
_RESERVED_PATTERN = re.compile(r"(?i)(rcs|cse_|x0)")
SEP = "_0_"
LIMIT = 120


def _shorten(name: str) -> str:
    if len(name) <= LIMIT:
        return name
    return name[: LIMIT - 11].rstrip("_") + "_0z" + nm.digest(name)


class AdaNames:
    """Names of one design.  `names`: every name the design declares (any kind),
    so that names equal when case is ignored are told apart."""

    def __init__(self, design: str, names: Iterable[str] = ()) -> None:
        counts = Counter(x.casefold() for x in set(names) | {design})
        self.ambiguous = {k for k, v in counts.items() if v > 1}
        self.unit = self.frag(design)

    # ---- the core ----------------------------------------------------------------

    def simple(self, name: str) -> bool:
        return (nm.is_plain(name) and "_0" not in name and name.casefold() not in RESERVED
                and not _RESERVED_PATTERN.match(name) and name.casefold() not in self.ambiguous)

    def frag(self, name: str) -> str:
        """The Ada form of one design name."""
        return _shorten(name if self.simple(name) else "X0" + name.encode("utf-8").hex())

    def join(self, *parts: str) -> str:
        return _shorten(SEP.join(parts))

    # ---- design-wide names (in the types, functions and externs packages) ---------

    def type(self, t: str) -> str:
        return self.join("T", self.frag(t))

    def const(self, k: str) -> str:
        return self.join("K", self.frag(k))

    def function(self, f: str) -> str:
        return self.join("F", self.frag(f))

    def _type_key(self, t) -> tuple[str, ...]:
        """A type as name parts: a built-in's name, a declared type's fragment,
        `A, <element>, <length>` for an array (no design name contains `_0`)."""
        elem = getattr(t, "elem", None)
        if elem is not None:
            return ("A", *self._type_key(elem), str(t.size))
        return (t.name.capitalize(),) if t.name in ("bool", "i32", "i64", "u32", "f64", "duration") else (self.frag(t.name),)

    def array_type(self, t) -> str:
        """The Ada array type of an array type of the design (`A_0_F64_0_16`)."""
        return self.join(*self._type_key(t))

    def array_fn(self, t, op: str) -> str:
        """An array type's helper: `Get` (element or zero), `Sum`, `Min_Of`, `Max_Of`."""
        return self.join(op, *self._type_key(t))

    def enum_member(self, t: str, x: str) -> str:
        return self.join("M", self.frag(t), self.frag(x))

    def period(self, cpu: str) -> str:
        return self.join("Period", self.frag(cpu))

    def verb(self, c: str, v: str) -> str:
        return self.join("Verb", self.frag(c), self.frag(v))

    def status(self, c: str, s: str) -> str:
        return self.join("Status", self.frag(c), self.frag(s))

    def ctrl_part(self, c: str, tag: str) -> str:
        """A controller's buffer types: `Cmd_Buffer`, `Status_Buffer`, `Args`, `Fields`."""
        return self.join(tag, self.frag(c))

    def verb_args(self, c: str, v: str) -> str:
        return self.join("Args", self.frag(c), self.frag(v))

    def buffer_member(self, c: str, tag: str) -> str:
        """`Cmd_0_<c>` / `Status_0_<c>` in the Buffers record."""
        return self.join(tag.capitalize(), self.frag(c))

    def member(self, name: str) -> str:
        """A record component, parameter, variant or Global Memory variable."""
        return self.frag(name)

    # ---- names local to a controller's package body --------------------------------

    def state(self, s: str) -> str:
        fixed = {"": "St_None", "new": "St_New", "done": "St_Done", "error": "St_Error"}
        return fixed[s] if s in fixed else self.join("S", self.frag(s))

    def rule(self, verb: str, label: str) -> str:
        return self.join("R", self.frag(verb), self.frag(label))

    def plan_fn(self, verb: str) -> str:
        return self.join("Plan", self.frag(verb))

    # ---- library units and files -----------------------------------------------------

    def package(self, kind: str) -> str:
        """`Types`, `Functions`, `Externs` of the design."""
        return self.join(self.unit, kind)

    def ctrl_package(self, c: str) -> str:
        return self.join(self.unit, "Ctrl", self.frag(c))

    def main_unit(self, cpu: str) -> str:
        return self.join(self.unit, "Main", self.frag(cpu))

    @staticmethod
    def file(unit: str, ext: str) -> str:
        """GNAT's default file name of a library unit."""
        return unit.lower() + ext
