"""Hierarchy checks (paper sections 3.2, 3.4, 3.5, 3.7).

The command hierarchy must be a tree: every controller has at most one
supervisor, following `subordinates` never leads back to where it started,
levels strictly descend, and all non-simulator controllers share one root
(operator commands enter at the top only).  Lints: span of control over
about nine subordinates.
"""

from __future__ import annotations

from rcsc.diagnostics import Diagnostics
from rcsc.semantics import graphs
from rcsc.semantics.model import Design

MAX_SUBORDINATES = 9


def command_graph(design: Design) -> dict[str, dict[str, None]]:
    """supervisor -> subordinates, in declaration order."""
    g: dict[str, dict[str, None]] = {c.name: {} for c in design.controllers.values()}
    for c in design.controllers.values():
        for use in c.subordinates:
            g[c.name][use.name] = None
            g.setdefault(use.name, {})
    return g


def check(design: Design, diags: Diagnostics) -> None:
    g = command_graph(design)
    ctrls = design.controllers

    # Exactly one supervisor: report every supervisor after the first.
    for c in ctrls.values():
        for use in c.subordinates:
            sub = ctrls[use.name]
            if use.name == c.name:
                diags.add("E0301", use.span, f"`{c.name}` lists itself as a subordinate", "itself")
                continue
            if sub.supervisor is None:
                sub.supervisor = c.name
                continue
            first = ctrls[sub.supervisor]
            first_use = next(u for u in first.subordinates if u.name == use.name)
            diag = diags.add("E0300", use.span, f"`{use.name}` already has the supervisor `{first.name}`", "second supervisor")
            diag.with_label(first_use.span, f"first supervisor `{first.name}`").with_note(
                "an RCS hierarchy is a tree: each controller takes commands from one supervisor"
            )

    # Cycles (self-loops were reported above).
    cycle_edges: set[tuple[str, str]] = set()
    for cycle in graphs.cycles(g):
        if len(cycle) == 1:
            continue
        cycle_edges.update(zip(cycle, cycle[1:] + cycle[:1]))
        start = min(cycle)
        k = cycle.index(start)
        order = cycle[k:] + cycle[:k]
        last, first = order[-1], order[0]
        use = next(u for u in ctrls[last].subordinates if u.name == first)
        diags.add("E0301", use.span, f"command hierarchy has a cycle through `{start}`", "closes the cycle").with_note(
            "cycle: " + " -> ".join(order + [start])
        )

    # Levels descend.  A cycle cannot descend (already E0301), and a missing
    # `level` (E0209, taken as 0) says nothing: no follow-on findings for those.
    for c in ctrls.values():
        for use in c.subordinates:
            sub = ctrls[use.name]
            if (c.name, use.name) in cycle_edges or c.level_span is None or sub.level_span is None:
                continue
            if use.name != c.name and sub.level >= c.level:
                diag = diags.add(
                    "E0302",
                    use.span,
                    f"subordinate `{sub.name}` (level {sub.level}) is not below `{c.name}` (level {c.level})",
                    "level not below",
                )
                if sub.level_span is not None:
                    diag.with_label(sub.level_span, f"`{sub.name}` is level {sub.level}")

    # One root among the controllers that are not simulators.
    roots = [c for c in ctrls.values() if c.supervisor is None and not c.simulator]
    for extra in roots[1:]:
        diag = diags.add("E0303", extra.name_span, f"`{extra.name}` is a second top-level controller", "no supervisor")
        diag.with_label(roots[0].name_span, f"`{roots[0].name}` is the top")
        diag.with_help(f"make `{extra.name}` a subordinate of a controller, or mark it `simulator` if it models the plant")

    # Span of control.
    for c in ctrls.values():
        if len(c.subordinates) > MAX_SUBORDINATES:
            span = c.subordinates[0].span.to(c.subordinates[-1].span)
            diags.add("W0310", span, f"`{c.name}` has {len(c.subordinates)} subordinates", f"more than {MAX_SUBORDINATES}").with_help(
                "group subordinates under an intermediate level"
            )
