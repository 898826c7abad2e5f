"""Shared helpers of the backend tests: generate a design's code, compile it, run it.

Builds are cached per (target, design, configuration) for the whole test
session, so each example is generated and compiled once per configuration
however many scenarios run on it.  The reference traces (`rcsc sim`) are
cached per scenario.  C is compiled with gcc/clang (`C_CONFIGS`), Rust with
cargo (`RUST_PROFILES`, one CARGO_TARGET_DIR per crate so that cargo reuses
its work between the profiles and between the tests).
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import subprocess
import time
import tomllib
from pathlib import Path

from rcsc import cli
from rcsc.driver import check_path
from rcsc.sim.runner import run_scenario
from rcsc.front.scenario import text_to_scenario
from rcsc.front.source import SourceFile
from rcsc.sim.trace import run_to_jsonl

ROOT = Path(__file__).resolve().parent.parent

STRICT = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wshadow", "-Werror", "-ffp-contract=off"]
SANITIZE = ["-fsanitize=undefined,address", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer", "-g"]

# name -> (compiler, flags)
C_CONFIGS = {
    "gcc-O0": ("gcc", ["-O0"]),
    "gcc-O2": ("gcc", ["-O2"]),
    "clang-O2": ("clang", ["-O2"]),
    "gcc-O1-asan-ubsan": ("gcc", ["-O1", *SANITIZE]),
    "clang-O1-asan-ubsan": ("clang", ["-O1", *SANITIZE]),
}


# Ada (GNAT, gprbuild): the generated project builds with -gnatwa -gnatwe -gnata -gnato; RCS_OPT sets -O.
ADA_OPTS = ("-O0", "-O2")


def gprbuild(src: Path, opt: str, exe: Path) -> None:
    """`gprbuild -P rcs_build.gpr -XRCS_OPT=OPT` in a generated Ada folder (asserts no error and no
    warning: the project makes every warning an error); copies its single Main Program to `exe`."""
    proc = subprocess.run(["gprbuild", "-q", "-P", "rcs_build.gpr", f"-XRCS_OPT={opt}"], cwd=src, capture_output=True, text=True)
    assert proc.returncode == 0, f"gprbuild {opt} failed on {src}:\n{proc.stdout[-3000:]}{proc.stderr[-3000:]}"
    assert "warning" not in proc.stdout + proc.stderr, proc.stdout + proc.stderr
    (main,) = re.findall(r'for Executable \("[^"]+"\) use "([^"]+)";', (src / "rcs_build.gpr").read_text(encoding="utf-8"))
    exe.write_bytes((src / main).read_bytes())
    exe.chmod(0o755)


# Both with overflow-checks = true (the generated Cargo.toml sets it in every profile).
RUST_PROFILES = ("debug", "release")


def cpu_count(design: Path) -> int:
    """How many CPUs a design declares (its `cpu NAME {` lines)."""
    return len(re.findall(r"^cpu\s+\w+\s*\{", design.read_text(encoding="utf-8"), re.M))


# The designs with a `scenarios/` folder beside them: the examples, and the
# designs written from the docs alone, as a new user would (tests/designs).
DESIGN_GLOBS = ("examples/*/*.rcs", "tests/designs/*/*.rcs")


def example_designs() -> list[Path]:
    return sorted(p for g in DESIGN_GLOBS for p in ROOT.glob(g))


def multi_cpu_examples() -> list[tuple[Path, Path]]:
    """(design, scenario) for every example scenario of a design with several CPUs:
    tests/test_multicpu_targets.py runs them (one process per CPU, the launcher)."""
    return [(d, s) for d in example_designs() if cpu_count(d) > 1 for s in sorted((d.parent / "scenarios").glob("*.scn"))]


def _examples() -> list[tuple[Path, Path]]:
    """(design, scenario) for every example scenario of a single-CPU design and the simulator's test designs
    (the multi-CPU examples: `multi_cpu_examples`)."""
    pairs = []
    for design in example_designs():
        if cpu_count(design) > 1:
            continue  # one program per CPU: tests/test_multicpu_targets.py
        for scn in sorted((design.parent / "scenarios").glob("*.scn")):
            pairs.append((design, scn))
    pairs.append((ROOT / "tests/sim/ahead_paper.rcs", ROOT / "tests/sim/ahead_branches.scn"))
    pairs.append((ROOT / "tests/sim/numeric.rcs", ROOT / "tests/sim/numeric_edges.scn"))
    # Every numeric type and conversion, records everywhere, target-language
    # keywords as names, names long enough to force line breaks.
    pairs.append((ROOT / "tests/stress/stress.rcs", ROOT / "tests/stress/stress.scn"))
    # Literals the target language would type by inference, design comments
    # quoted in the rule comments, records and controllers with nothing in them.
    pairs.append((ROOT / "tests/edge/edge.rcs", ROOT / "tests/edge/edge.scn"))
    # Nothing optional: no Global Memory, types, constants or functions.
    pairs.append((ROOT / "tests/bare/bare.rcs", ROOT / "tests/bare/bare.scn"))
    # The math built-ins and `cycle` at their edges (signed zeros, NaN, infinities, halves).
    pairs.append((ROOT / "tests/mathfn/mathfn.rcs", ROOT / "tests/mathfn/mathfn.scn"))
    # Arrays in every position, indices out of range (docs/language.md §4).
    pairs.append((ROOT / "tests/arrays/arrays.rcs", ROOT / "tests/arrays/arrays.scn"))
    # Arrays only as Global Memory outputs (the Rust Main Program's imports).
    pairs.append((ROOT / "tests/arrays/outputs_only.rcs", ROOT / "tests/arrays/outputs_only.scn"))
    # Names that the naming schemes must keep apart (tests/test_naming.py).
    pairs.append((ROOT / "tests/naming/rcs_runtime.rcs", ROOT / "tests/naming/scenarios.scn"))
    # Every block of std.blocks; a controller type with two instances.
    pairs.append((ROOT / "tests/blocks/blocks.rcs", ROOT / "tests/blocks/blocks.scn"))
    # Array arguments of types and blocks written as literals; negative zeros.
    pairs.append((ROOT / "tests/params/array_params.rcs", ROOT / "tests/params/array_params.scn"))
    # `gm` parameters bound to record fields, written and read, and `age(...)` of one.
    pairs.append((ROOT / "tests/bindings/bindings.rcs", ROOT / "tests/bindings/bindings.scn"))
    return pairs


CONFORMANCE = _examples()


def case_id(pair: tuple[Path, Path]) -> str:
    return f"{pair[0].stem}/{pair[1].stem}"


_REFERENCE: dict[Path, bytes] = {}


def reference_trace(design: Path, scn: Path) -> bytes:
    """The JSON-lines trace of `rcsc sim DESIGN --scenario SCN`."""
    if scn not in _REFERENCE:
        result = check_path(str(design))
        assert result.ok and result.model is not None, f"{design} does not check clean"
        sc = text_to_scenario(SourceFile(str(scn), scn.read_text(encoding="utf-8")), result.model, result.diags)
        assert sc is not None, f"{scn} does not load"
        run = run_scenario(result.model, sc)
        _REFERENCE[scn] = run_to_jsonl(result.model, run).encode("utf-8")
    return _REFERENCE[scn]


def generate(design: Path, target: str, out: Path, *extra: str) -> str:
    """`rcsc build DESIGN --target T -o OUT`; returns its stderr (asserts exit 0)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = cli.main(["build", str(design), "--target", target, "-o", str(out), *extra])
    assert rc == 0, f"rcsc build failed ({rc}):\n{err.getvalue()}"
    return err.getvalue()


