"""Several CPUs and divided rates: the model (periods, crossings, `age`), the
simulator's time base, fault injection and the multi-CPU trace."""

from __future__ import annotations

from pathlib import Path

import pytest

from rcsc.semantics import model as m
from rcsc.driver import check_path

SIM = Path(__file__).parent / "sim"


@pytest.fixture(scope="module")
def design() -> m.Design:
    result = check_path(str(SIM / "multicpu.rcs"))
    assert not result.diags.items, [d.message for d in result.diags]
    assert result.model is not None
    return result.model


def test_period_gives_divider(design) -> None:
    top, low = design.controllers["TOP"], design.controllers["LOW"]
    assert (top.cpu, top.divider, top.period_ns, top.declared_period_ns) == ("planner", 2, 40_000_000, 40_000_000)
    assert (low.cpu, low.divider, low.period_ns, low.declared_period_ns) == ("servo", 1, 10_000_000, 0)
    assert design.base_tick_ns == 10_000_000


def test_crossings_in_documented_order(design) -> None:
    got = [(x.kind, x.name, x.writer_cpu, x.reader_cpus) for x in design.crossings]
    assert got == [
        ("gm", "target", "planner", ["servo"]),
        ("gm", "speed", "servo", ["planner"]),
        ("cmd", "LOW", "planner", ["servo"]),
        ("status", "LOW", "servo", ["planner"]),
    ]


def test_age_is_a_duration_of_gm_or_status(design) -> None:
    top = design.controllers["TOP"]
    ages = [s.value for s in top.post if isinstance(s, m.Assign) and s.target.name.endswith("_age")]
    assert isinstance(ages[0], m.Age) and ages[0].name == "speed" and str(ages[0].type) == "duration"
    assert isinstance(ages[1], m.SubView) and (ages[1].sub, ages[1].attr) == ("LOW", "age")


def test_scenario_faults_parse(design) -> None:
    from rcsc.diagnostics import Diagnostics
    from rcsc.front.scenario import text_to_scenario
    from rcsc.front.source import SourceFile

    diags = Diagnostics()
    text = "cycles 20\nat 1: TOP.RUN()\nat 9: freeze LOW\nat 4: stop planner\n"
    sc = text_to_scenario(SourceFile("f.scn", text), design, diags)
    assert not diags.items and sc is not None
    assert [(f.cycle, f.kind, f.name) for f in sc.faults] == [(4, "stop", "planner"), (9, "freeze", "LOW")]


# ---- the simulator on the common time base ---------------------------------------------
#
# The expected values below are derived by hand from the timing rules: the
# servo CPU (10 ms) releases at 0, 10, 20, ...; the planner CPU (20 ms) at
# 0, 20, 40, ...; TOP (period 40 ms) steps at 0, 40, 80, ...  A value written
# in a cycle is visible on the other CPU from that cycle's deadline, stamped
# with it; a buffer never written has the stamp -10 ms (one base tick).


def run(design, text: str):
    from rcsc.diagnostics import Diagnostics
    from rcsc.sim.runner import run_scenario
    from rcsc.front.scenario import text_to_scenario
    from rcsc.front.source import SourceFile

    diags = Diagnostics()
    sc = text_to_scenario(SourceFile("t.scn", text), design, diags)
    assert sc is not None and not diags.items, [d.message for d in diags]
    return run_scenario(design, sc)


