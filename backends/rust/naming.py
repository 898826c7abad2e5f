"""Every name in the generated Rust: one function per kind of name, built on `rcsc.outputs.naming`.

The crate's design-wide items live in `types` and `functions`, which the
controllers and the Main Program import with `*`; a name defined in a module
silently hides one imported that way, and a constant in scope turns a `let`
or a parameter of the same name into a pattern.  So, as in C
(docs/backends.md, "Names"):

* design-wide names are the design's names as fragments joined by `__`, with
  fixed words (*tags*) where the kind needs them: `ShipDir` (a type),
  `MAX_RPM` (a constant), `PR__VERB__AHEAD`, `PR__cmd`, `MAIN__PERIOD_NS`;
  a fragment that starts with a digit (the wrapped form of a name such as
  `_`) gets a leading `_`;
* the Main Program's own items join a tag and fragments the same way
  (`T__ShipDir`, `PR__STATES`, `status__PR`, `ShipDir__of`);
* a controller's associated items start with a fixed lead and `_`
  (`S_IDLE`, `RULE_AHEAD__E0`, `plan_AHEAD`), its module is `ctrl_` and its
  fragment;
* fields, enum variants, extern methods and parameters keep the design's name
  unless the language or the scope takes it: then a trailing `_` (`type_`),
  and a name that is not plain gets the wrapped form with a leading `_`
  (`_0_0` for `_`); a parameter named like a design-wide value or that is
  not plain becomes `p_`, its wrapped form and `_` (`p_0K_`, `p_0_0_` for `_`);
  a keyword gets a trailing `_`.

Every name a fragment could meet is reserved (keywords, primitive types such
as `u64` and `str`, the prelude, the runtime's and the Main Program's own
names, the locals of generated functions).  Identifiers and file names are
cut at 63 characters; file names that differ only in case get a
hash.
"""

from __future__ import annotations

from rcsc.outputs import naming as nm

RUST_KEYWORDS = frozenset(
    "as break const continue crate else enum extern false fn for if impl in let loop match mod move mut pub ref "
    "return self Self static struct super trait true type unsafe use where while async await dyn abstract become "
    "box do final macro override priv typeof unsized virtual yield try gen union macro_rules raw safe".split()
)
PRIMITIVES = frozenset("bool char str u8 u16 u32 u64 u128 usize i8 i16 i32 i64 i128 isize f16 f32 f64 f128".split())
PRELUDE = frozenset(
    "Option Some None Result Ok Err Vec String Box Default Clone Copy Debug PartialEq Eq PartialOrd Ord Hash Send "
    "Sync Sized Unpin Drop Fn FnMut FnOnce Iterator IntoIterator DoubleEndedIterator ExactSizeIterator Extend "
    "FromIterator From Into TryFrom TryInto AsRef AsMut ToOwned ToString drop core std alloc test proc_macro".split()
)
# The names the generated crate and its runtime define or use beside the design's.
FIXED = frozenset(
    # types.rs, lib.rs, the controllers, num.rs
    "Buffers Gm GmStamps gm_stamp CrossingDesc MultiDesc CROSSINGS MULTI crossing set_crossing set_gm_stamp record launch multi shm "
    "StatusHead CommandHead Sent Sending Locals Externs ExternsImpl NoExterns Io Cell INIT "
    "sub_done sub_error sub_executing sub_status num types functions externs_impl io host "
    # the Main Program and host/
    "Main Value Kind TypeDesc FieldDesc VerbDesc ConstDesc GmDesc CtrlDesc DesignDesc StatusView HostDesign "
    "TYPES CONSTS GM CTRLS DESIGN name index main status_none field_desc const_desc gm_desc verb_desc run "
    # parameters and locals of generated functions
    "state verb cycle ext buf head sent ty from_env params names number gm ctrl value c f i r s v x".split()
)
# The values a parameter of a pure or extern function could meet: `types::*` and the prelude.
PARAM_FIXED = frozenset("sub_done sub_error sub_executing sub_status Some None Ok Err".split())
# Fixed words inside joined names.
TAGS = frozenset("VERB STATUS PERIOD_NS cmd status args fields STATES RULES of value ARRAY Arr".split())
RESERVED = nm.Reserved(RUST_KEYWORDS | PRIMITIVES | PRELUDE | FIXED | TAGS, [r"cse_\d+\Z"])
# Short enough that a template line holding a name and a type stays within rustfmt's
# 100 columns; a module is also a file name.
IDENT_LIMIT = 63
FILE_LIMIT = 63


def _start(ident: str) -> str:
    """A name may not start with a digit: a wrapped fragment first gets `_`."""
    return "_" + ident if ident[:1].isdigit() else ident


