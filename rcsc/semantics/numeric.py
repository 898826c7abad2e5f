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


# ---- the math built-ins (docs/language.md, "Math built-ins") -------------------------
#
# Each is defined bit for bit, so that the simulator, C and Rust agree on every
# input, signed zeros and NaN included.  The targets compute them with the same
# integer algorithms (rcs_num.h, num.rs): no libm, no dependence on the
# floating-point rounding mode or on compiler flags.  Python's math.sqrt is
# correctly rounded (IEEE-754 requires it), as are these.
#
# - sqrt(x): correctly rounded; sqrt(-0.0) == -0.0, sqrt(x < 0) and sqrt(NaN) are NaN.
# - floor, ceil, trunc, round_even: the integer (as an f64) below, above,
#   toward zero, nearest with ties to even; a zero result has the sign of x
#   (ceil(-0.5) == -0.0); NaN and +-inf are returned unchanged.
# - copysign(x, y): |x| with the sign of y; a NaN `y` counts as positive (the
#   sign bit of a NaN depends on the machine that made it).
# - min, max: NaN if either is NaN; min(-0.0, 0.0) == -0.0 and
#   max(-0.0, 0.0) == 0.0 in either order.

import struct as _struct

_SIGN = 1 << 63


def f64_bits(x: float) -> int:
    return _struct.unpack("<Q", _struct.pack("<d", x))[0]


def f64_from_bits(b: int) -> float:
    return _struct.unpack("<d", _struct.pack("<Q", b))[0]


def _signed_zero_of(r: float, x: float) -> float:
    return math.copysign(0.0, x) if r == 0.0 else r


def f64_trunc(x: float) -> float:
    if not math.isfinite(x):
        return x
    return _signed_zero_of(float(math.trunc(x)), x)


def f64_floor(x: float) -> float:
    if not math.isfinite(x):
        return x
    return _signed_zero_of(float(math.floor(x)), x)


def f64_ceil(x: float) -> float:
    if not math.isfinite(x):
        return x
    return _signed_zero_of(float(math.ceil(x)), x)


def f64_round_even(x: float) -> float:
    if not math.isfinite(x):
        return x
    return _signed_zero_of(float(round(x)), x)  # round(float) ties to even, exactly


def f64_sqrt(x: float) -> float:
    if math.isnan(x) or x < 0.0:
        return math.nan
    return math.sqrt(x)  # sqrt(-0.0) == -0.0


def f64_copysign(x: float, y: float) -> float:
    if math.isnan(y):
        return math.fabs(x)
    return math.copysign(x, y)


def f64_min(a: float, b: float) -> float:
    if math.isnan(a) or math.isnan(b):
        return math.nan
    if a == b:  # equal: only the zeros differ, and min prefers -0.0
        return f64_from_bits(f64_bits(a) | f64_bits(b))
    return a if a < b else b


def f64_max(a: float, b: float) -> float:
    if math.isnan(a) or math.isnan(b):
        return math.nan
    if a == b:
        return f64_from_bits(f64_bits(a) & f64_bits(b))
    return a if a > b else b


def sqrt_bits(x: float) -> float:
    """sqrt by the targets' integer algorithm (rcs_sqrt in rcs_num.h, num::sqrt_f64):
    kept here so that tests compare it with math.sqrt on many inputs."""
    if math.isnan(x) or x < 0.0:
        return math.nan
    if x == 0.0 or math.isinf(x):
        return x
    bits = f64_bits(x)
    e = (bits >> 52) & 0x7FF
    mant = bits & ((1 << 52) - 1)
    if e == 0:  # subnormal: normalise
        e = 1
        while not mant & (1 << 52):
            mant <<= 1
            e -= 1
    else:
        mant |= 1 << 52
    e -= 1023  # x == mant * 2^(e - 52)
    if e & 1:
        mant <<= 1
        e -= 1
    # q = isqrt(mant << 54), one result bit per step (54 bits: 53 and a guard bit)
    rem = q = 0
    for i in range(53, -1, -1):
        two = ((mant << 54) >> (2 * i)) & 3
        rem = (rem << 2) | two
        t = (q << 2) | 1
        q <<= 1
        if rem >= t:
            rem -= t
            q |= 1
    guard = q & 1
    q >>= 1
    if guard and (rem != 0 or q & 1):
        q += 1
    return f64_from_bits((((e >> 1) + 1023) << 52) + q - (1 << 52))
