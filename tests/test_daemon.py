"""The check daemon (`rcsc check --daemon`, rcsc.daemon): it answers what
`rcsc check` answers, byte for byte and exit code included, for every
example, after an edit inside a plan (re-checked in part, with the syntax
trees it kept) and for a file that does not parse; it leaves the cache
folder as `rcsc check` does; it refuses a socket folder others can enter
(and the command then checks in its own process); `rcsc daemon status` and
`stop` work; a socket left by a daemon that died does not stop a new one;
an idle daemon exits; messages and the report come in the order `rcsc
check` writes them; a `z3.py` in the caller's folder does not stand in for
z3; files are written with the caller's umask; a call the daemon cannot
answer is tried once.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted(ROOT.glob("examples/*/*.rcs"))


@pytest.fixture
def env(tmp_path, monkeypatch):
    """The environment of the commands: the cache on, a socket folder of the test's own."""
    monkeypatch.delenv("RCSC_NO_CACHE", raising=False)
    monkeypatch.delenv("RCSC_INCREMENTAL", raising=False)
    out = {k: v for k, v in os.environ.items() if k not in ("RCSC_NO_CACHE", "RCSC_INCREMENTAL", "NO_COLOR", "FORCE_COLOR")}
    out["PYTHONPATH"] = str(ROOT)
    # A Unix socket's path holds at most 107 bytes, and pytest's folders
    # are long (pytest-xdist adds a folder per worker): the sockets go in a
    # short folder of the test's own, which the daemon makes.
    short = tempfile.mkdtemp(prefix="rcsd-", dir="/tmp" if os.path.isdir("/tmp") else None)
    out["RCSC_DAEMON_DIR"] = os.path.join(short, "sockets")
    out["RCSC_DAEMON_IDLE"] = "120"
    yield out
    subprocess.run([sys.executable, "-m", "rcsc", "daemon", "stop"], env=out, capture_output=True, timeout=60)
    shutil.rmtree(short, ignore_errors=True)


def _rcsc(env: dict, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    proc = subprocess.run([sys.executable, "-m", "rcsc", *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=900)
    assert "Traceback" not in proc.stderr, proc.stderr
    return proc


def _answer(env: dict, cwd: Path, *args: str) -> dict:
    """The daemon's own answer (which also says how it checked), as `rcsc check --daemon` gets it."""
    code = "import json, sys; from rcsc import daemon; print(json.dumps(daemon.request(sys.argv[1:])))"
    proc = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=900)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def _same(a: subprocess.CompletedProcess, b: subprocess.CompletedProcess) -> None:
    assert (a.returncode, a.stdout) == (b.returncode, b.stdout)


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.parent.name)
def test_the_daemon_answers_what_rcsc_check_answers(example: Path, tmp_path: Path, env: dict) -> None:
    work = tmp_path / "work"
    shutil.copytree(example.parent, work)
    name = example.name
    for args in ([name, "--color", "never"], [name, "--format", "json"], [name, "--format", "short", "--deny-warnings"]):
        fresh = _rcsc(env, work, "check", "--no-cache", *args)
        _same(_rcsc(env, work, "check", "--daemon", *args), fresh)  # the first: a full check (or one the folder holds)
        _same(_rcsc(env, work, "check", "--daemon", *args), fresh)  # then replayed from memory
    status = _rcsc(env, work, "daemon", "status")
    assert status.returncode == 0 and "6 checks answered" in status.stdout, status.stdout


