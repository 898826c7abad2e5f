"""`rcsc console`: a live operator interface to a running compiled Main Program.

A single-CPU C or Rust Main Program started with `--run ID` publishes, in the
POSIX shared-memory segment `/rcs-<design>-<ID>.console`, every controller's
status (verb, state, status, last rule, echo, error code, its mode and its
timing) and reads operator requests from a small ring in the same segment
(docs/console.md has the layout).  This module attaches to that segment
(`Segment`) and runs the session (`Session`): the operator types commands in
the scenario syntax (`SM.TRANSIT(speed = MAX_KNOTS * 0.75)`,
`turbine_trip = true`), which are checked and compiled by the scenario parser
and the event compiler (rcsc/front/scenario.py, rcsc/outputs/events.py) into
an event record that the runtime's event reader applies; and console words:
`status`, `pause`, `resume`, `step [N]`, `pause NODE`, `step NODE [N]`,
`run NODE`, `quit`, `help`, `exit`.

The session reads lines from any text stream and prints to another: on a
terminal and through pipes alike (tests drive it through both).  Console
mistakes are diagnostics with a code (E0810-E0819, W0810), never a traceback.
"""

from __future__ import annotations

import fcntl
import mmap
import os
import re
import struct
import time
from dataclasses import dataclass, field
from pathlib import Path

from rcsc.diagnostics import Diagnostics
from rcsc.front.source import SourceFile, Span

SHM_DIR = Path("/dev/shm")
MAGIC = 0x31304E4F43534352  # "RCSCON01"
# Header words (backends/c/runtime/rcs_runtime.c, the operator segment; host/console.rs).
(H_MAGIC, H_VERSION, H_WORDS, H_PID, H_N_CTRLS, H_N_FIELDS, H_SEQ, H_CYCLE, H_RUN_STATE, H_PERIOD,
 H_REQ_HEAD, H_REQ_DONE, H_RING_SLOTS, H_SLOT_WORDS, H_TEXT_AT, H_TEXT_BYTES, H_CTRL_AT, H_RING_AT,
 H_MAX_WORK, H_CYCLE_OVERRUNS) = range(20)
HEADER_WORDS = 32
RUN_STATES = {0: "running", 1: "paused", 2: "finished"}
STATUS_NAMES = {-1: "UNINITIALIZED", 0: "-", 1: "DONE", 2: "EXEC", 3: "ERROR"}
ID_CHARS = re.compile(r"[A-Za-z0-9_.-]+\Z")


class ConsoleError(Exception):
    """A console problem with its code (E0810-E0819)."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


# The characters of a design's name that segment names hold: a name has at
# most NAME_MAX (255) bytes, a design's name is not bounded.  The same cut as
# the C runtime's `rcs_shm_name` and the Rust runtime's `design_part`.
DESIGN_CHARS = 100


def segment_name(design: str, run: str) -> str:
    """The segment of run `run` of design `design` (without the leading `/`)."""
    return f"rcs-{design[:DESIGN_CHARS]}-{run}.console"


def find_runs(design: str) -> list[str]:
    """The run ids of the design's Main Programs that publish a segment."""
    prefix, suffix = f"rcs-{design[:DESIGN_CHARS]}-", ".console"
    try:
        names = sorted(p.name for p in SHM_DIR.iterdir())
    except OSError:
        return []
    return [n[len(prefix):-len(suffix)] for n in names if n.startswith(prefix) and n.endswith(suffix) and len(n) > len(prefix) + len(suffix)]


@dataclass
class CtrlInfo:
    name: str
    top: bool
    verbs: list[str] = field(default_factory=list)
    states: list[str] = field(default_factory=list)
    rules: list[str] = field(default_factory=list)
    statuses: dict[int, str] = field(default_factory=dict)


@dataclass
class Snapshot:
    cycle: int
    run_state: str
    max_work_ns: int
    cycle_overruns: int
    rows: list[dict[str, int]]


def _signed(v: int) -> int:
    return v - (1 << 64) if v >= 1 << 63 else v


def request_check(number: int, data: bytes) -> int:
    """FNV-1a over a request's number, its length and its bytes (the slot's
    check word: the program serves a request only once it matches, so a
    request whose bytes are not all visible yet waits for the next poll)."""
    h = 0xCBF29CE484222325
    for b in struct.pack("<QQ", number, len(data)) + data:
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