def lines(run_result, cpu: str) -> dict[int, object]:
    """The CPU's trace lines by release instant in ms."""
    return {s.t // 1_000_000: s for s in run_result.cpu_cycles if s.cpu == cpu}


def test_divided_rate_and_crossing_stamps(design) -> None:
    r = run(design, "cycles 14\nat 1: TOP.RUN()\nat 3: load = 0.5\n")
    planner, servo = lines(r, "planner"), lines(r, "servo")
    assert sorted(planner) == list(range(0, 140, 20)) and sorted(servo) == list(range(0, 140, 10))
    # TOP steps every other planner cycle.
    assert [planner[t].ctrl["TOP"].fields["steps"] for t in sorted(planner)] == [1, 1, 2, 2, 3, 3, 4]
    # Before any write: age = release + one base tick.
    assert planner[0].ctrl["TOP"].fields["speed_age"] == 10_000_000
    assert servo[0].ctrl["LOW"].fields["target_age"] == 10_000_000
    # TOP's cycle 1 (0..20 ms) publishes `target` and the command at 20 ms.
    assert servo[10].gm["target"] == 0 and servo[10].ctrl["LOW"].echo == 0
    assert servo[20].gm["target"] == 1 and servo[20].ctrl["LOW"].fields["target_age"] == 0
    assert (servo[20].ctrl["LOW"].echo, servo[20].ctrl["LOW"].state) == (1, "S1")
    # `target` is written at every TOP step (0, 40, 80 ms) and stamped at the cycle's deadline.
    assert [servo[t].ctrl["LOW"].fields["target_age"] for t in (30, 50, 60, 70)] == [10_000_000, 30_000_000, 0, 10_000_000]
    # The input at tick 3 (20 ms) is stamped 20 ms and never rewritten.
    assert servo[20].ctrl["LOW"].fields["load_age"] == 0 and servo[70].ctrl["LOW"].fields["load_age"] == 50_000_000
    # LOW finishes at 70 ms (in_state 50 ms since 20 ms); TOP reads it at 80 ms:
    # the deadline at 80 ms publishes before the release at 80 ms reads.
    assert servo[70].ctrl["LOW"].status == "DONE" and servo[70].gm["speed"] == 1.5
    assert planner[80].ctrl["TOP"].status == "DONE" and planner[80].ctrl["TOP"].fields["low_age"] == 0
    assert planner[80].gm["speed"] == 1.5


def test_trace_lines_in_canonical_order(design) -> None:
    from rcsc.sim.trace import cycles_to_jsonl

    r = run(design, "cycles 4\nat 1: TOP.RUN()\n")
    text = cycles_to_jsonl(design, r.cpu_cycles)
    heads = [line.split(',"gm"')[0] for line in text.splitlines()]
    assert heads == [
        '{"cpu":"planner","cycle":1,"t":0',
        '{"cpu":"servo","cycle":1,"t":0',
        '{"cpu":"servo","cycle":2,"t":10000000',
        '{"cpu":"planner","cycle":2,"t":20000000',
        '{"cpu":"servo","cycle":3,"t":20000000',
        '{"cpu":"servo","cycle":4,"t":30000000',
    ]
    first = text.splitlines()[0]
    assert '"gm":{"target":1,"speed":0},"ctrl":{"TOP":{' in first  # only TOP's variables and controllers
    assert '"servo":' not in text and '"LOW"' not in first


def test_command_between_releases_waits_for_the_next_step(design) -> None:
    # Tick 2 is 10 ms: the planner's next release is 20 ms, TOP's next step 40 ms.
    r = run(design, "cycles 6\nat 2: TOP.RUN()\n")
    planner = lines(r, "planner")
    assert [planner[t].ctrl["TOP"].echo for t in (0, 20, 40)] == [0, 0, 1]


def test_stopped_cpu_ages_and_the_watchdog_fires(design) -> None:
    # The servo stops at tick 5 (40 ms): its last cycle (30 ms) published at 40 ms.
    r = run(design, "cycles 24\nat 1: TOP.RUN()\nat 5: stop servo\nexpect at 20: TOP.executing\nexpect at 21: TOP.error_code == 9\n")
    servo, planner = lines(r, "servo"), lines(r, "planner")
    assert max(servo) == 30  # a stopped CPU writes no more lines
    assert [planner[t].ctrl["TOP"].fields["low_age"] for t in (40, 80, 120, 160)] == [0, 40_000_000, 80_000_000, 120_000_000]
    assert (planner[200].ctrl["TOP"].rule, planner[200].ctrl["TOP"].status) == ("W1", "ERROR")
    assert r.passed, [(x.expect.text, x.cycle) for x in r.results if not x.passed]


def test_frozen_controller_keeps_its_stamp(design) -> None:
    # LOW is frozen from tick 3 (20 ms): its last step at 10 ms was published at 20 ms.
    r = run(design, "cycles 20\nat 1: TOP.RUN()\nat 3: freeze LOW\nexpect at 16: TOP.executing\nexpect at 17: TOP.error\n")
    servo, planner = lines(r, "servo"), lines(r, "planner")
    assert max(servo) == 190  # the CPU still runs
    assert servo[190].ctrl["LOW"].fields["steps"] == 2
    assert planner[120].ctrl["TOP"].fields["low_age"] == 100_000_000
    assert r.passed, [(x.expect.text, x.cycle) for x in r.results if not x.passed]


def test_expectations_see_each_buffer_as_its_writer_wrote_it(design) -> None:
    # LOW is done at tick 8 (70 ms) on its own CPU, TOP only at tick 9 (80 ms).
    r = run(design, "cycles 10\nat 1: TOP.RUN()\nexpect at 8: LOW.done and not TOP.done and speed == 1.0\nexpect at 9: TOP.done\n")
    assert r.passed, [(x.expect.text, x.cycle, x.values) for x in r.results if not x.passed]
    assert [s.cycle for s in r.snapshots] == list(range(1, 11))


def test_csv_and_vcd_show_the_observer_view_per_tick(design, tmp_path) -> None:
    from rcsc.cli import main

    scn = tmp_path / "t.scn"
    scn.write_text("cycles 10\nat 1: TOP.RUN()\n")
    out = tmp_path / "run.csv"
    assert main(["sim", str(SIM / "multicpu.rcs"), "--scenario", str(scn), "-o", str(out)]) == 0
    rows = out.read_text().splitlines()
    assert rows[0].startswith("cycle,target,speed,load,TOP.echo") and len(rows) == 11
    vcd = tmp_path / "run.vcd"
    assert main(["sim", str(SIM / "multicpu.rcs"), "--scenario", str(scn), "-o", str(vcd)]) == 0
    assert "#90000000" in vcd.read_text()  # tick 9 is at 80 ms; VCD times are ticks * base tick


# ---- rcsc budget: rate groups and frames -------------------------------------------------


@pytest.mark.parametrize("name", ["rates", "multicpu"])
def test_budget_table_golden(name, golden, capsys) -> None:
    from rcsc.cli import main

    assert main(["budget", str(SIM / f"{name}.rcs")]) == 0
    golden(f"budget/{name}.txt", capsys.readouterr().out)


def test_frames_follow_the_dividers() -> None:
    from rcsc.checks.frames import frames, hyperperiod, worst_frame

    d = check_path(str(SIM / "rates.rcs")).model
    cpu = d.cpus["main"]
    assert hyperperiod(d, cpu) == 10
    got = [(f.cycles, f.controllers, f.total_ns) for f in frames(d, cpu)]
    assert got == [
        ([1], ["PLAN", "PRIM", "SERVO"], 6_500_000),
        ([2, 3, 4, 5, 7, 8, 9, 10], ["SERVO"], 1_500_000),
        ([6], ["PRIM", "SERVO"], 3_500_000),
    ]
    assert worst_frame(d, cpu).cycles == [1]


def test_budget_reports_a_frame_overrun(capsys) -> None:
    from rcsc.cli import main

    code = main(["budget", str(Path(__file__).parent / "cases" / "E0600_frame_overrun.rcs")])
    out, err = capsys.readouterr()
    assert code != 0
    assert "cycle 1      11 ms  OVERRUN 1 ms  A, B\n" in out and "cycle 2       6 ms  slack 4 ms    A\n" in out
    assert "error[E0600]" in err and "not the heaviest frame" in err


def test_single_rate_table_is_unchanged(capsys) -> None:
    from rcsc.cli import main

    assert main(["budget", str(Path(__file__).parents[1] / "examples" / "submarine" / "submarine.rcs")]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[:2] == ["cpu MAIN: heartbeat 30 ms", "  controller   level     budget   share"]
    assert out.splitlines()[-1] == "  slack                 23.5 ms" and "frames" not in out


# ---- faults on a single-CPU design, and the CLI ----------------------------------------------


def test_single_cpu_stop_ends_the_trace_but_not_the_expectations(tmp_path, capsys) -> None:
    from rcsc.cli import main

    scn = tmp_path / "stop.scn"
    # ahead_paper: PR and TB on one 30 ms CPU.  After the stop at tick 5 the
    # trace has no more lines, and expectations see the state of cycle 4.
    scn.write_text("cycles 8\nat 1: PR.AHEAD(speed = 5)\nat 5: stop MAIN\nexpect at 8: PR.echo == 1\n")
    code = main(["sim", str(SIM / "ahead_paper.rcs"), "--scenario", str(scn)])
    out, err = capsys.readouterr()
    assert code == 0, err
    lines = out.splitlines()
    assert [int(x.split(",")[0].split(":")[1]) for x in lines] == [1, 2, 3, 4]


def test_single_cpu_freeze_keeps_the_status(tmp_path) -> None:
    d = check_path(str(SIM / "ahead_paper.rcs")).model
    r = run(d, "cycles 6\nat 1: PR.AHEAD(speed = 5)\nat 2: freeze TB\n")
    tb = [s.ctrl["TB"] for s in r.snapshots]
    assert tb[1:] == [tb[0]] * 5  # TB stepped in cycle 1 only
    assert [s.cycle for s in r.trace_snapshots] == [1, 2, 3, 4, 5, 6]


def test_sim_cli_writes_the_multi_cpu_trace(tmp_path, capsys) -> None:
    import json

    from rcsc.cli import main

    scn = tmp_path / "t.scn"
    scn.write_text("cycles 6\nat 1: TOP.RUN()\n")
    assert main(["sim", str(SIM / "multicpu.rcs"), "--scenario", str(scn)]) == 0
    out = capsys.readouterr().out
    rows = [json.loads(x) for x in out.splitlines()]
    assert [(r["cpu"], r["cycle"], r["t"]) for r in rows] == [
        ("planner", 1, 0), ("servo", 1, 0), ("servo", 2, 10_000_000), ("planner", 2, 20_000_000),
        ("servo", 3, 20_000_000), ("servo", 4, 30_000_000), ("planner", 3, 40_000_000), ("servo", 5, 40_000_000),
        ("servo", 6, 50_000_000),
    ]
    assert list(rows[0]) == ["cpu", "cycle", "t", "gm", "ctrl"]
    assert main(["sim", str(SIM / "multicpu.rcs"), "--scenario", str(scn)]) == 0
    assert capsys.readouterr().out == out  # same input, same bytes


def test_failures_of_multi_cpu_scenarios_name_ticks(design) -> None:
    from rcsc.sim.testrun import failure_text

    r = run(design, "cycles 10\nat 1: TOP.RUN()\nexpect at 7: LOW.done\n")
    assert not r.passed and r.multi_cpu
    assert "false at tick 7: LOW.status = EXEC" in failure_text(r)


# ---- an independent reading of the trace: rule 3 of the crossing semantics ------------------


@pytest.mark.parametrize(
    "design_path, scenario",
    [
        (SIM / "multicpu.rcs", "cycles 40\nat 1: TOP.RUN()\nat 3: load = 0.5\nat 17: stop servo\n"),
        (Path(__file__).parents[1] / "examples/machine_tool/machine_tool.rcs", (Path(__file__).parents[1] / "examples/machine_tool/scenarios/full_cut.scn").read_text()),
        (Path(__file__).parents[1] / "examples/machine_tool/machine_tool.rcs", (Path(__file__).parents[1] / "examples/machine_tool/scenarios/servo_cpu_stops.scn").read_text()),
    ],
    ids=["multicpu-stop", "machine_tool-full_cut", "machine_tool-servo_stops"],
)
def test_reader_copy_is_the_newest_published_by_a_deadline(design_path, scenario) -> None:
    """Each CPU line's copy of a GM variable written on another CPU equals the writer's
    copy after its latest cycle whose deadline is at or before the reader's release."""
    d = check_path(str(design_path)).model
    assert check_reader_copies(d, run(d, scenario)) > 20


def check_reader_copies(d, r) -> int:
    """Assert rule 3 on every crossing GM variable of a multi-CPU run; returns how many copies it checked."""
    period = {name: cpu.heartbeat_ns for name, cpu in d.cpus.items()}
    by_cpu: dict[str, list] = {}
    for line in r.cpu_cycles:
        by_cpu.setdefault(line.cpu, []).append(line)
    checked = 0
    for x in d.crossings:
        if x.kind != "gm":
            continue
        writer_lines = by_cpu.get(x.writer_cpu, [])
        for reader in x.reader_cpus:
            for line in by_cpu.get(reader, []):
                done = [w for w in writer_lines if w.t + period[x.writer_cpu] <= line.t]
                expected = done[-1].gm[x.name] if done else d.gm[x.name].init
                assert line.gm[x.name] == expected, (x.name, reader, line.t)
                checked += 1
    return checked


# ---- random placements: invariants of the time base ------------------------------------------

PROPERTY_DESIGN = """
design prop
gm a: f64 = 0.0
gm b: f64 = 0.0
gm c: f64 = 0.0
controller L3 level 3 budget 1 ms{p3} {{
    subordinates L2
    reads b
    writes c
    status sub_age: duration = 0 ms
    status in_age: duration = 0 ms
    verb RUN
    post {{ c = c + 1.0; sub_age = age(L2); in_age = age(b); }}
    plan RUN {{ E0: true | new -> S1 | L2.GO(); E1: L2.done | S1 -> done; E2: L2.error | S1 -> error(1); }}
}}
controller L2 level 2 budget 1 ms{p2} {{
    subordinates L1
    reads a, c
    writes b
    status sub_age: duration = 0 ms
    status in_age: duration = 0 ms
    verb GO
    post {{ b = b + 1.0; sub_age = age(L1); in_age = age(a); }}
    plan GO {{ E0: true | new -> S1 | L1.GO(); E1: L1.done | S1 -> done; E2: L1.error | S1 -> error(1); }}
}}
controller L1 level 1 budget 1 ms{p1} {{
    reads b
    writes a
    status in_age: duration = 0 ms
    verb GO
    post {{ a = a + 1.0; in_age = age(b); }}
    plan GO {{ E0: true | new -> S1; E1: in_state >= 120 ms | S1 -> done; }}
}}
{cpus}
"""


@pytest.mark.parametrize("seed", range(16))
def test_random_placements_keep_the_timing_invariants(seed, tmp_path) -> None:
    import random

    rnd = random.Random(seed)
    beats = rnd.choice([[10, 20, 40], [10, 30, 60], [20, 20, 60], [10, 10, 10]])
    ncpu = rnd.randint(1, 3)
    names = ["L1", "L2", "L3"]
    rnd.shuffle(names)  # every CPU gets a controller (an empty schedule is E0209)
    placement = {n: i if i < ncpu else rnd.randrange(ncpu) for i, n in enumerate(names)}
    dividers = {n: rnd.choice([1, 1, 2, 3]) for n in ("L1", "L2", "L3")}
    cpus = []
    for k in range(ncpu):
        sched = [n for n in ("L3", "L2", "L1") if placement[n] == k]
        rnd.shuffle(sched)
        cpus.append(f"cpu C{k} {{ heartbeat {beats[k]} ms" + (f" schedule {', '.join(sched)}" if sched else "") + " }")
    periods = {n: f" period {dividers[n] * beats[placement[n]]} ms" if dividers[n] > 1 else "" for n in dividers}
    path = tmp_path / "prop.rcs"
    path.write_text(PROPERTY_DESIGN.format(p1=periods["L1"], p2=periods["L2"], p3=periods["L3"], cpus="\n".join(cpus)))
    result = check_path(str(path))
    assert result.ok and result.model is not None, [f"{x.code} {x.message}" for x in result.diags.errors]
    d = result.model
    ticks = 120
    r = run(d, f"cycles {ticks}\nat 1: L3.RUN()\n")
    r2 = run(d, f"cycles {ticks}\nat 1: L3.RUN()\n")  # determinism
    assert (r2.cpu_cycles, r2.trace_snapshots, r2.snapshots) == (r.cpu_cycles, r.trace_snapshots, r.snapshots)
    if len(d.cpus) == 1:  # one CPU: the single-CPU trace, read as that CPU's lines
        from rcsc.sim.trace import CpuSnapshot

        (name, cpu), = d.cpus.items()
        r.cpu_cycles = [CpuSnapshot(name, s.cycle, (s.cycle - 1) * cpu.heartbeat_ns, s.gm, s.ctrl) for s in r.trace_snapshots]
    base = d.base_tick_ns
    horizon = ticks * base
    used = {c.cpu for c in d.controllers.values()}
    for name, cpu in d.cpus.items():
        lines = [x for x in r.cpu_cycles if x.cpu == name]
        if name in used:  # one line per cycle, released on its grid
            assert [x.t for x in lines] == list(range(0, horizon, cpu.heartbeat_ns))
    # Each controller steps on its own grid: its `steps`-like counter is its GM output.
    written = {"L1": "a", "L2": "b", "L3": "c"}
    for n, v in written.items():
        c = d.controllers[n]
        own = [x for x in r.cpu_cycles if x.cpu == c.cpu]
        assert [x.gm[v] for x in own] == [float(1 + i // c.divider) for i in range(len(own))], n
    check_reader_copies(d, r)
    # While the writer runs, a reader's copy is never older than the writer's period
    # (once the first value has arrived).
    settle = 2 * max(c.period_ns for c in d.controllers.values()) + max(x.heartbeat_ns for x in d.cpus.values())
    readers = {"L3": [("sub_age", "L2"), ("in_age", "L2")], "L2": [("sub_age", "L1"), ("in_age", "L1")], "L1": [("in_age", "L2")]}
    for n, pairs in readers.items():
        c = d.controllers[n]
        for line in (x for x in r.cpu_cycles if x.cpu == c.cpu and x.t >= settle):
            for fld, writer in pairs:
                assert 0 <= line.ctrl[n].fields[fld] <= d.controllers[writer].period_ns, (n, fld, line.t)
