"""Compiled multi-CPU designs: one Main Program per CPU, each its own process.

`rcsc build` of a design with several CPUs gives one program per CPU and a
launcher (`run_<design>`) that starts them all with one run id; they
exchange the buffers that cross between CPUs through POSIX shared memory.
Checked here, for C (gcc -O2 and clang under ASan/UBSan), Rust (release) and
Ada (GNAT -O2, run-time checks on; its programs use the C runtime's exchange
and the C launcher):

- with `--lockstep` (each CPU waits for the samples it reads) the launcher's
  merged trace equals `rcsc sim`'s byte for byte, on every multi-CPU design
  and scenario of tests/mc and tests/sim (commands and status both ways, GM
  both ways, divided rates, ages, inputs, `stop` and `freeze` faults);
- a real-time run (absolute deadlines on a shared start) of a 10 ms design
  over 2 s gives the simulator's trace, and says so clearly when the machine
  missed a deadline or a sample instead of comparing;
- Ctrl-C stops every CPU cleanly (each prints its timing table); a CPU that
  crashes stops the others;
- no run leaves a process or a /dev/shm segment behind.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import shutil
import signal
import subprocess
import time
import tomllib
from pathlib import Path

import pytest

from c_build import event_file, first_difference, generate, multi_cpu_examples

from rcsc import cli

# Real-time runs and machine-wide resources: these tests run alone, after the
# others (the README's test command, `-m serial`).
pytestmark = pytest.mark.serial

ROOT = Path(__file__).resolve().parent.parent
MC = ROOT / "tests" / "mc"
TWOCPU = ROOT / "tests" / "sim" / "multicpu.rcs"
RELAY = MC / "relay.rcs"
SINGLE = MC / "single.rcs"
SINGLE_CASES = [(SINGLE, MC / "single_run.scn"), (SINGLE, MC / "single_faults.scn")]

# Every scenario of every multi-CPU example, and the designs of the tests.
CASES = multi_cpu_examples() + [
    (TWOCPU, MC / "twocpu_run.scn"),
    (RELAY, MC / "relay_run.scn"),
    (RELAY, MC / "relay_stop.scn"),
    (RELAY, MC / "relay_freeze.scn"),
    (MC / "extern_cpu.rcs", MC / "extern_cpu_run.scn"),
    (MC / "apart.rcs", MC / "apart_run.scn"),
    # Names longer than a file name may be (a trace part, a segment): the
    # launcher must not build file names of them.
    (MC / "long_names.rcs", MC / "long_names_run.scn"),
]

SANITIZE = "-O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=all"
C_CONFIGS = {
    "gcc-O2": ("gcc", "-O2", ""),
    "clang-asan-ubsan": ("clang", SANITIZE, SANITIZE),
}


def sim_trace(design: Path, scn: Path, tmp: Path) -> bytes:
    out = tmp / f"{design.stem}-{scn.stem}.sim.jsonl"
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = cli.main(["sim", str(design), "--scenario", str(scn), "-o", str(out)])
    assert rc == 0, err.getvalue()
    return out.read_bytes()


@pytest.fixture(scope="module")
def c_builds(tmp_path_factory):
    """(design, config) -> the folder with the CPUs' programs and the launcher."""
    base = tmp_path_factory.mktemp("mc_c")
    cache: dict[tuple[Path, str], Path] = {}

    def get(design: Path, config: str) -> Path:
        key = (design, config)
        if key not in cache:
            src = base / f"src-{design.stem}"
            if not src.exists():
                generate(design, "c", src)
            out = base / f"{design.stem}-{config}"
            shutil.copytree(src, out)
            cc, cflags, ldflags = C_CONFIGS[config]
            r = subprocess.run(["make", "-s", f"CC={cc}", f"CFLAGS={cflags} -Werror", f"LDFLAGS={ldflags}"], cwd=out, capture_output=True, text=True)
            assert r.returncode == 0 and r.stderr == "", r.stderr
            cache[key] = out
        return cache[key]

    return get


def leftovers(design: str) -> list[str]:
    # Segment names hold the first 100 characters of the design's name.
    return [n for n in os.listdir("/dev/shm") if n.startswith(f"rcs-{design[:100]}-")]


def cpu_pids(stderr: str) -> dict[str, int]:
    return {m.group(1): int(m.group(2)) for m in re.finditer(r"rcs: CPU (\w+) is process (\d+)", stderr)}


def assert_gone(pids) -> None:
    for pid in pids:
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)


