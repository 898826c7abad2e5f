"""The targets' naming schemes: no two things of a design get one name (issue 13).

Three layers:

* properties of `rcsc.outputs.naming`, `backends/c/naming.py` and
  `backends/rust/naming.py` on random and hostile names (hypothesis): every
  kind of name is injective, the kinds that share a C or Rust scope never
  meet, nothing equals a reserved name, and lengths stay in their limits;
* the header lists of `backends/c/headers.py` still cover what the C
  compilers here define;
* designs whose every name is drawn from a pool of hostile names (separators,
  keywords, macros of the C headers, Rust's primitive types, the generated
  code's own names, names differing only in case, a 250-character name) are
  built in C (gcc, strict warnings) and Rust (cargo, clippy, rustfmt) and their
  traces equal `rcsc sim`'s.  tests/naming/rcs_runtime.rcs, which holds each
  collision that once went through unnoticed, is part of the conformance
  suite of both targets (tests/c_build.py).
"""

from __future__ import annotations

import random
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from c_build import Builds, cargo_build, compile_c, first_difference, generate, gprbuild, reference_trace, run_main
from rcsc.semantics.sema import RESERVED_NAMES
from rcsc.outputs import naming as nm
from rcsc.backends.c import headers
from rcsc.backends.c.naming import C_KEYWORDS, HEADER_NAMES, CNames
from rcsc.backends.rust.naming import RESERVED, RUST_KEYWORDS, RustNames
from rcsc.backends.ada.naming import ADA_KEYWORDS, FIXED as ADA_FIXED, AdaNames

C_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
ROOT = Path(__file__).resolve().parent.parent
# The names the C runtime defines (rcs_num.h, rcs_runtime.h, rcs_link.h).
RUNTIME_NAMES = set(re.findall(r"\b(?:rcs|RCS)_\w+", "".join((ROOT / "backends/c/runtime" / f).read_text() for f in ("rcs_num.h", "rcs_runtime.h", "rcs_link.h"))))

# Names chosen to collide: separators, the generated code's own words, keywords, macros.
HOSTILE = [
    "_", "__", "_x", "x_", "a__b", "A_B", "A", "B_C", "Ea", "Ea_B", "C", "Mode", "IDLE", "Mode_IDLE", "MAIN", "MAIN_PERIOD_NS",
    "PERIOD_NS", "TOP", "TOP_VERB_GO", "VERB", "STATUS", "GO", "GO_W", "W_R1", "R1", "TOP_cmd", "cmd_", "args", "fields",
    "buffers", "buffers_init", "gm", "io", "io_read", "externs", "init", "step", "H", "S", "ST", "ST_NEW", "RULE", "plan",
    "ctrl", "type", "main", "rcs", "rcs_runtime", "RCS_DONE", "EOF", "NULL", "INT32_MAX", "INT32", "int32_t", "stdin", "printf",
    "_Atomic", "_Generic", "_Bool", "int", "self", "Self", "u64", "usize", "str", "Value", "Buffers", "Gm", "None", "state",
    "cycle", "buf", "ext", "cse_1", "T", "T_Mode", "Mode_of", "status_TOP", "x", "Foo", "foo", "FOO", "L" + "o" * 248 + "ng",
]
NAMES = st.one_of(st.sampled_from(HOSTILE), st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,12}", fullmatch=True))


def _distinct(draw, n: int) -> list[str]:
    return draw(st.lists(NAMES, min_size=n, max_size=n, unique=True))


# ---- the core --------------------------------------------------------------------------------


@given(st.lists(NAMES, unique=True, max_size=30))
def test_fragments_are_injective_and_keep_the_shape(names: list[str]) -> None:
    reserved = {"VERB", "cmd", "int"}
    frags = [nm.fragment(x, lambda n: n in reserved) for x in names]
    assert len(set(frags)) == len(frags)
    for x, f in zip(names, frags):
        assert "__" not in f and not f.startswith("_"), (x, f)
        assert f not in reserved
        if nm.is_plain(x) and x not in reserved:
            assert f == x  # plain names are kept as written


@given(st.lists(st.lists(NAMES, min_size=1, max_size=3), unique_by=tuple, max_size=20))
def test_joined_fragments_split_back(parts_list: list[list[str]]) -> None:
    """`__` marks exactly the boundaries: joined fragments of different name lists differ."""
    joined = ["__".join(nm.fragment(x, lambda n: False) for x in parts) for parts in parts_list]
    assert len(set(joined)) == len(joined)