class Segment:
    """A Main Program's operator segment, mapped read-write."""

    def __init__(self, design: str, run: str) -> None:
        if not ID_CHARS.match(run):
            raise ConsoleError("E0810", f"`{run}` is not a run id (letters, digits, `_`, `.` and `-`)")
        self.name = segment_name(design, run)
        path = SHM_DIR / self.name
        try:
            self.fd = os.open(path, os.O_RDWR)
        except OSError as exc:
            raise ConsoleError("E0810", f"no running Main Program of `{design}` with `--run {run}` ({path}: {exc.strerror})") from exc
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(self.fd)
            raise ConsoleError("E0816", f"another console is attached to run `{run}`") from exc
        # A program that is starting sizes the segment, then writes its
        # header, the magic word last: give it a second.
        give_up = time.monotonic() + 1.0
        while os.fstat(self.fd).st_size < HEADER_WORDS * 8 and time.monotonic() < give_up:
            time.sleep(0.01)
        size = os.fstat(self.fd).st_size
        if size < HEADER_WORDS * 8:
            os.close(self.fd)
            raise ConsoleError("E0810", f"{path} is not an operator segment (too small)")
        self.mm = mmap.mmap(self.fd, size)
        while self.word(H_MAGIC) == 0 and time.monotonic() < give_up:
            time.sleep(0.01)
        if self.word(H_MAGIC) != MAGIC or self.word(H_VERSION) != 1 or self.word(H_WORDS) * 8 != size:
            self.close()
            raise ConsoleError("E0810", f"{path} is not an operator segment of this rcsc version")
        if self.word(H_RUN_STATE) != 2 and not self.alive():
            # A program that ends marks its segment ended (and removes it);
            # one killed (SIGKILL, a crash) leaves it as it was, paused or
            # running, and would be shown so.
            pid = self.word(H_PID)
            self.close()
            raise ConsoleError("E0810", f"the Main Program of run `{run}` is no longer running: process {pid} ended without "
                                        f"removing {path} (it was killed or crashed; delete that file)")
        self.text_read = 0
        self.info: dict[str, str] = {}
        self.fields: list[str] = []
        self.ctrls: list[CtrlInfo] = []
        self.read_text()

    def read_text(self) -> None:
        """The names: written at start-up, and (Rust) a state or rule name
        appended as `state CTRL ID NAME` when first seen."""
        text_at, text_bytes = self.word(H_TEXT_AT), self.word(H_TEXT_BYTES)
        if text_bytes == self.text_read:
            return
        text = self.mm[text_at * 8 + self.text_read : text_at * 8 + text_bytes].decode("ascii", "replace")
        self.text_read = text_bytes
        for line in text.splitlines():
            key, _, rest = line.partition(" ")
            words = rest.split()
            if key == "fields":
                self.fields = words
            elif key == "ctrl":
                self.ctrls.append(CtrlInfo(words[0], words[1] == "top"))
            elif key in ("verbs", "states", "rules") and self.ctrls:
                setattr(self.ctrls[-1], key, ["" if w == "-" else w for w in words])
            elif key == "statuses" and self.ctrls:
                self.ctrls[-1].statuses = {int(v): n for n, v in (w.split("=") for w in words)}
            elif key in ("state", "rule") and len(words) == 3 and _digits(words[0]) and _digits(words[1]):
                names = getattr(self.ctrls[int(words[0])], key + "s")
                names.extend([""] * (int(words[1]) + 1 - len(names)))
                names[int(words[1])] = words[2]
            else:
                self.info[key] = rest

    def word(self, i: int) -> int:
        return struct.unpack_from("<Q", self.mm, 8 * i)[0]

    def set_word(self, i: int, v: int) -> None:
        struct.pack_into("<Q", self.mm, 8 * i, v)

    def alive(self) -> bool:
        pid = self.word(H_PID)
        if pid == 0:
            return False
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        except PermissionError:
            return True
        return True

    def snapshot(self) -> Snapshot:
        """The status table, read under the segment's seqlock."""
        n, nf, at = self.word(H_N_CTRLS), self.word(H_N_FIELDS), self.word(H_CTRL_AT)
        for _ in range(1000):
            s0 = self.word(H_SEQ)
            if s0 & 1:
                time.sleep(0.0005)
                continue
            raw = struct.unpack_from(f"<{n * nf}Q", self.mm, 8 * at)
            head = [self.word(i) for i in (H_CYCLE, H_RUN_STATE, H_MAX_WORK, H_CYCLE_OVERRUNS)]
            if self.word(H_SEQ) == s0:
                break
        self.read_text()
        rows = [{f: _signed(raw[i * nf + k]) for k, f in enumerate(self.fields)} for i in range(n)]
        return Snapshot(head[0], RUN_STATES.get(head[1], str(head[1])), head[2], head[3], rows)

    def request(self, text: str, timeout: float = 5.0) -> str | None:
        """Sends one request; returns None when done, else the program's reason."""
        data = text.encode("ascii")
        slots, slot_words, ring_at = self.word(H_RING_SLOTS), self.word(H_SLOT_WORDS), self.word(H_RING_AT)
        if len(data) >= (slot_words - 4) * 8:
            raise ConsoleError("E0815", f"the request is too long ({len(data)} bytes)")
        number = self.word(H_REQ_HEAD)
        base = 8 * (ring_at + (number % slots) * slot_words)
        self.mm[base + 32 : base + 32 + len(data) + 1] = data + b"\0"
        struct.pack_into("<QQQ", self.mm, base + 8, len(data), 0, request_check(number + 1, data))
        struct.pack_into("<Q", self.mm, base, number + 1)
        self.set_word(H_REQ_HEAD, number + 1)
        give_up = time.monotonic() + timeout
        while self.word(H_REQ_DONE) <= number:
            if not self.alive() or time.monotonic() > give_up:
                raise ConsoleError("E0815", "the Main Program did not answer (it has ended or is stuck)")
            time.sleep(0.002)
        result, length = struct.unpack_from("<QQ", self.mm, base + 16)[0], struct.unpack_from("<Q", self.mm, base + 8)[0]
        if result == 1:
            return None
        return self.mm[base + 32 : base + 32 + length].decode("ascii", "replace").strip() or "refused"

    def close(self) -> None:
        try:
            self.mm.close()
        except (AttributeError, ValueError, BufferError):
            pass
        os.close(self.fd)


