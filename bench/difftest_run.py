"""The harness of the differential tester: one generated case through every build, traces compared.

For a batch of `Case`s (bench/difftest_gen.py) it runs the reference
simulator in process, builds the C target with gcc -O0, gcc -O2, clang -O2
and clang with AddressSanitizer and UndefinedBehaviorSanitizer (the
project's strict warning flags; the runtime files, the same bytes for every
design, are compiled once per configuration and run and linked in), and the Rust
target as one cargo workspace for the whole batch (debug, release and
`cargo clippy -- -D warnings`, one shared target folder), the Ada target
with gprbuild at -O0 and -O2 (-gnatwa -gnatwe -gnata -gnato), runs every Main
Program on the case's scenario and compares its trace with the simulator's
byte for byte.  Every difference, every compiler or clippy message, every
exit code other than 0 and every line a program prints on stderr (a sanitizer
report) is a `Finding`.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import re
import subprocess
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from difftest_externs import ada_source, c_source, externs_of, python_externs, rust_source
from difftest_gen import Case, solver_cache

STRICT = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wshadow", "-Werror", "-ffp-contract=off"]
C_CONFIGS = {
    "gcc-O0": ("gcc", ["-O0"]),
    "gcc-O2": ("gcc", ["-O2"]),
    "clang-O2": ("clang", ["-O2"]),
    "clang-asan-ubsan": ("clang", ["-O1", "-g", "-fsanitize=address,undefined", "-fno-sanitize-recover=all",
                                   "-fno-omit-frame-pointer"]),
}
RUST_CONFIGS = ("rust-debug", "rust-release")
# The Ada target: the generated GNAT project (-gnatwa -gnatwe -gnata -gnato) at two levels.
ADA_CONFIGS = {"ada-O0": "-O0", "ada-O2": "-O2"}
# Cargo's own note that the members' [profile] tables are not read in a
# workspace: the workspace root carries the same tables (checked below).
_PROFILE_NOTE = re.compile(r"^warning: profiles for the non root package will be ignored.*\n(^(package|workspace):.*\n)*", re.M)


_INFRA = re.compile(r"failed to run `rustc` to learn about target-specific information")


@dataclass
class Finding:
    seed: int
    kind: str  # "disagree", "warning", "fail", "crash", "invalid"
    where: str  # the build configuration (or "rcsc")
    detail: str

    def line(self) -> str:
        first = self.detail.strip().splitlines()[0] if self.detail.strip() else ""
        return f"seed {self.seed}: {self.kind} in {self.where}: {first[:200]}"


@dataclass
class Prepared:
    case: Case
    folder: Path
    design: Path
    scenario: Path
    events: Path | None = None  # the scenario compiled for the Main Programs (`rcsc events`)
    reference: bytes = b""
    findings: list[Finding] = field(default_factory=list)
    model: object = None  # the checked design (rcsc.semantics.model.Design)


def _rcsc(argv: list[str]) -> tuple[int, str]:
    from rcsc import cli

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = cli.main(argv)
    return rc, err.getvalue()


def prepare(case: Case, base: Path) -> Prepared:
    """Write the case, check it and run the reference simulator."""
    from rcsc.diagnostics import Diagnostics
    from rcsc.driver import check_path
    from rcsc.sim.runner import run_scenario
    from rcsc.front.scenario import text_to_scenario
    from rcsc.front.source import SourceFile
    from rcsc.sim.trace import run_to_jsonl

    folder = base / case.name
    folder.mkdir(parents=True, exist_ok=True)
    design = folder / f"{case.name}.rcs"
    design.write_text(case.design, encoding="utf-8")
    scn = folder / f"{case.name}.scn"
    scn.write_text(case.scenario, encoding="utf-8")
    p = Prepared(case, folder, design, scn)
    # The builds below (`rcsc build`, which checks first) read the solver
    # results of the design's `.rcsc-cache/`: it is the run's shared folder.
    link = folder / ".rcsc-cache"
    if not link.exists():
        link.symlink_to(solver_cache(), target_is_directory=True)
    result = check_path(str(design), cache_dir=str(link))
    if not result.ok or result.model is None:
        p.findings.append(Finding(case.seed, "invalid", "rcsc", "\n".join(d.message for d in result.diags.errors)))
        return p
    diags = Diagnostics()
    sc = text_to_scenario(SourceFile(str(scn), case.scenario), result.model, diags)
    if sc is None or diags.has_errors():
        p.findings.append(Finding(case.seed, "invalid", "rcsc", "\n".join(d.message for d in diags.errors)))
        return p
    from rcsc.outputs.backend import BuildOptions, built_controllers
    from rcsc.outputs.events import event_text

    p.events = folder / f"{case.name}.events"
    p.events.write_text(event_text(result.model, sc, built_controllers(result.model, BuildOptions())), encoding="utf-8")
    try:
        # The externs keep a journal of their calls (bench/difftest_externs.py):
        # each target gets the same implementation, written before `rcsc build`.
        p.model = result.model
        model = result.model
        run = run_scenario(model, sc, externs=lambda: python_externs(model))  # one journal per CPU
        p.reference = run_to_jsonl(result.model, run).encode("utf-8")
    except Exception as exc:  # a crash of the simulator is a finding, not the end of the run
        p.findings.append(Finding(case.seed, "crash", "rcsc sim", f"{type(exc).__name__}: {exc}"))
        return p
    p.findings += observed_from_trace(case.seed, model, sc, run, p.reference)
    return p


def observed_from_trace(seed: int, model, sc, run, trace: bytes) -> list[Finding]:
    """`rcsc test --target T` evaluates expectations on what it rebuilds
    from the program's trace (rcsc.sim.compiled); the simulator on what it
    observed.  The compiled traces equal the simulator's (compared below),
    so rebuilding from the simulator's own trace must give, tick by tick,
    what the simulator observed: Global Memory, every status, every field,
    negative zeros and NaNs included (several CPUs: each buffer as its
    writer's latest released cycle left it)."""
    from rcsc.sim import compiled

    try:
        rebuilt = compiled.snapshots(model, sc, compiled.read_trace(trace.decode("utf-8")), run.multi_cpu)
    except Exception as exc:  # an unreadable trace is a finding too
        return [Finding(seed, "crash", "rcsc test --target (trace)", f"{type(exc).__name__}: {exc}")]
    for want, got in zip(run.snapshots, rebuilt):
        a, b = _observed(want), _observed(got)
        if a != b:
            diff = next((f"{k}: sim {a.get(k)!r}, from the trace {b.get(k)!r}" for k in sorted(a.keys() | b.keys())
                         if a.get(k) != b.get(k)))
            return [Finding(seed, "disagree", "rcsc test --target (what expectations see)", f"tick {want.cycle}: {diff}")]
    if len(run.snapshots) != len(rebuilt):
        return [Finding(seed, "disagree", "rcsc test --target (what expectations see)",
                        f"{len(run.snapshots)} ticks observed, {len(rebuilt)} rebuilt")]
    # The scenario's `expect` lines: each must find on the rebuilt snapshots
    # what it found in the simulator (held or not, the cycle, the values read).
    from rcsc.sim.runner import evaluate_expectations

    try:
        found = evaluate_expectations(model, [want.expect for want in run.results], rebuilt)
    except Exception as exc:
        return [Finding(seed, "crash", "rcsc test --target (expectations)", f"{type(exc).__name__}: {exc}")]
    for want, got in zip(run.results, found):
        if (want.passed, want.cycle, want.values) != (got.passed, got.cycle, got.values):
            return [Finding(seed, "disagree", "rcsc test --target (expectations)",
                            f"expect {want.expect.text}: sim {want.passed} at {want.cycle} {want.values}, "
                            f"from the trace {got.passed} at {got.cycle} {got.values}")]
    return []


def _observed(snap) -> dict:
    """A snapshot as comparable values: floats by their bits (so -0.0 and NaN count)."""
    import struct

    def norm(v):
        if isinstance(v, bool):
            return v
        if isinstance(v, float):
            return ("f64", struct.pack(">d", v).hex()) if v == v else ("f64", "nan")
        if isinstance(v, dict):
            return {k: norm(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [norm(x) for x in v]
        return v

    out = {f"gm.{k}": norm(v) for k, v in snap.gm.items()}
    for name, c in snap.ctrl.items():
        for attr in ("echo", "status", "verb", "state", "rule", "error_code"):
            out[f"{name}.{attr}"] = getattr(c, attr)
        out.update({f"{name}.{k}": norm(v) for k, v in c.fields.items()})
    return out


def first_difference(ref: bytes, got: bytes) -> str:
    a, b = ref.decode(errors="replace").splitlines(), got.decode(errors="replace").splitlines()
    for i, (x, y) in enumerate(zip(a, b), 1):
        if x != y:
            return f"cycle {i} differs:\n  sim:      {x}\n  compiled: {y}"
    return f"lengths differ: sim {len(a)} lines, compiled {len(b)} lines"


def run_program(p: Prepared, exe: Path, where: str) -> list[Finding]:
    """Run one Main Program (or, for a design of several CPUs, its launcher
    `run_<design>` in lockstep: each CPU waits for the samples it reads, so
    the merged trace is the simulator's) on the case's scenario; compare."""
    trace = exe.with_suffix(".jsonl")
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1", UBSAN_OPTIONS="print_stacktrace=1")
    if exe.name.startswith("run_"):
        argv = [str(exe), "--lockstep", "--no-timing"]
    else:
        argv = [str(exe), "--fast", "--no-console", "--no-timing"]
    try:
        proc = subprocess.run(argv + ["--scenario", str(p.events), "--trace", str(trace)], capture_output=True, text=True,
                              timeout=120, env=env, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return [Finding(p.case.seed, "fail", where, "timed out after 120 s")]
    out = []
    # The launcher names the process of each CPU on stderr; anything else there is a finding.
    stderr = "".join(x for x in proc.stderr.splitlines(keepends=True) if not _LAUNCH_NOTE.match(x))
    if proc.returncode != 0 or stderr:
        out.append(Finding(p.case.seed, "fail", where, f"exit {proc.returncode}\n{proc.stderr[-3000:]}"))
    got = trace.read_bytes() if trace.exists() else b""
    if got != p.reference:
        out.append(Finding(p.case.seed, "disagree", where, first_difference(p.reference, got)))
    return out


_LAUNCH_NOTE = re.compile(r"^rcs: CPU \S+ is process \d+$")


def c_programs(src: Path) -> list[tuple[str, list[str]]]:
    """The programs of a generated C folder, from its Makefile: (binary, sources)
    for each CPU's Main Program and, with several CPUs, the launcher."""
    text = (src / "Makefile").read_text(encoding="utf-8")
    sources = re.search(r"^SOURCES = (.*)$", text, re.M).group(1).split()
    out = []
    for binary, deps in re.findall(r"^([\w.-]+): ((?:\S+\.o ?)+(?:\$\(OBJECTS\))?)$", text, re.M):
        files = []
        for d in deps.split():
            files += sources if d == "$(OBJECTS)" else [d[:-2] + ".c"]
        out.append((binary, files))
    return out


def c_generate(p: Prepared) -> list[Finding]:
    """`rcsc build --target c` of one case (in the main thread: it redirects stderr)."""
    if p.model is not None and externs_of(p.model):  # type: ignore[arg-type]
        name, text = c_source(p.model)  # type: ignore[arg-type]
        (p.folder / "c").mkdir(parents=True, exist_ok=True)
        (p.folder / "c" / name).write_text(text, encoding="utf-8")
    rc, err = _rcsc(["build", str(p.design), "--target", "c", "-o", str(p.folder / "c")])
    return [] if rc == 0 else [Finding(p.case.seed, "crash", "rcsc build c", err[-3000:])]


# The runtime files are the same bytes for every design (rcs_*.c and the
# headers they include): each configuration compiles them once per run, into
# an object kept under a key of their content, the compiler and its flags.
# Under the sanitizers that is two thirds of a design's C build time.
_RUNTIME_OBJECTS: dict[str, Path] = {}
_RUNTIME_LOCK = threading.Lock()


def _runtime_object(src: Path, cc: str, flags: list[str], source: Path) -> tuple[Path | None, str]:
    """The object of one runtime file under `cc flags` (compiled on first use); (None, stderr) when it warns or fails."""
    digest = hashlib.sha256("\0".join([cc, *STRICT, *flags]).encode())
    for f in sorted(src.glob("rcs_*")):
        digest.update(f.name.encode() + b"\0" + f.read_bytes() + b"\0")
    key = f"{source.name}-{digest.hexdigest()[:24]}"
    with _RUNTIME_LOCK:
        obj = _RUNTIME_OBJECTS.get(key)
        if obj is not None:
            return obj, ""
        obj = Path(solver_cache()) / "objects" / f"{key}.o"
        obj.parent.mkdir(exist_ok=True)
        proc = subprocess.run([cc, *STRICT, *flags, "-I", str(src), "-c", "-o", str(obj), str(source)], capture_output=True, text=True)
        if proc.returncode != 0 or proc.stderr:
            return None, proc.stderr or f"{cc} exited with {proc.returncode}"
        _RUNTIME_OBJECTS[key] = obj
        return obj, ""


def c_case(p: Prepared, configs: list[str]) -> list[Finding]:
    """Build each C configuration of a generated case (every program of its
    Makefile, the runtime files from their cached objects) and run it."""
    src = p.folder / "c"
    out = []
    programs = c_programs(src)
    for config in configs:
        cc, flags = C_CONFIGS[config]
        folder = p.folder / config
        folder.mkdir(exist_ok=True)
        failed = False
        for binary, files in programs:
            objects, err = [], ""
            for s in files:
                if s.startswith("rcs_"):
                    obj, err = _runtime_object(src, cc, flags, src / s)
                    if obj is None:
                        break
                    objects.append(str(obj))
            if err:
                out.append(Finding(p.case.seed, "warning", config, err[-4000:]))
                failed = True
                break
            design_sources = [str(src / s) for s in files if not s.startswith("rcs_")]
            proc = subprocess.run([cc, *STRICT, *flags, "-I", str(src), "-o", str(folder / binary), *design_sources, *objects, "-lm"],
                                  capture_output=True, text=True)
            if proc.returncode != 0 or proc.stderr:
                kind = "warning" if proc.returncode == 0 or "-Werror" in proc.stderr or "error: " in proc.stderr else "fail"
                out.append(Finding(p.case.seed, kind, config, proc.stderr[-4000:]))
                failed = True
                break
        if failed:
            continue
        launcher = [b for b, _ in programs if b.startswith("run_")]
        exe = folder / (launcher[0] if launcher else programs[0][0])
        out += run_program(p, exe, config)
    return out


def ada_generate(p: Prepared) -> list[Finding]:
    """`rcsc build --target ada` of one case (in the main thread: it redirects stderr)."""
    if p.model is not None and externs_of(p.model):  # type: ignore[arg-type]
        name, text = ada_source(p.model)  # type: ignore[arg-type]
        (p.folder / "ada").mkdir(parents=True, exist_ok=True)
        (p.folder / "ada" / name).write_text(text, encoding="utf-8")
    rc, err = _rcsc(["build", str(p.design), "--target", "ada", "-o", str(p.folder / "ada")])
    return [] if rc == 0 else [Finding(p.case.seed, "crash", "rcsc build ada", err[-3000:])]


def ada_case(p: Prepared) -> list[Finding]:
    """Build each Ada configuration of a generated case with gprbuild and run it
    (with several CPUs: every CPU's program and the C launcher, in lockstep)."""
    src = p.folder / "ada"
    out = []
    projects = ["rcs_build.gpr"] + (["rcs_launch.gpr"] if (src / "rcs_launch.gpr").exists() else [])
    for config, opt in ADA_CONFIGS.items():
        failed = False
        for project in projects:
            proc = subprocess.run(["gprbuild", "-q", "-P", project, f"-XRCS_OPT={opt}"], cwd=src, capture_output=True, text=True)
            text = proc.stdout + proc.stderr
            if proc.returncode != 0 or "warning" in text:
                out.append(Finding(p.case.seed, "warning" if "warning" in text else "fail", config, text[-4000:]))
                failed = True
                break
        if failed:
            continue
        mains = re.findall(r'for Executable \("[^"]+"\) use "([^"]+)";', (src / "rcs_build.gpr").read_text(encoding="utf-8"))
        launcher = [x.name for x in src.glob("run_*") if "." not in x.name]
        folder = p.folder / config
        folder.mkdir(exist_ok=True)
        for name in mains + launcher:  # copies: the next level rebuilds the same files
            (folder / name).write_bytes((src / name).read_bytes())
            (folder / name).chmod(0o755)
        out += run_program(p, folder / (launcher[0] if launcher else mains[0]), config)
    return out


def _profiles(toml: str) -> str:
    return toml[toml.index("[profile."):] if "[profile." in toml else ""


def rust_generate(prepared: list[Prepared], base: Path) -> tuple[list[Prepared], list[Finding]]:
    """Generate every case's crate into one cargo workspace (in the main thread)."""
    ws = base / "rust-ws"
    ws.mkdir(parents=True, exist_ok=True)
    members: dict[str, Prepared] = {}
    out: list[Finding] = []
    profiles = None
    for p in prepared:
        crate = ws / p.case.name
        if p.model is not None and externs_of(p.model):  # type: ignore[arg-type]
            (crate / "src").mkdir(parents=True, exist_ok=True)
            (crate / "src" / "externs_impl.rs").write_text(rust_source(p.model), encoding="utf-8")  # type: ignore[arg-type]
        rc, err = _rcsc(["build", str(p.design), "--target", "rust", "-o", str(crate)])
        if rc != 0:
            out.append(Finding(p.case.seed, "crash", "rcsc build rust", err[-3000:]))
            continue
        prof = _profiles((crate / "Cargo.toml").read_text(encoding="utf-8"))
        if profiles is not None and prof != profiles:
            raise RuntimeError("generated crates differ in their [profile] tables; the workspace cannot share them")
        profiles = prof
        members[p.case.name] = p
    (ws / "Cargo.toml").write_text(
        "[workspace]\nresolver = \"2\"\nmembers = [" + ", ".join(f'"{m}"' for m in sorted(members)) + "]\n\n" + (profiles or ""),
        encoding="utf-8")
    return list(members.values()), out


def rust_programs(crate: Path) -> list[str]:
    """The binaries of a generated crate (each CPU's Main Program and, with several CPUs, the launcher)."""
    return re.findall(r'^\[\[bin\]\]\nname = "([^"]+)"', (crate / "Cargo.toml").read_text(encoding="utf-8"), re.M)


RUST_STEPS = {"rust-debug": ["build"], "rust-release": ["build", "--release"], "clippy": ["clippy", "--all-targets"]}


def rust_batch(prepared: list[Prepared], base: Path, jobs: int, steps: tuple[str, ...] = tuple(RUST_STEPS)) -> list[Finding]:
    """Build the workspace in debug and release and run clippy on it (one target
    folder), then run the programs."""
    ws = base / "rust-ws"
    members = {p.case.name: p for p in prepared}
    out: list[Finding] = []
    env = dict(os.environ, CARGO_TARGET_DIR=str(base / "cargo-target"), CARGO_TERM_COLOR="never")
    failed: set[str] = set()
    for what in steps:
        cmd = RUST_STEPS[what]
        argv = ["cargo", *cmd, "--offline", "--workspace", "--keep-going", "-j", str(jobs), "--message-format=json"]
        if what == "clippy":
            argv += ["--", "-D", "warnings"]
        proc = subprocess.run(argv, cwd=ws, env=env, capture_output=True, text=True)
        if _INFRA.search(proc.stderr):
            # cargo could not start rustc at all (seen on a loaded machine):
            # not a finding about the code; the step is run again once.
            proc = subprocess.run(argv, cwd=ws, env=env, capture_output=True, text=True)
        for line in proc.stdout.splitlines():
            msg = json.loads(line)
            if msg.get("reason") != "compiler-message":
                continue
            src = Path(msg.get("target", {}).get("src_path", ""))
            name = src.relative_to(ws).parts[0] if src.is_relative_to(ws) else ""
            diag = msg["message"]
            if diag.get("level") in ("warning", "error") and not diag["message"].startswith("aborting due to"):
                if diag["level"] == "error":
                    failed.add(name)
                seed = members[name].case.seed if name in members else -1
                out.append(Finding(seed, "warning", what, diag.get("rendered") or diag["message"]))
        stderr = _PROFILE_NOTE.sub("", proc.stderr)
        noise = [x for x in stderr.splitlines() if re.match(r"^(warning|error)", x) and "build failed" not in x
                 and "could not compile" not in x and "generated" not in x]
        if noise:
            out.append(Finding(-1, "warning", what, "\n".join(noise) + "\n" + stderr[-3000:]))
    for name, p in members.items():
        if name in failed:
            continue
        bins = rust_programs(ws / name)
        launcher = [b for b in bins if b.startswith("run_")]
        for config, profile in (("rust-debug", "debug"), ("rust-release", "release")):
            if config not in steps:
                continue
            exe = base / "cargo-target" / profile / (launcher[0] if launcher else bins[0])
            if exe.exists():
                out += run_program(p, exe, config)
            else:
                out.append(Finding(p.case.seed, "fail", config, "no program was built"))
    return out


def run_batch(cases: list[Case], targets: list[str], jobs: int = 1, c_configs: list[str] | None = None,
              workdir: Path | None = None, rust_steps: tuple[str, ...] = tuple(RUST_STEPS)) -> list[Finding]:
    """Every case of the batch through every build; the findings."""
    configs = list(c_configs or C_CONFIGS)
    with tempfile.TemporaryDirectory(prefix="difftest-") as tmp:
        base = workdir or Path(tmp)
        prepared = [prepare(c, base) for c in cases]
        findings = [f for p in prepared for f in p.findings]
        good = [p for p in prepared if not p.findings]
        c_ready = []
        if "c" in targets:
            for p in good:
                got = c_generate(p)
                findings += got
                if not got:
                    c_ready.append(p)
        ada_ready = []
        if "ada" in targets:
            for p in good:
                got = ada_generate(p)
                findings += got
                if not got:
                    ada_ready.append(p)
        rust_ready = []
        if "rust" in targets and good:
            rust_ready, got = rust_generate(good, base)
            findings += got
        with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            futures = [pool.submit(c_case, p, configs) for p in c_ready] + [pool.submit(ada_case, p) for p in ada_ready]
            if rust_ready:
                findings += rust_batch(rust_ready, base, jobs, rust_steps)
            for fut in futures:
                findings += fut.result()
    return findings
