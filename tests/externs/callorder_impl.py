"""The extern functions of callorder.rcs for `rcsc sim` (the reference the
compiled targets are compared with; tests/test_extern_order.py).

Each call folds its inputs into a running number, the journal `s`, kept
from call to call: a different order of calls, a call too many or too few,
or an argument passed in the wrong place changes every value after it.
callorder_externs.c, externs_impl.rs and callorder_0_externs.adb compute
the same in C, Rust and Ada.
"""

MODES = ("A", "B", "C")


def externs() -> dict:
    state = {"s": 0}

    def mix(v: int) -> int:
        state["s"] = (state["s"] * 31 + v) % 1000003
        return state["s"]

    def t_i32(k):
        return mix(k)

    def t_f64(x, k):
        return x + float(mix(k))

    def t_bool(k):
        return mix(k) % 2 == 1

    def t_mode(m, k):
        return MODES[mix(k * 4 + MODES.index(m)) % 3]

    def t_pt(p, k):
        s = mix(k * 7 + (p["a"] & 1023))
        return {"a": s % 100, "b": p["b"] + 1.0}

    def t_dur(d, k):
        return d + mix(k) * 1_000_000

    def t_u32(u, k):
        return (u + mix(k)) % 2**32

    def t_i64(v, k):
        return mix(k) * 1024 + (v & 1023)

    def t_arr(xs, k):
        mix(k)
        for x in xs:
            mix(x & 1023)
        return state["s"]

    def pair(a, b):
        mix(a & 1023)
        return mix(b & 1023)

    def peek():
        return state["s"]

    return {f.__name__: f for f in (t_i32, t_f64, t_bool, t_mode, t_pt, t_dur, t_u32, t_i64, t_arr, pair, peek)}
