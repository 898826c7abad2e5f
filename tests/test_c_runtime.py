"""The design-independent C Main Program (backends/c/runtime/rcs_runtime.c).

Built with a hand-made design (tests/c/runtime_fixture.c, described at its
top) under the strict warning flags, with gcc and, when installed, clang; run
on scenarios written here.  Checks the exact trace lines (and that they are
what rcsc/sim/trace.py writes for the same values), the exact event-file errors,
the options, the timing table, SIGINT, the console on a pseudo-terminal,
real-time mode refused without privileges, and a clean run under UBSan and
ASan.
"""

from __future__ import annotations

import json
import os
import pty
import re
import select
import shutil
import signal
import subprocess
import tempfile
import termios
import time
from pathlib import Path

import pytest

from event_cases import COMPUTED, event_errors, events, fixture_hash, mutations
from rcsc.sim import trace

ROOT = Path(__file__).resolve().parents[1]
RUNTIME = ROOT / "backends" / "c" / "runtime"
FIXTURE = ROOT / "tests" / "c" / "runtime_fixture.c"

STRICT = [
    "-std=c99",
    "-Wall",
    "-Wextra",
    "-Wpedantic",
    "-Wconversion",
    "-Wshadow",
    "-Wsign-conversion",
    "-Werror",
    "-ffp-contract=off",
]
SANITIZE = ["-O1", "-g", "-fno-omit-frame-pointer", "-fsanitize=undefined,address", "-fno-sanitize-recover=all"]
# Both compilers are required (.ci/run installs clang): a missing one fails, never skips.
COMPILERS = ["gcc", "clang"]


def _compile(cc: str, extra: list[str], out: Path) -> Path:
    cmd = [cc, *STRICT, *extra, f"-I{RUNTIME}", str(RUNTIME / "rcs_runtime.c"), str(RUNTIME / "rcs_shm.c"), str(FIXTURE), "-o", str(out)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0 and r.stderr == "", f"{' '.join(cmd)}\n{r.stderr}"
    return out


@pytest.fixture(scope="module", params=COMPILERS)
def exe(request, tmp_path_factory) -> Path:
    return _compile(request.param, ["-O2"], tmp_path_factory.mktemp("crt") / f"fixture_{request.param}")


@pytest.fixture(scope="module")
def san_exe(tmp_path_factory) -> Path:
    return _compile(COMPILERS[0], SANITIZE, tmp_path_factory.mktemp("crt_san") / "fixture_san")


def run(exe: Path, tmp_path: Path, scenario: str | bytes | None, *args: str, name: str = "s.events", env=None):
    """The fixture on a scenario (text: compiled by `rcsc events` first) or on an event file's bytes."""
    cmd = [str(exe), "--fast", "--no-console", "--no-timing"]
    if scenario is not None:
        path = tmp_path / name
        path.write_bytes(scenario if isinstance(scenario, bytes) else events(scenario).encode("utf-8"))
        cmd += ["--scenario", str(path)]
    cmd += list(args)
    return subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=20, env=env)


# ---- traces ----------------------------------------------------------------------

GOOD = """\
// A run of the fixture design.
scenario "fixture run"
cycles 5
at 1: TOP.INIT()
at 1: door = true          /* an input */
at 2: TOP.MOVE(speed = 0.1, dt = 2.5e-3 s, mode = Mode.RUN, to = Pose(x = 1.5, y = -2, mode = Mode.HALT),)
at 2: limit = -0x10
at 2: gain = 3
expect at 2: TOP.state == MOVING and not TOP.error
expect within 1..5: TOP.AT_GOAL
at 4: TOP.SET(7, -9_223_372_036_854_775_808)
at 4: gain = 1.7976931348623157e308
at 5: TOP.MOVE(-MAX_SPEED, STEP_T, FAST, HOME)
expect final: TOP.done
"""


def _sub(ticks: int) -> str:
    return f'"SUB":{{"echo":0,"status":"UNINITIALIZED","verb":"","state":"","rule":"","error_code":0,"fields":{{"ticks":{ticks}}}}}'