@given(st.lists(st.text(alphabet="ab_", min_size=1, max_size=90), unique=True, max_size=20), st.integers(20, 63))
def test_shortened_names_stay_apart_and_fit(names: list[str], limit: int) -> None:
    out = [nm.shorten(x, limit) for x in names]
    assert len(set(out)) == len(out)
    assert all(len(x) <= limit for x in out)


@given(st.lists(st.sampled_from(["Foo", "foo", "FOO", "bar", "Bar", "x"]), unique=True))
def test_file_stems_stay_apart_when_case_is_ignored(stems: list[str]) -> None:
    out = nm.casefold_unique(stems)
    assert len({v.casefold() for v in out.values()}) == len(stems)
    assert all(out[s] == s for s in stems if sum(t.casefold() == s.casefold() for t in stems) == 1)


# ---- C ------------------------------------------------------------------------------------------


@st.composite
def designs(draw):
    """A design's names: top-level names are one namespace; the rest are per scope."""
    top = _distinct(draw, 8)
    return {
        "design": draw(NAMES), "design_is_ctrl": draw(st.booleans()), "types": top[0:2], "consts": top[2:4], "fns": top[4:5], "ctrls": top[5:7], "cpus": top[7:8],
        "members": _distinct(draw, 3), "verbs": _distinct(draw, 3), "statuses": _distinct(draw, 2),
        "states": _distinct(draw, 3), "labels": _distinct(draw, 3), "fields": _distinct(draw, 4),
    }


def c_file_scope(n: CNames, d: dict) -> list[str]:
    """Every name a design puts at the file scope of a C translation unit (and the macros)."""
    out = [n.type(t) for t in d["types"]] + [n.const(k) for k in d["consts"]] + [n.function(f) for f in d["fns"]]
    out += [n.enum_member(t, x) for t in d["types"] for x in d["members"]]
    out += [n.period(c) for c in d["cpus"]]
    out += [n.fixed(*t) for t in (("gm",), ("buffers",), ("buffers_init",), ("io_read",), ("io_write",), ("H",), ("externs", "H"), ("io", "H"))]
    for c in d["ctrls"]:
        out.append(n.ctrl_type(c))
        out += [n.ctrl_part(c, tag) for tag in ("init", "step", "args", "cmd", "status", "fields", "state", "rule", "BUDGET_NS", "H")]
        out += [n.verb(c, v) for v in d["verbs"]] + [n.status(c, s) for s in d["statuses"]] + [n.verb_args(c, v) for v in d["verbs"]]
    return out


def c_file_local(n: CNames, d: dict) -> list[str]:
    """The names local to a controller's file and to the Main Program's."""
    out = [n.state(s) for s in ["", "new", "done", "error", *d["states"]]]
    out += [n.rule(v, x) for v in d["verbs"] for x in d["labels"]] + [n.plan_fn(v) for v in d["verbs"]]
    for t in d["types"]:
        out += [n.local("type", t), n.local("members", t), n.local("fields", t)]
    out += [n.local("const", k) for k in d["consts"]]
    for c in d["ctrls"]:
        out += [n.local(lead, c) for lead in ("ctrl", "step", "verbs", "status_fields", "states", "rules", "statuses")]
        out += [n.local("params", c, v) for v in d["verbs"]]
    return out + ["buf", "types", "consts", "gm_fields", "gm_from_env", "ctrls", "schedule", "design", "main", "io_read", "io_write", "state", "cse_1"]


