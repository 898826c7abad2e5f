"""Extern functions with effects for the differential tester, in Python, C, Rust and Ada.

The generated designs declare extern functions and call them anywhere an
expression may (bench/difftest_gen.py).  The stubs rcsc writes return zero
values, which would hide both the arguments passed and the order and number
of the calls.  This module writes, for a checked design, one implementation
of its externs per target, all computing the same thing: a journal.

Every call folds the function's number and each argument, field by field and
element by element, into a running number `s` kept from call to call, and
returns a value made from `s`.  So a call too many or too few, calls in
another order, an argument passed in the wrong place or converted wrongly
change every value after it, and the traces show it.

    mix(v):  s = (s * 31 + (v & 1023)) mod 1000003      (v a 64-bit integer)
    a bool is 1 or 0, an enum its member's index, an f64 1 if NaN, 2 above
    1e15, 3 below -1e15, else its integer part; records and arrays fold
    their fields and elements in order.
    returns: i32 s - 500000, i64 s * 1024 - 1, u32 s * 4000, bool s odd,
    f64 s / 8 - 1000, duration s * 1000 ns, an enum member s mod n; records
    and arrays the zero value.

The identifiers come from the targets' own naming (`CBackend`, `RustTarget`,
`AdaBackend`), so the files fit what `rcsc build` generates around them.
"""

from __future__ import annotations

from rcsc.semantics import model as m
from rcsc.semantics.evaluate import zero_value
from rcsc.semantics.types import BOOL, DURATION, ArrayType, EnumType, FloatType, IntType, RecordType, Type

MOD = 1000003


def externs_of(design: m.Design) -> list[m.Function]:
    return [f for f in design.functions.values() if f.extern]


def _journaled(t: Type) -> bool:
    """Whether a result of type `t` is made from the journal (else the zero value)."""
    return not isinstance(t, (RecordType, ArrayType))


# ---- Python (the reference simulator) ----------------------------------------------------


def python_externs(design: m.Design) -> dict:
    state = {"s": 0}

    def mix(v: int) -> None:
        state["s"] = (state["s"] * 31 + (v & 1023)) % MOD

    def fold(x, t: Type) -> None:
        if t == BOOL:
            mix(1 if x else 0)
        elif isinstance(t, EnumType):
            mix(t.members.index(x))
        elif isinstance(t, FloatType):
            mix(1 if x != x else 2 if x > 1e15 else 3 if x < -1e15 else int(x))
        elif isinstance(t, RecordType):
            for name, ft in t.fields:
                fold(x[name], ft)
        elif isinstance(t, ArrayType):
            for e in x:
                fold(e, t.elem)
        else:
            mix(int(x))

    def result(t: Type):
        s = state["s"]
        if t == BOOL:
            return s % 2 == 1
        if t == DURATION:
            return s * 1000
        if isinstance(t, EnumType):
            return t.members[s % len(t.members)]
        if isinstance(t, FloatType):
            return s / 8.0 - 1000.0
        if isinstance(t, IntType):
            return {"i32": s - 500000, "i64": s * 1024 - 1, "u32": s * 4000}[t.name]
        return zero_value(t)

    def make(k: int, f: m.Function):
        def call(*args):
            mix(k + 1)
            for a, q in zip(args, f.params):
                fold(a, q.type)
            return result(f.ret)

        return call

    return {f.name: make(k, f) for k, f in enumerate(externs_of(design))}


# ---- C -------------------------------------------------------------------------------------


