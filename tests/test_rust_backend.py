"""The Rust target: conformance with the reference simulator, strictness, ownership of files.

Conformance (issue 5): for every example scenario and the simulator's test
designs (c_build.CONFORMANCE), plus tests/rust_stress (every numeric type and
conversion, records everywhere, Rust keywords as names, names long enough to
make rustfmt break lines), the JSON-lines trace of the crate's Main Program
equals `rcsc sim`'s byte for byte, built by cargo in debug and in release
(overflow checks on in both); in release it also equals the C Main Program's.
The crates build without a warning, `cargo clippy -- -D warnings` is clean
(the library denies indexing, panics and unwrap itself), every .rs file is
exactly as `rustfmt --edition 2021` writes it, and the output is reproducible.
"""

from __future__ import annotations

import random
import re
import subprocess
import tomllib
from pathlib import Path

import pytest

from c_build import CONFORMANCE, ROOT, RUST_PROFILES, Builds, case_id, cargo_build, first_difference, generate, reference_trace, run_main

SUBMARINE = ROOT / "examples/submarine/submarine.rcs"
CELL = ROOT / "examples/machining_cell/machining_cell.rcs"
STRESS = ROOT / "tests/stress/stress.rcs"
EDGE = ROOT / "tests/edge/edge.rcs"
BARE = ROOT / "tests/bare/bare.rcs"
HOSTILE_NAMES = ROOT / "tests/naming/rcs_runtime.rcs"
MATHFN = ROOT / "tests/mathfn/mathfn.rcs"  # the math built-ins, `cycle`, doc comments in comments
PAIRS = CONFORMANCE
ARRAYS = ROOT / "tests/arrays/arrays.rcs"
PATH_FOLLOW = ROOT / "examples/path_follow/path_follow.rcs"
CRATES = [SUBMARINE, CELL, STRESS, EDGE, BARE, HOSTILE_NAMES, MATHFN, ARRAYS, PATH_FOLLOW]



@pytest.fixture(scope="session")
def builds(tmp_path_factory) -> Builds:
    return Builds(tmp_path_factory.mktemp("builds"))


def _run(exe: Path, design: Path, scn: Path, tmp_path: Path) -> bytes:
    trace = tmp_path / "trace.jsonl"
    proc = run_main(exe, design, scn, trace)
    assert proc.returncode == 0, f"exit {proc.returncode}:\n{proc.stderr[-3000:]}"
    assert proc.stderr == "", f"the program printed diagnostics:\n{proc.stderr[-3000:]}"
    return trace.read_bytes()


@pytest.mark.parametrize("profile", RUST_PROFILES)
@pytest.mark.parametrize("pair", PAIRS, ids=[case_id(p) for p in PAIRS])
def test_trace_equals_simulator(builds: Builds, pair, profile: str, tmp_path: Path) -> None:
    design, scn = pair
    got = _run(builds.rust_binary(design, profile), design, scn, tmp_path)
    expected = reference_trace(design, scn)
    assert got == expected, first_difference(expected, got)


@pytest.mark.parametrize("pair", CONFORMANCE, ids=[case_id(p) for p in CONFORMANCE])
def test_trace_equals_c_main_program(builds: Builds, pair, tmp_path: Path) -> None:
    design, scn = pair
    rust = _run(builds.rust_binary(design, "release"), design, scn, tmp_path)
    c = _run(builds.c_binary(design, "gcc-O2"), design, scn, tmp_path)
    assert rust == c, first_difference(c, rust)


@pytest.mark.parametrize("design", CRATES, ids=lambda p: p.stem)
def test_clippy_is_clean(builds: Builds, design: Path) -> None:
    builds.rust_binary(design, "debug")  # built and free of warnings
    crate = builds.source(design, "rust")
    proc = subprocess.run(
        ["cargo", "clippy", "--offline", "--all-targets", "--", "-D", "warnings"],
        cwd=crate, env=builds.cargo_env(design), capture_output=True, text=True,
    )
    assert proc.returncode == 0, proc.stderr[-6000:]
    assert not re.search(r"^(warning|error)", proc.stderr, re.M), proc.stderr[-6000:]


