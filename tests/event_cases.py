"""Shared by the runtime tests (tests/test_c_runtime.py, tests/test_rust_runtime.py):
the hand-made fixture design in the design language, its event files, and
corrupt event files with the exact error each runtime's reader gives."""

from __future__ import annotations

from functools import lru_cache

# The fixture's declarations (tests/c/runtime_fixture.c, tests/rust_fixture) in the design language.
FIXTURE_RCS = """\
design fixture
enum Mode { IDLE, RUN, HALT }
enum Color { RED, GREEN }
record Pose { x: f64, y: f64, mode: Mode }
const MAX_SPEED: f64 = 12.5
const LIMIT_K: i32 = 7
const STEP_T: duration = 250 ms
const FAST: Mode = Mode.RUN
const HOME: Pose = Pose(x = 1.0, y = 2.0, mode = Mode.RUN)
const NEG_U: u32 = 5
gm pose: Pose = Pose(x = 0.0, y = 0.0, mode = Mode.IDLE)
gm mode: Mode = Mode.IDLE
gm door: bool = false from env
gm limit: i32 = 0 from env
gm gain: f64 = 0.0 from env
controller TOP level 2 budget 1 ms {
    subordinates SUB
    reads door, limit, gain, pose, mode
    writes pose, mode
    verb INIT
    verb MOVE(speed: f64, dt: duration, mode: Mode, to: Pose)
    verb SET(n: u32, big: i64)
    reports AT_GOAL
    status speed: f64 = 0.0
    status n: u32 = 0
    plan INIT { N0: true | new -> done; }
    plan MOVE continuous { N0: true | new -> MOVING | speed = cmd.speed; A1: true | MOVING -> MOVING | report AT_GOAL; }
    plan SET { N0: true | new -> done; }
}
controller SUB level 1 budget 1 ms {
    verb GO
    status ticks: i32 = 0
    plan GO { G0: true | new -> done; }
}
cpu MAIN {
    heartbeat 10 ms
    schedule SUB, TOP
}
"""


@lru_cache(maxsize=1)
def fixture_model():
    import tempfile
    from pathlib import Path

    from rcsc.driver import check_path

    path = Path(tempfile.mkdtemp(prefix="rcsc-fixture-")) / "fixture.rcs"
    path.write_text(FIXTURE_RCS, encoding="utf-8")
    result = check_path(str(path))
    assert result.ok and result.model is not None
    return result.model


def fixture_hash() -> str:
    from rcsc.outputs.events import interface_hash

    d = fixture_model()
    return interface_hash(d, list(d.controllers.values()))


def events(scenario: str) -> str:
    """The event file of a scenario of the fixture design (asserts it checks clean)."""
    from rcsc.diagnostics import Diagnostics
    from rcsc.front.scenario import text_to_scenario
    from rcsc.front.source import SourceFile
    from rcsc.outputs.events import event_text

    d = fixture_model()
    diags = Diagnostics()
    sc = text_to_scenario(SourceFile("s.scn", scenario), d, diags)
    assert sc is not None, [x.message for x in diags.errors]
    return event_text(d, sc, list(d.controllers.values()))


# Computed values: arithmetic on constants, a function call, a record built from them.
COMPUTED = """\
cycles 2
at 1: gain = MAX_SPEED * 0.75
at 1: TOP.MOVE(speed = MAX_SPEED * 0.75, dt = STEP_T + 1 ms, mode = FAST, to = Pose(x = HOME.x * 2.0, y = abs(-3.0), mode = Mode.HALT))
"""

HINT = "compile the scenario with `rcsc events DESIGN SCENARIO -o FILE` (docs/events.md)"