def launch(folder: Path, design: str, *args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    r = subprocess.run([str(folder / f"run_{design}"), *args], capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)
    assert_gone(cpu_pids(r.stderr).values())
    assert leftovers(design) == []
    return r


@pytest.mark.parametrize("config", list(C_CONFIGS))
@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c[0].stem}/{c[1].stem}")
def test_lockstep_trace_equals_simulator(c_builds, case, config, tmp_path):
    design, scn = case
    folder = c_builds(design, config)
    name = next(p.name for p in folder.glob("run_*") if "." not in p.name)[4:]
    trace = tmp_path / "c.jsonl"
    r = launch(folder, name, "--lockstep", "--no-timing", "--scenario", str(event_file(design, scn)), "--trace", str(trace))
    assert r.returncode == 0, r.stderr
    want = sim_trace(design, scn, tmp_path)
    got = trace.read_bytes()
    assert got == want, first_difference(got, want)
    assert len(cpu_pids(r.stderr)) == len(set(re.findall(rb'"cpu":"(\w+)"', want)))


def test_the_build_has_a_program_per_cpu_and_a_launcher(c_builds):
    folder = c_builds(RELAY, "gcc-O2")
    names = {p.name for p in folder.iterdir()}
    assert {"main_slow.c", "main_fast.c", "run_relay.c", "relay_slow", "relay_fast", "run_relay", "rcs_shm.c", "rcs_launch.c"} <= names
    # Each CPU's Main Program steps only its own schedule and traces only its controllers.
    main_fast = (folder / "main_fast.c").read_text()
    assert re.search(r"static const size_t ctrls_here\[\] = \{ 1u, 3u \};", main_fast)


def test_a_cpu_alone_says_it_needs_the_launcher(c_builds):
    folder = c_builds(RELAY, "gcc-O2")
    r = subprocess.run([str(folder / "relay_fast"), "--lockstep", "--cycles", "3"], capture_output=True, text=True, timeout=20)
    assert r.returncode == 2
    assert "runs under its launcher (run_relay)" in r.stderr
    r = subprocess.run([str(folder / "relay_fast"), "--fast", "--run", "x"], capture_output=True, text=True, timeout=20)
    assert r.returncode == 2 and "--lockstep (not --fast)" in r.stderr
    assert leftovers("relay") == []


@pytest.fixture(scope="module")
def rust_builds(tmp_path_factory):
    """design -> the cargo release folder with the CPUs' programs and the launcher."""
    base = tmp_path_factory.mktemp("mc_rust")
    cache: dict[Path, Path] = {}

    def get(design: Path) -> Path:
        if design not in cache:
            crate = base / design.stem
            generate(design, "rust", crate)
            env = dict(os.environ, CARGO_TARGET_DIR=str(base / f"target-{design.stem}"), CARGO_TERM_COLOR="never")
            for cmd in (["cargo", "build", "--offline", "--release"], ["cargo", "clippy", "--offline", "--release", "--", "-D", "warnings"]):
                r = subprocess.run(cmd, cwd=crate, env=env, capture_output=True, text=True)
                assert r.returncode == 0, r.stderr[-4000:]
                assert not re.search(r"^warning", r.stderr, re.M), r.stderr[-4000:]
            files = [str(p) for p in crate.rglob("*.rs") if "target" not in p.parts]
            r = subprocess.run(["rustfmt", "--check", "--edition", "2021", *files], capture_output=True, text=True)
            assert r.returncode == 0, r.stdout[-4000:]
            cache[design] = base / f"target-{design.stem}" / "release"
        return cache[design]

    return get


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c[0].stem}/{c[1].stem}")
def test_rust_lockstep_trace_equals_simulator(rust_builds, case, tmp_path):
    design, scn = case
    folder = rust_builds(design)
    name = next(p.name for p in folder.glob("run_*") if "." not in p.name)[4:]
    trace = tmp_path / "rust.jsonl"
    r = launch(folder, name, "--lockstep", "--no-timing", "--scenario", str(event_file(design, scn)), "--trace", str(trace))
    assert r.returncode == 0, r.stderr
    want = sim_trace(design, scn, tmp_path)
    got = trace.read_bytes()
    assert got == want, first_difference(got, want)


