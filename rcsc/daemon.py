"""The check daemon: `rcsc check --daemon` answered by a process that stays.

A fresh `rcsc check` of a large design pays, before it checks anything, for
starting Python, importing the checks (networkx, z3: about half a second)
and reading every controller's header again; after a one-rule edit that is
most of its time.  The language server does not pay it, because it stays:
it keeps the last check of each design in memory, and re-checks only the
edited controllers (`rcsc.checks.incremental`) using the syntax trees it
kept of the others.  The daemon is the same for the command line (as `dmypy`
is for mypy): `rcsc check --daemon ARGS` starts it on first use, hands it
the command, and prints what it answers; later calls find it running.

What it answers is what `rcsc check ARGS` answers, byte for byte, exit code
included: it runs the same command in the caller's folder with the caller's
environment, and its caches are the design's `.rcsc-cache/` folder (read
and written as `rcsc check` does) with the language server's memory in
front (`cache.LayeredStore`).  Only `check` goes to the daemon; it answers
one call at a time.

Where it listens: a Unix socket in a folder of the user's own (mode 0700,
under `$XDG_RUNTIME_DIR` or the temporary folder, or `RCSC_DAEMON_DIR`),
named by the version of rcsc's code and the Python that runs it, so an
upgraded rcsc starts a daemon of its own.  A daemon exits after
`RCSC_DAEMON_IDLE` seconds without a call (default 900), on `rcsc daemon
stop`, or when its socket is removed.

The protocol is one JSON object per connection each way (the request:
arguments, folder, environment, whether stdout is a terminal; the answer:
stdout, stderr, exit code and the CPU seconds the daemon spent), written by
hand on the standard library's `socket`: nothing here warrants a framework.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import socket
import stat
import sys
import time

# The client imports only what it needs: `rcsc check --daemon` is worth its
# while when the command itself starts in a few hundredths of a second.

# How long a client waits for a daemon it started to listen; how long the
# daemon waits for a request once a caller connected; how long `status` and
# `stop` wait for an answer (a check may be running).
_START_TIMEOUT_S = 30.0
_REQUEST_TIMEOUT_S = 10.0
_CONTROL_TIMEOUT_S = 120.0
_IDLE_DEFAULT_S = 900.0
_MAX_MESSAGE = 256 * 1024 * 1024


class DaemonError(Exception):
    """The daemon could not be reached or started (the message says why)."""


def folder() -> str:
    """The user's own folder for daemon sockets, created mode 0700; a folder
    that exists but belongs to someone else or others can enter is refused
    (a socket there could be another user's impostor)."""
    base = os.path.abspath(os.environ["RCSC_DAEMON_DIR"]) if os.environ.get("RCSC_DAEMON_DIR") else ""
    if not base:
        runtime = os.environ.get("XDG_RUNTIME_DIR")
        if not runtime:
            import tempfile

            runtime = tempfile.gettempdir()
        base = os.path.join(runtime, f"rcsc-daemon-{os.getuid()}")
    try:
        os.makedirs(base, mode=0o700, exist_ok=True)
        st = os.lstat(base)
    except OSError as exc:
        raise DaemonError(f"cannot make the daemon's folder `{base}`: {exc.strerror or exc}") from exc
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid() or st.st_mode & 0o077:
        raise DaemonError(f"the daemon's folder `{base}` must be a folder of yours that only you can enter (mode 0700)")
    return base


def _code_identity() -> bytes:
    """What tells this rcsc's code from another's, cheaply: the path, size
    and time of each of its source files (a changed checkout, an upgrade),
    and the same of z3's libraries.  Hashing the sources themselves, as the
    cache does (`cache.code_version`), would take most of a call's time."""
    import importlib.util

    out = []
    base = os.path.dirname(os.path.abspath(__file__))
    for top, dirs, files in os.walk(base):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        for name in sorted(files):
            if name.endswith(".py"):
                st = os.stat(os.path.join(top, name))
                out.append(f"{os.path.join(top, name)}:{st.st_size}:{st.st_mtime_ns}")
    spec = importlib.util.find_spec("z3")
    lib = os.path.join(os.path.dirname(spec.origin), "lib") if spec is not None and spec.origin else ""
    if os.path.isdir(lib):
        for name in sorted(os.listdir(lib)):
            st = os.stat(os.path.join(lib, name))
            out.append(f"{name}:{st.st_size}:{st.st_mtime_ns}")
    return "\0".join(out).encode()


def socket_path() -> str:
    """The socket of the daemon for this rcsc, this z3 and this Python."""
    # The environment (a virtual one is its own) and the interpreter, not the
    # name it was started by (`python`, `python3` and a script's first line
    # name the same one).
    python = f"\0{sys.prefix}\0{os.path.realpath(sys.executable)}\0{sys.version}\0{os.environ.get('PYTHONPATH', '')}"
    name = hashlib.sha256(_code_identity() + python.encode()).hexdigest()[:16]
    path = os.path.join(folder(), f"{name}.sock")
    if len(os.fsencode(path)) > 100:  # a Unix socket's path holds 107 bytes on Linux, 103 on macOS
        raise DaemonError(f"the daemon's socket path `{path}` is too long for a Unix socket: set RCSC_DAEMON_DIR to a shorter folder")
    return path


# ---- the client ---------------------------------------------------------------------------


def _send(sock: socket.socket, message: dict) -> None:
    sock.sendall(json.dumps(message).encode("utf-8") + b"\n")


def _receive(sock: socket.socket) -> dict:
    chunks, size = [], 0
    while True:
        chunk = sock.recv(1 << 20)
        if not chunk:
            break
        chunks.append(chunk)
        size += len(chunk)
        if chunk.endswith(b"\n") or size > _MAX_MESSAGE:
            break
    try:
        value = json.loads(b"".join(chunks).decode("utf-8"))
    except ValueError as exc:
        raise DaemonError("the daemon's answer is not one") from exc
    if not isinstance(value, dict):
        raise DaemonError("the daemon's answer is not one")
    return value


def _connect(path: str) -> socket.socket | None:
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        sock.connect(path)
    except OSError:
        sock.close()
        return None
    return sock


def _start(path: str):
    """Start a daemon listening on `path`, detached from this process (its
    output, which should be none, goes to a .log file next to the socket)."""
    import subprocess

    log = os.path.join(os.path.dirname(path), os.path.basename(path)[:-len(".sock")] + ".log")
    # It runs in `/` (it must not keep the caller's folder busy, and `-P`
    # keeps the folder it starts in off its import path: a `z3.py` lying in
    # the caller's folder must not stand in for z3), with the caller's
    # PYTHONPATH made absolute (it was relative to the caller's folder).
    env = dict(os.environ)
    if env.get("PYTHONPATH"):
        env["PYTHONPATH"] = os.pathsep.join(os.path.abspath(x) if x else os.getcwd() for x in env["PYTHONPATH"].split(os.pathsep))
    with open(log, "ab") as out:
        return subprocess.Popen([sys.executable, "-P", "-m", "rcsc", "daemon", "serve", "--socket", path], stdin=subprocess.DEVNULL,
                                stdout=out, stderr=out, start_new_session=True, close_fds=True, cwd="/", env=env)


def request(argv: list[str], stdout_is_tty: bool = False, start: bool = True) -> dict:
    """Have the daemon run `rcsc check ARGV` here, starting it if need be
    (`start`): its answer, {"stdout", "stderr", "code", "cpu"}."""
    path = socket_path()
    sock = _connect(path)
    if sock is None and start:
        started, began = _start(path), time.monotonic()
        while sock is None and time.monotonic() < began + _START_TIMEOUT_S:
            time.sleep(0.02)
            sock = _connect(path)
            # A daemon that left met another one starting (give that one
            # two seconds to listen) or failed (its .log says why).
            if sock is None and started.poll() is not None and time.monotonic() > began + 2.0:
                break
    if sock is None:
        raise DaemonError(f"no daemon listens on `{path}`" + (" (see the .log file next to it)" if start else ""))
    umask = os.umask(0o022)
    os.umask(umask)
    env = dict(os.environ)
    if "COLUMNS" not in env:
        # What argparse would measure here (the daemon's own stdout is no terminal).
        with contextlib.suppress(OSError, ValueError, AttributeError):
            env["COLUMNS"] = str(os.get_terminal_size(sys.stdout.fileno()).columns)
    with sock:
        _send(sock, {"argv": argv, "cwd": os.getcwd(), "env": env, "tty": stdout_is_tty, "umask": umask,
                     "tty_err": bool(getattr(sys.stderr, "isatty", lambda: False)())})
        answer = _receive(sock)
    writes = answer.get("writes")
    if (not isinstance(answer.get("code"), int) or not isinstance(writes, list)
            or not all(isinstance(w, list) and len(w) == 2 and w[0] in (1, 2) and isinstance(w[1], str) for w in writes)):
        raise DaemonError(str(answer.get("error") or "the daemon's answer is not one"))
    return answer


def wants_daemon(argv: list[str]) -> bool:
    """Whether `argv` is `check ... --daemon ...` (the option before any `--`)."""
    command = None
    for word in argv:
        if word == "--":
            return False
        if command is None and not word.startswith("-"):
            command = word
            if command != "check":
                return False
        elif word == "--daemon":
            return command == "check"
    return False


def forwarded(argv: list[str]) -> list[str]:
    """The arguments of `rcsc check` in `argv`, without the command word and `--daemon`."""
    out, command_seen, options = [], False, True
    for word in argv:
        if word == "--":
            options = False
        elif options and word == "--daemon":
            continue
        elif options and not command_seen and word == "check":
            command_seen = True
            continue
        out.append(word)
    return out


# Whether this process asked the daemon already (`rcsc.launch` does, then
# `rcsc.cli` would again when the daemon could not answer).
attempted = False


def client_main(argv: list[str]) -> int | None:
    """`rcsc check --daemon ARGS` (argv): the daemon's answer printed, its
    exit code returned; None, with a note on stderr, when no daemon can
    answer (the caller then checks in its own process)."""
    global attempted
    attempted = True
    try:
        answer = request(forwarded(argv), stdout_is_tty=bool(getattr(sys.stdout, "isatty", lambda: False)()))
    except (DaemonError, OSError) as exc:
        _write(sys.stderr, f"note: the check daemon could not answer ({exc}); checking in this process\n")
        return None
    except KeyboardInterrupt:
        # As `rcsc check` after Ctrl-C (the daemon finishes the check and
        # keeps it: the next call replays it).
        _write(sys.stderr, "\nerror: interrupted\n")
        return 130
    code = int(answer["code"])
    stdout_ok = True
    for number, text in answer["writes"] + [[1, ""]]:  # the last: flush stdout
        try:
            if number == 2:
                if stdout_ok:
                    sys.stdout.flush()  # what came before it comes first
                _write(sys.stderr, text)
                sys.stderr.flush()
            elif stdout_ok:
                _write(sys.stdout, text)
                sys.stdout.flush()
        except BrokenPipeError:
            # The reader of stdout went away (`rcsc check --daemon ... |
            # head`), as `rcsc.cli.main` handles it: stderr still gets its part.
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
            stdout_ok, code = False, 2
    return code


def _write(stream, text: str) -> None:
    """As `rcsc.cli._write`: what the stream's encoding cannot show is replaced, not fatal."""
    try:
        stream.write(text)
    except UnicodeEncodeError:
        encoding = getattr(stream, "encoding", None) or "ascii"
        stream.write(text.encode(encoding, "replace").decode(encoding))


def _control(message: dict) -> dict | None:
    """Send the daemon of this rcsc a control message (`status`, `stop`):
    its answer, or None when none runs."""
    sock = _connect(socket_path())
    if sock is None:
        return None
    with sock:
        sock.settimeout(_CONTROL_TIMEOUT_S)  # it answers once the check it may be running is done
        _send(sock, message)
        try:
            return _receive(sock)
        except OSError as exc:  # (a time-out too)
            raise DaemonError(f"the daemon did not answer within {_CONTROL_TIMEOUT_S:g} s (busy with a long check?)") from exc


def stop() -> bool:
    """Ask the daemon of this rcsc to exit; whether one was running."""
    try:
        return _control({"stop": True}) is not None
    except DaemonError:
        return True  # it did not say so, but one was running


def status() -> dict | None:
    """What the running daemon says of itself, or None when none runs."""
    return _control({"status": True})


# ---- the daemon ---------------------------------------------------------------------------


class _Stream(io.TextIOBase):
    """A captured stdout or stderr: its writes go, in order with the other
    stream's, to one list (`rcsc check` writes messages to stderr while it
    runs and the report to stdout at the end: the caller replays them in
    that order); it says whether the caller's stream is a terminal (colour
    follows it)."""

    def __init__(self, number: int, writes: list, tty: bool) -> None:
        super().__init__()
        self.number, self.writes, self._tty = number, writes, tty

    def write(self, text: str) -> int:
        if text:
            self.writes.append([self.number, text])
        return len(text)

    def isatty(self) -> bool:
        return self._tty

    def text(self) -> str:
        return "".join(t for n, t in self.writes if n == self.number)


def _run(message: dict, memory: dict) -> dict:
    """Run one `rcsc check` for a caller, in its folder and environment."""
    from rcsc import cli

    argv, cwd, env, umask = message.get("argv"), message.get("cwd"), message.get("env"), message.get("umask")
    if not (isinstance(argv, list) and all(isinstance(a, str) for a in argv) and isinstance(cwd, str) and isinstance(env, dict)
            and isinstance(umask, int)):
        return {"error": "a request the daemon does not understand"}
    writes: list = []
    out, err = _Stream(1, writes, bool(message.get("tty"))), _Stream(2, writes, bool(message.get("tty_err")))
    saved_env, saved_cwd = dict(os.environ), os.getcwd()
    started = time.process_time()
    saved_umask = os.umask(umask & 0o777)  # what it writes (`-o`, the cache) is the caller's
    try:
        os.chdir(cwd)
        os.environ.clear()
        os.environ.update({str(k): str(v) for k, v in env.items()})
        cli.DAEMON_MEMORY = memory
        cli.DAEMON_ANSWERS.clear()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = cli.main(["check", *argv])
    except OSError as exc:
        return {"error": f"the daemon cannot work in `{cwd}`: {exc.strerror or exc}"}
    finally:
        cli.DAEMON_MEMORY = None
        os.umask(saved_umask)
        os.environ.clear()
        os.environ.update(saved_env)
        os.chdir(saved_cwd)
    return {"writes": writes, "stdout": out.text(), "stderr": err.text(), "code": code, "cpu": time.process_time() - started,
            "answers": list(cli.DAEMON_ANSWERS)}


def serve(path: str, idle_s: float | None = None) -> int:
    """Listen on `path` and answer calls until idle for `idle_s` seconds,
    told to stop, or the socket is gone."""
    import fcntl

    from rcsc.checks import cache, incremental

    if idle_s is None:
        try:
            idle_s = float(os.environ.get("RCSC_DAEMON_IDLE", _IDLE_DEFAULT_S))
        except ValueError:
            idle_s = _IDLE_DEFAULT_S
    if not idle_s >= 1.0:  # NaN, zero and negative values too
        idle_s = 1.0
    # One daemon per socket: the lock is held for the daemon's life (two
    # clients that start one at once make two, and the second leaves).
    lock = open(path + ".lock", "a")  # noqa: SIM115 - held until exit
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return 0
    with contextlib.suppress(FileNotFoundError):
        os.unlink(path)  # a daemon that died left it; none listens (the lock)
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(path)
    os.chmod(path, 0o600)
    server.listen(8)
    server.settimeout(min(idle_s, 5.0))
    identity = os.stat(path).st_ino
    memory = incremental.memory_stores(cache.MemoryStore())
    calls, last_call = 0, time.monotonic()
    try:
        while True:
            try:
                conn, _ = server.accept()
            except socket.timeout:
                if time.monotonic() - last_call >= idle_s or not _still_ours(path, identity):
                    return 0
                continue
            with conn:
                # A caller that connects and sends nothing must not hold the others.
                conn.settimeout(_REQUEST_TIMEOUT_S)
                try:
                    message = _receive(conn)
                except (DaemonError, OSError):
                    continue
                conn.settimeout(None)
                if message.get("stop"):
                    with contextlib.suppress(OSError):
                        _send(conn, {"stopped": True})
                    return 0
                if message.get("status"):
                    answer = {"pid": os.getpid(), "calls": calls, "socket": path, "idle_s": idle_s,
                              "designs": len(memory[incremental.TREES]), "cpu": time.process_time()}
                else:
                    answer = _run(message, memory)
                    calls += 1
                with contextlib.suppress(OSError):
                    _send(conn, answer)
            if not (message.get("status") or message.get("stop")):
                # The caller has its answer: what the last checks left can go.
                from rcsc.driver import collect_if_grown

                collect_if_grown()
            last_call = time.monotonic()
    finally:
        server.close()
        if _still_ours(path, identity):
            with contextlib.suppress(OSError):
                os.unlink(path)


def _still_ours(path: str, identity: int) -> bool:
    try:
        return os.stat(path).st_ino == identity
    except OSError:
        return False
