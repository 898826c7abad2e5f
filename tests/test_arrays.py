"""Fixed-size arrays (docs/language.md §4.1): cases the differential tester's
generator found."""

from __future__ import annotations

import json
from pathlib import Path

from c_build import reference_trace
from rcsc.driver import check_path

NESTED_RECORDS = """design nested
record P { x: i32 }
gm o: i32 = 0 to env
controller Z level 1 budget 100 us {
    writes o
    verb GO
    local a: [[P; 2]; 2] = [[P(x = 1), P(x = 2)], [P(x = 3), P(x = 4)]]
    pre { o = a[1][0].x + a[cycle][1].x; }
    plan GO { R0: true | new -> done; }
}
cpu MAIN {
    heartbeat 10 ms
    schedule Z
}
"""


def test_an_array_of_arrays_of_records_is_a_constant_initial_value(tmp_path: Path) -> None:
    """`[[P(x = 1), P(x = 2)], [P(x = 3), P(x = 4)]]` is a constant (it was
    E0204 while `[[P(x = 1); 2]; 2]` and `[P(x = 1), P(x = 2)]` were not)."""
    design = tmp_path / "nested.rcs"
    design.write_text(NESTED_RECORDS, encoding="utf-8")
    result = check_path(str(design))
    assert result.ok and not result.diags.errors, [(d.code, d.message) for d in result.diags.items]
    scn = tmp_path / "nested.scn"
    scn.write_text('scenario "nested"\ncycles 2\n', encoding="utf-8")
    trace = [json.loads(line) for line in reference_trace(design, scn).decode().splitlines()]
    # cycle 1: a[1][0].x + a[1][1].x; cycle 2: a[2] is out of range, a zero P.
    assert [c["gm"]["o"] for c in trace] == [7, 3]
    bad = tmp_path / "bad.rcs"
    bad.write_text(NESTED_RECORDS.replace("P(x = 4)]]", "P(x = i32(cycle))]]"), encoding="utf-8")
    assert [d.code for d in check_path(str(bad)).diags.errors] == ["E0100"]  # `cycle` is no constant
