"""The graph questions every design is asked (rcsc/semantics/graphs.py).

They are answered without networkx, which is imported only to describe what
is wrong.  Here the answers are compared with networkx's on random graphs,
and a check of a well-formed design is shown not to import networkx while a
design with an unreachable state does, and reports it.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import networkx as nx
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rcsc.semantics import graphs

ROOT = Path(__file__).resolve().parent.parent

NODES = [f"s{i}" for i in range(7)]
edges = st.lists(st.tuples(st.sampled_from(NODES), st.sampled_from(NODES)), max_size=16)


def _succ(pairs: list[tuple[str, str]]) -> dict[str, dict[str, None]]:
    succ: dict[str, dict[str, None]] = {n: {} for n in NODES}
    for a, b in pairs:
        succ[a][b] = None
    return succ


def _nx(pairs: list[tuple[str, str]]) -> nx.DiGraph:
    g = nx.DiGraph()
    g.add_nodes_from(NODES)
    g.add_edges_from(pairs)
    return g


@settings(max_examples=300, deadline=None)
@given(edges)
def test_reachability_and_cycles_agree_with_networkx(pairs: list[tuple[str, str]]) -> None:
    succ, g = _succ(pairs), _nx(pairs)
    pred = graphs.reverse(succ)
    for n in NODES:
        assert graphs.descendants(succ, n) == nx.descendants(g, n)
        assert graphs.descendants(pred, n) == nx.ancestors(g, n)
        assert graphs.reach(succ, n) == nx.descendants(g, n) | ({n} if any(n in c for c in nx.simple_cycles(g)) else set())
    assert graphs.has_cycle(succ) == (not nx.is_directed_acyclic_graph(g))
    found = graphs.cycles(succ)
    assert sorted(map(tuple, found)) == sorted(map(tuple, nx.simple_cycles(g)))
    assert [sorted(c) for c in found] == sorted(sorted(c) for c in found)


_PROBE = """
import json, sys
from rcsc.diagnostics import Diagnostics
from rcsc.driver import check_path
result = check_path(sys.argv[1])
print(json.dumps({"codes": sorted({d.code for d in result.diags.items}), "networkx": "networkx" in sys.modules}))
"""


def _check(path: Path) -> dict:
    out = subprocess.run([sys.executable, "-c", _PROBE, str(path)], capture_output=True, text=True, check=True,
                         env={**__import__("os").environ, "RCSC_NO_CACHE": "1"}).stdout
    return json.loads(out.splitlines()[-1])


@pytest.mark.parametrize("example", ["machine_tool", "submarine"])
def test_a_well_formed_design_is_checked_without_importing_networkx(example: str) -> None:
    found = _check(ROOT / "examples" / example / f"{example}.rcs")
    assert not any(c.startswith("E") for c in found["codes"])
    assert found["networkx"] is False


@pytest.mark.parametrize("case, code", [
    ("E0502_unreachable_state", "E0502"),
    ("E0503_only_the_trap_is_reported", "E0503"),
    ("W0526_only_fails", "W0526"),
    ("E0301_cycle", "E0301"),
    ("E0205_recursive_function", "E0205"),
])
def test_networkx_describes_what_is_wrong(case: str, code: str) -> None:
    found = _check(ROOT / "tests" / "cases" / f"{case}.rcs")
    assert code in found["codes"]
    assert found["networkx"] is True