def c_source(design: m.Design) -> tuple[str, str]:
    """The C target's `<prefix>_externs.c`: (file name, text)."""
    from rcsc.backends.c import CBackend

    tg = CBackend(design)
    lines = [f'#include "{tg.n.p}.h"', "", "static int64_t dt_journal = 0;", "",
             "static void dt_mix(int64_t v)", "{", "    dt_journal = (dt_journal * 31 + (v & 1023)) % 1000003;", "}", ""]

    def fold(x: str, t: Type, depth: int) -> list[str]:
        if t == BOOL:
            return [f"dt_mix({x} ? 1 : 0);"]
        if isinstance(t, FloatType):
            return [f"dt_mix({x} != {x} ? 1 : {x} > 1e15 ? 2 : {x} < -1e15 ? 3 : (int64_t){x});"]
        if isinstance(t, RecordType):
            return [line for name, ft in t.fields for line in fold(f"{x}.{tg.ident(name)}", ft, depth)]
        if isinstance(t, ArrayType):
            k = f"dt_k{depth}"
            inner = fold(f"{x}.v[{k}]", t.elem, depth + 1)
            return [f"for (int {k} = 0; {k} < {t.size}; {k}++) {{", *("    " + y for y in inner), "}"]
        return [f"dt_mix((int64_t){x});"]

    def result(t: Type) -> str:
        if t == BOOL:
            return "dt_journal % 2 == 1"
        if t == DURATION:
            return "dt_journal * 1000"
        if isinstance(t, EnumType):
            return f"({tg.ctype(t)})(dt_journal % {len(t.members)})"
        if isinstance(t, FloatType):
            return "(double)dt_journal / 8.0 - 1000.0"
        if isinstance(t, IntType):
            return {"i32": "(int32_t)(dt_journal - 500000)", "i64": "dt_journal * 1024 - 1", "u32": "(uint32_t)(dt_journal * 4000)"}[t.name]
        return tg.literal(zero_value(t), t)

    for k, f in enumerate(externs_of(design)):
        lines += [tg.prototype(f), "{", f"    dt_mix({k + 1});"]
        for q in f.params:
            lines += ["    " + y for y in fold(tg.ident(q.name), q.type, 0)]
        lines += [f"    return {result(f.ret)};", "}", ""]
    return f"{tg.n.p}_externs.c", "\n".join(lines)


# ---- Rust ----------------------------------------------------------------------------------


def rust_source(design: m.Design) -> str:
    """The Rust target's `src/externs_impl.rs`."""
    from rcsc.backends.rust import RustTarget

    tg = RustTarget(design)
    fns = externs_of(design)
    types = [t for f in fns for t in [f.ret] + [q.type for q in f.params]]

    def inner(t: Type) -> Type:
        while isinstance(t, ArrayType):
            t = t.elem
        return t

    def named(t: Type) -> bool:
        if isinstance(t, RecordType):
            return True
        return isinstance(inner(t), (EnumType, RecordType))

    lines = ["use crate::Externs;"]
    if any(isinstance(t, ArrayType) for t in types):
        lines.append("use crate::num;")
    if any(named(t) or isinstance(t, EnumType) for t in types):
        lines.append("use crate::types::*;")
    lines += ["use core::cell::Cell;", "", "#[derive(Debug, Default)]", "pub struct ExternsImpl {", "    journal: Cell<i64>,", "}", "",
              "impl ExternsImpl {", "    fn mix(&self, v: i64) {", "        self.journal.set((self.journal.get() * 31 + (v & 1023)) % 1000003);",
              "    }", "}", "", "impl Externs for ExternsImpl {"]

    def fold(x: str, t: Type, depth: int) -> list[str]:
        if t == BOOL:
            return [f"self.mix(i64::from({x}));"]
        if isinstance(t, EnumType):
            return [f"self.mix({x} as i64);"]
        if isinstance(t, FloatType):
            return [f"self.mix(if {x}.is_nan() {{ 1 }} else if {x} > 1e15 {{ 2 }} else if {x} < -1e15 {{ 3 }} else {{ {x} as i64 }});"]
        if isinstance(t, RecordType):
            return [line for name, ft in t.fields for line in fold(f"{x}.{tg.ident(name)}", ft, depth)]
        if isinstance(t, ArrayType):
            e = f"dt_e{depth}"
            body = fold(e, t.elem, depth + 1)
            return [f"for {e} in {x}.0 {{", *("    " + y for y in body), "}"]
        if t == DURATION or t.name == "i64":
            return [f"self.mix({x});"]
        return [f"self.mix(i64::from({x}));"]

    def result(t: Type) -> str:
        if t == BOOL:
            return "s % 2 == 1"
        if t == DURATION:
            return "s * 1000"
        if isinstance(t, EnumType):
            arms = " ".join(f"{i} => {tg.rtype(t)}::{tg.ident(x)}," for i, x in enumerate(t.members[:-1]))
            return f"match s % {len(t.members)} {{ {arms} _ => {tg.rtype(t)}::{tg.ident(t.members[-1])} }}"
        if isinstance(t, FloatType):
            return "s as f64 / 8.0 - 1000.0"
        if isinstance(t, IntType):
            return {"i32": "(s - 500000) as i32", "i64": "s * 1024 - 1", "u32": "(s * 4000) as u32"}[t.name]
        return str(tg.literal(zero_value(t), t))

    for k, f in enumerate(fns):
        params = ", ".join(["&self"] + [f"{tg.param(q.name)}: {tg.rtype(q.type)}" for q in f.params])
        lines += ["", f"    fn {tg.ident(f.name)}({params}) -> {tg.rtype(f.ret)} {{", f"        self.mix({k + 1});"]
        for q in f.params:
            lines += ["        " + y for y in fold(tg.param(q.name), q.type, 0)]
        if _journaled(f.ret) and not (isinstance(f.ret, EnumType) and len(f.ret.members) == 1):
            lines += ["        let s = self.journal.get();", f"        {result(f.ret)}", "    }"]
        elif isinstance(f.ret, EnumType):
            lines += [f"        {tg.rtype(f.ret)}::{tg.ident(f.ret.members[0])}", "    }"]
        else:
            lines += [f"        {result(f.ret)}", "    }"]
    lines += ["}", ""]
    return "\n".join(lines)