def event_errors() -> list[tuple[str, bytes, str]]:
    """(name, file contents, the error after `FILE:`) of event files both readers refuse."""
    h = f"rcsc-events 1 fixture {fixture_hash()}\n"
    c5 = h + "cycles 5\n"
    cases = [
        ("empty", "", f"1: error: not an rcsc event file; {HINT}"),
        ("scenario_text", "cycles 5\nat 1: TOP.INIT()\n", f"1: error: not an rcsc event file; {HINT}"),
        ("nul_byte", "rcsc-events 1\0", "1: error: byte 0x00 is not printable ASCII"),
        ("not_ascii", c5 + "input 1 4 1 \x7f\nend 1\n", "3: error: byte 0x7f is not printable ASCII"),
        ("carriage_return", h + "cycles 5\r\nend 0\r\n", "2: error: byte 0x0d is not printable ASCII"),
        ("header_prefix", "rcsc-event 1 fixture x\n", f"1: error: not an rcsc event file; {HINT}"),
        ("header_only_word", "rcsc-events\n", f"1: error: not an rcsc event file; {HINT}"),
        ("header_words", "rcsc-events 1 fixture\ncycles 5\nend 0\n", f"1: error: not an rcsc event file; {HINT}"),
        ("wrong_version", f"rcsc-events 2 fixture {fixture_hash()}\ncycles 5\nend 0\n", "1: error: event file version 2; this Main Program reads version 1"),
        ("wrong_hash", "rcsc-events 1 fixture 0123456789abcdef\ncycles 5\nend 0\n",
         f"1: error: the event file is for design `fixture` (interface 0123456789abcdef), this Main Program for `fixture` (interface {fixture_hash()}); {HINT}"),
        ("wrong_design", f"rcsc-events 1 other {fixture_hash()}\ncycles 5\nend 0\n",
         f"1: error: the event file is for design `other` (interface {fixture_hash()}), this Main Program for `fixture` (interface {fixture_hash()}); {HINT}"),
        ("header_no_newline", h[:-1], "1: error: the file is truncated (no `end` line)"),
        ("no_cycles", h + "end 0\n", "2: error: expected `cycles N`"),
        ("cycles_zero", h + "cycles 0\nend 0\n", "2: error: cycles 0 is outside 1..4294967295"),
        ("cycles_huge", h + "cycles 4294967296\nend 0\n", "2: error: cycles 4294967296 is outside 1..4294967295"),
        ("truncated", c5 + "command 1 0 0 0\n", "4: error: the file is truncated (no `end` line)"),
        ("end_without_newline", c5 + "end 0", "3: error: the file is truncated (no `end` line)"),
        ("end_count", c5 + "end 1\n", "3: error: `end 1` but the file has 0 events"),
        ("after_end", c5 + "end 0\nend 0\n", "3: error: text after the `end` line"),
        ("unknown_record", c5 + "jump 1 0\nend 1\n", "3: error: unknown record `jump` (expected input, command, stop, freeze or end)"),
        ("ctrl_range", c5 + "command 1 2 0 0\nend 1\n", "3: error: controller 2 is out of range (the design has 2)"),
        ("not_top", c5 + "command 1 1 0 0\nend 1\n", "3: error: `SUB` takes commands only from its supervisor"),
        ("verb_range", c5 + "command 1 0 3 0\nend 1\n", "3: error: verb 3 is out of range (the design has 3)"),
        ("leaf_count", c5 + "command 1 0 2 1 7\nend 1\n", "3: error: 1 values given, the design expects 2"),
        ("leaves_missing", c5 + "command 1 0 2 2 7\nend 1\n", "3: error: 1 values given, the design expects 2"),
        ("line_ends_early", c5 + "command 1 0\nend 1\n", "3: error: the line ends early: 2 numbers, expected more"),
        ("enum_range", c5 + "command 1 0 1 6 0 0 3 0 0 0\nend 1\n", "3: error: value 3 does not fit the type `Mode`"),
        ("record_enum_range", c5 + "command 1 0 1 6 0 0 0 0 0 9\nend 1\n", "3: error: value 9 does not fit the type `Mode`"),
        ("bool_range", c5 + "input 1 2 1 2\nend 1\n", "3: error: value 2 does not fit the type `bool`"),
        ("i32_range", c5 + "input 1 3 1 100000000\nend 1\n", "3: error: value 100000000 does not fit the type `i32`"),
        ("u32_range", c5 + "command 1 0 2 2 100000000 0\nend 1\n", "3: error: value 100000000 does not fit the type `u32`"),
        ("not_env", c5 + "input 1 0 3 0 0 0\nend 1\n", "3: error: `pose` is written by a controller, not by the environment"),
        ("gm_range", c5 + "input 1 5 1 0\nend 1\n", "3: error: Global Memory variable 5 is out of range (the design has 5)"),
        ("tick_zero", c5 + "input 0 2 1 1\nend 1\n", "3: error: tick 0 is outside the scenario's cycles 1..5"),
        ("tick_after", c5 + "freeze 6 0\nend 1\n", "3: error: tick 6 is outside the scenario's cycles 1..5"),
        ("time_order", c5 + "input 3 2 1 1\ninput 2 2 1 0\nend 2\n", "4: error: tick 2 comes after tick 3: events are in time order"),
        ("hex_prefix", c5 + "input 1 4 1 0x10\nend 1\n", "3: error: `0x10` is not a hexadecimal number"),
        ("hex_long", c5 + "input 1 4 1 10000000000000000\nend 1\n", "3: error: `10000000000000000` is not a hexadecimal number"),
        ("decimal_overflow", c5 + "input 18446744073709551616 2 1 1\nend 1\n", "3: error: `18446744073709551616` is not a decimal number"),
        ("negative", c5 + "input -1 2 1 1\nend 1\n", "3: error: `-1` is not a decimal number"),
        ("double_space", c5 + "input 1  2 1 1\nend 1\n", "3: error: an empty word (numbers are separated by one space)"),
        ("cpu_range", c5 + "stop 1 1\nend 1\n", "3: error: CPU 1 is out of range (the design has 1)"),
        ("stop_extra", c5 + "stop 1 0 0\nend 1\n", "3: error: `stop` takes a tick and one id"),
    ]
    return [(n, t.encode("utf-8"), e) for n, t, e in cases]


def mutations(data: bytes, n: int, seed: int = 15) -> list[bytes]:
    """`n` corrupted copies of an event file: a byte changed, dropped or doubled (seeded)."""
    import random

    rng = random.Random(seed)
    alphabet = b"0123456789abcdefx -\n\0\xff"
    out = []
    for _ in range(n):
        b = bytearray(data)
        i = rng.randrange(len(b))
        kind = rng.randrange(3)
        if kind == 0:
            b[i] = rng.choice(alphabet)
        elif kind == 1:
            del b[i]
        else:
            b.insert(i, b[i])
        out.append(bytes(b))
    return out
