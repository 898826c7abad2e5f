"""The reference simulator: the cycle semantics executed.

One CPU's cycle (`simulate`), several CPUs on one time base (`timebase`), the
trace formats, and scenario runs with their expectations (`runner`, `testrun`).
"""