# Cycle 2 shows that a cycle's inputs are applied before its commands: the
# fixture copies gm.limit into error_code when a command arrives.
GOOD_TRACE = [
    '{"cycle":1,"gm":{"pose":{"x":0,"y":0,"mode":"IDLE"},"mode":"IDLE","door":true,"limit":0,"gain":0},'
    '"ctrl":{"TOP":{"echo":1,"status":"DONE","verb":"INIT","state":"done","rule":"N0","error_code":0,'
    '"fields":{"speed":0,"dt":0,"target":{"x":0,"y":0,"mode":"IDLE"},"n":0,"big":0,"ratio":"nan","door_seen":true}},'
    + _sub(1) + "}}",
    '{"cycle":2,"gm":{"pose":{"x":0,"y":0,"mode":"IDLE"},"mode":"RUN","door":true,"limit":-16,"gain":3},'
    '"ctrl":{"TOP":{"echo":2,"status":"EXEC","verb":"MOVE","state":"MOVING","rule":"N0","error_code":-16,'
    '"fields":{"speed":0.10000000000000001,"dt":2500000,"target":{"x":1.5,"y":-2,"mode":"HALT"},"n":0,"big":0,'
    '"ratio":10,"door_seen":true}},' + _sub(2) + "}}",
    '{"cycle":3,"gm":{"pose":{"x":1.5,"y":-2,"mode":"HALT"},"mode":"RUN","door":true,"limit":-16,"gain":3},'
    '"ctrl":{"TOP":{"echo":2,"status":"AT_GOAL","verb":"MOVE","state":"MOVING","rule":"Q\\"1\\\\\\u0001","error_code":-16,'
    '"fields":{"speed":0.10000000000000001,"dt":2500000,"target":{"x":1.5,"y":-2,"mode":"HALT"},"n":0,"big":0,'
    '"ratio":10,"door_seen":true}},' + _sub(3) + "}}",
    '{"cycle":4,"gm":{"pose":{"x":1.5,"y":-2,"mode":"HALT"},"mode":"RUN","door":true,"limit":-16,"gain":1.7976931348623157e+308},'
    '"ctrl":{"TOP":{"echo":3,"status":"DONE","verb":"SET","state":"done","rule":"N0","error_code":-16,'
    '"fields":{"speed":0.10000000000000001,"dt":2500000,"target":{"x":1.5,"y":-2,"mode":"HALT"},"n":7,'
    '"big":-9223372036854775808,"ratio":10,"door_seen":true}},' + _sub(4) + "}}",
    '{"cycle":5,"gm":{"pose":{"x":1.5,"y":-2,"mode":"HALT"},"mode":"RUN","door":true,"limit":-16,"gain":1.7976931348623157e+308},'
    '"ctrl":{"TOP":{"echo":4,"status":"EXEC","verb":"MOVE","state":"MOVING","rule":"N0","error_code":-16,'
    '"fields":{"speed":-12.5,"dt":250000000,"target":{"x":1,"y":2,"mode":"RUN"},"n":7,"big":-9223372036854775808,'
    '"ratio":"-inf","door_seen":true}},' + _sub(5) + "}}",
]

# Number forms: hex, underscores, exponents, -0 (an integer: +0.0) and -0.0,
# exact durations from decimals, negated constants (u32 wraps like rcsc's
# folding), arguments by name in any order, two commands in one cycle (the
# second supersedes: serial 3 then 4).
VALUES = """\
cycles 4
at 1: gain = 0x10
at 1: limit = -2147483648
at 1: TOP.MOVE(speed = 1_000.5, dt = 0x10 ms, mode = FAST, to = Pose(-0, -0.0, Mode.IDLE))
at 2: gain = 2.5e-3
at 2: TOP.MOVE(to = HOME, mode = Mode.HALT, dt = 9_223_372_036.854_775_807 s, speed = -0)
at 3: TOP.INIT()
at 3: TOP.SET(n = -NEG_U, big = -(9_223_372_036_854_775_807))
at 4: TOP.MOVE(2.5e-3, 25e-2 ms, Mode.RUN, Pose(y = 1e-3, x = 1, mode = Mode.RUN))
at 4: door = true
expect always: TOP.verb == MOVE or (TOP.done and TOP.n == 4294967291)
"""

