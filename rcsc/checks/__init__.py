"""Structural checks on the design model, one check family per module.

Each family is a function `check(design, diags)` that only reads the model
(except the hierarchy check, which records each controller's supervisor, and
the timing check, which records each controller's CPU, divider and period and
the design's crossing buffers, for later stages).

The families (and z3) are imported when first used (`FAMILIES`,
`check_model`), so that the light modules of this package (`cache`,
`replay`) load without them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from rcsc.checks import guards
    from rcsc.diagnostics import Diagnostics
    from rcsc.semantics.model import Design


def _families() -> tuple:
    from rcsc.checks import commands, cycle, floats, guards, hierarchy, ownership, plans, timing, values

    return (hierarchy, ownership, plans, commands, floats, timing, cycle, guards, values)


def __getattr__(name: str):
    if name == "FAMILIES":
        return _families()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def check_model(design: "Design", diags: "Diagnostics", guard_options: "guards.Options | None" = None, value_store=None,
                before_solver=None) -> None:
    """Run every check family; findings go to `diags`.  `value_store` (a
    `rcsc.checks.cache` store) keeps the value analysis between runs.
    `before_solver()`, if given, is called after the structural families,
    before the first that asks z3 (`rcsc.checks.incremental` decides there
    whether to go on)."""
    from rcsc.checks import guards, values

    for family in _families():
        if family is guards and before_solver is not None:
            before_solver()
        if family is guards:
            guards.check(design, diags, guard_options)
        elif family is values:
            values.check(design, diags, value_store)
        else:
            family.check(design, diags)
