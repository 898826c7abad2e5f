"""Several CPUs and divided rates: the model (periods, crossings, `age`), the
simulator's time base, fault injection and the multi-CPU trace."""

from __future__ import annotations

from pathlib import Path

import pytest

from rcsc import model as m
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
    from rcsc.scenario import text_to_scenario
    from rcsc.source import SourceFile

    diags = Diagnostics()
    text = "cycles 20\nat 1: TOP.RUN()\nat 9: freeze LOW\nat 4: stop planner\n"
    sc = text_to_scenario(SourceFile("f.scn", text), design, diags)
    assert not diags.items and sc is not None
    assert [(f.cycle, f.kind, f.name) for f in sc.faults] == [(4, "stop", "planner"), (9, "freeze", "LOW")]