VALUES_TRACE = [
    '{"cycle":1,"gm":{"pose":{"x":0,"y":0,"mode":"IDLE"},"mode":"RUN","door":false,"limit":-2147483648,"gain":16},'
    '"ctrl":{"TOP":{"echo":1,"status":"EXEC","verb":"MOVE","state":"MOVING","rule":"N0","error_code":-2147483648,'
    '"fields":{"speed":1000.5,"dt":16000000,"target":{"x":0,"y":-0,"mode":"IDLE"},"n":0,"big":0,'
    '"ratio":0.00099950024987506244,"door_seen":false}},' + _sub(1) + "}}",
    '{"cycle":2,"gm":{"pose":{"x":0,"y":0,"mode":"IDLE"},"mode":"HALT","door":false,"limit":-2147483648,'
    '"gain":0.0025000000000000001},"ctrl":{"TOP":{"echo":2,"status":"EXEC","verb":"MOVE","state":"MOVING","rule":"N0",'
    '"error_code":-2147483648,"fields":{"speed":0,"dt":9223372036854775807,"target":{"x":1,"y":2,"mode":"RUN"},"n":0,'
    '"big":0,"ratio":"nan","door_seen":false}},' + _sub(2) + "}}",
    '{"cycle":3,"gm":{"pose":{"x":0,"y":0,"mode":"IDLE"},"mode":"HALT","door":false,"limit":-2147483648,'
    '"gain":0.0025000000000000001},"ctrl":{"TOP":{"echo":4,"status":"DONE","verb":"SET","state":"done","rule":"N0",'
    '"error_code":-2147483648,"fields":{"speed":0,"dt":9223372036854775807,"target":{"x":1,"y":2,"mode":"RUN"},'
    '"n":4294967291,"big":-9223372036854775807,"ratio":"nan","door_seen":false}},' + _sub(3) + "}}",
    '{"cycle":4,"gm":{"pose":{"x":0,"y":0,"mode":"IDLE"},"mode":"RUN","door":true,"limit":-2147483648,'
    '"gain":0.0025000000000000001},"ctrl":{"TOP":{"echo":5,"status":"EXEC","verb":"MOVE","state":"MOVING","rule":"N0",'
    '"error_code":-2147483648,"fields":{"speed":0.0025000000000000001,"dt":250000,"target":{"x":1,"y":0.001,"mode":"RUN"},'
    '"n":4294967291,"big":-9223372036854775807,"ratio":400,"door_seen":true}},' + _sub(4) + "}}",
]


def test_trace_of_a_scenario(exe, tmp_path):
    r = run(exe, tmp_path, GOOD, "--trace", "-")
    assert (r.returncode, r.stderr) == (0, "")
    assert r.stdout == "".join(line + "\n" for line in GOOD_TRACE)


def test_trace_of_value_forms(exe, tmp_path):
    r = run(exe, tmp_path, VALUES, "--trace", "-")
    assert (r.returncode, r.stderr) == (0, "")
    assert r.stdout == "".join(line + "\n" for line in VALUES_TRACE)


def _fixture_design():
    """The fixture's declarations as rcsc/sim/trace.py sees a design."""
    from types import SimpleNamespace as NS

    from rcsc.semantics.types import BOOL, DURATION, F64, I32, I64, U32, EnumType, RecordType

    mode = EnumType("Mode", ("IDLE", "RUN", "HALT"))
    pose = RecordType("Pose", (("x", F64), ("y", F64), ("mode", mode)))
    gm = {"pose": pose, "mode": mode, "door": BOOL, "limit": I32, "gain": F64}
    top = {"speed": F64, "dt": DURATION, "target": pose, "n": U32, "big": I64, "ratio": F64, "door_seen": BOOL}
    return NS(
        gm={n: NS(type=t) for n, t in gm.items()},
        controllers={
            "TOP": NS(status_fields={n: NS(type=t) for n, t in top.items()}),
            "SUB": NS(status_fields={"ticks": NS(type=I32)}),
        },
    )


