# The stand-in for path_length, with a colon missing.
import math


def path_length(dx, dy)  # expect: E0830 @ 5:26
    return math.hypot(dx, dy)
