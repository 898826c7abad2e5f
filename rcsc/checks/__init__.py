"""Structural checks on the design model, one check family per module.

Each family is a function `check(design, diags)` that only reads the model
(except the hierarchy check, which records each controller's supervisor, and
the timing check, which records each controller's CPU, divider and period and
the design's crossing buffers, for later stages).
"""

from __future__ import annotations

from rcsc.checks import commands, cycle, floats, guards, hierarchy, ownership, plans, timing, values
from rcsc.diagnostics import Diagnostics
from rcsc.semantics.model import Design

FAMILIES = (hierarchy, ownership, plans, commands, floats, timing, cycle, guards, values)


def check_model(design: Design, diags: Diagnostics, guard_options: guards.Options | None = None) -> None:
    """Run every check family; findings go to `diags`."""
    for family in FAMILIES:
        if family is guards:
            guards.check(design, diags, guard_options)
        else:
            family.check(design, diags)