@settings(max_examples=150, deadline=None)
@given(designs())
def test_c_names_never_meet(d: dict) -> None:
    n = CNames(d["design"], d["ctrls"], d["cpus"])
    scope = c_file_scope(n, d)
    local = c_file_local(n, d)
    everything = scope + local
    assert len(set(everything)) == len(everything), sorted(x for x in everything if everything.count(x) > 1)
    for x in everything:
        assert C_IDENT.match(x) and len(x) <= 63, x
        assert x not in HEADER_NAMES and x not in C_KEYWORDS, x
        assert not x.startswith("__") and not re.match(r"_[A-Z]", x), x
    # No name of the headers or the runtime is ever reached through the design's prefix.
    assert not any(h.startswith(n.p + "_") for h in HEADER_NAMES), n.p
    assert not any(r.startswith(n.p + "_") for r in RUNTIME_NAMES), n.p
    # Members and parameters: injective, and never a macro, a keyword or a design-wide name.
    members = [n.member(x) for x in d["fields"] + d["members"] + d["verbs"]]
    uniq = set(d["fields"] + d["members"] + d["verbs"])
    assert len(set(members)) == len(uniq)
    for x in members:
        assert C_IDENT.match(x) and len(x) <= 63, x
        assert x not in headers.MACROS and x not in headers.OTHERS and x not in C_KEYWORDS and x not in scope, x
        assert not x.startswith("__") and not re.match(r"_[A-Z]", x), x
    buffer_members = ["gm"] + [n.buffer_member(c, t) for c in d["ctrls"] for t in ("cmd", "status")]
    assert len(set(buffer_members)) == len(buffer_members)
    # File names: apart (also when case is ignored), short, never a runtime file's.
    files = [f"{n.p}.h", f"{n.p}.c", f"{n.p}_externs.h", f"{n.p}_externs.c", f"{n.p}_io.h", f"{n.p}_io.c", "rcs_num.h", "rcs_runtime.h", "rcs_runtime.c"]
    files += [f"{n.ctrl_stem(c)}{ext}" for c in d["ctrls"] for ext in (".h", ".c")] + [f"{n.main_stem(c)}.c" for c in d["cpus"]]
    assert len({f.casefold() for f in files}) == len(files), files
    assert all(len(f) < 130 for f in files)


def test_the_collisions_of_issue_13_are_gone() -> None:
    n = CNames("d", ["TOP", "externs"], ["MAIN"])
    assert n.const("Mode_IDLE") != n.enum_member("Mode", "IDLE")
    assert n.const("MAIN_PERIOD_NS") != n.period("MAIN")
    assert n.const("TOP_VERB_GO") != n.verb("TOP", "GO")
    assert n.enum_member("Ea", "B_C") != n.enum_member("Ea_B", "C")
    assert n.type("TOP_cmd") != n.ctrl_part("TOP", "cmd") and n.type("buffers") != n.fixed("buffers") and n.type("gm") != n.fixed("gm")
    assert n.function("TOP_step") != n.ctrl_part("TOP", "step")
    assert n.rule("GO", "W_R1") != n.rule("GO_W", "R1")
    assert n.ctrl_stem("externs") != f"{n.p}_externs"
    assert [n.member(x) for x in ("EOF", "NULL", "INT32_MAX", "RCS_DONE", "_Atomic", "_Generic", "int")] == [
        "EOF_", "NULL_", "INT32_MAX_", "RCS_DONE_", "_0_0Atomic", "_0_0Generic", "int_"]
    assert CNames("rcs").p == "rcs_" and CNames("rcs_runtime").p == "rcs_runtime_" and CNames("INT32").p == "INT32_"
    long = "L" + "o" * 248 + "ng"
    assert len(CNames(long).p) <= 24 and len(CNames("d", [long]).ctrl_stem(long)) <= 120
    r = RustNames("d", ["u64", "TOP"], ["TOP"], ["MAIN"])
    assert r.global_("u64") == "u64_" and r.global_("str") == "str_" and r.global_("_") == "_0_0"
    assert r.rule("GO", "W_R1") != r.rule("GO_W", "R1")


# ---- Rust ---------------------------------------------------------------------------------------


