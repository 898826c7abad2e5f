"""The CPUs of a multi-CPU design exchanging their buffers over Cyclone DDS.

`rcsc build --target c --transport dds` gives the same programs and launcher
as the shared-memory build, linked with libddsc (backends/c/runtime/rcs_dds.c);
`--target rust --transport dds` the same through the crate rcs_dds, a safe
wrapper of that C file kept outside the no_std, unsafe-free controller crate.
Checked here, every process on the loopback interface only (a Cyclone
configuration with the `lo` interface, no multicast, the peer 127.0.0.1) on a
domain id drawn at random for this test run, so that parallel runs and other
DDS users of the machine never meet:

- with `--lockstep` the launcher's merged trace equals `rcsc sim`'s byte for
  byte on every multi-CPU design and scenario of tests/test_multicpu_targets.py;
- the CPUs started by hand, each in its own IPC namespace (no shared memory
  could reach the other), give the simulator's trace too;
- two runs of one design on one domain at once never mix (the partition);
- a CPU killed in the middle is seen gone by the other within seconds (the
  1 s liveliness lease), which stops instead of hanging;
- what the build writes, and the refusals (E0820, E0821, `--domain`);
- Rust+Rust: the Rust launcher's lockstep trace equals the simulator's (the
  build passes clippy -D warnings and rustfmt, the wrapper crate too).
"""

from __future__ import annotations

import contextlib
import io
import os
import random
import re
import signal
import subprocess
import time
from pathlib import Path

import pytest

from c_build import event_file, first_difference, generate
from test_multicpu_targets import C_CONFIGS, CASES, RELAY, TWOCPU, _realtime_report, cpu_pids, sim_trace

from rcsc import cli

# Real-time runs and machine-wide resources: these tests run alone, after the
# others (the README's test command, `-m serial`).
pytestmark = pytest.mark.serial

ROOT = Path(__file__).resolve().parent.parent
MC = ROOT / "tests" / "mc"

LOOPBACK = """<CycloneDDS><Domain>
  <General><Interfaces><NetworkInterface name="lo"/></Interfaces><AllowMulticast>false</AllowMulticast></General>
  <Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>40</MaxAutoParticipantIndex>
    <Peers><Peer address="127.0.0.1"/></Peers></Discovery>
</Domain></CycloneDDS>
"""


@pytest.fixture(scope="module")
def dds_env(tmp_path_factory):
    """The environment of every DDS process: loopback only, and this run's domain id."""
    config = tmp_path_factory.mktemp("cyclone") / "loopback.xml"
    config.write_text(LOOPBACK, encoding="utf-8")
    domain = random.SystemRandom().randint(1, 232)
    return dict(os.environ, CYCLONEDDS_URI=config.as_uri()), str(domain)


@pytest.fixture(scope="module")
def dds_builds(tmp_path_factory):
    """(design, config) -> the folder of its `--transport dds` C build (no warning)."""
    base = tmp_path_factory.mktemp("dds_c")
    cache: dict[tuple[Path, str], Path] = {}

    def get(design: Path, config: str = "gcc-O2") -> Path:
        if (design, config) not in cache:
            out = base / f"{design.stem}-{config}"
            generate(design, "c", out, "--transport", "dds")
            cc, cflags, ldflags = C_CONFIGS[config]
            r = subprocess.run(["make", "-s", f"CC={cc}", f"CFLAGS={cflags} -Werror", f"LDFLAGS={ldflags}"], cwd=out, capture_output=True, text=True)
            assert r.returncode == 0 and r.stderr == "", r.stderr
            cache[(design, config)] = out
        return cache[(design, config)]

    return get


def launcher(folder: Path) -> Path:
    return next(p for p in folder.glob("run_*") if "." not in p.name)


