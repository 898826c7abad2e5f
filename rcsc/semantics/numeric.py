"""The numeric rules of the language (docs/language.md §5), in one place.

These functions are the reference: the constant folder, the simulator and the
conformance tests of the backends all use them.  Integers are fixed width and
wrap (two's complement); integer division truncates toward zero and division
or remainder by zero gives 0; float-to-int conversion saturates and NaN gives
0; f64 is plain IEEE-754 (Python floats).
"""

from __future__ import annotations

import math

from rcsc.semantics.types import IntType


def wrap(value: int, t: IntType) -> int:
    """Reduce `value` into the range of `t` the way two's-complement hardware does."""
    mask = (1 << t.bits) - 1
    value &= mask
    if t.signed and value >= 1 << (t.bits - 1):
        value -= 1 << t.bits
    return value


def int_div(a: int, b: int, t: IntType) -> int:
    """Truncating division; x / 0 == 0; MIN / -1 wraps to MIN."""
    if b == 0:
        return 0
    q = abs(a) // abs(b)
    if (a < 0) != (b < 0):
        q = -q
    return wrap(q, t)


def int_rem(a: int, b: int, t: IntType) -> int:
    """Remainder with the sign of the dividend; x % 0 == 0; MIN % -1 == 0."""
    if b == 0:
        return 0
    r = abs(a) % abs(b)
    if a < 0:
        r = -r
    return wrap(r, t)


def float_to_int(x: float, t: IntType) -> int:
    """Saturating conversion toward zero; NaN gives 0."""
    if math.isnan(x):
        return 0
    if x >= t.max:
        return t.max
    if x <= t.min:
        return t.min
    return int(x)  # truncates toward zero


def float_div(a: float, b: float) -> float:
    """IEEE division (x / 0.0 is +-inf or NaN), without Python's exception."""
    try:
        return a / b
    except ZeroDivisionError:
        if a == 0.0 or math.isnan(a):
            return math.nan
        negative = (math.copysign(1.0, a) < 0) != (math.copysign(1.0, b) < 0)
        return -math.inf if negative else math.inf