@pytest.mark.parametrize("design", CRATES, ids=lambda p: p.stem)
def test_rustfmt_is_clean(builds: Builds, design: Path) -> None:
    crate = builds.source(design, "rust")
    files = sorted(str(p) for p in crate.rglob("*.rs") if "target" not in p.parts)
    proc = subprocess.run(["rustfmt", "--check", "--edition", "2021", *files], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-6000:] + proc.stderr[-2000:]


def test_library_is_no_std_safe_and_strict(builds: Builds) -> None:
    crate = builds.source(CELL, "rust")
    lib = (crate / "src/lib.rs").read_text(encoding="utf-8")
    for attr in ("#![no_std]", "#![forbid(unsafe_code)]", "#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used)]"):
        assert attr in lib, attr
    assert "pub trait Externs" in lib
    for p in (crate / "src").glob("*.rs"):
        text = p.read_text(encoding="utf-8")
        assert not re.search(r"\bunsafe\s*(\{|fn\b|impl\b)", text), p.name
        # Integer arithmetic of the design wraps explicitly; nothing may index.
        assert not re.search(r"\w\[\w", text), f"{p.name} indexes"
    toml = tomllib.loads((crate / "Cargo.toml").read_text(encoding="utf-8"))
    assert toml["package"]["name"] == "machining_cell" and toml["package"]["edition"] == "2021"
    assert toml["profile"]["dev"]["overflow-checks"] is True and toml["profile"]["release"]["overflow-checks"] is True
    assert toml["bin"] == [{"name": "machining_cell_CELL", "path": "src/bin/CELL.rs"}]
    assert toml.get("dependencies", {}) == {}


def test_output_is_reproducible(tmp_path: Path) -> None:
    a, b = tmp_path / "a", tmp_path / "b"
    generate(CELL, "rust", a)
    generate(CELL, "rust", b)
    names = sorted(str(p.relative_to(a)) for p in a.rglob("*") if p.is_file())
    assert names == sorted(str(p.relative_to(b)) for p in b.rglob("*") if p.is_file())
    for n in names:
        assert (a / n).read_bytes() == (b / n).read_bytes(), n
    # A second build into the same folder changes nothing.
    note = generate(CELL, "rust", a)
    assert re.search(r"wrote 0 files, \d+ unchanged, kept 1 of yours", note), note


def test_every_generated_file_has_the_banner_except_the_users(tmp_path: Path) -> None:
    generate(SUBMARINE, "rust", tmp_path, "--exclude-simulators")
    generate(CELL, "rust", tmp_path / "cell")
    for p in list(tmp_path.rglob("*")):
        if not p.is_file():
            continue
        first = p.read_text(encoding="utf-8").split("\n", 1)[0]
        if p.name in ("externs_impl.rs", "io.rs"):
            assert "generated by rcsc - do not edit" not in p.read_text(encoding="utf-8").lower()
            assert "this file is yours" in p.read_text(encoding="utf-8")
        else:
            assert first.startswith(("// generated by rcsc - do not edit", "# generated by rcsc - do not edit")), p


def test_externs_impl_is_written_only_when_missing(tmp_path: Path) -> None:
    generate(CELL, "rust", tmp_path)
    stub = tmp_path / "src/externs_impl.rs"
    assert stub.is_file()
    mine = stub.read_text(encoding="utf-8").replace("        0.0\n", "        1.0 // mine\n", 1)
    stub.write_text(mine, encoding="utf-8")
    note = generate(CELL, "rust", tmp_path)
    assert stub.read_text(encoding="utf-8") == mine
    assert "kept 1 of yours (src/externs_impl.rs)" in note
    stub.unlink()
    generate(CELL, "rust", tmp_path)
    assert "this file is yours" in stub.read_text(encoding="utf-8")


def test_build_refuses_to_replace_a_file_a_person_wrote(tmp_path: Path, capsys) -> None:
    from rcsc import cli

    mine = tmp_path / "src/ctrl_PR.rs"
    mine.parent.mkdir()
    mine.write_text("// my own PR controller\n", encoding="utf-8")
    rc = cli.main(["build", str(SUBMARINE), "--target", "rust", "-o", str(tmp_path)])
    assert rc == 2
    assert "src/ctrl_PR.rs: it was not generated by rcsc" in capsys.readouterr().err
    assert mine.read_text(encoding="utf-8") == "// my own PR controller\n"
    assert [p.name for p in tmp_path.rglob("*") if p.is_file()] == ["ctrl_PR.rs"], "nothing else may be written"