def test_after_an_edit_in_a_plan_the_daemon_checks_in_part_and_agrees(tmp_path: Path, env: dict) -> None:
    work = tmp_path / "work"
    shutil.copytree(ROOT / "examples" / "machine_tool", work)
    design = work / "machine_tool.rcs"
    first = _answer(env, work, "machine_tool.rcs", "--format", "json")
    assert first["answers"] == ["full"]
    text = design.read_text(encoding="utf-8")
    plans = [i for i in range(len(text)) if text.startswith("plan ", i)]
    assert len(plans) >= 3
    for n, at in enumerate(plans[:3]):
        text = design.read_text(encoding="utf-8")
        # A rule's guard edited: a constant the design compares with, in the plan at `at`.
        body = text.index("{", at)
        rule = text.index(":", body) + 1
        edited = text[:rule] + f" (cycle >= {n}) and" + text[rule:]
        design.write_text(edited, encoding="utf-8")
        got = _answer(env, work, "machine_tool.rcs", "--format", "json")
        fresh = _rcsc(env, work, "check", "--no-cache", "machine_tool.rcs", "--format", "json")
        assert (got["code"], got["stdout"]) == (fresh.returncode, fresh.stdout)
        assert got["answers"] in (["partial"], ["full"])
        if n > 0:
            assert got["answers"] == ["partial"], got["answers"]
    # The folder holds what `rcsc check` stores: a fresh process replays it.
    again = _rcsc(env, work, "check", "machine_tool.rcs", "--format", "json")
    assert (again.returncode, again.stdout) == (got["code"], got["stdout"])


def test_a_syntax_error_and_a_missing_file_are_answered_as_rcsc_check_answers(tmp_path: Path, env: dict) -> None:
    (tmp_path / "bad.rcs").write_text("design d\ncontroller C level 1 budget 1 ms {\n  verb GO\n  plan GO { R1: true | new -> \n}\n",
                                      encoding="utf-8")
    for args in (["bad.rcs", "--color", "never"], ["nothing.rcs"]):
        fresh = _rcsc(env, tmp_path, "check", "--no-cache", *args)
        via = _rcsc(env, tmp_path, "check", "--daemon", *args)
        assert fresh.returncode in (1, 2)
        _same(via, fresh)
        assert via.stderr == fresh.stderr


def test_a_socket_folder_others_can_enter_is_refused_and_the_check_runs_here(tmp_path: Path, env: dict) -> None:
    shutil.copy(ROOT / "examples" / "machine_tool" / "machine_tool.rcs", tmp_path / "d.rcs")
    open_folder = tmp_path / "open"
    open_folder.mkdir(mode=0o777)
    os.chmod(open_folder, 0o777)
    env = {**env, "RCSC_DAEMON_DIR": str(open_folder)}
    fresh = _rcsc(env, tmp_path, "check", "--no-cache", "d.rcs")
    via = _rcsc(env, tmp_path, "check", "--daemon", "d.rcs")
    _same(via, fresh)
    assert "only you can enter" in via.stderr and "checking in this process" in via.stderr
    assert not list(open_folder.iterdir())  # no daemon started there
    status = _rcsc(env, tmp_path, "daemon", "status")
    assert status.returncode == 2 and "only you can enter" in status.stderr