@settings(max_examples=150, deadline=None)
@given(designs())
def test_rust_names_never_meet(d: dict) -> None:
    top = d["types"] + d["consts"] + d["fns"] + d["ctrls"] + d["cpus"]
    design = d["ctrls"][0] if d["design_is_ctrl"] else d["design"]
    n = RustNames(design, top, d["ctrls"], d["cpus"], d["consts"] + d["fns"])
    # `types` and `functions` are imported with `*` into every module: one scope for
    # types and one for values, and the Main Program's own items beside them.
    types = [n.global_(t) for t in d["types"] + d["ctrls"]]
    for c in d["ctrls"]:
        types += [n.ctrl_part(c, t) for t in ("cmd", "status", "args", "fields")] + [n.verb_args(c, v) for v in d["verbs"]]
    values = [n.global_(x) for x in d["consts"] + d["fns"]] + [n.period(c) for c in d["cpus"]]
    for c in d["ctrls"]:
        values += [n.verb(c, v) for v in d["verbs"]] + [n.status(c, s) for s in d["statuses"]]
    main_items = [n.type_desc(t) for t in d["types"]] + [n.helper(t, k) for t in d["types"] for k in ("of", "value")]
    main_items += [n.ctrl_part(c, t) for c in d["ctrls"] for t in ("STATES", "RULES")] + [n.status_view(c) for c in d["ctrls"]]
    for group in (types, values + main_items):
        assert len(set(group)) == len(group), sorted(x for x in group if group.count(x) > 1)
    for x in types + values + main_items:
        assert re.match(r"[A-Za-z_][A-Za-z0-9_]*\Z", x) and x != "_" and len(x) <= 63, x
        assert x not in RESERVED or x in main_items, x
    # A parameter never meets a design-wide value (it would be a pattern) or a keyword.
    params = [n.param(x) for x in d["fields"]]
    assert len(set(params)) == len(params)
    assert not set(params) & (set(values) | RUST_KEYWORDS | {"_"})
    # Fields and variants: injective, never a keyword; controllers' associated items apart.
    members = [n.member(x) for x in d["fields"]]
    assert len(set(members)) == len(members) and not set(members) & (RUST_KEYWORDS | {"_"})
    assoc = [n.state(s) for s in ["", "new", "done", "error", *d["states"]]] + [n.rule(v, x) for v in d["verbs"] for x in d["labels"]]
    assoc += [n.plan_fn(v) for v in d["verbs"]] + ["BUDGET_NS", "new", "step", "default"]
    assert len(set(assoc)) == len(assoc)
    assert n.crate not in set(types) | set(values) | set(main_items) | RESERVED.names, n.crate
    modules = [n.module(c) for c in d["ctrls"]] + ["num", "types", "functions", "externs_impl"]
    assert len({x.casefold() for x in modules}) == len(modules)


# ---- Ada ----------------------------------------------------------------------------------------

ADA_IDENT = re.compile(r"[A-Za-z](?:_?[A-Za-z0-9])*\Z")


def _all_names(d: dict) -> list[str]:
    keys = ("types", "consts", "fns", "ctrls", "cpus", "members", "verbs", "statuses", "states", "labels", "fields")
    return [d["design"]] + [x for k in keys for x in d[k]]


@settings(max_examples=150, deadline=None)
@given(designs())
def test_ada_names_never_meet(d: dict) -> None:
    """Ada ignores case: every scope must stay apart under casefold, and every name be an Ada identifier."""
    n = AdaNames(d["design"], _all_names(d))
    scope = [n.type(t) for t in d["types"]] + [n.const(k) for k in d["consts"]] + [n.function(f) for f in d["fns"]]
    scope += [n.enum_member(t, x) for t in d["types"] for x in d["members"]] + [n.period(c) for c in d["cpus"]]
    for c in d["ctrls"]:
        scope += [n.ctrl_part(c, tag) for tag in ("Args", "Cmd_Buffer", "Fields", "Status_Buffer")]
        scope += [n.verb(c, v) for v in d["verbs"]] + [n.status(c, s) for s in d["statuses"]] + [n.verb_args(c, v) for v in d["verbs"]]
    scope += ["Buffers", "Gm_Record", "Gm_Stamps", "Buf", "Buf_Size"]
    body = [n.state(s) for s in ["", "new", "done", "error", *d["states"]]]
    body += [n.rule(v, x) for v in d["verbs"] for x in d["labels"]] + [n.plan_fn(v) for v in d["verbs"]]
    body += ["Init", "Step", "Plan", "Entry_Cycle", "Loc", "Sent", "Send", "State", "Cycle", "Budget_Ns"]
    units = [n.package(k) for k in ("Types", "Functions", "Externs")] + [n.ctrl_package(c) for c in d["ctrls"]]
    units += [n.main_unit(c) for c in d["cpus"]] + ["Rcs_Num"]
    keywords = {k.casefold() for k in ADA_KEYWORDS}
    for group in (scope, body, units):
        folded = [x.casefold() for x in group]
        assert len(set(folded)) == len(folded), sorted(x for x in group if folded.count(x.casefold()) > 1)
        for x in group:
            assert ADA_IDENT.match(x) and len(x) <= 120 and x.casefold() not in keywords, x
    # Components and parameters: apart under casefold, Ada identifiers, never a
    # design-wide name, a keyword or a name of Standard, Interfaces or the templates.
    uniq = sorted(set(d["fields"] + d["members"] + d["verbs"]))
    members = [n.member(x) for x in uniq]
    assert len({x.casefold() for x in members}) == len(uniq)
    fixed = {x.casefold() for x in ADA_FIXED} | keywords | {x.casefold() for x in scope + body}
    for x in members:
        assert ADA_IDENT.match(x) and len(x) <= 120 and x.casefold() not in fixed, x
    assert n.member("Foo") != n.member("foo") if {"Foo", "foo"} <= set(uniq) else True


