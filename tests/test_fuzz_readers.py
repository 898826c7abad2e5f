"""A bounded slice of the event-reader fuzzer (bench/fuzz_events.py, libFuzzer).

libFuzzer runs a fixed number of inputs from a fixed seed on the C reader
(ASan and UBSan, the harness's oracle), starting from the seed corpus in
bench/fuzz/corpus/, then cargo-fuzz as many on the Rust reader on the same
corpus; then every input of the resulting corpus goes through the C and the
Rust Main Programs of the fixture design, which must agree (exit status,
message, first-cycle trace).  Longer campaigns are the
script's job (`nice python bench/fuzz_events.py -max_total_time=300`).  A
planted bug shows that the harness reports what its oracle finds, and a
forged pair of programs that the comparison reports a disagreement.
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "bench" / "fuzz_events.py"
RUNS = 2000


def _fuzz(tmp_path: Path, *argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(SCRIPT), *argv], cwd=tmp_path, capture_output=True, text=True, timeout=900)


def _module():
    spec = importlib.util.spec_from_file_location("fuzz_events", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _summary(out: str) -> dict[str, int]:
    m = re.search(r"^inputs (\d+), corpus (\d+), crashes (\d+), disagreements (\d+), cov (\d+)$", out, re.M)
    assert m, out[-3000:]
    return dict(zip(["inputs", "corpus", "crashes", "disagreements", "cov"], map(int, m.groups())))


def test_seed_corpus_is_current():
    """bench/fuzz/corpus/ is what `--write-seeds` makes: the fixture's event files and every corrupt case."""
    mod = _module()
    want = mod.seeds()
    have = {p.name: p.read_bytes() for p in mod.CORPUS.iterdir()}
    assert have == want, "run `python bench/fuzz_events.py --write-seeds`"
    assert sum(n.startswith("valid-") for n in have) == 4 and len(have) > 40
    assert sum(len(b) for b in have.values()) < 16000


def test_bounded_fuzz_run_finds_nothing(tmp_path: Path):
    proc = _fuzz(tmp_path, "--rust", f"-runs={RUNS}", "-seed=1")
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-6000:]
    s = _summary(out)
    assert s["inputs"] == 2 * RUNS and s["crashes"] == 0 and s["disagreements"] == 0, s
    rust = re.search(r"^rust: inputs (\d+), crashes 0, cov (\d+)$", out, re.M)
    assert rust and int(rust.group(1)) == RUNS and int(rust.group(2)) > 150, out[-3000:]
    # libFuzzer saw the reader's branches and kept inputs beyond the seeds, and all were compared.
    assert s["cov"] > 150, s
    assert s["corpus"] > len(_module().seeds()), s
    assert not [p for p in tmp_path.iterdir() if re.match(r"(crash|timeout|oom|leak|disagree)-", p.name)]


def test_a_planted_bug_is_reported(tmp_path: Path):
    """Both harnesses (libFuzzer on C, cargo-fuzz on Rust) find the planted failure by mutation."""
    proc = _fuzz(tmp_path, "--rust", "--plant-bug", f"-runs={RUNS}", "-seed=1")
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0 and "events_fuzz: FINDING: planted: a malformed version number" in out, out[-3000:]
    assert re.search(r"panicked at fuzz_targets/events.rs.*\n.*FINDING: planted: a malformed version number", out), out[-3000:]
    assert _summary(out)["crashes"] == 2
    crashes = list(tmp_path.glob("crash-*")) + list(tmp_path.glob("rust-crash-*"))
    assert len(crashes) == 2, out[-3000:]
    for crash in crashes:
        first = crash.read_bytes().split(b"\n")[0].split(b" ")
        assert first[0] == b"rcsc-events" and len(first) >= 2 and not first[1].isdigit(), first
    crashes = list(tmp_path.glob("crash-*"))
    # The crash file replays on its own, and only with the planted bug.
    replay = _fuzz(tmp_path, "--plant-bug", str(crashes[0]))
    assert replay.returncode != 0 and "FINDING: planted" in replay.stdout + replay.stderr
    clean = _fuzz(tmp_path, str(crashes[0]))
    assert clean.returncode == 0 and "inputs 1, crashes 0, disagreements 0" in clean.stdout, clean.stdout + clean.stderr


def test_a_disagreement_is_reported(tmp_path: Path):
    """The comparison step: two programs that differ on one file give one disagreement, saved."""
    mod = _module()
    same = tmp_path / "same"
    same.write_text("#!/bin/sh\necho ok\nexit 2\n")
    other = tmp_path / "other"
    other.write_text('#!/bin/sh\nfor a; do f=$a; done\ngrep -q cycles "$f" && echo ko\necho ok\nexit 2\n')
    for p in (same, other):
        p.chmod(0o755)
    files = [mod.CORPUS / "bad-empty.events", mod.CORPUS / "valid-run.events"]
    n, dis = mod.compare(same, other, files, tmp_path, tmp_path)
    assert (n, dis) == (2, 1)
    assert (tmp_path / "disagree-valid-run.events").read_bytes() == files[1].read_bytes()