@pytest.mark.parametrize("line", GOOD_TRACE + VALUES_TRACE)
def test_trace_lines_are_what_trace_py_writes(line):
    """Read back, the values give the same bytes through rcsc/sim/trace.py's jsonl_line."""
    obj = json.loads(line, parse_int=lambda s: -0.0 if s == "-0" else int(s))  # f64 -0 prints as -0
    ctrl = {n: trace.CtrlSnapshot(**c) for n, c in obj["ctrl"].items()}
    assert trace.jsonl_line(_fixture_design(), trace.Snapshot(obj["cycle"], obj["gm"], ctrl)) == line


def test_cycles_option_overrides_the_scenario(exe, tmp_path):
    r = run(exe, tmp_path, GOOD, "--trace", "-", "--cycles", "2")
    assert r.stdout == "".join(line + "\n" for line in GOOD_TRACE[:2])
    r = run(exe, tmp_path, GOOD, "--trace", "-", "--cycles", "7")
    lines = r.stdout.splitlines()
    assert lines[:5] == GOOD_TRACE
    assert [json.loads(x)["cycle"] for x in lines] == list(range(1, 8))
    # cycle 6: the second MOVE arrives (HOME) and reports AT_GOAL
    assert '"gm":{"pose":{"x":1,"y":2,"mode":"RUN"}' in lines[5] and '"status":"AT_GOAL"' in lines[5]


def test_no_trace_without_the_option(exe, tmp_path):
    r = run(exe, tmp_path, GOOD)
    assert (r.returncode, r.stdout, r.stderr) == (0, "", "")


def test_trace_to_a_file(exe, tmp_path):
    out = tmp_path / "run.jsonl"
    r = run(exe, tmp_path, GOOD, "--trace", str(out))
    assert (r.returncode, r.stdout, r.stderr) == (0, "", "")
    assert out.read_text() == "".join(line + "\n" for line in GOOD_TRACE)


# ---- event files ----------------------------------------------------------------
# The scenario grammar and its checks are rcsc's (rcsc/front/scenario.py); the
# Main Program reads the event file `rcsc events` makes of it (docs/events.md).

def test_fixture_carries_the_interface_hash_of_its_design():
    """The hand-made tables carry the hash rcsc computes for the same declarations."""
    assert f'"{fixture_hash()}"' in FIXTURE.read_text(encoding="utf-8")


def test_computed_values(exe, tmp_path):
    r = run(exe, tmp_path, COMPUTED, "--trace", "-")
    assert (r.returncode, r.stderr) == (0, "")
    first = json.loads(r.stdout.splitlines()[0])
    assert first["gm"]["gain"] == 9.375
    assert first["ctrl"]["TOP"]["fields"]["speed"] == 9.375 and first["ctrl"]["TOP"]["fields"]["dt"] == 251000000
    assert first["ctrl"]["TOP"]["fields"]["target"] == {"x": 2, "y": 3, "mode": "HALT"}


@pytest.fixture(scope="module")
def rcsc_design():
    from event_cases import fixture_model

    return fixture_model()


def _rcsc_first_error(design, text: str):
    from rcsc.diagnostics import Diagnostics
    from rcsc.front.scenario import text_to_scenario
    from rcsc.front.source import SourceFile

    diags = Diagnostics()
    sc = text_to_scenario(SourceFile("s.scn", text), design, diags)
    return sc, (f"{diags.errors[0].span.line}:{diags.errors[0].span.col}" if diags.errors else None)