@pytest.fixture(scope="module")
def ada_builds(tmp_path_factory):
    """design -> the folder with the Ada CPUs' programs (GNAT -O2, checks on) and the C launcher."""
    base = tmp_path_factory.mktemp("mc_ada")
    cache: dict[Path, Path] = {}

    def get(design: Path) -> Path:
        if design not in cache:
            src = base / design.stem
            generate(design, "ada", src)
            for project in ("rcs_build.gpr", "rcs_launch.gpr"):
                r = subprocess.run(["gprbuild", "-q", "-P", project, "-XRCS_OPT=-O2"], cwd=src, capture_output=True, text=True)
                assert r.returncode == 0, (r.stdout + r.stderr)[-4000:]
                assert "warning" not in r.stdout + r.stderr, r.stdout + r.stderr
            cache[design] = src
        return cache[design]

    return get


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c[0].stem}/{c[1].stem}")
def test_ada_lockstep_trace_equals_simulator(ada_builds, case, tmp_path):
    design, scn = case
    folder = ada_builds(design)
    name = next(p.name for p in folder.glob("run_*") if "." not in p.name)[4:]
    trace = tmp_path / "ada.jsonl"
    r = launch(folder, name, "--lockstep", "--no-timing", "--scenario", str(event_file(design, scn)), "--trace", str(trace))
    assert r.returncode == 0, r.stderr
    want = sim_trace(design, scn, tmp_path)
    got = trace.read_bytes()
    assert got == want, first_difference(got, want)
    assert len(cpu_pids(r.stderr)) == len(set(re.findall(rb'"cpu":"(\w+)"', want)))


def test_ada_build_has_a_program_per_cpu_and_the_c_launcher(ada_builds):
    folder = ada_builds(RELAY)
    names = {p.name for p in folder.iterdir()}
    assert {"relay_0_main_0_slow.adb", "relay_0_main_0_fast.adb", "rcs_tables_0.c", "rcs_tables_1.c", "run_relay.c", "rcs_launch.gpr",
            "relay_slow", "relay_fast", "run_relay"} <= names
    # Each CPU's tables step only its own schedule; the buffers are defined once.
    assert re.search(r"static const size_t ctrls_here\[\] = \{ 1u, 3u \};", (folder / "rcs_tables_1.c").read_text())
    assert sum("relay_buffers rcs_ada_buf;" in (folder / f"rcs_tables_{k}.c").read_text() for k in (0, 1)) == 2
    assert sum(re.search(r"^relay_buffers rcs_ada_buf;", (folder / f"rcs_tables_{k}.c").read_text(), re.M) is not None for k in (0, 1)) == 1


def test_rust_crashed_cpu_stops_the_others(rust_builds):
    folder = rust_builds(TWOCPU)
    p, pids = _start(folder, "twocpu")
    os.kill(pids["planner"], signal.SIGKILL)
    _, err = p.communicate(timeout=30)
    assert p.returncode == 1
    assert "rcs: CPU planner was killed by signal 9" in err
    assert "rcs: timing of twocpu on servo" in err
    assert_gone(pids.values())
    assert leftovers("twocpu") == []


def test_rust_ctrl_c_stops_every_cpu_cleanly(rust_builds, tmp_path):
    folder = rust_builds(TWOCPU)
    trace = tmp_path / "t.jsonl"
    p, pids = _start(folder, "twocpu", "--trace", str(trace))
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=30)
    assert p.returncode == 0, err
    assert sorted(re.findall(r"rcs: timing of twocpu on (\w+)", err)) == ["planner", "servo"]
    assert_gone(pids.values())
    assert leftovers("twocpu") == []
    assert len(trace.read_text().splitlines()) > 10


def _realtime_report(stderr: str) -> list[str]:
    """What the CPUs' timing tables say went wrong in a real-time run (empty: nothing)."""
    problems = []
    for m in re.finditer(r"rcs: timing of \w+ on (\w+).*?cycles: \d+, .*?, (\d+) cycle overruns?\nmissing samples: (\d+)", stderr, re.S):
        cpu, overruns, missing = m.group(1), int(m.group(2)), int(m.group(3))
        if overruns or missing:
            problems.append(f"CPU {cpu}: {overruns} missed deadlines, {missing} missing samples")
    return problems