def test_ada_names_of_the_hostile_list() -> None:
    n = AdaNames("d", ["Foo", "foo", "_", "a__b", "x_", "type", "Integer_32", "X0", "a_0"])
    assert n.member("Foo") == "X0466f6f" and n.member("foo") == "X0666f6f"
    assert [n.member(x) for x in ("_", "a__b", "x_", "type", "Integer_32", "a_0")] == [
        "X05f", "X0615f5f62", "X0785f", "X074797065", "X0496e74656765725f3332", "X0615f30"]
    assert n.member("X0") == "X05830" and n.member("MAX_RPM") == "MAX_RPM"
    assert n.enum_member("Ea_B", "C") == "M_0_Ea_B_0_C" != n.enum_member("Ea", "B_C")
    assert n.main_unit("MAIN") == "d_0_Main_0_MAIN"


# ---- the C headers -------------------------------------------------------------------------------


@pytest.mark.parametrize("cc", ["gcc", "clang"])
def test_header_lists_cover_the_compilers_here(cc: str) -> None:
    assert shutil.which(cc), f"{cc} is required"
    macros, functions, others = headers.collect(cc)
    assert macros <= headers.MACROS, sorted(macros - headers.MACROS)
    assert functions <= headers.FUNCTIONS | headers.MACROS, sorted(functions - headers.FUNCTIONS)
    assert others <= headers.OTHERS | headers.FUNCTIONS | headers.MACROS, sorted(others - headers.OTHERS)


# ---- designs made of hostile names, built and run ----------------------------------------------

# The design language's own words (a name cannot be one).
_LANGUAGE = set(re.findall(r'"([a-z_]+)"', (ROOT / "grammar/rcs.lark").read_text())) - {"gm"}
# ... nor a built-in name (types, functions, `cmd`, `cycle`, ...: the checker's one list).
_POOL = [x for x in HOSTILE if x not in _LANGUAGE and x not in RESERVED_NAMES]

TEMPLATE = """design {D}

enum {E} {{ {E1}, {E2} }}
record {R} {{ {F1}: i32, {F2}: i32 }}
const {K}: i32 = 3
const {K2}: i32 = 5
fn {FN}({P1}: i32, {P2}: i32) -> i32 = {P1} * 10 + {P2} + {K}
extern fn {X}({P3}: i32) -> i32 budget 1 us
gm {G1}: i32 = 0 from env
gm {G2}: {E} = {E}.{E1}
gm {G3}: {R} = {R}({F1} = 1, {F2} = 2)

controller {C1} level 2 budget 1 ms {{
    verb {V1}({VP}: i32)
    verb {V2}
    subordinates {C2}
    reads {G1}
    writes {G2}, {G3}
    reports {ST}
    status {SF}: i32 = 0
    local {LC}: i32 = 0
    pre {{
        {LC} = {FN}({G1}, {K2}) + {X}({G1});
        {G3}.{F1} = {LC} + {G3}.{F2};
        {G2} = if {G1} > 2 then {E}.{E2} else {E}.{E1};
    }}
    plan {V1} {{
        {L1}: cmd.{VP} > 0 | new -> {S1} | {SF} = cmd.{VP}, {C2}.{W1}();
        {L2}: {C2}.done | {S1} -> {S2} | report {ST};
        {L6}: {C2}.error | {S1} -> error({K2});
        {L3}: in_state >= 30 ms | {S2} -> done;
        {L4}: otherwise | {S2} -> {S2};
        {L5}: otherwise | new -> error({K});
    }}
    plan {V2} {{
        {L1}: true | new -> done;
    }}
}}

controller {C2} level 1 budget 1 ms {{
    verb {W1}
    reads {G2}, {G3}
    status {SF2}: {E} = {E}.{E1}
    status {SF3}: i32 = 0
    post {{
        {SF2} = {G2};
        {SF3} = {G3}.{F1};
    }}
    plan {W1} {{ {L1}: true | new -> done; }}
}}

cpu {CPU} {{
    heartbeat 10 ms
    schedule {C1}, {C2}
}}
"""
SCENARIO = """cycles 10
at 1: {G1} = 3
at 2: {C1}.{V1}({VP} = 4)
at 8: {C1}.{V2}()
"""
_SLOTS = sorted(set(re.findall(r"\{([A-Z][A-Z0-9]*)\}", TEMPLATE)))