# ---- Ada -----------------------------------------------------------------------------------


def ada_source(design: m.Design) -> tuple[str, str]:
    """The Ada target's body of the externs package: (file name, text)."""
    from rcsc.backends.ada import AdaBackend

    tg = AdaBackend(design)
    pkg = tg.n.package("Externs")
    lines = [f"package body {pkg} is", "", "   Dt_Journal : Integer_64 := 0;", "",
             "   procedure Dt_Mix (V : Integer_64) is", "   begin",
             "      Dt_Journal := (Dt_Journal * 31 + Integer_64 (Unsigned_64'Mod (V) and 1023)) mod 1000003;", "   end Dt_Mix;"]

    def fold(x: str, t: Type, depth: int) -> list[str]:
        if t == BOOL:
            return [f"Dt_Mix ((if {x} then 1 else 0));"]
        if isinstance(t, FloatType):
            return [f"Dt_Mix ((if {x} /= {x} then 1 elsif {x} > 1.0E+15 then 2 elsif {x} < -1.0E+15 then 3 "
                    f"else Integer_64 (F64'Truncation ({x}))));"]
        if isinstance(t, RecordType):
            return [line for name, ft in t.fields for line in fold(f"{x}.{tg.n.member(name)}", ft, depth)]
        if isinstance(t, ArrayType):
            e = f"Dt_E{depth}"
            body = fold(e, t.elem, depth + 1)
            return [f"for {e} of {x} loop", *("   " + y for y in body), "end loop;"]
        if t == DURATION or t.name == "i64":
            return [f"Dt_Mix ({x});"]  # already an Integer_64 (GNAT warns of a redundant conversion)
        return [f"Dt_Mix (Integer_64 ({x}));"]

    def result(t: Type) -> str:
        if t == BOOL:
            return "Dt_Journal mod 2 = 1"
        if t == DURATION:
            return "Dt_Journal * 1000"
        if isinstance(t, EnumType):
            return f"{tg.atype(t)} (Dt_Journal mod {len(t.members)})"
        if isinstance(t, FloatType):
            return "F64 (Dt_Journal) / 8.0 - 1000.0"
        if isinstance(t, IntType):
            return {"i32": "Integer_32 (Dt_Journal - 500000)", "i64": "Dt_Journal * 1024 - 1",
                    "u32": "Unsigned_32 (Dt_Journal * 4000)"}[t.name]
        return tg.literal(zero_value(t), t)

    for k, f in enumerate(externs_of(design)):
        spec = tg.function(f)
        lines += ["", f"   {spec['spec']} is", "   begin", f"      Dt_Mix ({k + 1});"]
        for q in f.params:
            lines += ["      " + y for y in fold(tg.n.member(q.name), q.type, 0)]
        lines += [f"      return {result(f.ret)};", f"   end {spec['name']};"]
    lines += ["", f"end {pkg};", ""]
    return tg.n.file(pkg, ".adb"), "\n".join(lines)
