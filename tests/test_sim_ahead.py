"""The paper's AHEAD plan (Appendix C), walked through its branches cycle by cycle.

The design (tests/sim/ahead_paper.rcs) schedules PR before TB on one CPU.
TB finishes any command in two cycles: in the cycle a command arrives it
takes its `new` rule, in the next cycle it reports DONE.  Inputs and operator
commands for cycle N are applied before any controller steps in cycle N.

Derivation from the cycle semantics (docs/language.md) (PR steps first, then TB, every cycle):

 c1  ship BACK, operator AHEAD(5) serial 1.  PR: new command (echo 1, state
     new); E1 fires (ship moving back): TB.STOP with serial 1; next S2.
     TB (same cycle, after PR's write): new command serial 1, P0 -> S1.
 c2  PR in S2: TB's echo is 1 = last sent but its status is EXEC, so TB.done
     is false; no rule fires (rule stays E1).  TB: P1 -> done (DONE).
 c3  PR: TB.done -> E5: prop_speed = 50, TB.AHEAD(rpm=50) serial 2, -> S1.
     TB: new command serial 2, A0 -> RUN, rpm = 50.
 c4  PR: TB EXEC -> nothing.  TB: A1 -> done.
 c5  speed BELOW.  PR: E2: prop_speed = 51, TB.AHEAD(51) serial 3.  TB: RUN.
 c6  PR: nothing (TB EXEC for serial 3).  TB: done.
 c7  speed AT.  PR: E3 reports AT_GOAL (state stays S1).
 c8  PR: E3 again (AT_GOAL holds).
 c9  speed ABOVE.  PR: E4 (status back to EXEC): prop_speed = 50,
     TB.AHEAD(50) serial 4.  TB: RUN.
 c10 PR: nothing.  TB: done.
 c11 speed AT.  PR: E3, AT_GOAL.   c12: E3 again.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rcsc.diagnostics import Diagnostics
from rcsc.driver import check_path
from rcsc.sim.runner import run_scenario
from rcsc.front.scenario import text_to_scenario
from rcsc.sim.simulate import Simulator
from rcsc.front.source import SourceFile

HERE = Path(__file__).parent / "sim"

# cycle: (PR.state, PR.rule, PR.status, prop_speed, TB.echo, TB.status, TB.state, TB.rpm)
EXPECTED = {
    1: ("S2", "E1", "EXEC", 0, 1, "EXEC", "S1", 0),
    2: ("S2", "E1", "EXEC", 0, 1, "DONE", "done", 0),
    3: ("S1", "E5", "EXEC", 50, 2, "EXEC", "RUN", 50),
    4: ("S1", "E5", "EXEC", 50, 2, "DONE", "done", 50),
    5: ("S1", "E2", "EXEC", 51, 3, "EXEC", "RUN", 51),
    6: ("S1", "E2", "EXEC", 51, 3, "DONE", "done", 51),
    7: ("S1", "E3", "AT_GOAL", 51, 3, "DONE", "done", 51),
    8: ("S1", "E3", "AT_GOAL", 51, 3, "DONE", "done", 51),
    9: ("S1", "E4", "EXEC", 50, 4, "EXEC", "RUN", 50),
    10: ("S1", "E4", "EXEC", 50, 4, "DONE", "done", 50),
    11: ("S1", "E3", "AT_GOAL", 50, 4, "DONE", "done", 50),
    12: ("S1", "E3", "AT_GOAL", 50, 4, "DONE", "done", 50),
}


@pytest.fixture(scope="module")
def design():
    result = check_path(str(HERE / "ahead_paper.rcs"))
    assert not result.diags.items, [d.message for d in result.diags]
    return result.model


def _scenario(design, text: str, name: str = "inline.scn"):
    diags = Diagnostics()
    sc = text_to_scenario(SourceFile(name, text), design, diags)
    assert sc is not None, [(d.code, d.message) for d in diags]
    return sc


def test_ahead_branches_cycle_by_cycle(design) -> None:
    sc = _scenario(design, (HERE / "ahead_branches.scn").read_text(), "ahead_branches.scn")
    run = run_scenario(design, sc)
    seen = {}
    for snap in run.snapshots:
        pr, tb = snap.ctrl["PR"], snap.ctrl["TB"]
        seen[snap.cycle] = (pr.state, pr.rule, pr.status, pr.fields["prop_speed"], tb.echo, tb.status, tb.state, tb.fields["rpm"])
    assert seen == EXPECTED
    assert run.passed, [(r.expect.text, r.cycle, r.values) for r in run.results if not r.passed]
    assert [s.ctrl["PR"].echo for s in run.snapshots] == [1] * 12


def test_ship_ahead_takes_e0(design) -> None:
    sc = _scenario(design, "cycles 2\nat 1: ship_dir = ShipDir.AHEAD\nat 1: PR.AHEAD(speed = 3)\n")
    run = run_scenario(design, sc)
    pr = run.snapshots[0].ctrl["PR"]
    assert (pr.state, pr.rule, pr.fields["prop_speed"]) == ("S1", "E0", 30)
    assert run.snapshots[0].ctrl["TB"].state == "RUN"


def test_new_command_supersedes_running_plan(design) -> None:
    # c1: AHEAD(5) with the ship moving back: E1, waiting in S2 for TB's STOP.
    # c2: a new AHEAD(7) arrives while PR waits in S2.  It supersedes the
    # running plan at once: echo 2, state new, and with the ship now stopped
    # E0 fires in the same cycle: prop_speed = 70, TB.AHEAD(70) (TB serial 2).
    sc = _scenario(
        design,
        "cycles 3\nat 1: ship_dir = ShipDir.BACK\nat 1: PR.AHEAD(speed = 5)\n"
        "at 2: ship_dir = ShipDir.STOPPED\nat 2: PR.AHEAD(speed = 7)\n",
    )
    run = run_scenario(design, sc)
    c1, c2 = run.snapshots[0].ctrl, run.snapshots[1].ctrl
    assert (c1["PR"].echo, c1["PR"].state, c1["PR"].rule) == (1, "S2", "E1")
    assert (c2["PR"].echo, c2["PR"].state, c2["PR"].rule, c2["PR"].fields["prop_speed"]) == (2, "S1", "E0", 70)
    # TB dropped its STOP (serial 1) for AHEAD (serial 2) the same cycle.
    assert (c2["TB"].echo, c2["TB"].verb, c2["TB"].state, c2["TB"].fields["rpm"]) == (2, "AHEAD", "RUN", 70)


def test_stale_done_of_previous_command_is_not_done(design) -> None:
    """TB's DONE for serial 2 must not count as DONE for serial 3.

    On one CPU TB always answers a command in the cycle it is issued (it runs
    after PR), so the stale window only opens when TB has not stepped yet, as
    across CPUs.  Step PR alone to open it: after E2 issues serial 3, TB's
    status buffer still says echo 2 / DONE.
    """
    sim = Simulator(design)
    sim.set_input("speed_status", "BELOW")
    pr, tb = sim.runtimes["PR"], sim.runtimes["TB"]
    sim.operator_command("PR", "AHEAD", {"speed": 5})
    for _ in range(4):  # c1: E0 (TB serial 1) ... TB done for serial 1 by c2; c3: E2 serial 2; c4: TB done
        sim.begin_cycle()
        sim.run_cycle()
    assert (pr.status.rule, pr.last_sent["TB"], sim.statuses["TB"].echo_serial, sim.statuses["TB"].status) == ("E2", 2, 2, 1)
    sim.begin_cycle()
    sim.step(pr)  # c5: TB done for serial 2 -> E2 again, serial 3 sent
    assert (pr.status.rule, pr.last_sent["TB"]) == ("E2", 3)
    assert (sim.statuses["TB"].echo_serial, sim.statuses["TB"].status) == (2, 1)  # stale DONE of serial 2
    rpm_before = pr.fields["prop_speed"]
    for _ in range(3):  # TB does not step: PR must keep waiting, not trim again
        sim.begin_cycle()
        sim.step(pr)
        assert pr.status.rule == "E2" and pr.fields["prop_speed"] == rpm_before
        assert pr.last_sent["TB"] == 3
    sim.step(tb)  # TB takes serial 3
    sim.begin_cycle()
    sim.step(pr)
    assert pr.fields["prop_speed"] == rpm_before  # TB is EXEC for serial 3: still waiting
    sim.step(tb)  # TB done for serial 3
    sim.begin_cycle()
    sim.step(pr)
    assert pr.fields["prop_speed"] == rpm_before + 1 and pr.last_sent["TB"] == 4


def test_serial_wraps_past_u32_max_and_skips_zero(design) -> None:
    from rcsc.sim.simulate import next_serial

    assert next_serial(0) == 1
    assert next_serial(41) == 42
    assert next_serial(0xFFFFFFFF) == 1
    sim = Simulator(design)
    sim.runtimes["PR"].last_sent["TB"] = 0xFFFFFFFF
    sim.set_input("ship_dir", "AHEAD")
    sim.operator_command("PR", "AHEAD", {"speed": 1})
    sim.begin_cycle()
    sim.run_cycle()
    assert sim.commands["TB"].serial == 1 and sim.statuses["TB"].echo_serial == 1
    sim.begin_cycle()
    sim.run_cycle()  # TB done: the supervisor sees it through the wrapped serial
    sim.set_input("speed_status", "BELOW")
    sim.begin_cycle()
    sim.run_cycle()
    assert sim.runtimes["PR"].status.rule == "E2" and sim.commands["TB"].serial == 2
