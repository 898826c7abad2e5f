"""Exact comparisons of floating-point values in conditions (a lint).

W0523 `==` on f64 in a guard
    A measured or computed `f64` is almost never exactly equal to a value:
    `level == 2.0` can be skipped over between two cycles and the rule never
    fires.  Compare with a tolerance (`abs(level - 2.0) <= 0.01`) or with an
    inequality.  When exact equality is meant (a value copied unchanged, a
    flag stored as 0.0/1.0), say so on the line:
    `// rcsc: allow(W0523) set only to 0.0 or 1.0`.
"""

from __future__ import annotations

from rcsc.semantics import model as m
from rcsc.diagnostics import Diagnostics
from rcsc.semantics.model import Design
from rcsc.semantics.types import FloatType


def check(design: Design, diags: Diagnostics) -> None:
    for c in m.checked_controllers(design):
        for plan in c.plans.values():
            for r in plan.rules:
                if r.guard is None:
                    continue
                for e in m.walk_expr(r.guard):
                    if isinstance(e, m.Binary) and e.op == "==" and isinstance(e.left.type, FloatType) and isinstance(e.right.type, FloatType):
                        diag = diags.add("W0523", e.span, f"rule `{r.label}` compares f64 values with `==`", "exact comparison")
                        diag.with_note("a measured or computed value is rarely exactly equal: the rule may never fire")
                        diag.with_help("compare with a tolerance, `abs(a - b) <= TOL`, or an inequality; if exact equality is meant, add `// rcsc: allow(W0523) why`")