def test_rcsc_reads_the_same_values(rcsc_design):
    sc, where = _rcsc_first_error(rcsc_design, GOOD)
    assert where is None
    assert [(c.cycle, c.verb, c.args) for c in sc.commands] == [
        (1, "INIT", {}),
        (2, "MOVE", {"speed": 0.1, "dt": 2500000, "mode": "RUN", "to": {"x": 1.5, "y": -2.0, "mode": "HALT"}}),
        (4, "SET", {"n": 7, "big": -9223372036854775808}),
        (5, "MOVE", {"speed": -12.5, "dt": 250000000, "mode": "RUN", "to": {"x": 1.0, "y": 2.0, "mode": "RUN"}}),
    ]
    assert [(i.cycle, i.var, i.value) for i in sc.inputs] == [(1, "door", True), (2, "limit", -16), (2, "gain", 3.0), (4, "gain", 1.7976931348623157e308)]
    sc, where = _rcsc_first_error(rcsc_design, VALUES)
    assert where is None
    assert [(c.cycle, c.verb, c.args) for c in sc.commands] == [
        (1, "MOVE", {"speed": 1000.5, "dt": 16000000, "mode": "RUN", "to": {"x": 0.0, "y": -0.0, "mode": "IDLE"}}),
        (2, "MOVE", {"speed": 0.0, "dt": 9223372036854775807, "mode": "HALT", "to": {"x": 1.0, "y": 2.0, "mode": "RUN"}}),
        (3, "INIT", {}),
        (3, "SET", {"n": 4294967291, "big": -9223372036854775807}),
        (4, "MOVE", {"speed": 0.0025, "dt": 250000, "mode": "RUN", "to": {"x": 1.0, "y": 0.001, "mode": "RUN"}}),
    ]


@pytest.mark.parametrize("name,text,message", event_errors(), ids=[c[0] for c in event_errors()])
def test_event_file_errors(exe, tmp_path, name, text, message):
    r = run(exe, tmp_path, text, "--trace", "-", name=f"{name}.events")
    assert (r.returncode, r.stdout) == (2, "")
    assert r.stderr == f"{tmp_path / (name + '.events')}:{message}\n"


def test_unreadable_event_file(exe, tmp_path):
    r = subprocess.run([str(exe), "--scenario", str(tmp_path / "missing.events")], capture_output=True, text=True)
    assert (r.returncode, r.stderr) == (2, f"{tmp_path / 'missing.events'}: error: cannot read the event file: No such file or directory\n")


def test_every_truncation_is_refused(exe, tmp_path):
    """Each proper prefix of a good event file: exit 2 with one error line, never a crash."""
    data = events(GOOD).encode("utf-8")
    for n in range(len(data)):
        r = run(exe, tmp_path, data[:n], "--trace", "-")
        assert (r.returncode, r.stdout, r.stderr.count("\n")) == (2, "", 1), (n, r.stderr)
        assert ": error: " in r.stderr


# ---- options ---------------------------------------------------------------------


def test_help(exe):
    r = subprocess.run([str(exe), "--help"], capture_output=True, text=True)
    assert r.returncode == 0 and r.stderr == ""
    assert r.stdout.startswith(f"usage: {exe} [options]\nMain Program of design fixture, CPU MAIN (heartbeat 1000.0 us).\n")
    for opt in ("--fast", "--cycles N", "--realtime", "--scenario FILE", "--trace FILE", "--no-timing", "--no-console", "--help"):
        assert f"\n  {opt} " in r.stdout


@pytest.mark.parametrize(
    "args, message",
    [
        (["--bogus"], "rcs: unknown option `--bogus`"),
        (["--cycles", "abc"], "rcs: --cycles needs a positive whole number, not `abc`"),
        (["--cycles=0"], "rcs: --cycles needs a positive whole number, not `0`"),
        (["--cycles", "99999999999999999999999"], "rcs: --cycles needs a positive whole number, not `99999999999999999999999`"),
        (["--scenario"], "rcs: --scenario needs a value"),
        (["--fast=1"], "rcs: unknown option `--fast=1`"),
    ],
)
def test_bad_options(exe, args, message):
    r = subprocess.run([str(exe), *args], capture_output=True, text=True)
    assert (r.returncode, r.stdout) == (2, "")
    assert r.stderr.startswith(message + "\nusage: ")