LONG = "L" + "o" * 248 + "ng"
# Slots some seeds fill on purpose: the 250-character name as a controller, the design and a
# type; controllers and verbs that differ only in case; the design named like a runtime file.
OVERRIDES = {
    0: {"C2": LONG},
    1: {"D": LONG, "C1": "Foo", "C2": "foo"},
    2: {"E": LONG, "V1": "FOO", "V2": "foo", "D": "rcs"},
    3: {"CPU": LONG, "D": "rcs_runtime", "C2": "externs"},
}


def hostile_design(seed: int) -> tuple[str, str]:
    """A design and scenario whose every name comes from the hostile pool (no name twice)."""
    rng = random.Random(seed)
    fixed = OVERRIDES.get(seed, {})
    free = [x for x in _SLOTS if x not in fixed]
    names = dict(zip(free, rng.sample([x for x in _POOL if x not in fixed.values()], len(free)))) | fixed
    return TEMPLATE.format(**names), SCENARIO.format(**names)


def _write(tmp_path: Path, seed: int) -> tuple[Path, Path]:
    text, scn_text = hostile_design(seed)
    design, scn = tmp_path / f"hostile{seed}.rcs", tmp_path / f"hostile{seed}.scn"
    design.write_text(text, encoding="utf-8")
    scn.write_text(scn_text, encoding="utf-8")
    return design, scn


@pytest.mark.parametrize("seed", range(8))
def test_hostile_design_in_c_equals_the_simulator(seed: int, tmp_path: Path) -> None:
    design, scn = _write(tmp_path, seed)
    out = tmp_path / "c"
    generate(design, "c", out, "--deny-warnings")
    exe = tmp_path / "prog"
    compile_c(out, "gcc", ["-O0"], exe)
    trace = tmp_path / "trace.jsonl"
    proc = run_main(exe, design, scn, trace)
    assert proc.returncode == 0, proc.stderr
    expected = reference_trace(design, scn)
    assert trace.read_bytes() == expected, first_difference(expected, trace.read_bytes())


@pytest.mark.parametrize("seed", range(4))
def test_hostile_design_in_ada_equals_the_simulator(seed: int, tmp_path: Path) -> None:
    """Ada ignores case and takes no `_` at either end of a name: the names of
    the hostile designs (`Foo` beside `foo`, `_`, `a__b`, keywords) still build
    warning-free and run as in the simulator."""
    design, scn = _write(tmp_path, seed)
    out = tmp_path / "ada"
    generate(design, "ada", out, "--deny-warnings")
    exe = tmp_path / "prog"
    gprbuild(out, "-O0", exe)
    trace = tmp_path / "trace.jsonl"
    proc = run_main(exe, design, scn, trace)
    assert proc.returncode == 0, proc.stderr
    expected = reference_trace(design, scn)
    assert trace.read_bytes() == expected, first_difference(expected, trace.read_bytes())


@pytest.mark.parametrize("seed", range(4))
def test_hostile_design_in_rust_equals_the_simulator_and_is_lint_clean(seed: int, tmp_path: Path) -> None:
    design, scn = _write(tmp_path, seed)
    builds = Builds(tmp_path)
    crate = builds.source(design, "rust")
    exe = cargo_build(crate, "debug", builds.cargo_env(design))
    trace = tmp_path / "trace.jsonl"
    proc = run_main(exe, design, scn, trace)
    assert proc.returncode == 0, proc.stderr
    expected = reference_trace(design, scn)
    assert trace.read_bytes() == expected, first_difference(expected, trace.read_bytes())
    clippy = subprocess.run(["cargo", "clippy", "--offline", "--", "-D", "warnings"], cwd=crate, env=builds.cargo_env(design),
                            capture_output=True, text=True, stdin=subprocess.DEVNULL)
    assert clippy.returncode == 0, clippy.stderr[-3000:]
    files = sorted(str(p) for p in crate.rglob("*.rs") if "target" not in p.parts)
    fmt = subprocess.run(["rustfmt", "--check", "--edition", "2021", *files], capture_output=True, text=True)
    assert fmt.returncode == 0, fmt.stdout[-3000:]


