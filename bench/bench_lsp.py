"""The language server's re-check after a one-line edit, per example.

The server runs the whole front end on the edited, unsaved text (the loader's
overlay) each time the typing pauses; this times exactly that call
(`driver.check_path(path, overlay=..., memory=...)`, with what the server
keeps in memory between checks: the last check of the design, for the
incremental re-check of the controllers an edit changed, and the guard and
value analyses) after changing one rule's guard, as the median of N runs in
a warm process (the server is a long-lived process).
Goal: under 100 ms on the examples.  Run from the repository root:

    python bench/bench_lsp.py [--runs 9]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted((ROOT / "examples").glob("*/*.rcs"))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=9)
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    from rcsc import driver
    from rcsc.checks import cache, incremental

    print(f"{'example':<44} {'median ms':>10} {'goal ms':>8}")
    for path in EXAMPLES:
        text = path.read_text(encoding="utf-8")
        memory = incremental.memory_stores(cache.MemoryStore())  # the server's (rcsc.editor.lsp)
        driver.check_path(str(path), memory=memory)  # warm: grammar built, modules imported, the file analysed
        times = []
        for i in range(args.runs):
            # A one-line edit: a different constant in the first `true` guard.
            edited = text.replace(": true ", f": {i} >= 0 ", 1)
            t0 = time.perf_counter()
            result = driver.check_path(str(path), overlay={os.path.realpath(path): edited}, memory=memory)
            times.append(time.perf_counter() - t0)
            assert result.files, "nothing was checked"
        ms = statistics.median(times) * 1000
        print(f"{path.relative_to(ROOT).as_posix():<44} {ms:10.1f} {100:8} {'ok' if ms < 100 else 'missed'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