@pytest.mark.parametrize("config", list(C_CONFIGS))
@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c[0].stem}/{c[1].stem}")
def test_lockstep_trace_over_dds_equals_simulator(dds_builds, dds_env, case, config, tmp_path):
    """gcc -O2, and clang under ASan/UBSan (and LeakSanitizer: nothing leaks)."""
    design, scn = case
    env, domain = dds_env
    trace = tmp_path / "dds.jsonl"
    r = subprocess.run([str(launcher(dds_builds(design, config))), "--lockstep", "--no-timing", "--domain", domain, "--scenario", str(event_file(design, scn)),
                        "--trace", str(trace)], capture_output=True, text=True, timeout=120, env=env, stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stderr
    want = sim_trace(design, scn, tmp_path)
    got = trace.read_bytes()
    assert got == want, first_difference(got, want)
    assert len(cpu_pids(r.stderr)) == len(set(re.findall(rb'"cpu":"(\w+)"', want))) > 1


def merge(parts: list[Path]) -> bytes:
    """The launcher's merge: by release instant, then CPU declaration order."""
    lines = []
    for i, p in enumerate(parts):
        for line in p.read_bytes().splitlines(keepends=True):
            lines.append((int(re.search(rb',"t":(-?\d+)', line).group(1)), i, line))
    return b"".join(line for _, _, line in sorted(lines, key=lambda x: (x[0], x[1])))


def start_cpu(folder: Path, binary: str, run: str, env, domain: str, *args: str) -> subprocess.Popen:
    """One CPU's program by hand, in an IPC namespace of its own: no shared
    memory can reach it, only the network (here the loopback interface)."""
    cmd = ["unshare", "--user", "--map-root-user", "--ipc", str(folder / binary), "--run", run, "--domain", domain, "--no-console", *args]
    return subprocess.Popen(cmd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_cpus_in_separate_ipc_namespaces_give_the_simulators_trace(dds_builds, dds_env, tmp_path):
    env, domain = dds_env
    folder, scn = dds_builds(RELAY), MC / "relay_run.scn"
    procs, parts = [], []
    for cpu in ("slow", "fast"):  # declaration order
        parts.append(tmp_path / f"{cpu}.jsonl")
        procs.append(start_cpu(folder, f"relay_{cpu}", "by-hand", env, domain, "--lockstep", "--no-timing", "--scenario", str(event_file(RELAY, scn)), "--trace", str(parts[-1])))
    for p in procs:
        _, err = p.communicate(timeout=60)
        assert p.returncode == 0, err
    want = sim_trace(RELAY, scn, tmp_path)
    got = merge(parts)
    assert got == want, first_difference(got, want)
    assert all(p.read_bytes() for p in parts)


def test_two_runs_on_one_domain_never_mix(dds_builds, dds_env, tmp_path):
    """Each run is its own partition: both give the simulator's trace."""
    env, domain = dds_env
    folder, scn = dds_builds(TWOCPU), MC / "twocpu_run.scn"
    runs = []
    for i in range(2):
        trace = tmp_path / f"run{i}.jsonl"
        p = subprocess.Popen([str(launcher(folder)), "--lockstep", "--no-timing", "--domain", domain, "--scenario", str(event_file(TWOCPU, scn)), "--trace", str(trace)],
                             env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        runs.append((p, trace))
    want = sim_trace(TWOCPU, scn, tmp_path)
    for p, trace in runs:
        _, err = p.communicate(timeout=120)
        assert p.returncode == 0, err
        assert trace.read_bytes() == want, first_difference(trace.read_bytes(), want)


def test_a_killed_cpu_is_seen_gone_and_nothing_hangs(dds_builds, dds_env):
    env, domain = dds_env
    folder = dds_builds(RELAY)
    run = f"kill-{os.getpid()}"
    slow = start_cpu(folder, "relay_slow", run, env, domain, "--lockstep", "--no-timing", "--cycles", "100000000")
    fast = start_cpu(folder, "relay_fast", run, env, domain, "--lockstep", "--no-timing", "--cycles", "100000000")
    try:
        time.sleep(1.5)
        assert slow.poll() is None and fast.poll() is None, "both CPUs run until one is killed"
        # unshare execs the program: its process id is the CPU's.
        os.kill(slow.pid, signal.SIGKILL)
        t0 = time.monotonic()
        _, err = fast.communicate(timeout=20)
        took = time.monotonic() - t0
    finally:
        for p in (slow, fast):
            if p.poll() is None:
                p.kill()
            p.communicate()
    assert fast.returncode == 1, err
    assert re.search(r"rcs: CPU fast: (CPU slow|a CPU that reads it) failed or is gone", err), err
    assert took < 10, f"the killed CPU was seen gone after {took:.1f} s"


def build_cli(*argv: str) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = cli.main(["build", *argv])
    return rc, err.getvalue()


def test_the_dds_build_links_libddsc_and_the_shm_build_does_not(dds_builds, tmp_path):
    folder = dds_builds(RELAY)
    assert {"rcs_dds.c", "rcs_dds.h", "rcs_shm.c"} <= {p.name for p in folder.iterdir()}
    assert "-lddsc" in (folder / "Makefile").read_text()
    assert "CycloneDDS::ddsc" in (folder / "CMakeLists.txt").read_text()
    assert "&rcs_dds_transport" in (folder / "main_fast.c").read_text()
    shm = tmp_path / "shm"
    generate(RELAY, "c", shm)
    assert not (shm / "rcs_dds.c").exists()
    assert "ddsc" not in (shm / "Makefile").read_text()
    assert "&rcs_shm_transport" in (shm / "main_fast.c").read_text()


def test_domain_option_is_checked(dds_builds, dds_env, tmp_path):
    env, _ = dds_env
    folder = dds_builds(RELAY)
    r = subprocess.run([str(folder / "relay_fast"), "--run", "x", "--domain", "233"], capture_output=True, text=True, timeout=20, env=env)
    assert r.returncode == 2 and "--domain needs a DDS domain id from 0 to 232, not `233`" in r.stderr
    shm = tmp_path / "shm"
    generate(RELAY, "c", shm)
    subprocess.run(["make", "-s"], cwd=shm, check=True, capture_output=True)
    r = subprocess.run([str(shm / "relay_fast"), "--run", "x", "--domain", "7"], capture_output=True, text=True, timeout=20)
    assert r.returncode == 2 and "--domain is for the CPUs of a design built with `--transport dds`" in r.stderr


def test_a_target_or_design_without_a_dds_exchange_is_refused(tmp_path):
    from rcsc.diagnostics import Diagnostics
    from rcsc.driver import check_path
    from rcsc.outputs.backend import BuildOptions, Target

    class SharedMemoryOnly(Target):
        name = "plain"
        multi_cpu = True

    result = check_path(str(RELAY))
    assert result.model is not None
    diags = Diagnostics()
    SharedMemoryOnly(result.model, BuildOptions(transport="dds")).check(diags)
    assert [(d.code, d.message) for d in diags.items] == [("E0820", "the plain target cannot exchange buffers over `dds`; it has shm")]
    diags = Diagnostics()
    SharedMemoryOnly(result.model, BuildOptions(transport="shm")).check(diags)
    assert diags.items == []
    rc, err = build_cli(str(MC / "single.rcs"), "--target", "c", "--transport", "dds", "-o", str(tmp_path / "s"))
    assert rc != 0 and "error[E0821]: `--transport dds` carries buffers between CPUs, and this design has one CPU" in err
    assert not (tmp_path / "s").exists()


def test_discovery_trace_shows_the_topics_types_partition_and_qos(dds_builds, dds_env, tmp_path):
    """What docs/backends.md says a user sees in Cyclone's discovery trace."""
    env, domain = dds_env
    # one log per process (Cyclone expands ${CYCLONEDDS_PID})
    tracing = f"<Tracing><Category>discovery</Category><OutputFile>{tmp_path}/cdds-${{CYCLONEDDS_PID}}.log</OutputFile></Tracing></Domain>"
    config = tmp_path / "traced.xml"
    config.write_text(LOOPBACK.replace("</Domain>", tracing), encoding="utf-8")
    env = dict(env, CYCLONEDDS_URI=config.as_uri())
    r = subprocess.run([str(launcher(dds_builds(RELAY))), "--lockstep", "--no-timing", "--domain", domain, "--cycles", "6"],
                       capture_output=True, text=True, timeout=60, env=env, stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stderr
    logs = sorted(tmp_path.glob("cdds-*.log"))
    assert len(logs) == 2, logs
    text = "".join(log.read_text(errors="replace") for log in logs)
    writers = {}
    for m in re.finditer(r'topic_name="(rcs/relay/[^"]+)",type_name="([^"]+)",.*?deadline=(\d+),.*?liveliness=0:(\d+),'
                         r'reliability=(\d):.*?history=(\d+):(\d+),.*?partition=\{"(rcs/relay/[^"]+)"\}', text):
        writers[m.group(1)] = m.groups()[1:]
    assert set(writers) == {"rcs/relay/cpu/fast", "rcs/relay/cpu/slow", "rcs/relay/control"}, sorted(writers)
    fast, slow, control = writers["rcs/relay/cpu/fast"], writers["rcs/relay/cpu/slow"], writers["rcs/relay/control"]
    assert re.fullmatch(r"rcs::relay::fast_[0-9a-f]{16}", fast[0]) and control[0] == "rcs::control"
    # deadline = the writer's heartbeat (fast 10 ms, slow 30 ms), a 1 s liveliness lease,
    # reliable, KEEP_LAST 4 (the control topic: 1 per CPU), one partition per run.
    assert fast[1:6] == ("10000000", "1000000000", "1", "0", "4")
    assert slow[1:6] == ("30000000", "1000000000", "1", "0", "4")
    assert control[5] == "1"
    assert fast[6] == slow[6] == control[6] and fast[6].startswith("rcs/relay/")


@pytest.fixture(scope="module")
def rust_dds_builds(tmp_path_factory):
    """design -> the cargo release folder of its `--transport dds` Rust build."""
    base = tmp_path_factory.mktemp("dds_rust")
    cache: dict[Path, Path] = {}

    def get(design: Path) -> Path:
        if design not in cache:
            crate = base / design.stem
            generate(design, "rust", crate, "--transport", "dds")
            env = dict(os.environ, CARGO_TARGET_DIR=str(base / f"target-{design.stem}"), CARGO_TERM_COLOR="never")
            for folder in (crate, crate / "rcs_dds"):  # clippy lints the wrapper crate on its own
                for cmd in (["cargo", "build", "--offline", "--release"], ["cargo", "clippy", "--offline", "--release", "--", "-D", "warnings"]):
                    r = subprocess.run(cmd, cwd=folder, env=env, capture_output=True, text=True)
                    assert r.returncode == 0, r.stderr[-4000:]
                    assert not re.search(r"^warning", r.stderr, re.M), r.stderr[-4000:]
            files = [str(p) for p in crate.rglob("*.rs")]
            r = subprocess.run(["rustfmt", "--check", "--edition", "2021", *files], capture_output=True, text=True)
            assert r.returncode == 0, r.stdout[-4000:]
            cache[design] = base / f"target-{design.stem}" / "release"
        return cache[design]

    return get


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c[0].stem}/{c[1].stem}")
def test_rust_lockstep_trace_over_dds_equals_simulator(rust_dds_builds, dds_env, case, tmp_path):
    design, scn = case
    env, domain = dds_env
    trace = tmp_path / "rust-dds.jsonl"
    r = subprocess.run([str(launcher(rust_dds_builds(design))), "--lockstep", "--no-timing", "--domain", domain, "--scenario", str(event_file(design, scn)),
                        "--trace", str(trace)], capture_output=True, text=True, timeout=120, env=env, stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stderr
    want = sim_trace(design, scn, tmp_path)
    got = trace.read_bytes()
    assert got == want, first_difference(got, want)
    assert len(cpu_pids(r.stderr)) > 1


def test_rust_dds_build_keeps_the_controller_crate_free_of_unsafe_and_c(rust_dds_builds, tmp_path):
    crate = tmp_path / "crate"
    generate(RELAY, "rust", crate, "--transport", "dds")
    lib = (crate / "src" / "lib.rs").read_text()
    assert "#![no_std]" in lib and "#![forbid(unsafe_code)]" in lib
    assert not any(re.search(r"\bunsafe\s*(\{|fn\b|extern\b|impl\b)", p.read_text()) for p in (crate / "src").rglob("*.rs"))
    assert re.search(r"\bunsafe\s*\{", (crate / "rcs_dds" / "src" / "lib.rs").read_text())
    cargo = (crate / "Cargo.toml").read_text()
    assert 'rcs_dds = { path = "rcs_dds", optional = true }' in cargo and 'default = ["dds"]' in cargo
    assert {p.name for p in (crate / "rcs_dds" / "c").iterdir()} == {"rcs_dds.c", "rcs_dds.h", "rcs_link.h", "rcs_shm.h"}
    # The C file is the C target's, byte for byte: one definition of the protocol.
    c_build = tmp_path / "c"
    generate(RELAY, "c", c_build, "--transport", "dds")
    assert (crate / "rcs_dds" / "c" / "rcs_dds.c").read_bytes() == (c_build / "rcs_dds.c").read_bytes()
    shm = tmp_path / "shm"
    generate(RELAY, "rust", shm)
    assert not (shm / "rcs_dds").exists() and "rcs_dds" not in (shm / "Cargo.toml").read_text().split("[dependencies]")[1]
    r = subprocess.run([str(rust_dds_builds(RELAY) / "relay_fast"), "--run", "x", "--domain", "233"], capture_output=True, text=True, timeout=20)
    assert r.returncode == 2 and "--domain needs a DDS domain id from 0 to 232, not `233`" in r.stderr


@pytest.mark.parametrize("target", ["c", "rust"])
def test_dds_build_is_reproducible_and_every_file_says_generated(target, tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    generate(RELAY, target, a, "--transport", "dds")
    generate(RELAY, target, b, "--transport", "dds")
    files = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    assert all((a / f).read_bytes() == (b / f).read_bytes() for f in files)
    for f in files:
        assert "generated by rcsc - do not edit" in "\n".join((a / f).read_text(encoding="utf-8").splitlines()[:3]), f


def cpu_programs(design: Path) -> list[tuple[str, dict[str, str]]]:
    """Each CPU of the design, and the file name of its program per target
    (the targets' own naming: a long name is cut and given a digest)."""
    from rcsc.backends.c.target import CTarget
    from rcsc.backends.rust.target import RustTarget
    from rcsc.driver import check_path

    result = check_path(str(design))
    assert result.model is not None
    c, rust = CTarget(result.model).n, RustTarget(result.model).n
    return [(cpu, {"c": c.binary(cpu), "rust": rust.binary(cpu)}) for cpu in result.model.cpus]


@pytest.mark.parametrize("first", ["c", "rust"])
@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c[0].stem}/{c[1].stem}")
def test_c_and_rust_cpus_interoperate(dds_builds, rust_dds_builds, dds_env, case, first, tmp_path):
    """The first CPU in one language, the others in the other, started by
    hand: the merged trace is the simulator's."""
    design, scn = case
    env, domain = dds_env
    folders = {"c": dds_builds(design), "rust": rust_dds_builds(design)}
    other = "rust" if first == "c" else "c"
    run = f"mix-{first}-{os.getpid()}-{design.stem}-{scn.stem}"
    procs, parts = [], []
    for i, (cpu, programs) in enumerate(cpu_programs(design)):
        parts.append(tmp_path / f"cpu{i}.jsonl")
        lang = first if i == 0 else other
        procs.append((lang, start_cpu(folders[lang], programs[lang], run, env, domain, "--lockstep", "--no-timing",
                                      "--scenario", str(event_file(design, scn)), "--trace", str(parts[-1]))))
    for lang, p in procs:
        _, err = p.communicate(timeout=120)
        assert p.returncode == 0, f"{lang}: {err}"
    want = sim_trace(design, scn, tmp_path)
    got = merge(parts)
    assert got == want, first_difference(got, want)


KILL_SCN = """scenario "the servo CPU killed and started again"
cycles 600
at 1: MT.CUT(x0 = 20.0, x1 = 120.0, rpm = 3000.0, feed = 1200.0)
"""


@pytest.mark.parametrize("servo", ["c", "rust"])
def test_a_killed_cpu_started_again_resumes_the_exchange(dds_builds, rust_dds_builds, dds_env, servo, tmp_path):
    """Real time, each CPU by hand: SERVO_CPU is killed during the cut.  The
    planner keeps its heartbeat, AXIS's watchdog on age(x_pos) fires; SERVO_CPU
    started again joins the running timeline (its first cycle is the next
    release, not 1) and the planner's copies are fresh again."""
    env, domain = dds_env
    design = ROOT / "examples" / "machine_tool" / "machine_tool.rcs"
    folders = {"c": dds_builds(design), "rust": rust_dds_builds(design)}
    scn = tmp_path / "kill.scn"
    scn.write_text(KILL_SCN, encoding="utf-8")
    run = f"restart-{servo}-{os.getpid()}"
    common = ("--scenario", str(event_file(design, scn)), "--no-timing")
    plan_trace, first_trace, again_trace = tmp_path / "plan.jsonl", tmp_path / "servo1.jsonl", tmp_path / "servo2.jsonl"
    planner = start_cpu(folders["c"], "machine_tool_PLAN_CPU", run, env, domain, *common, "--trace", str(plan_trace))
    first = start_cpu(folders[servo], "machine_tool_SERVO_CPU", run, env, domain, *common, "--trace", str(first_trace))
    again = None
    try:
        time.sleep(2.0)
        assert first.poll() is None and planner.poll() is None
        os.kill(first.pid, signal.SIGKILL)
        first.communicate(timeout=10)
        time.sleep(1.0)
        again = start_cpu(folders[servo], "machine_tool_SERVO_CPU", run, env, domain, *common, "--trace", str(again_trace))
        _, err = planner.communicate(timeout=30)
        assert planner.returncode == 0, err
        _, err = again.communicate(timeout=30)
        assert again.returncode == 0, err
    finally:
        for p in (planner, first, again):
            if p is not None and p.poll() is None:
                p.kill()
                p.communicate()
    import json

    plan = [json.loads(x) for x in plan_trace.read_text().splitlines()]
    assert [j["cycle"] for j in plan] == list(range(1, 121)), "the planner kept its heartbeat: 120 cycles of 50 ms"
    again_lines = [json.loads(x) for x in again_trace.read_text().splitlines()]
    back_at = again_lines[0]["t"]
    assert again_lines[0]["cycle"] > 1 and again_lines[0]["t"] == (again_lines[0]["cycle"] - 1) * 10_000_000
    axis = [(j["t"], j["ctrl"]["AXIS"]) for j in plan]
    # The kill shows as the first copy older than a servo cycle (50 ms: a planner cycle).
    killed_at = next(t for t, a in axis if a["fields"]["pos_age"] > 50_000_000)
    assert 500_000_000 <= killed_at < back_at - 500_000_000, (killed_at, back_at)
    # While it is dead the copies age and the watchdog fires (STALE is 150 ms).
    stale = [(t, a) for t, a in axis if killed_at + 200_000_000 <= t < back_at]
    assert stale and all(a["fields"]["pos_age"] > 150_000_000 for _, a in stale)
    assert any(a["status"] == "ERROR" and a["rule"] == "W1" for _, a in stale)
    # Started again: the exchange resumes, the copies are fresh and x_pos moves again.
    after = [j for j in plan if j["t"] >= back_at + 200_000_000]
    assert after and all(j["ctrl"]["AXIS"]["fields"]["pos_age"] <= 50_000_000 for j in after)
    assert len({j["gm"]["x_pos"] for j in after}) > 3


def test_cmake_builds_the_dds_programs(dds_env, tmp_path):
    env, domain = dds_env
    out = tmp_path / "relay"
    generate(RELAY, "c", out, "--transport", "dds")
    for cmd in (["cmake", "-S", ".", "-B", "build"], ["cmake", "--build", "build"]):
        r = subprocess.run(cmd, cwd=out, capture_output=True, text=True)
        assert r.returncode == 0, r.stdout + r.stderr
    scn, trace = MC / "relay_run.scn", tmp_path / "t.jsonl"
    r = subprocess.run([str(out / "build" / "run_relay"), "--lockstep", "--no-timing", "--domain", domain, "--scenario", str(event_file(RELAY, scn)), "--trace", str(trace)],
                       capture_output=True, text=True, timeout=60, env=env, stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stderr
    assert trace.read_bytes() == sim_trace(RELAY, scn, tmp_path)


@pytest.mark.parametrize("target", ["c", "rust"])
def test_realtime_run_over_dds_equals_simulator(dds_builds, rust_dds_builds, dds_env, target, tmp_path):
    """2 s of a 10 ms design on the clock over DDS (the start agreed on the
    control topic): the simulator's trace, unless the host missed a deadline
    (then up to three runs, as for shared memory)."""
    env, domain = dds_env
    folder = dds_builds(TWOCPU) if target == "c" else rust_dds_builds(TWOCPU)
    scn = tmp_path / "two_seconds.scn"
    scn.write_text((MC / "twocpu_run.scn").read_text().replace("cycles 40", "cycles 200"))
    reports = []
    for attempt in range(3):
        trace = tmp_path / f"rt{attempt}.jsonl"
        t0 = time.monotonic()
        r = subprocess.run([str(launcher(folder)), "--domain", domain, "--scenario", str(event_file(TWOCPU, scn)), "--trace", str(trace)],
                           capture_output=True, text=True, timeout=120, env=env, stdin=subprocess.DEVNULL)
        elapsed = time.monotonic() - t0
        assert r.returncode == 0, r.stderr
        assert elapsed >= 2.0, f"a real-time run of 200 ticks of 10 ms took {elapsed:.2f} s"
        problems = _realtime_report(r.stderr)
        if not problems:
            want = sim_trace(TWOCPU, scn, tmp_path)
            got = trace.read_bytes()
            assert got == want, first_difference(got, want)
            return
        reports.append(f"run {attempt + 1}: " + "; ".join(problems))
    pytest.fail("every real-time run missed its timing, so no trace was compared: " + " | ".join(reports))