def compile_c(src: Path, cc: str, flags: list[str], exe: Path) -> None:
    sources = sorted(str(p) for p in src.glob("*.c"))
    proc = subprocess.run([cc, *STRICT, *flags, "-o", str(exe), *sources], capture_output=True, text=True)
    assert proc.returncode == 0, f"{cc} {' '.join(flags)} failed on {src}:\n{proc.stderr}"
    assert proc.stderr == "", f"{cc} printed warnings:\n{proc.stderr}"


def cargo_build(crate: Path, profile: str, env: dict) -> Path:
    """`cargo build --offline` of a generated crate (asserts no error and no warning);
    returns the Main Program of its (single) CPU."""
    cmd = ["cargo", "build", "--offline", *(["--release"] if profile == "release" else [])]
    proc = subprocess.run(cmd, cwd=crate, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, f"cargo build ({profile}) failed on {crate}:\n{proc.stderr[-4000:]}"
    assert not re.search(r"^warning", proc.stderr, re.M), f"cargo build ({profile}) warned:\n{proc.stderr[-4000:]}"
    bins = tomllib.loads((crate / "Cargo.toml").read_text(encoding="utf-8"))["bin"]
    assert len(bins) == 1, "one Main Program per CPU; the conformance designs have one CPU"
    return Path(env["CARGO_TARGET_DIR"]) / profile / bins[0]["name"]


class Builds:
    """Session cache of generated and compiled designs."""

    def __init__(self, base: Path) -> None:
        self.base = base
        self.sources: dict[tuple[str, Path], Path] = {}
        self.binaries: dict[tuple[Path, str], Path] = {}

    def source(self, design: Path, target: str = "c") -> Path:
        key = (target, design)
        if key not in self.sources:
            out = self.base / f"{target}-{design.stem}"
            generate(design, target, out)
            self.sources[key] = out
        return self.sources[key]

    def c_binary(self, design: Path, config: str) -> Path:
        key = (design, config)
        if key not in self.binaries:
            cc, flags = C_CONFIGS[config]
            src = self.source(design, "c")
            exe = self.base / f"c-{design.stem}-{config}.bin"
            compile_c(src, cc, flags, exe)
            self.binaries[key] = exe
        return self.binaries[key]

    def ada_binary(self, design: Path, opt: str) -> Path:
        key = (design, f"ada{opt}")
        if key not in self.binaries:
            exe = self.base / f"ada-{design.stem}{opt}.bin"
            gprbuild(self.source(design, "ada"), opt, exe)
            self.binaries[key] = exe
        return self.binaries[key]

    def cargo_env(self, design: Path) -> dict:
        """The environment of cargo for a design's crate: its own target folder."""
        return dict(os.environ, CARGO_TARGET_DIR=str(self.base / f"cargo-{design.stem}"), CARGO_TERM_COLOR="never")

    def rust_binary(self, design: Path, profile: str) -> Path:
        key = (design, f"rust-{profile}")
        if key not in self.binaries:
            self.binaries[key] = cargo_build(self.source(design, "rust"), profile, self.cargo_env(design))
        return self.binaries[key]


_EVENTS: dict[tuple[Path, Path, bool], Path] = {}


def event_file(design: Path, scn: Path, exclude_simulators: bool = False) -> Path:
    """`rcsc events DESIGN SCN`: the event file the compiled Main Programs read (cached per session)."""
    key = (design, scn, exclude_simulators)
    if key not in _EVENTS:
        import tempfile

        out = Path(tempfile.mkdtemp(prefix="rcsc-events-")) / (scn.stem + ".events")
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            rc = cli.main(["events", str(design), str(scn), "-o", str(out), *(["--exclude-simulators"] if exclude_simulators else [])])
        assert rc == 0, f"rcsc events failed ({rc}):\n{err.getvalue()}"
        _EVENTS[key] = out
    return _EVENTS[key]


def run_main(exe: Path, design: Path, scn: Path, trace: Path, *extra: str, timeout: float = 300) -> subprocess.CompletedProcess:
    """The Main Program `exe` on scenario `scn` of `design` (compiled to its event file first)."""
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1:abort_on_error=0", UBSAN_OPTIONS="print_stacktrace=1")
    events = event_file(design, scn)
    return subprocess.run(
        [str(exe), "--fast", "--no-console", "--no-timing", "--scenario", str(events), "--trace", str(trace), *extra],
        capture_output=True, text=True, timeout=timeout, env=env, stdin=subprocess.DEVNULL,
    )


class Console:
    """A Main Program on a pseudo-terminal, for the keyboard tests (Appendix B's pause and single step)."""

    def __init__(self, argv: list[str]) -> None:
        import pty

        self.pid, self.fd = pty.fork()
        if self.pid == 0:  # the child: the Main Program on the pty
            os.execv(argv[0], argv)
        self.out = b""  # everything read so far

    def read_for(self, seconds: float) -> bytes:
        """What the program prints within `seconds` (also added to `out`)."""
        import select

        end = time.monotonic() + seconds
        got = b""
        while time.monotonic() < end:
            ready, _, _ = select.select([self.fd], [], [], 0.05)
            if ready:
                try:
                    got += os.read(self.fd, 4096)
                except OSError:
                    break
        self.out += got
        return got

    def key(self, k: bytes) -> None:
        os.write(self.fd, k)

    def wait(self) -> int:
        """The exit status (os.waitpid's); the pty stays open until close()."""
        return os.waitpid(self.pid, 0)[1]

    def close(self) -> None:
        os.close(self.fd)


def first_difference(a: bytes, b: bytes) -> str:
    la, lb = a.decode().splitlines(), b.decode().splitlines()
    for i, (x, y) in enumerate(zip(la, lb), 1):
        if x != y:
            return f"line {i} differs:\n  sim:      {x}\n  compiled: {y}"
    return f"lengths differ: sim {len(la)} lines, compiled {len(lb)} lines"