def _us(ns: int) -> str:
    return f"{ns / 1000:.3f}"


def format_table(seg: Segment, snap: Snapshot) -> str:
    """The status table: one line per controller, then the program's line."""
    timing = [f for f in seg.fields if f.endswith("_ns") or f in ("overruns", "steps", "since")]
    cols = ["controller", "mode", "verb", "state", "status", "rule", *[f.removesuffix("_ns") + ("_us" if f.endswith("_ns") else "") for f in timing]]
    lines = []
    for c, row in zip(seg.ctrls, snap.rows):
        def name(names: list[str], i: int) -> str:
            return names[i] if 0 <= i < len(names) and names[i] else ("-" if i == 0 else str(i))

        verb = c.verbs[row["verb"] - 1] if 1 <= row.get("verb", 0) <= len(c.verbs) else "-"
        status = c.statuses.get(row.get("status", 0)) or STATUS_NAMES.get(row.get("status", 0), str(row.get("status")))
        mode = "paused" if row.get("mode") else "run"
        if row.get("pending_steps"):
            mode += f"+{row['pending_steps']}"
        vals = [c.name, mode, verb, name(c.states, row.get("state", 0)), status, name(c.rules, row.get("rule", 0))]
        vals += [_us(row[f]) if f.endswith("_ns") else str(row[f]) for f in timing]
        lines.append(vals)
    widths = [max(len(str(x)) for x in col) for col in zip(cols, *lines)]
    out = ["  ".join(str(x).ljust(w) for x, w in zip(r, widths)).rstrip() for r in [cols, *lines]]
    out.append(f"cycle {snap.cycle}, {snap.run_state}, max work {_us(snap.max_work_ns)} us, {snap.cycle_overruns} cycle overruns")
    return "\n".join(out) + "\n"


HELP = """\
commands (scenario syntax, sent at the next cycle):
  CTRL.VERB(arg = value, ...)   an operator command to a top controller
  VAR = value                   an input to a `from env` Global Memory variable
console words:
  status                        print the status table
  pause | resume                pause / resume the whole Main Program
  step [N]                      run N cycles (default 1), then stay paused
  pause NODE | run NODE         PR_MODE of one controller: not stepped / stepped again
  step NODE [N]                 pause NODE, then let it step N more times (default 1)
  quit                          end the Main Program
  help | exit                   this text / leave the console (the program runs on)
"""