NAMED_LIKE_ITS_CONTROLLER = """design TOP

enum _ { _, u64 }
gm _x: _ = _._
gm go: bool = false from env

controller TOP level 1 budget 1 ms {
    verb TOP
    reads go, _x
    writes _x
    status str: _ = _._
    post { str = _x; }
    plan TOP {
        _: go | new -> _ | _x = _.u64;
        x_: otherwise | _ -> done;
        y: otherwise | new -> error(1);
    }
}

cpu __ {
    heartbeat 10 ms
    schedule TOP
}
"""


def test_a_design_named_like_its_controller_with_underscore_names(tmp_path: Path) -> None:
    """The crate's name meets the glob-imported controller and `_` is a type, a member, a
    state and a rule, `__` a CPU; C and Rust run it as `rcsc sim` does."""
    design, scn = tmp_path / "top.rcs", tmp_path / "top.scn"
    design.write_text(NAMED_LIKE_ITS_CONTROLLER, encoding="utf-8")
    scn.write_text("cycles 4\nat 1: go = true\nat 1: TOP.TOP()\n", encoding="utf-8")
    expected = reference_trace(design, scn)
    builds = Builds(tmp_path)
    for exe in (builds.c_binary(design, "gcc-O0"), builds.rust_binary(design, "debug")):
        trace = tmp_path / "trace.jsonl"
        proc = run_main(exe, design, scn, trace)
        assert proc.returncode == 0, proc.stderr
        assert trace.read_bytes() == expected, first_difference(expected, trace.read_bytes())
    assert '"state":"done","rule":"x_"' in expected.decode().splitlines()[-1]


def test_a_member_named_like_a_design_wide_name_stays_apart() -> None:
    """Found by the property test: field `MAIN_PERIOD_NS` of design `MAIN` once
    became `MAIN_PERIOD_NS_`, the type of a controller named `PERIOD_NS`."""
    from rcsc.backends.c.naming import CNames

    n = CNames("MAIN", controllers=["PERIOD_NS"], cpus=["A"])
    assert n.member("MAIN_PERIOD_NS") != n.ctrl_type("PERIOD_NS")
    assert n.member("MAIN_PERIOD_NS").startswith("_0")


def test_c_buffer_members_are_identifiers() -> None:
    """A wrapped controller fragment starts with a digit; its buffer members may not."""
    from rcsc.backends.c.naming import CNames

    names = ["_x", "__", "x_", "C_very_long_name__" * 8, "A"]
    n = CNames("d", controllers=names, cpus=["A"])
    members = [n.buffer_member(c, t) for c in names for t in ("cmd", "status")]
    assert all(re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", m) for m in members), members
    assert len(set(members)) == len(members)


def test_a_compiled_test_run_builds_a_design_with_a_250_character_name(tmp_path: Path) -> None:
    """`rcsc test --target` builds in a folder named after the design: its
    name is cut there (a folder's name has at most 255 bytes; the digest of
    the build's files tells builds apart)."""
    from rcsc.driver import check_path
    from rcsc.sim import compiled

    name = "d" + "_very_long_design_name" * 11 + "_x" * 6  # 255 characters: a valid name, too long for a folder with a suffix
    text = (ROOT / "tests" / "mc" / "single.rcs").read_text(encoding="utf-8")
    text = re.sub(r"^design \w+", f"design {name}", text, count=1, flags=re.M)
    (tmp_path / "d.rcs").write_text(text, encoding="utf-8")
    result = check_path(str(tmp_path / "d.rcs"))
    assert result.model is not None and not result.diags.has_errors() and result.model.name == name
    built = compiled.build(result.model, "c", str(tmp_path / "build"))
    assert built.program.is_file() and len(built.folder.name) <= 255
