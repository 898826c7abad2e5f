"""`rcsc console` against a running compiled Main Program (C and Rust).

The Main Program runs with `--run ID` (it publishes its operator segment,
docs/console.md); `rcsc console DESIGN --run ID` attaches, sends operator
commands in the scenario syntax (computed values included), pauses, steps and
resumes the whole program, pauses and single-steps one controller (PR_MODE),
and prints status tables.  Each target is driven once through pipes (no TTY)
and once on a pty.  Bad console input gets a diagnostic with a code, never
a traceback.
"""

from __future__ import annotations

import os
import pty
import re
import select
import subprocess
import sys
import time
import uuid
from pathlib import Path

import pytest

from c_build import ROOT, Builds

SUBMARINE = ROOT / "examples" / "submarine" / "submarine.rcs"
RCSC = [sys.executable, "-m", "rcsc"]
TARGETS = ("c", "rust")


@pytest.fixture(scope="module")
def builds(tmp_path_factory) -> Builds:
    return Builds(tmp_path_factory.mktemp("console_builds"))


def main_program(builds: Builds, target: str) -> Path:
    return builds.c_binary(SUBMARINE, "gcc-O2") if target == "c" else builds.rust_binary(SUBMARINE, "release")


class Running:
    """A Main Program started with `--run ID` (killed at the end if still running)."""

    def __init__(self, exe: Path, *args: str) -> None:
        self.run = f"t{uuid.uuid4().hex[:10]}"
        self.proc = subprocess.Popen([str(exe), "--run", self.run, "--no-timing", *args], stdin=subprocess.DEVNULL,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        seg = Path("/dev/shm") / f"rcs-submarine-{self.run}.console"
        give_up = time.monotonic() + 10
        while not seg.exists() and self.proc.poll() is None and time.monotonic() < give_up:
            time.sleep(0.01)
        assert seg.exists(), f"no operator segment: {self.proc.poll()} {self.proc.stderr.read() if self.proc.poll() is not None else ''}"

    def __enter__(self) -> "Running":
        return self

    def __exit__(self, *exc) -> None:
        # SIGTERM, as an operator or a service manager stops a Main Program:
        # it finishes the cycle and removes its operator segment.  SIGKILL
        # only if it does not end (a killed program cannot remove the
        # segment, which would stay in /dev/shm after the suite).
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
        self.proc.wait(timeout=10)
        for stream in (self.proc.stdout, self.proc.stderr):
            stream.close()
        if exc[0] is None:
            assert not (Path("/dev/shm") / f"rcs-submarine-{self.run}.console").exists(), "the operator segment was left behind"


def console_pipes(run: str, script: str, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([*RCSC, "console", str(SUBMARINE), "--run", run, *extra], input=script, capture_output=True,
                          text=True, timeout=120, cwd=ROOT)


def tables(out: str) -> list[dict[str, dict[str, str]]]:
    """The status tables printed in `out`: per table, controller -> column -> value."""
    found = []
    lines = out.splitlines()
    for i, line in enumerate(lines):
        if not line.startswith("controller "):
            continue
        cols = line.split()
        table = {}
        for row in lines[i + 1:]:
            if row.startswith("cycle "):
                table["_program"] = {"line": row}
                break
            vals = row.split()
            table[vals[0]] = dict(zip(cols, vals))
        found.append(table)
    return found


SCRIPT = """\
status
SM.INIT()
step 5
status
SM.TRANSIT(speed = MAX_AHEAD_KNOTS * 0.5, leg_time = 60 s)
pause TB
step 3
status
step TB 2
step 3
status
run TB
step 2
status
quit
"""


def check_session(out: str) -> None:
    t = tables(out)
    assert len(t) == 5, out
    # Paused before cycle 1: nothing has run.
    assert t[0]["SM"]["status"] == "UNINITIALIZED" and t[0]["_program"]["line"].startswith("cycle 0, paused")
    # The command and five single steps: the INIT cascade is done.
    assert (t[1]["SM"]["verb"], t[1]["SM"]["status"], t[1]["TB"]["status"]) == ("INIT", "DONE", "DONE")
    assert t[1]["_program"]["line"].startswith("cycle 5, paused") and t[1]["SM"]["steps"] == "5"
    # The timing figures are the window since the controller took INIT (cycle 1).
    assert (t[0]["SM"]["since"], t[1]["SM"]["since"]) == ("0", "1")
    # A computed argument reached SM; TB, paused, was not stepped (its buffers kept INIT/DONE).
    assert (t[2]["SM"]["verb"], t[2]["SM"]["status"]) == ("TRANSIT", "EXEC")
    assert (t[2]["TB"]["mode"], t[2]["TB"]["steps"], t[2]["TB"]["verb"]) == ("paused", "5", "INIT")
    assert t[2]["SM"]["steps"] == "8"
    # `step TB 2` lets it run twice in the next three cycles, then it is held again.
    assert (t[3]["TB"]["steps"], t[3]["TB"]["mode"], t[3]["TB"]["verb"]) == ("7", "paused", "AHEAD")
    assert t[3]["SM"]["steps"] == "11"
    # `run TB`: stepped every cycle again.
    assert (t[4]["TB"]["mode"], t[4]["TB"]["steps"], t[4]["SM"]["steps"]) == ("run", "9", "13")
    assert float(t[4]["SM"]["max_us"]) > 0 and t[4]["SM"]["budget_us"] == "1000.000"


@pytest.mark.parametrize("target", TARGETS)
def test_console_through_pipes(builds: Builds, target: str) -> None:
    exe = main_program(builds, target)
    with Running(exe, "--paused") as prog:
        r = console_pipes(prog.run, SCRIPT)
        assert r.returncode == 0, r.stderr
        assert "Traceback" not in r.stdout + r.stderr
        check_session(r.stdout)
        assert prog.proc.wait(timeout=10) == 0  # `quit` ends the Main Program
    assert not (Path("/dev/shm") / f"rcs-submarine-{prog.run}.console").exists()


def read_until(fd: int, marker: str, timeout: float = 30.0) -> str:
    buf = b""
    give_up = time.monotonic() + timeout
    while marker.encode() not in buf:
        left = give_up - time.monotonic()
        assert left > 0, f"no {marker!r} in {buf.decode(errors='replace')!r}"
        ready, _, _ = select.select([fd], [], [], left)
        if ready:
            try:
                chunk = os.read(fd, 65536)
            except OSError:
                break
            if not chunk:
                break
            buf += chunk
    return buf.decode(errors="replace").replace("\r\n", "\n")


@pytest.mark.parametrize("target", TARGETS)
def test_console_on_a_pty(builds: Builds, target: str) -> None:
    exe = main_program(builds, target)
    with Running(exe, "--paused") as prog:
        master, slave = pty.openpty()
        con = subprocess.Popen([*RCSC, "console", str(SUBMARINE), "--run", prog.run, "--color", "never"], stdin=slave,
                               stdout=slave, stderr=slave, cwd=ROOT, close_fds=True)
        os.close(slave)
        try:
            out = read_until(master, "> ")
            assert "rcsc console: submarine on MAIN" in out and "(paused)" in out
            transcript = ""
            for line in SCRIPT.splitlines()[:-1]:
                os.write(master, (line + "\n").encode())
                transcript += read_until(master, "\n> ")
            os.write(master, b"step NOPE 0\n")
            bad = read_until(master, "\n> ")
            os.write(master, b"exit\n")
            assert con.wait(timeout=30) == 0
        finally:
            if con.poll() is None:
                con.kill()
            os.close(master)
        check_session(transcript)
        assert "error[E0813]" in bad and "Traceback" not in transcript + bad
        # `exit` leaves the console; the Main Program stays paused and running.
        assert prog.proc.poll() is None


BAD_LINES = [
    ("step 0", "E0812"),
    ("pause SM now", "E0812"),
    ("pause NOPE", "E0813"),
    ("at 3: SM.INIT()", "E0814"),
    ("freeze TB", "E0814"),
    ("TB.INIT()", "E0700"),
    ("SM.TRANSIT(speed = 99.0 * 2, leg_time = 1 s)", "E0206"),
    ("SM.FLY()", "E0105"),
    ("SM.INIT(", "E0001"),
    # Digits that str.isdigit accepts and int() refuses or reads otherwise.
    ("step \u00b2", "E0812"),
    ("step \u0663", "E0812"),
    ("stop", "E0814"),
    ("stop MAIN", "E0814"),
    # Names that only start like a scenario keyword are names (no such variable here).
    ("expected_load = 2.5", "E0100"),
    ("cycles_left = 3", "E0100"),
]


def test_bad_console_input_gets_a_coded_diagnostic(builds: Builds) -> None:
    with Running(main_program(builds, "c"), "--paused") as prog:
        r = console_pipes(prog.run, "".join(line + "\nstatus\n" for line, _ in BAD_LINES) + "exit\n", "--color", "never")
    assert r.returncode == 0 and "Traceback" not in r.stdout + r.stderr, r.stdout + r.stderr
    chunks = re.split(r"^controller ", r.stdout, flags=re.M)[: len(BAD_LINES)]
    for (line, code), chunk in zip(BAD_LINES, chunks):
        assert f"error[{code}]" in chunk, (line, chunk)
    # Every finding points into the line typed, never into text the console added.
    assert "cycles 1" not in r.stdout
    # Nothing bad was applied: SM is still uninitialised at cycle 0.
    last = tables(r.stdout)[-1]
    assert last["SM"]["status"] == "UNINITIALIZED" and last["_program"]["line"].startswith("cycle 0, paused")


def test_console_without_a_running_program() -> None:
    r = subprocess.run([*RCSC, "console", str(SUBMARINE), "--run", "nobody-here"], capture_output=True, text=True,
                       input="status\n", timeout=60, cwd=ROOT)
    assert r.returncode == 1 and "error[E0810]" in r.stderr and "Traceback" not in r.stderr, r.stderr


def test_second_console_and_second_program_are_refused(builds: Builds) -> None:
    exe = main_program(builds, "c")
    with Running(exe, "--paused") as prog:
        first = subprocess.Popen([*RCSC, "console", str(SUBMARINE), "--run", prog.run], stdin=subprocess.PIPE,
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
        try:
            assert "rcsc console:" in first.stdout.readline()
            second = console_pipes(prog.run, "status\n")
            assert second.returncode == 1 and "error[E0816]" in second.stderr, second.stderr
        finally:
            first.communicate("exit\n", timeout=60)
        again = subprocess.run([str(exe), "--run", prog.run, "--no-timing", "--cycles", "1"], capture_output=True,
                               text=True, timeout=30)
        assert again.returncode == 2 and "is in use by process" in again.stderr


def test_program_that_ended_gets_a_warning(builds: Builds) -> None:
    with Running(main_program(builds, "c"), "--paused", "--fast", "--cycles", "3") as prog:
        r = console_pipes(prog.run, "resume\nstatus\nSM.INIT()\n")
        assert prog.proc.wait(timeout=10) == 0
    assert "warning[W0810]" in r.stdout, r.stdout
    assert "cycle 3, finished" in r.stdout


def test_a_killed_program_is_not_shown_as_running(builds: Builds) -> None:
    """A program killed with SIGKILL cannot remove its segment: the console
    says it is gone (E0810) instead of showing its last table as paused."""
    with Running(main_program(builds, "c"), "--paused") as prog:
        seg = Path("/dev/shm") / f"rcs-submarine-{prog.run}.console"
        prog.proc.kill()
        prog.proc.wait(timeout=10)
        try:
            r = console_pipes(prog.run, "status\n")
        finally:
            seg.unlink(missing_ok=True)
    assert r.returncode == 1 and "error[E0810]" in r.stderr and "is no longer running" in r.stderr, r.stdout + r.stderr


@pytest.mark.parametrize("target", TARGETS)
def test_init_option_sends_the_verb_at_start_up(builds: Builds, target: str) -> None:
    exe = main_program(builds, target)
    r = subprocess.run([str(exe), "--fast", "--no-console", "--no-timing", "--cycles", "4", "--init", "INIT", "--trace", "-"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    first = r.stdout.splitlines()[0]
    assert re.search(r'"SM":\{"echo":1,"status":"EXEC","verb":"INIT"', first), first
    for verb, message in (("TRANSIT", "takes parameters"), ("NOPE", "no top controller accepts")):
        bad = subprocess.run([str(exe), "--fast", "--cycles", "1", "--init", verb], capture_output=True, text=True, timeout=60)
        assert bad.returncode == 2 and message in bad.stderr, bad.stderr
    # --paused with nothing to resume from is refused rather than hanging.
    stuck = subprocess.run([str(exe), "--paused", "--cycles", "1"], capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert stuck.returncode == 2 and "--paused needs a console" in stuck.stderr


@pytest.mark.serial  # waits for the screen with time limits: alone, not next to a build
def test_full_screen_view_on_a_pty(builds: Builds) -> None:
    """`--screen` (curses): the table is drawn, typed lines reach the program
    (checked afterwards from a line-mode console), `exit` leaves it running."""
    import fcntl
    import struct
    import termios

    with Running(main_program(builds, "c"), "--paused") as prog:
        master, slave = pty.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 140, 0, 0))
        # curses takes LINES and COLUMNS over the terminal's size when they
        # are set (pytest-xdist's workers set 24 x 80): the pty's size counts.
        screen_env = {k: v for k, v in os.environ.items() if k not in ("LINES", "COLUMNS")} | {"TERM": "xterm"}
        con = subprocess.Popen([*RCSC, "console", str(SUBMARINE), "--run", prog.run, "--screen"], stdin=slave,
                               stdout=slave, stderr=slave, cwd=ROOT, close_fds=True, env=screen_env)
        os.close(slave)
        try:
            drawn = read_until(master, "budget_us")
            for line in ("SM.INIT()", "step 4", "pause TB"):
                os.write(master, (line + "\r").encode())
                time.sleep(0.5)
            os.write(master, b"exit\r")
            assert con.wait(timeout=30) == 0
        finally:
            if con.poll() is None:
                con.kill()
            os.close(master)
        assert "controller" in drawn and "Traceback" not in drawn
        r = console_pipes(prog.run, "status\nquit\n")
    row = tables(r.stdout)[0]
    assert (row["SM"]["verb"], row["SM"]["status"], row["TB"]["mode"]) == ("INIT", "DONE", "paused")
    assert row["_program"]["line"].startswith("cycle 4, paused")


def test_screen_needs_a_terminal() -> None:
    r = subprocess.run([*RCSC, "console", str(SUBMARINE), "--run", "x", "--screen"], capture_output=True, text=True,
                       input="", timeout=60, cwd=ROOT)
    assert r.returncode == 2 and "--screen needs a terminal" in r.stderr and "Traceback" not in r.stderr


@pytest.mark.parametrize("target", TARGETS)
def test_the_program_refuses_bad_requests_with_a_reason(builds: Builds, target: str) -> None:
    """The runtime's side of the ring: what the console never sends is refused, with the reason."""
    from rcsc.sim.console import Segment

    with Running(main_program(builds, target), "--paused") as prog:
        seg = Segment("submarine", prog.run)
        try:
            assert seg.request("mode 99 run") == "no controller 99"
            assert seg.request("step 0") == "bad step count"
            assert seg.request("fly") == "unknown request `fly`"
            why = seg.request("events\nrcsc-events 1 submarine 0000000000000000\ncycles 1\nend 0\n")
            assert why is not None and "<console>:1: error: the event file is for design `submarine` (interface 0000000000000000)" in why
            assert seg.request("mode 2 pause") is None and seg.snapshot().rows[2]["mode"] == 1
            # E0815: a request larger than the ring's text area is refused before it is sent.
            from rcsc.sim.console import ConsoleError

            with pytest.raises(ConsoleError) as err:
                seg.request("x" * (1 << 22))
            assert err.value.code == "E0815" and "too long" in str(err.value)
        finally:
            seg.close()


def test_a_program_built_from_another_interface_is_refused(builds: Builds) -> None:
    """E0811: the console compiles ids and bit patterns for the interface the
    program publishes; another hash (an older build) is refused at attach."""
    import io

    from rcsc.driver import check_path
    from rcsc.sim.console import ConsoleError, Segment, Session

    design = check_path(str(SUBMARINE)).model
    with Running(main_program(builds, "c"), "--paused") as prog:
        seg = Segment("submarine", prog.run)
        try:
            Session(design, seg, io.StringIO())  # the same build: accepted
            seg.info["hash"] = "0123456789abcdef"
            with pytest.raises(ConsoleError) as err:
                Session(design, seg, io.StringIO())
            assert err.value.code == "E0811"
        finally:
            seg.close()
