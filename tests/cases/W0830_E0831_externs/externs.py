# pathlength is misspelt (W0830 says so); gear_of returns a number, not a
# member of Gear (E0831).


def pathlength(dx, dy):
    return (dx * dx + dy * dy) ** 0.5


def gear_of(rpm):
    return rpm / 1000.0