def test_timing_table_and_heartbeat(exe):
    t0 = time.monotonic()
    r = subprocess.run([str(exe), "--cycles", "20", "--no-console"], capture_output=True, text=True, stdin=subprocess.DEVNULL)
    elapsed = time.monotonic() - t0
    assert r.returncode == 0 and r.stdout == ""
    assert elapsed >= 0.019  # 20 cycles of 1 ms on absolute deadlines
    # (a step preempted past its budget adds an overrun line while running: tests/test_perfstat.py)
    lines = [x for x in r.stderr.splitlines() if not x.startswith("rcs: overrun: ")]
    assert lines[0] == "rcs: timing of fixture on MAIN, 20 cycles, heartbeat 1000.0 us"
    assert lines[1].split() == ["controller", "budget", "last", "min", "max", "mean", "overruns"]
    t = r"\d+\.\d{3} us"
    assert re.fullmatch(rf"SUB +- +{t} +{t} +{t} +{t} +0", lines[2]), lines[2]  # schedule order: SUB, TOP
    assert re.fullmatch(rf"TOP +1000\.000 us +{t} +{t} +{t} +{t} +\d+", lines[3]), lines[3]
    assert re.fullmatch(r"cycles: 20, max work \d+\.\d us of the 1000\.0 us period, \d+ cycle overruns?", lines[4]), lines[4]
    assert len(lines) == 5


def test_sigint_finishes_the_cycle_and_prints_the_table(exe, tmp_path):
    out = tmp_path / "run.jsonl"
    p = subprocess.Popen(
        [str(exe), "--fast", "--no-console", "--trace", str(out)],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(0.3)
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=10)
    assert p.returncode == 0 and stdout == ""
    stderr = "".join(x for x in stderr.splitlines(keepends=True) if not x.startswith("rcs: overrun: "))
    m = re.match(r"rcs: timing of fixture on MAIN, (\d+) cycles, heartbeat 1000\.0 us\n", stderr)
    assert m, stderr
    text = out.read_text()
    assert text.endswith("\n")
    cycles = [json.loads(line)["cycle"] for line in text.splitlines()]
    assert cycles == list(range(1, int(m.group(1)) + 1)) and len(cycles) > 1


def _read_until(fd: int, pattern: str, buf: list[str], timeout: float = 5.0) -> re.Match:
    deadline = time.monotonic() + timeout
    while True:
        m = re.search(pattern, buf[0])
        if m:
            buf[0] = buf[0][m.end():]
            return m
        left = deadline - time.monotonic()
        assert left > 0, f"timed out waiting for {pattern!r}; got {buf[0]!r}"
        ready, _, _ = select.select([fd], [], [], left)
        if ready:
            chunk = os.read(fd, 4096)
            assert chunk, f"stderr closed waiting for {pattern!r}; got {buf[0]!r}"
            buf[0] += chunk.decode()