@pytest.mark.parametrize("target", ["c", "rust"])
def test_realtime_run_equals_simulator(c_builds, rust_builds, target, tmp_path):
    """2 s of a 10 ms design on the clock: the simulator's trace, unless the host missed a deadline."""
    folder = c_builds(TWOCPU, "gcc-O2") if target == "c" else rust_builds(TWOCPU)
    scn = tmp_path / "two_seconds.scn"
    scn.write_text((MC / "twocpu_run.scn").read_text().replace("cycles 40", "cycles 200"))
    # A busy host may miss a deadline; then the run says so and is not
    # compared.  Up to three runs: the first that keeps every deadline must
    # give the simulator's trace; if none does, the test fails saying why.
    reports = []
    for attempt in range(3):
        trace = tmp_path / f"rt{attempt}.jsonl"
        t0 = time.monotonic()
        r = launch(folder, "twocpu", "--scenario", str(event_file(TWOCPU, scn)), "--trace", str(trace))
        elapsed = time.monotonic() - t0
        assert r.returncode == 0, r.stderr
        assert elapsed >= 2.0, f"a real-time run of 200 ticks of 10 ms took {elapsed:.2f} s"
        tables = re.findall(r"rcs: timing of twocpu on (\w+)", r.stderr)
        assert sorted(tables) == ["planner", "servo"], r.stderr
        problems = _realtime_report(r.stderr)
        if not problems:
            want = sim_trace(TWOCPU, scn, tmp_path)
            got = trace.read_bytes()
            assert got == want, first_difference(got, want)
            return
        reports.append(f"run {attempt + 1}: " + "; ".join(problems))
    pytest.fail("every real-time run missed its timing, so no trace was compared: " + " | ".join(reports))


def _start(folder: Path, design: str, *args: str) -> tuple[subprocess.Popen, dict[str, int]]:
    p = subprocess.Popen([str(folder / f"run_{design}"), *args], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    pids: dict[str, int] = {}
    assert p.stderr is not None
    while len(pids) < 2:
        line = p.stderr.readline()
        assert line, "the launcher ended before starting its CPUs"
        pids.update(cpu_pids(line))
    time.sleep(0.5)  # past the start barrier: the CPUs run on their heartbeat
    return p, pids


def test_ctrl_c_stops_every_cpu_cleanly(c_builds, tmp_path):
    folder = c_builds(TWOCPU, "gcc-O2")
    trace = tmp_path / "t.jsonl"
    p, pids = _start(folder, "twocpu", "--trace", str(trace))
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=30)
    assert p.returncode == 0, err
    assert sorted(re.findall(r"rcs: timing of twocpu on (\w+)", err)) == ["planner", "servo"]
    assert_gone(pids.values())
    assert leftovers("twocpu") == []
    lines = trace.read_text().splitlines()
    assert len(lines) > 10 and all(line.startswith('{"cpu":') for line in lines)


def test_a_crashed_cpu_stops_the_others(c_builds):
    folder = c_builds(TWOCPU, "gcc-O2")
    p, pids = _start(folder, "twocpu")
    os.kill(pids["servo"], signal.SIGKILL)
    _, err = p.communicate(timeout=30)
    assert p.returncode == 1
    assert "rcs: CPU servo was killed by signal 9" in err
    assert "rcs: timing of twocpu on planner" in err  # stopped cleanly by the launcher
    assert_gone(pids.values())
    assert leftovers("twocpu") == []


def test_a_cpu_that_cannot_start_stops_the_run(c_builds, tmp_path):
    """A CPU program missing: the others, waiting at the start barrier, are stopped; nothing is left behind."""
    folder = tmp_path / "broken"
    shutil.copytree(c_builds(TWOCPU, "gcc-O2"), folder)
    (folder / "twocpu_servo").unlink()
    r = launch(folder, "twocpu", "--lockstep", "--cycles", "10")
    assert r.returncode == 1
    assert "cannot start" in r.stderr and "rcs: CPU servo exited with status 127" in r.stderr


