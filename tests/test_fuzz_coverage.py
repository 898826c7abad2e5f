"""A bounded slice of the coverage-guided fuzzer (bench/fuzz_front.py, atheris).

Each target runs a fixed number of inputs from a fixed seed, starting from
the repository's own files: the fast parser against the reference grammar,
the whole `rcsc check`, the scenario parser, and `rcsc fmt`'s round trip.  Longer campaigns are the
script's job (`python bench/fuzz_front.py TARGET -max_total_time=600`).  A
planted bug shows that the harness reports what its oracle finds.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# libFuzzer counts the seed corpus (every .rcs / .scn file of the repository,
# over 150 of them) in -runs; the rest are mutations that coverage steers.
RUNS = 400


def _fuzz(tmp_path: Path, *argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(ROOT / "bench" / "fuzz_front.py"), *argv],
                          cwd=tmp_path, capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize("target", ["parsers", "check", "scenario", "fmt"])
def test_bounded_fuzz_run_finds_nothing(tmp_path: Path, target: str) -> None:
    proc = _fuzz(tmp_path, target, f"-runs={RUNS}", "-seed=1", "-max_len=4096")
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-6000:]
    done = re.search(r"Done (\d+) runs", out)
    assert done and int(done.group(1)) >= RUNS, out[-3000:]
    seeds = re.search(r"INFO: seed corpus: files: (\d+)", out)
    assert seeds and int(seeds.group(1)) < RUNS, out[-3000:]  # mutations were run, not only the seeds
    # The instrumentation works: libFuzzer saw rcsc's branches.
    coverage = [int(n) for n in re.findall(r"cov: (\d+)", out)]
    assert coverage and max(coverage) > 300, out[-3000:]
    assert not list(tmp_path.glob("crash-*"))
    # Memory stays flat over the run: nothing of an input outlives it (each
    # plan's z3 context in particular; bench/fuzz_front.py gives back what
    # atheris's comparison hook would keep).  A run takes about 140 MB.  The
    # harness's own figure, not libFuzzer's `rss:`, which says the size of
    # this test process (Linux carries the peak over `exec`).
    peaks = [int(n) for n in re.findall(r"peak memory (\d+) MB", out)]
    assert peaks and max(peaks) < 600, out[-3000:]


def test_a_planted_bug_is_reported(tmp_path: Path) -> None:
    proc = _fuzz(tmp_path, "parsers", "--plant-bug", f"-runs={RUNS}", "-seed=1", "-max_len=4096")
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0 and "trees differ at planted" in out, out[-3000:]
    crashes = list(tmp_path.glob("crash-*"))
    assert len(crashes) == 1 and b" period " in crashes[0].read_bytes()
    # The crash file replays on its own.
    replay = _fuzz(tmp_path, "parsers", "--plant-bug", str(crashes[0]))
    assert replay.returncode != 0 and "trees differ at planted" in replay.stdout + replay.stderr