class Session:
    """One console session on a segment: `handle` one line at a time."""

    def __init__(self, design, seg: Segment, out, color: bool = False) -> None:
        from rcsc.outputs import backend
        from rcsc.outputs.events import interface_hash

        self.design = design
        self.seg = seg
        self.out = out
        self.color = color
        self.ctrls = None
        for exclude in (False, True):
            ctrls = backend.built_controllers(design, backend.BuildOptions(exclude_simulators=exclude))
            if interface_hash(design, ctrls) == seg.info.get("hash"):
                self.ctrls = ctrls
                break
        if seg.info.get("design") != design.name or self.ctrls is None:
            raise ConsoleError(
                "E0811",
                f"the running Main Program (design `{seg.info.get('design')}`, interface {seg.info.get('hash')}) was not built from this design; rebuild it",
            )
        self.ctrl_ids = {c.name: i for i, c in enumerate(seg.ctrls)}
        self.finished_said = False
        self.lineno = 0

    # ---- output -------------------------------------------------------------

    def say(self, text: str) -> None:
        self.out.write(text if text.endswith("\n") else text + "\n")
        self.out.flush()

    def report(self, diags: Diagnostics) -> None:
        from rcsc import render

        self.say(render.render_human(diags, color=self.color, summary=False))

    def problem(self, code: str, line: str, message: str, label: str = "") -> bool:
        diags = Diagnostics()
        src = SourceFile("<console>", line)
        diags.add(code, Span(src, 0, len(line)), message, label)
        self.report(diags)
        return False

    # ---- requests -----------------------------------------------------------

    def send(self, line: str, request: str) -> bool:
        if self.seg.word(H_RUN_STATE) == 2 or not self.seg.alive():
            return self.problem("W0810", line, "the Main Program has ended; nothing was sent", "not sent")
        try:
            why = self.seg.request(request)
        except ConsoleError as exc:
            return self.problem(exc.code, line, exc.message)
        if why is not None:
            return self.problem("E0815", line, f"the Main Program refused the request: {why}", "refused")
        return True

    def wait_cycles(self, start: int, n: int, timeout: float = 10.0) -> None:
        give_up = time.monotonic() + timeout
        while self.seg.word(H_CYCLE) < start + n and self.seg.word(H_RUN_STATE) != 2 and self.seg.alive() and time.monotonic() < give_up:
            time.sleep(0.002)

    def node(self, line: str, name: str) -> int | None:
        if name not in self.ctrl_ids:
            self.problem("E0813", line, f"no controller named `{name}` in the running Main Program", "unknown controller")
            return None
        return self.ctrl_ids[name]

    def count(self, line: str, word: str) -> int | None:
        if not _digits(word) or not 1 <= int(word) <= 2**32 - 1:
            self.problem("E0812", line, f"`{word}` is not a step count (1..4294967295)", "not a count")
            return None
        return int(word)

    def handle(self, line: str) -> bool:
        """Handles one input line; False when the session should end."""
        self.lineno += 1
        line = line.rstrip("\r\n")
        text = line.split("//", 1)[0].strip()
        words = text.split()
        if not words:
            return True
        head = words[0]
        if head in ("exit", "detach") and len(words) == 1:
            return False
        if head == "help" and len(words) == 1:
            self.say(HELP)
        elif head == "status" and len(words) == 1:
            self.say(format_table(self.seg, self.seg.snapshot()))
        elif head in ("pause", "resume", "quit") and len(words) == 1:
            self.send(line, head)
            if head == "quit":
                return False
        elif head == "step" and len(words) == 1 or (head == "step" and len(words) == 2 and _digits(words[1])):
            n = self.count(line, words[1]) if len(words) == 2 else 1
            if n is not None:
                start = self.seg.word(H_CYCLE)
                if self.send(line, f"step {n}"):
                    self.wait_cycles(start, n, timeout=10.0 + 2 * n * self.seg.word(H_PERIOD) / 1e9)
        elif head in ("pause", "run", "step") and len(words) in (2, 3) and re.fullmatch(r"[A-Za-z_]\w*", words[1]):
            if head != "step" and len(words) == 3:
                return self.problem("E0812", line, f"`{head} NODE` takes no count", "unexpected word") or True
            i = self.node(line, words[1])
            n = self.count(line, words[2]) if len(words) == 3 else 1
            if i is not None and n is not None:
                self.send(line, f"mode {i} " + ({"pause": "pause", "run": "run"}.get(head) or f"step {n}"))
        elif head in ("pause", "resume", "quit", "status", "help", "exit", "step", "run"):
            self.problem("E0812", line, f"`{text}` is not a console command; type `help`", "unknown console command")
        else:
            self.operator_line(line, text)
        return True

    def operator_line(self, line: str, text: str) -> None:
        """A command or input in the scenario syntax, compiled like `rcsc events`."""
        from rcsc.front.scenario import text_to_scenario
        from rcsc.outputs.events import event_text

        if re.match(r"(at|expect|cycles|scenario)\b(?!\s*[=.(\[])", text):
            self.problem("E0814", line, "type the command or input alone (`SM.INIT()`, `trip = true`): the console sends it at the next cycle", "not an operator action")
            return
        if re.match(r"(stop|freeze)\b(?!\s*[=.(\[])", text):
            self.problem("E0814", line, "`stop` and `freeze` are scenario faults; pause one controller with `pause NODE`", "not an operator action")
            return
        # The line as the one event of a one-cycle scenario, last, so that
        # every diagnostic points into it (`at 1: LINE`, line 2 of
        # `<console>`), an unfinished line at its end.
        src = SourceFile("<console>", f"cycles 1\nat 1: {text}")
        diags = Diagnostics()
        sc = text_to_scenario(src, self.design, diags)
        if sc is None or diags.has_errors():
            self.report(diags)
            return
        if sc.faults:
            self.problem("E0814", line, "`stop` and `freeze` are scenario faults; pause one controller with `pause NODE`", "not an operator action")
            return
        self.send(line, "events\n" + event_text(self.design, sc, self.ctrls))