class RustNames:
    """The names of one design's Rust crate."""

    def __init__(self, design: str, top_level: list[str] = (), controllers: list[str] = (), cpus: list[str] = (),  # type: ignore[assignment]
                 values: list[str] = ()) -> None:  # type: ignore[assignment]
        """`top_level`: every design-wide name; `values`: the constants and functions among them."""
        # The crate is named in `use` paths beside the glob-imported design names: it
        # keeps the design's name unless that is a design-wide name too (or wrapped).
        # `d___` (a run of three, which only a reserved fragment and a join make) is no
        # other name.
        crate = self.frag(design)
        self.crate = nm.shorten("d___" + crate if crate[0].isdigit() or design in top_level else crate, 40)
        # Parameters must not meet a value in scope (a constant would make them a pattern).
        self._param_reserved = nm.Reserved(set(values) | PARAM_FIXED)
        self._member_reserved = nm.Reserved(RUST_KEYWORDS | {"_"})
        stems = {("ctrl", c): "ctrl_" + self.frag(c) for c in controllers}
        stems.update({("cpu", c): self.frag(c) for c in cpus})
        stems = {k: nm.shorten(v, FILE_LIMIT) for k, v in stems.items()}
        unique = nm.casefold_unique(stems.values())
        self._stems = {k: unique[v] for k, v in stems.items()}

    @staticmethod
    def frag(name: str) -> str:
        return nm.fragment(name, lambda n: n in RESERVED)

    def join(self, *parts: str) -> str:
        """Fragments and tags joined by `__`."""
        return nm.shorten(_start(nm.SEP.join(parts)), IDENT_LIMIT)

    # ---- design-wide names ----------------------------------------------------------------

    def global_(self, name: str) -> str:
        """A type, constant, function or controller struct."""
        return self.join(self.frag(name))

    def ctrl_part(self, ctrl: str, tag: str) -> str:
        """`cmd`, `status`, `args`, `fields` (types), `STATES`, `RULES` (the Main Program's tables)."""
        assert tag in TAGS, tag
        return self.join(self.frag(ctrl), tag)

    def verb(self, ctrl: str, verb: str) -> str:
        return self.join(self.frag(ctrl), "VERB", self.frag(verb))

    def status(self, ctrl: str, status: str) -> str:
        return self.join(self.frag(ctrl), "STATUS", self.frag(status))

    def verb_args(self, ctrl: str, verb: str) -> str:
        return self.join(self.frag(ctrl), self.frag(verb), "args")

    def period(self, cpu: str) -> str:
        return self.join(self.frag(cpu), "PERIOD_NS")

    def buffer_member(self, ctrl: str, tag: str) -> str:
        """The fields of `Buffers`: `gm`, and `<C>__cmd`, `<C>__status` per controller."""
        return self.join(self.frag(ctrl), tag)

    # ---- the Main Program's items ------------------------------------------------------------

    def type_desc(self, type_name: str) -> str:
        return self.join("T", self.frag(type_name))

    def status_view(self, ctrl: str) -> str:
        return self.join("status", self.frag(ctrl))

    def array_key(self, t) -> str:
        """An array type as a name part: `ARRAY__<element>__<length>` (ARRAY is a tag)."""
        elem = getattr(t, "elem", None)
        if elem is not None:
            return nm.SEP.join(("ARRAY", self.array_key(elem), str(t.size)))
        return t.name if t.name in ("bool", "i32", "i64", "u32", "f64", "duration") else self.frag(t.name)

    def helper(self, type_name: str, tag: str, builtin: bool = False) -> str:
        """`<T>__of` (a `Value` to the type) and `<T>__value` (the type to a `Value`).
        A built-in type keeps its name: no design name can be one."""
        assert tag in ("of", "value")
        return self.join(type_name if builtin else self.frag(type_name), tag)

    # ---- a controller's items --------------------------------------------------------------

    def module(self, ctrl: str) -> str:
        return self._stems[("ctrl", ctrl)]

    def bin_stem(self, cpu: str) -> str:
        return self._stems[("cpu", cpu)]

    def binary(self, cpu: str) -> str:
        return nm.shorten(f"{self.crate}_{self.frag(cpu)}", FILE_LIMIT)

    def state(self, name: str) -> str:
        fixed = {"": "ST_NONE", "new": "ST_NEW", "done": "ST_DONE", "error": "ST_ERROR"}
        return fixed[name] if name in fixed else nm.shorten("S_" + self.frag(name), IDENT_LIMIT)

    def rule(self, verb: str, label: str) -> str:
        return nm.shorten(f"RULE_{self.frag(verb)}{nm.SEP}{self.frag(label)}", IDENT_LIMIT)

    def plan_fn(self, verb: str) -> str:
        return nm.shorten("plan_" + self.frag(verb), IDENT_LIMIT)

    # ---- fields, variants, methods, parameters -------------------------------------------------

    def _escape(self, name: str, reserved: nm.Reserved) -> str:
        if not nm.is_plain(name):
            return nm.shorten("_" + nm.wrap(name), IDENT_LIMIT)
        return nm.shorten(name + "_" if name in reserved else name, IDENT_LIMIT)

    def member(self, name: str) -> str:
        """A struct field, an enum variant or an extern method."""
        return self._escape(name, self._member_reserved)

    def main_member(self, ctrl: str) -> str:
        """The field of `Main` that holds a controller (beside `buf`, `ext` and `io`)."""
        return self._escape(ctrl, nm.Reserved(RUST_KEYWORDS | {"buf", "ext", "io"}))

    def param(self, name: str) -> str:
        """A parameter of a function: a keyword gets a trailing `_`; `p_`, the wrapped form and
        `_` when it is not plain or a value in scope has its name.  No other name has that shape
        (a plain name does not end with `_`, no reserved name starts with `p_`, a joined name
        has `__`; `kw_` is a value's name only when the value is named `kw`, which is then
        wrapped), and it has a letter (clippy rejects a binding of only underscores and digits)."""
        if not nm.is_plain(name) or name in self._param_reserved:
            return nm.shorten("p_" + nm.wrap(name) + "_", IDENT_LIMIT)
        if name in RUST_KEYWORDS:
            return nm.shorten(name + "_", IDENT_LIMIT)
        return nm.shorten(name, IDENT_LIMIT)
