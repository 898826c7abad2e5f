"""The graph questions every design is asked, answered without importing networkx.

Every plan's state graph is asked what `new` reaches and what reaches
`done` or `error`; every design's command hierarchy and function calls are
asked whether they have a cycle.  On a well-formed design those are all the
questions, asked of graphs of a handful of nodes, where each answer takes
microseconds.  Importing networkx takes 70 ms, about a quarter of what a
re-check after an edit may cost in a fresh process, and its dispatch layer
costs more per call than these answers do.  So they come from the standard
library: a breadth-first walk (`reach`) and graphlib's cycle detection
(`has_cycle`).

networkx is imported (`networkx()`) only to describe what is wrong, when
something is: the cycles themselves, where an unreachable region is entered,
the loops a plan cannot leave.
"""

from __future__ import annotations

import graphlib
from collections.abc import Iterable, Mapping


def reach(succ: Mapping[str, Iterable[str]], start: str) -> set[str]:
    """The nodes reachable from `start` along `succ` in one step or more;
    `start` itself only if it lies on a cycle.  `networkx.descendants`
    leaves `start` out in both cases: callers that want it add it."""
    seen: set[str] = set()
    stack = [start]
    while stack:
        for n in succ.get(stack.pop(), ()):
            if n not in seen:
                seen.add(n)
                stack.append(n)
    return seen


def descendants(succ: Mapping[str, Iterable[str]], start: str) -> set[str]:
    """As `networkx.descendants`: what `start` leads to, without `start`."""
    return reach(succ, start) - {start}


def reverse(succ: Mapping[str, Iterable[str]]) -> dict[str, list[str]]:
    """The predecessors of each node (the graph with its edges turned round)."""
    pred: dict[str, list[str]] = {}
    for a, bs in succ.items():
        for b in bs:
            pred.setdefault(b, []).append(a)
    return pred


def has_cycle(succ: Mapping[str, Iterable[str]]) -> bool:
    """Whether following `succ` can come back to where it started (a node
    that leads to itself counts)."""
    try:
        graphlib.TopologicalSorter({a: tuple(bs) for a, bs in succ.items()}).prepare()
    except graphlib.CycleError:
        return True
    return False


def networkx():
    """The networkx module, imported when a finding needs it described."""
    import networkx

    return networkx


def to_networkx(succ: Mapping[str, Iterable[str]], keep: set[str] | None = None):
    """`succ` as a `networkx.DiGraph`, nodes and edges in `succ`'s order;
    with `keep`, only those nodes and the edges among them."""
    nx = networkx()
    g = nx.DiGraph()
    g.add_nodes_from(n for n in succ if keep is None or n in keep)
    g.add_edges_from((a, b) for a, bs in succ.items() if keep is None or a in keep for b in bs if keep is None or b in keep)
    return g


def cycles(succ: Mapping[str, Iterable[str]]) -> list[list[str]]:
    """The simple cycles of `succ` (a node that leads to itself is one),
    each as the nodes along it, sorted by their sorted nodes; networkx is
    imported only when there is one."""
    if not has_cycle(succ):
        return []
    return sorted(networkx().simple_cycles(to_networkx(succ)), key=sorted)
