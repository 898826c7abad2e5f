# The stand-in for extern_fails.rcs: fails at its sixth call (tests/test_long_runs.py).
n = 0
def f(v):
    global n
    n += 1
    if n > 5:
        raise RuntimeError("boom")
    return v