def test_more_than_64_cpus_are_refused(tmp_path: Path, capsys) -> None:
    from rcsc import cli

    design = ROOT / "tests/cases/E0800_several_cpus/main.rcs"
    rc = cli.main(["build", str(design), "--target", "rust", "-o", str(tmp_path / "out")])
    assert rc == 1
    err = capsys.readouterr().err
    assert "error[E0800]" in err and "the rust target builds designs of at most 64 CPUs; this design has 65" in err
    assert not (tmp_path / "out").exists()


def test_deployment_build_leaves_out_the_simulators(builds: Builds, tmp_path: Path) -> None:
    out = tmp_path / "deploy"
    generate(SUBMARINE, "rust", out, "--exclude-simulators")
    names = {p.name for p in (out / "src").iterdir()}
    assert "ctrl_TURBINE_SIM.rs" not in names and "ctrl_SHIP_SIM.rs" not in names
    assert {"io.rs", "ctrl_PR.rs"} <= names
    main = (out / "src/bin/MAIN.rs").read_text(encoding="utf-8")
    assert "TURBINE_SIM" not in main and "self.io.read(&mut self.buf.gm)" in main
    io = (out / "src/io.rs").read_text(encoding="utf-8")
    (out / "src/io.rs").write_text(io + "// mine\n", encoding="utf-8")
    assert "kept 1 of yours (src/io.rs)" in generate(SUBMARINE, "rust", out, "--exclude-simulators")
    # Its own target folder: its binary has the name of the full build's.
    exe = cargo_build(out, "debug", dict(builds.cargo_env(SUBMARINE), CARGO_TARGET_DIR=str(builds.base / "cargo-deploy")))
    proc = subprocess.run([str(exe), "--fast", "--no-console", "--no-timing", "--cycles", "5", "--trace", "-"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert len(lines) == 5 and '"TURBINE_SIM"' not in lines[0]


def test_timing_table_lists_every_scheduled_controller(builds: Builds) -> None:
    exe = builds.rust_binary(SUBMARINE, "release")
    proc = subprocess.run([str(exe), "--fast", "--no-console", "--cycles", "50"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    for name in ("TURBINE_SIM", "SHIP_SIM", "SM", "PR", "TB"):
        assert any(line.split()[:1] == [name] for line in proc.stderr.splitlines()), proc.stderr


MINIMAL = """design minimal

controller ONLY level 1 budget 1 ms {
    verb GO
    plan GO {
        G0: true | new -> done;
    }
}

cpu MAIN {
    heartbeat 10 ms
    schedule ONLY
}
"""


def test_a_minimal_design_builds_clean(builds: Builds, tmp_path: Path) -> None:
    """No Global Memory, constants, types, functions or externs: nothing generated is unused."""
    design = tmp_path / "minimal.rcs"
    design.write_text(MINIMAL, encoding="utf-8")
    (tmp_path / "go.scn").write_text("cycles 3\nat 2: ONLY.GO()\n", encoding="utf-8")
    crate = tmp_path / "out"
    generate(design, "rust", crate)
    files = sorted(str(p) for p in crate.rglob("*.rs"))
    assert subprocess.run(["rustfmt", "--check", "--edition", "2021", *files], capture_output=True).returncode == 0
    env = builds.cargo_env(design)
    exe = cargo_build(crate, "debug", env)
    proc = subprocess.run(["cargo", "clippy", "--offline", "--all-targets", "--", "-D", "warnings"], cwd=crate, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-4000:]
    assert _run(exe, design, tmp_path / "go.scn", tmp_path) == reference_trace(design, tmp_path / "go.scn")


def test_abs_of_u32_imports_nothing(tmp_path: Path) -> None:
    """`abs(x)` of a u32 is `x`: a function module that needs nothing else does not import `num`."""
    design = tmp_path / "absu.rcs"
    design.write_text(MINIMAL + "\nfn keep(x: u32) -> u32 = abs(x)\n", encoding="utf-8")
    generate(design, "rust", tmp_path / "out")
    functions = (tmp_path / "out/src/functions.rs").read_text(encoding="utf-8")
    assert "pub fn keep(x: u32) -> u32" in functions
    assert "use crate::num;" not in functions


def test_controller_works_in_the_buffers_with_the_shared_rule_layout(tmp_path: Path) -> None:
    """As the C target: the command, the subordinates' status, Global Memory and the
    own status are read and written in place (no copies in the controller), commands
    are written into the subordinate's buffer and made new by the serial at the write
    phase, `plan == 0` is idle, and the plans follow rcsc.outputs.backend.plan_layout."""
    generate(SUBMARINE, "rust", tmp_path)
    pr = (tmp_path / "src/ctrl_PR.rs").read_text(encoding="utf-8")
    struct = pr[pr.index("pub struct PR {"):pr.index("impl PR {")]
    assert re.findall(r"pub (\w+):", struct) == ["sent", "send", "loc", "plan", "entry_cycle", "steps"]
    for copy in ("self.cmd", "self.status", "self.sub", "self.gm", "self.out", "self.idle"):
        assert copy not in pr, copy
    ahead = pr[pr.index("fn plan_AHEAD("):pr.index("fn plan_ASTERN(")]
    assert "let state = buf.PR__status.head.state;" in ahead
    # E2..E4 share `state == S1` and `TB.done`, tested once, and their speed_status(...) call.
    assert ahead.count("if state == Self::S_S1 {") == 1
    assert ahead.count("sub_done(&buf.TB__status.head, self.sent.TB)") == 2  # the S1 group and E5
    code = "\n".join(ln for ln in ahead.splitlines() if not ln.lstrip().startswith("//"))
    assert code.count("speed_status(") == 1 and "let cse_1 = speed_status(" in code
    assert [ln.strip() for ln in ahead.splitlines() if "cse_1 ==" in ln] == [
        "if cse_1 == SpeedStatus::BELOW {", "if cse_1 == SpeedStatus::AT {", "if cse_1 == SpeedStatus::ABOVE {"]
    # No EXEC store that the rule overwrites (E9 ends in error, E3 reports AT_GOAL).
    for label, stores_exec in (("E0", True), ("E9", False), ("E3", False), ("E5", True)):
        rule = ahead[ahead.index(f"// {label} "):]
        rule = rule[:rule.index("Self::RULE_AHEAD__")]
        assert ("buf.PR__status.head.status = num::EXEC;" in rule) == stores_exec, label
    assert "buf.TB__cmd.head.verb = TB__VERB__AHEAD;" in ahead and "buf.TB__cmd.args.AHEAD.rpm = self.loc.prop_rpm;" in ahead
    assert ahead.count("self.plan = 0;") == 1  # E9, the only rule that ends the plan
    step = pr[pr.index("pub fn step("):]
    assert "buf.TB__cmd.head.serial = self.sent.TB;" in step and "buf.PR__status = " not in step and "buf.TB__cmd = " not in step
    assert "match self.plan {" in step and "_ => {}" in step


# Every shape of rcsc.outputs.backend.plan_layout: groups by state and by a shared leading
# condition, hoisted calls (cse_1) in a group that returns and in one that ends the
# plan, a rule that always fires inside a group (C2) and at the end of the plan
# (the `*` rule S2), reports, done and error.
LAYOUTS = """design layouts

fn twice(x: i32) -> i32 = x * 2
fn band(x: i32) -> i32 = if x < 0 then 0 else if x < 10 then 1 else 2

const LIMIT: i32 = 20

gm margin: i32 = 100 from env

controller TOP level 2 budget 1 ms {
    verb RUN(n: i32)
    verb SPIN
    subordinates LOW
    reports HIGH

    status count: i32 = 0
    local spins: i32 = 0

    plan RUN ordered {
        R0: cmd.n > 0 | new -> COUNT | count = 0, LOW.GO(k = cmd.n);
        R1: true | new -> error(1);
        R9: LOW.error | * -> error(2);
        C0: band(count) == 1 and twice(count) < 6 | COUNT -> COUNT | count += 1;
        C1: band(count) == 1 and twice(count) < 12 | COUNT -> COUNT | count += 2, report HIGH;
        C2: true | COUNT -> WAIT | LOW.GO(k = count);
        W0: LOW.done and twice(count) > LIMIT | WAIT -> done;
        W1: LOW.done and twice(count) <= LIMIT | WAIT -> COUNT | count += 5;
    }

    plan SPIN ordered {
        S0: true | new -> SPINNING | spins = 0;
        S1: spins >= 5 | SPINNING -> done;
        S2: true | * -> SPINNING | spins += 1;
    }
}

controller LOW level 1 budget 1 ms {
    verb GO(k: i32)
    reads margin
    local left: i32 = 0

    plan GO {
        G0: true | new -> RUNNING | left = cmd.k;
        G1: left <= 0 | RUNNING -> done;
        G2: left > margin | RUNNING -> error(5);
        G3: otherwise | RUNNING -> RUNNING | left -= 1;
    }
}

cpu MAIN {
    heartbeat 10 ms
    schedule TOP, LOW
}
"""

LAYOUTS_SCENARIO = """scenario "layouts"
cycles 90
at 2: TOP.RUN(n = 3)
at 45: TOP.SPIN()
at 55: TOP.RUN(n = 0)
at 60: TOP.RUN(n = 200)
"""


def test_rule_layouts_build_clean_and_conform(builds: Builds, tmp_path: Path) -> None:
    design, scn = tmp_path / "layouts.rcs", tmp_path / "layouts.scn"
    design.write_text(LAYOUTS, encoding="utf-8")
    scn.write_text(LAYOUTS_SCENARIO, encoding="utf-8")
    crate = builds.source(design, "rust")
    top = (crate / "src/ctrl_TOP.rs").read_text(encoding="utf-8")
    assert top.count("let cse_1 = twice(buf.TOP__status.f.count);") == 2
    # The plan's last rule has no `return;` (clippy::needless_return); clippy below also
    # rejects code after a rule that always fires (unreachable code).
    for fn in ("plan_RUN", "plan_SPIN"):
        body = top[top.index(f"fn {fn}("):]
        body = body[:body.index("\n    }\n")]
        assert not body.rstrip("} \n").endswith("return;"), fn
    files = sorted(str(p) for p in crate.rglob("*.rs") if "target" not in p.parts)
    proc = subprocess.run(["rustfmt", "--check", "--edition", "2021", *files], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-6000:]
    env = builds.cargo_env(design)
    proc = subprocess.run(["cargo", "clippy", "--offline", "--all-targets", "--", "-D", "warnings"], cwd=crate, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-4000:]
    expected = reference_trace(design, scn)
    for profile in RUST_PROFILES:
        got = _run(builds.rust_binary(design, profile), design, scn, tmp_path)
        assert got == expected, first_difference(expected, got)
    c = _run(builds.c_binary(design, "gcc-O2"), design, scn, tmp_path)
    assert c == expected, first_difference(expected, c)


def test_targets_lists_every_target(capsys) -> None:
    from rcsc import cli

    assert cli.main(["targets"]) == 0
    names = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert names == ["ada", "c", "rust"]


# ---- the layout engine against rustfmt itself ----------------------------------------------


def test_layout_equals_rustfmt_on_random_statements(tmp_path: Path) -> None:
    """fmt.py is a port of rustfmt's rules for the shapes the target emits: lay out
    random expressions in every statement form and compare with rustfmt."""
    from rcsc.backends.rust import fmt as f

    names = ["x", "DT", "self.loc.prop_rpm", "buf.PR_cmd.args.AHEAD.speed", "MAX_AHEAD_RPM", "ShipDir::AHEAD",
             "num::EXEC", "self.loc.a_rather_long_local_variable_name", "f64::NAN", "1.0", "-2.5", "10", "1e-05",
             "buf.WORKER_status.f.reached_position_in_millimetres_along_the_track", "cse_1"]
    fns = ["clamp", "num::fabs", "i32::wrapping_add", "speed_status", "ramp_toward", "Externs::path_length",
           "a_function_with_a_long_name"]
    ops = ["+", "-", "*", "/", "==", "<", ">=", "&&", "||"]

    def expr(r: random.Random, depth: int) -> f.Node:
        k = r.random()
        if depth <= 0 or k < 0.25:
            return f.Atom(r.choice(names))
        if k < 0.5:
            return f.Call(r.choice(fns), [expr(r, depth - 1) for _ in range(r.choice([0, 1, 2, 3, 4]))])
        if k < 0.8:
            return f.Bin.make(r.choice(ops), expr(r, depth - 1), expr(r, depth - 1))
        if k < 0.85:
            return f.Unary.make(r.choice(["-", "!"]), expr(r, depth - 1))
        if k < 0.9:
            return f.Cast.make(expr(r, depth - 1), "f64")
        if k < 0.95:
            return f.If(expr(r, depth - 1), expr(r, depth - 1), expr(r, depth - 1))
        return f.FieldOf(f.Call(r.choice(fns), [expr(r, depth - 1)]), "position")

    r = random.Random(5)
    chunks = []
    for i in range(150):
        indent = r.choice([1, 2, 3, 4])
        e = expr(r, r.choice([2, 3, 4, 5]))
        kind = i % 4
        if kind == 0:
            body = f.assign("buf.TB_cmd.args.AHEAD.rpm", "=", e, indent)
        elif kind == 1:
            body = f.if_open(e, indent) + [f.pad(indent + 1) + "return;", f.pad(indent) + "}"]
        elif kind == 2:
            body = f.tail(e, indent)
        else:
            body = f.arm("MACHINE_VERB_MOVE", e, indent + 1)
            body = [f.pad(indent) + "match v {"] + body + [f.pad(indent + 1) + "_ => {}", f.pad(indent) + "}"]
        opened = [f.pad(j) + "if c {" for j in range(1, indent)]
        closed = [f.pad(j) + "}" for j in range(indent - 1, 0, -1)]
        chunks.append("\n".join([f"fn f{i}() {{"] + opened + body + closed + ["}"]) + "\n")
    src = "\n".join(chunks)
    proc = subprocess.run(["rustfmt", "--edition", "2021", "--emit", "stdout", "-q"], input=src, capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.fail(f"rustfmt rejected the input:\n{proc.stderr[-2000:]}")
    got = proc.stdout.split("\nfn f")
    want = src.split("\nfn f")
    for g, w in zip(got, want):
        assert g == w, f"rustfmt lays out\nfn f{w}\nas\nfn f{g}"
    assert len(got) == len(want)


def test_the_runtime_is_copied_in(tmp_path: Path) -> None:
    generate(SUBMARINE, "rust", tmp_path)
    runtime = ROOT / "backends/rust/runtime"
    assert sorted(p.name for p in (tmp_path / "host").iterdir()) == sorted(p.name for p in (runtime / "host").iterdir() if p.suffix == ".rs")
    for copy, original in [(tmp_path / "src/num.rs", runtime / "num.rs")] + [(p, runtime / "host" / p.name) for p in (tmp_path / "host").iterdir()]:
        # Unchanged but for the banner line, which the copy carries in the exact form write_files looks for.
        assert copy.read_text(encoding="utf-8").split("\n")[1:] == original.read_text(encoding="utf-8").split("\n")[1:], copy.name


def test_a_comparison_after_a_cast_inside_a_sum_is_parenthesised() -> None:
    """`a + b as f64 < c` makes rustc read `f64<` as generic arguments."""
    from rcsc.backends.rust.fmt import Atom, Bin, Cast

    e = Bin.make("<", Bin.make("+", Atom("a"), Cast.make(Atom("b"), "f64")), Atom("c"))
    assert e.flat() == "(a + b as f64) < c"
    assert Bin.make("<", Cast.make(Atom("b"), "f64"), Atom("c")).flat() == "(b as f64) < c"
    assert Bin.make("<", Bin.make("+", Cast.make(Atom("b"), "f64"), Atom("a")), Atom("c")).flat() == "b as f64 + a < c"