def test_console_pause_step_quit(exe, tmp_path):
    out = tmp_path / "run.jsonl"
    master, slave = pty.openpty()
    before = termios.tcgetattr(slave)
    p = subprocess.Popen([str(exe), "--no-timing", "--trace", str(out)], stdin=slave, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        err = p.stderr.fileno()
        buf = [""]
        _read_until(err, r"rcs: console: p or space pause/resume, s single step while paused, q quit\n", buf)
        raw = termios.tcgetattr(slave)
        assert not raw[3] & (termios.ICANON | termios.ECHO)  # keys one by one, no echo
        os.write(master, b"p")
        n = int(_read_until(err, r"rcs: paused after cycle (\d+) \(p/space resume, s step, q quit\)\n", buf).group(1))
        time.sleep(0.05)
        os.write(master, b"s")
        time.sleep(0.1)
        os.write(master, b" ")  # space resumes: exactly one cycle ran while paused
        _read_until(err, rf"rcs: resumed after cycle {n + 1}\n", buf)
        os.write(master, b"q")
        assert p.wait(timeout=5) == 0
        assert len(out.read_text().splitlines()) >= n + 1
        after = termios.tcgetattr(slave)
        assert after[3] == before[3]  # the terminal is restored
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
        p.stderr.close()
        os.close(master)
        os.close(slave)


def test_realtime_refused_without_privileges(exe):
    """--realtime never runs silently without real time: a clear message and status 2."""
    cmd = [str(exe), "--realtime", "--fast", "--cycles", "1", "--no-console", "--no-timing"]
    tmpdir = None
    if os.geteuid() == 0:
        assert shutil.which("setpriv"), "setpriv (util-linux) is needed to drop root's privileges for this test"
        tmpdir = tempfile.mkdtemp()
        os.chmod(tmpdir, 0o755)
        copy = Path(tmpdir) / "fixture"
        shutil.copy(exe, copy)
        os.chmod(copy, 0o755)
        cmd = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", "--inh-caps=-all", str(copy), *cmd[1:]]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    finally:
        if tmpdir:
            shutil.rmtree(tmpdir)
    if r.returncode == 0 and os.geteuid() != 0:
        pytest.skip("this user may run SCHED_FIFO with locked memory")
    assert (r.returncode, r.stdout) == (2, "")
    assert r.stderr in (
        "rcs: --realtime: sched_setscheduler(SCHED_FIFO) not permitted (needs root or CAP_SYS_NICE / an rtprio limit)\n",
        "rcs: --realtime: mlockall(MCL_CURRENT|MCL_FUTURE) failed: Cannot allocate memory (needs root or "
        "CAP_IPC_LOCK, or a large enough memlock limit: ulimit -l)\n",
    )


# ---- sanitizers ------------------------------------------------------------------


def test_clean_under_ubsan_and_asan(san_exe, tmp_path):
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1:abort_on_error=0", UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1")
    r = run(san_exe, tmp_path, GOOD, "--trace", "-", env=env)
    assert (r.returncode, r.stderr) == (0, "")
    assert r.stdout == "".join(line + "\n" for line in GOOD_TRACE)
    r = run(san_exe, tmp_path, VALUES, "--trace", "-", env=env)
    assert (r.returncode, r.stderr) == (0, "")
    assert r.stdout == "".join(line + "\n" for line in VALUES_TRACE)
    for name, text, message in event_errors():
        r = run(san_exe, tmp_path, text, name=f"{name}.events", env=env)
        assert (r.returncode, r.stderr) == (2, f"{tmp_path / (name + '.events')}:{message}\n")
    data = events(GOOD).encode("utf-8")
    for n in range(0, len(data), 7):
        r = run(san_exe, tmp_path, data[:n], env=env)
        assert r.returncode == 2 and r.stderr.count("\n") == 1, (n, r.stderr)
    for k, bad in enumerate(mutations(events(GOOD).encode("utf-8"), 150)):
        r = run(san_exe, tmp_path, bad, "--trace", "-", env=env)
        # a mutation may still be a valid file (another value): it runs, else one error line
        assert (r.returncode, r.stderr.count("\n")) in ((0, 0), (2, 1)), (k, bad, r.stderr)
        assert r.returncode == 0 or ": error: " in r.stderr
    r = subprocess.run([str(san_exe), "--cycles", "3", "--no-console"], capture_output=True, text=True, env=env, stdin=subprocess.DEVNULL)
    table = "".join(x for x in r.stderr.splitlines(keepends=True) if not x.startswith("rcs: overrun: "))
    assert r.returncode == 0 and table.startswith("rcs: timing of fixture on MAIN, 3 cycles")
    r = subprocess.run([str(san_exe), "--bogus"], capture_output=True, text=True, env=env)
    assert r.returncode == 2 and r.stderr.startswith("rcs: unknown option `--bogus`\nusage: ")