def test_lockstep_reader_sees_a_crashed_writer(c_builds, tmp_path):
    """Without the launcher: a CPU waiting in lockstep for a writer whose process died gives up with a message."""
    folder = c_builds(TWOCPU, "gcc-O2")
    run = f"crash{os.getpid()}"
    planner = subprocess.Popen([str(folder / "twocpu_planner"), "--lockstep", "--run", run, "--no-timing"], stdin=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    servo = subprocess.Popen([str(folder / "twocpu_servo"), "--lockstep", "--run", run, "--no-timing", "--cycles", "1000000000"], stdin=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    time.sleep(0.5)
    planner.kill()
    planner.wait(timeout=10)
    _, err = servo.communicate(timeout=30)
    assert servo.returncode == 1 and "CPU planner failed or is gone" in err
    assert leftovers("twocpu") == []


def _single_c(tmp_path_factory_base: Path, config: str) -> Path:
    src = tmp_path_factory_base / "single-src"
    if not src.exists():
        generate(SINGLE, "c", src)
    exe = tmp_path_factory_base / f"single-{config}"
    if not exe.exists():
        cc, cflags, ldflags = C_CONFIGS[config]
        sources = sorted(str(p) for p in src.glob("*.c"))
        r = subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wshadow", "-Werror", "-ffp-contract=off", *cflags.split(), *ldflags.split(), "-o", str(exe), *sources], capture_output=True, text=True)
        assert r.returncode == 0 and r.stderr == "", r.stderr
    return exe


@pytest.fixture(scope="module")
def single_base(tmp_path_factory):
    return tmp_path_factory.mktemp("single")


def _run_single(exe: Path, design: Path, scn: Path, trace: Path) -> subprocess.CompletedProcess:
    events = event_file(design, scn)
    return subprocess.run([str(exe), "--fast", "--no-console", "--no-timing", "--scenario", str(events), "--trace", str(trace)], capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)


@pytest.mark.parametrize("config", list(C_CONFIGS))
@pytest.mark.parametrize("case", SINGLE_CASES, ids=lambda c: c[1].stem)
def test_single_cpu_divided_rate_ages_and_freeze(single_base, case, config, tmp_path):
    """One CPU: a `period` controller, age(V) of Global Memory and of a subordinate, `freeze`."""
    design, scn = case
    exe = _single_c(single_base, config)
    r = _run_single(exe, design, scn, tmp_path / "c.jsonl")
    assert r.returncode == 0, r.stderr
    want = sim_trace(design, scn, tmp_path)
    got = (tmp_path / "c.jsonl").read_bytes()
    assert got == want, first_difference(got, want)


def test_single_cpu_stop_ends_the_run(single_base, rust_single, tmp_path):
    """`stop` of the only CPU at tick 30: the run ends after cycle 29, as in the simulator."""
    scn = MC / "single_stop.scn"
    want = sim_trace(SINGLE, scn, tmp_path)
    assert want.count(b"\n") == 29 and b'{"cycle":29,' in want.splitlines()[-1]
    for exe in (_single_c(single_base, "gcc-O2"), rust_single):
        r = _run_single(exe, SINGLE, scn, tmp_path / "t.jsonl")
        assert r.returncode == 0, r.stderr
        got = (tmp_path / "t.jsonl").read_bytes()
        assert got == want, first_difference(got, want)


@pytest.fixture(scope="module")
def rust_single(single_base):
    crate = single_base / "rust"
    generate(SINGLE, "rust", crate)
    env = dict(os.environ, CARGO_TARGET_DIR=str(single_base / "target"), CARGO_TERM_COLOR="never")
    r = subprocess.run(["cargo", "build", "--offline", "--release"], cwd=crate, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-4000:]
    # The binary's name comes from the Rust naming scheme (`main` is reserved there).
    (binary,) = tomllib.loads((crate / "Cargo.toml").read_text())["bin"]
    return single_base / "target" / "release" / binary["name"]


@pytest.mark.parametrize("case", SINGLE_CASES, ids=lambda c: c[1].stem)
def test_rust_single_cpu_divided_rate_ages_and_freeze(rust_single, case, tmp_path):
    design, scn = case
    r = _run_single(rust_single, design, scn, tmp_path / "r.jsonl")
    assert r.returncode == 0, r.stderr
    want = sim_trace(design, scn, tmp_path)
    got = (tmp_path / "r.jsonl").read_bytes()
    assert got == want, first_difference(got, want)


def test_a_target_without_a_transport_refuses_what_it_cannot_build():
    """The default of `Target.check`: several CPUs, divided rates and ages of Global Memory are refused."""
    from rcsc.outputs.backend import Target
    from rcsc.diagnostics import Diagnostics
    from rcsc.driver import check_path

    class Plain(Target):
        name = "plain"

    result = check_path(str(RELAY))
    assert result.model is not None
    diags = Diagnostics()
    Plain(result.model).check(diags)
    messages = [d.message for d in diags.items]
    assert all(d.code == "E0800" for d in diags.items)
    assert messages[0] == "the plain target builds single-CPU designs; this design has 2 CPUs"
    assert "`DIV` has a period" in messages[1]
    assert [m for m in messages if "age(" in m] == [f"the plain target keeps no stamps of Global Memory for `age({v})`" for v in ("pos", "wind", "goal")]


@pytest.mark.parametrize("target", ["c", "rust"])
def test_multi_cpu_build_is_reproducible(target, tmp_path):
    """Same design, same bytes: every file of a multi-CPU build, twice."""
    a, b = tmp_path / "a", tmp_path / "b"
    generate(RELAY, target, a)
    generate(RELAY, target, b)
    files_a = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    assert files_a == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    assert all((a / f).read_bytes() == (b / f).read_bytes() for f in files_a)
    for f in files_a:
        head = "\n".join((a / f).read_text(encoding="utf-8").splitlines()[:3])
        assert "generated by rcsc - do not edit" in head, f