def test_status_stop_and_a_socket_left_behind(tmp_path: Path, env: dict) -> None:
    shutil.copy(ROOT / "examples" / "machine_tool" / "machine_tool.rcs", tmp_path / "d.rcs")
    assert "no check daemon is running" in _rcsc(env, tmp_path, "daemon", "status").stdout
    assert _rcsc(env, tmp_path, "check", "--daemon", "d.rcs").returncode == 0
    assert "1 checks answered" in _rcsc(env, tmp_path, "daemon", "status").stdout
    assert "stopped the check daemon" in _rcsc(env, tmp_path, "daemon", "stop").stdout
    sockets = Path(env["RCSC_DAEMON_DIR"])
    deadline = time.monotonic() + 60
    while list(sockets.glob("*.sock")) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not list(sockets.glob("*.sock"))
    assert "no check daemon was running" in _rcsc(env, tmp_path, "daemon", "stop").stdout
    # A daemon killed outright leaves its socket file: the next call starts another.
    assert _rcsc(env, tmp_path, "check", "--daemon", "d.rcs").returncode == 0
    pid = int(_rcsc(env, tmp_path, "daemon", "status").stdout.split("process ")[1].split()[0])
    os.kill(pid, 9)
    deadline = time.monotonic() + 60
    while _pid_alive(pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert list(sockets.glob("*.sock"))  # left behind
    via = _rcsc(env, tmp_path, "check", "--daemon", "d.rcs")
    assert via.returncode == 0 and "could not answer" not in via.stderr, via.stderr
    assert f"process {pid} " not in _rcsc(env, tmp_path, "daemon", "status").stdout


def _pid_alive(pid: int) -> bool:
    try:
        waited, _ = os.waitpid(pid, os.WNOHANG)
    except ChildProcessError:
        waited = 0
    if waited == pid:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat", encoding="ascii") as f:
        return f.read().split()[2] != "Z"


def test_an_idle_daemon_exits(tmp_path: Path, env: dict) -> None:
    shutil.copy(ROOT / "examples" / "machine_tool" / "machine_tool.rcs", tmp_path / "d.rcs")
    env = {**env, "RCSC_DAEMON_IDLE": "1"}
    assert _rcsc(env, tmp_path, "check", "--daemon", "d.rcs").returncode == 0
    sockets = Path(env["RCSC_DAEMON_DIR"])
    deadline = time.monotonic() + 120
    while list(sockets.glob("*.sock")) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not list(sockets.glob("*.sock"))
    assert "no check daemon is running" in _rcsc(env, tmp_path, "daemon", "status").stdout


def _entry(env: dict, cwd: Path, *args: str, umask: int = 0o022) -> subprocess.CompletedProcess:
    """The `rcsc` command as installed (a script: the current folder is not
    on its import path), with `umask`, stdout and stderr in one stream."""
    code = (f"import os, sys; sys.path.pop(0); os.umask({umask}); sys.argv = ['rcsc', *sys.argv[1:]]; "
            "from rcsc.launch import entry; entry()")
    return subprocess.run([sys.executable, "-c", code, *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                          cwd=cwd, timeout=900)


def test_order_of_messages_umask_and_a_shadowing_module(tmp_path: Path, env: dict) -> None:
    shutil.copy(ROOT / "tests" / "cases" / "W0008_suppressions.rcs", tmp_path / "d.rcs")
    # Modules lying in the caller's folder, where the daemon is started from.
    (tmp_path / "z3.py").write_text('raise ImportError("not the real z3")\n', encoding="utf-8")
    (tmp_path / "networkx.py").write_text('raise ImportError("not the real networkx")\n', encoding="utf-8")
    args = ("check", "d.rcs", "missing.rcs", "--no-cache", "--color", "never")
    fresh = _entry(env, tmp_path, *args)
    assert fresh.returncode == 2 and fresh.stdout.index("missing.rcs") < fresh.stdout.index("warning[")
    via = _entry(env, tmp_path, *args, "--daemon")
    assert "not the real" not in via.stdout and "could not answer" not in via.stdout, via.stdout
    assert (via.returncode, via.stdout) == (fresh.returncode, fresh.stdout)  # messages first, then the report
    for umask in (0o022, 0o077):
        out = tmp_path / f"report-{umask:o}.txt"
        assert _entry(env, tmp_path, "check", "d.rcs", "--daemon", "-o", str(out), umask=umask).returncode == 0
        assert out.stat().st_mode & 0o777 == 0o666 & ~umask


def test_a_daemon_that_cannot_be_reached_is_tried_once(tmp_path: Path, env: dict) -> None:
    shutil.copy(ROOT / "examples" / "machine_tool" / "machine_tool.rcs", tmp_path / "d.rcs")
    open_folder = tmp_path / "open"
    open_folder.mkdir()
    os.chmod(open_folder, 0o755)
    via = _rcsc({**env, "RCSC_DAEMON_DIR": str(open_folder)}, tmp_path, "check", "--daemon", "d.rcs")
    assert via.returncode == 0 and via.stderr.count("could not answer") == 1, via.stderr
    # An idle time of zero is taken as the shortest there is, not refused.
    zero = {**env, "RCSC_DAEMON_IDLE": "0"}
    via = _rcsc(zero, tmp_path, "check", "--daemon", "d.rcs")
    assert via.returncode == 0 and "could not answer" not in via.stderr, via.stderr