def _digits(word: str) -> bool:
    """ASCII digits only: str.isdigit also accepts `²` and `٣`, which int() refuses or reads otherwise."""
    return re.fullmatch(r"[0-9]+", word) is not None


def run_console(design, run: str, lines, out, color: bool = False, prompt: bool = False) -> int:
    """The console loop over `lines` (an iterable of text lines); the exit code."""
    seg = Segment(design.name, run)
    try:
        session = Session(design, seg, out, color)
        state = RUN_STATES.get(seg.word(H_RUN_STATE), "?")
        session.say(f"rcsc console: {design.name} on {seg.info.get('cpu')}, run `{run}` ({state}); type `help`")
        if prompt:
            out.write("> ")
            out.flush()
        for line in lines:
            if not session.handle(line):
                break
            if prompt:
                out.write("> ")
                out.flush()
        return 0
    finally:
        seg.close()


def run_screen(design, run: str) -> int:
    """The full-screen view (stdlib curses): the status table refreshed five
    times a second, the session's replies below it, the command line at the
    bottom.  The same `Session` handles each line as in the line mode."""
    import curses
    import io

    seg = Segment(design.name, run)
    replies = io.StringIO()
    try:
        session = Session(design, seg, replies)
        log = [f"rcsc console: {design.name} on {seg.info.get('cpu')}, run `{run}`; type `help`, `exit` to leave"]

        def screen(scr) -> None:
            scr.timeout(200)
            typed = ""
            while True:
                height, width = scr.getmaxyx()
                table = format_table(seg, seg.snapshot()).splitlines()
                scr.erase()
                rows = table[: max(height - 3, 1)]
                for y, text in enumerate(rows):
                    scr.addnstr(y, 0, text, max(width - 1, 1), curses.A_BOLD if y == 0 else curses.A_NORMAL)
                room = height - len(rows) - 2
                for k, text in enumerate(log[-room:] if room > 0 else []):
                    scr.addnstr(len(rows) + 1 + k, 0, text, max(width - 1, 1))
                scr.addnstr(height - 1, 0, "> " + typed, max(width - 1, 1))
                scr.refresh()
                try:
                    ch = scr.get_wch()
                except curses.error:
                    continue  # no key within 200 ms: refresh the table
                if ch in ("\n", "\r") or ch == curses.KEY_ENTER:
                    log.append("> " + typed)
                    go_on = session.handle(typed)
                    log.extend(replies.getvalue().rstrip("\n").splitlines())
                    replies.seek(0)
                    replies.truncate()
                    typed = ""
                    if not go_on:
                        return
                elif ch in ("\x7f", "\b") or ch == curses.KEY_BACKSPACE:
                    typed = typed[:-1]
                elif ch == "\x04" and not typed:
                    return
                elif isinstance(ch, str) and ch.isprintable():
                    typed += ch

        curses.wrapper(screen)
        return 0
    finally:
        seg.close()
