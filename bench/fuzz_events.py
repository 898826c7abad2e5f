"""Coverage-guided fuzzing of the compiled programs' event readers (docs/events.md).

Two steps, each with an oracle that can fail:

  fuzz    libFuzzer on the C reader (backends/c/runtime/rcs_runtime.c) through
          bench/fuzz/events_fuzz.c, built with clang
          -fsanitize=fuzzer,address,undefined: no crash, no sanitizer report,
          no hang (-timeout), a refusal is one `PATH:LINE: error: ...` line
          naming a line of the file, an accepted file prints nothing, and two
          readings agree;
  compare every input of the resulting corpus (the seeds and what libFuzzer
          kept for new coverage) through the C Main Program and the Rust Main
          Program (backends/rust/runtime/host/scenario.rs) of the same fixture
          design (tests/c/runtime_fixture.c, tests/rust_fixture): the same exit
          status, the same error message and, for an accepted file, the same
          trace of the first cycle.  Any difference is a disagreement.

The reader checks a file against one design: the fixture design of the
runtime tests (tests/event_cases.py).  The seed corpus, bench/fuzz/corpus/,
holds event files of that design compiled by `rcsc events` and the corrupt
files of tests/event_cases.py; `--write-seeds` regenerates it (the suite
checks it is current).

    python bench/fuzz_events.py -runs=2000 -seed=1            # the suite's slice
    python bench/fuzz_events.py --rust -runs=2000 -seed=1     # the same, then cargo-fuzz on the Rust reader
    nice python bench/fuzz_events.py --rust -max_total_time=150   # a longer run (each reader 150 s)
    python bench/fuzz_events.py --write-seeds

Any further arguments are libFuzzer's.  A finding is written as
`crash-<hash>` (or `timeout-`/`oom-`) in the working folder; a disagreement
is copied there as `disagree-<name>`.  The last line is a summary:
`inputs N, corpus M, crashes C, disagreements D, cov K`; the exit status is 0
only when C and D are 0.  `--plant-bug` builds the harness with a planted
oracle failure (the refusal of a malformed version number in the header,
which no seed has): the suite uses it to show that the
harness really reports what it finds (with --rust, the Rust target has the same
planted failure).  `--rust` adds a cargo-fuzz run on the Rust reader
(bench/fuzz/rust, `cargo +nightly fuzz`; needs `cargo install cargo-fuzz` and
the nightly toolchain) on the same corpus, before the comparison.
`--keep DIR` keeps the corpus there.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

C_RUNTIME = ROOT / "backends" / "c" / "runtime"
C_FIXTURE = ROOT / "tests" / "c" / "runtime_fixture.c"
RUST_RUNTIME = ROOT / "backends" / "rust" / "runtime"
RUST_FIXTURE = ROOT / "tests" / "rust_fixture"
HARNESS = ROOT / "bench" / "fuzz" / "events_fuzz.c"
CORPUS = ROOT / "bench" / "fuzz" / "corpus"
SANITIZE = ["-g", "-O1", "-fno-omit-frame-pointer", "-fno-sanitize-recover=all"]
RUN = ["--fast", "--no-console", "--no-timing", "--cycles", "1", "--trace", "-"]

# Scenarios of the fixture design (tests/event_cases.py FIXTURE_RCS) whose event
# files are the valid seeds: every record kind, every leaf type.
SCENARIOS = {
    "run": """\
cycles 5
at 1: TOP.INIT()
at 1: door = true
at 2: TOP.MOVE(speed = 0.1, dt = 2.5e-3 s, mode = Mode.RUN, to = Pose(x = 1.5, y = -2, mode = Mode.HALT))
at 2: limit = -0x10
at 2: gain = 3
at 4: TOP.SET(7, -9_223_372_036_854_775_808)
at 4: gain = 1.7976931348623157e308
at 5: TOP.MOVE(-MAX_SPEED, STEP_T, FAST, HOME)
""",
    "faults": """\
cycles 9
at 1: door = false
at 1: TOP.SET(n = 0xFFFF_FFFF, big = 1)
at 3: freeze SUB
at 4: limit = 2147483647
at 6: stop MAIN
at 7: freeze TOP
""",
    "empty": "cycles 1\n",
}


def seeds() -> dict[str, bytes]:
    """The seed corpus: valid files of the fixture design, then the corrupt cases."""
    from event_cases import COMPUTED, event_errors, events

    out = {f"valid-{name}.events": events(text).encode("utf-8") for name, text in SCENARIOS.items()}
    out["valid-computed.events"] = events(COMPUTED).encode("utf-8")
    for name, data, _message in event_errors():
        out[f"bad-{name}.events"] = data
    return out


def write_seeds() -> None:
    if CORPUS.exists():
        shutil.rmtree(CORPUS)
    CORPUS.mkdir(parents=True)
    for name, data in seeds().items():
        (CORPUS / name).write_bytes(data)


def _run(cmd: list[str], **kw) -> subprocess.CompletedProcess:
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        sys.exit(f"{' '.join(map(str, cmd))}\n{r.stdout}{r.stderr}")
    return r


def build(work: Path, plant_bug: bool) -> tuple[Path, Path, Path]:
    """The libFuzzer harness, the C fixture (sanitized) and the Rust fixture (release)."""
    harness, c_exe = work / "events_fuzz", work / "fixture_c"
    c_sources = [str(C_RUNTIME / "rcs_runtime.c"), str(C_RUNTIME / "rcs_shm.c")]
    _run(["clang", *SANITIZE, "-fsanitize=fuzzer,address,undefined", *(["-DPLANT_BUG"] if plant_bug else []),
          f"-I{C_RUNTIME}", str(HARNESS), *c_sources, "-o", str(harness), "-lm"])
    _run(["clang", "-std=c99", *SANITIZE, "-fsanitize=address,undefined", f"-I{C_RUNTIME}", str(C_FIXTURE),
          *c_sources, "-o", str(c_exe), "-lm"])
    crate = work / "rust_fixture"
    shutil.copytree(RUST_FIXTURE, crate, ignore=shutil.ignore_patterns("target", "Cargo.lock"))
    shutil.copy(RUST_RUNTIME / "num.rs", crate / "src" / "num.rs")
    shutil.copytree(RUST_RUNTIME / "host", crate / "host")
    env = dict(os.environ, CARGO_TARGET_DIR=str(work / "target"), CARGO_TERM_COLOR="never")
    _run(["cargo", "build", "--offline", "--quiet", "--release"], cwd=crate, env=env)
    return harness, c_exe, work / "target" / "release" / "fixture"


def rust_fuzz(work: Path, corpus: Path, args: list[str], here: Path, plant_bug: bool) -> tuple[int, int, int]:
    """cargo-fuzz on the Rust reader (bench/fuzz/rust/fuzz_targets/events.rs), on the same corpus.

    Runs in the fixture crate's copy that build() made, as its `fuzz/` folder;
    the copy's bin makes its design tables public for the target.  Returns
    (runs, crashes, coverage).  The build is kept in build/fuzz-events-rust."""
    crate = work / "rust_fixture"
    shutil.copytree(ROOT / "bench" / "fuzz" / "rust", crate / "fuzz")
    bin_rs = crate / "src" / "bin" / "fixture.rs"
    text = bin_rs.read_text(encoding="utf-8")
    for old, new in (("\nstatic DESIGN:", "\npub static DESIGN:"), ("\nmod host;", "\npub mod host;")):
        assert old in text, old
        text = text.replace(old, new, 1)
    bin_rs.write_text(text, encoding="utf-8")
    target = ROOT / "build" / "fuzz-events-rust"
    env = dict(os.environ, CARGO_TERM_COLOR="never")
    if plant_bug:
        env["RCSC_FUZZ_PLANT_BUG"] = "1"
    cmd = ["cargo", "+nightly", "fuzz", "run", "--target-dir", str(target), "events", str(corpus), "--",
           "-timeout=2", "-rss_limit_mb=1024", "-max_len=4096", "-print_final_stats=1", f"-artifact_prefix={here}/rust-",
           *args]
    fz = subprocess.run(cmd, cwd=crate, env=env, capture_output=True, text=True)
    log = fz.stderr
    print(log[-6000:] if fz.returncode else log[-1000:], end="")
    for line in log.splitlines():  # the panic's message comes before a long stack
        if "panicked at" in line or "FINDING" in line:
            print(line)
    m = re.search(r"Done (\d+) runs", log) or re.search(r"stat::number_of_executed_units:\s*(\d+)", log)
    cov = max((int(n) for n in re.findall(r"cov: (\d+)", log)), default=0)
    return (int(m.group(1)) if m else 0), int(fz.returncode != 0), cov


def compare(c_exe: Path, rust_exe: Path, files: list[Path], work: Path, out: Path) -> tuple[int, int]:
    """Runs each file through both Main Programs; (files compared, disagreements).

    The file is copied to one path first so that both print the same name."""
    path = work / "input.events"
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1", UBSAN_OPTIONS="halt_on_error=1")
    disagreements = 0
    for f in files:
        shutil.copyfile(f, path)
        c = subprocess.run([str(c_exe), *RUN, "--scenario", str(path)], capture_output=True, env=env,
                           stdin=subprocess.DEVNULL, timeout=60)
        r = subprocess.run([str(rust_exe), *RUN, "--scenario", str(path)], capture_output=True,
                           stdin=subprocess.DEVNULL, timeout=60)
        if (c.returncode, c.stdout, c.stderr) != (r.returncode, r.stdout, r.stderr) or c.returncode not in (0, 2):
            disagreements += 1
            shutil.copyfile(f, out / f"disagree-{f.name}")
            print(f"DISAGREE {f.name}: C exit {c.returncode} {c.stderr[-400:]!r} {c.stdout[:200]!r}\n"
                  f"    Rust exit {r.returncode} {r.stderr[-400:]!r} {r.stdout[:200]!r}", flush=True)
    return len(files), disagreements


def main(argv: list[str]) -> int:
    args = argv[1:]
    if "--write-seeds" in args:
        write_seeds()
        print(f"wrote {len(list(CORPUS.iterdir()))} seeds to {CORPUS.relative_to(ROOT)}")
        return 0
    plant_bug = "--plant-bug" in args
    rust = "--rust" in args
    keep = None
    if "--keep" in args:
        i = args.index("--keep")
        keep = Path(args[i + 1])
        del args[i:i + 2]
    args = [a for a in args if a not in ("--plant-bug", "--rust")]
    here = Path.cwd()
    work = Path(tempfile.mkdtemp(prefix="rcsc-fuzz-events-"))
    try:
        return _fuzz(args, here, work, keep, plant_bug, rust)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _fuzz(args: list[str], here: Path, work: Path, keep: Path | None, plant_bug: bool, rust: bool) -> int:
    harness, c_exe, rust_exe = build(work, plant_bug)
    henv = dict(os.environ, TMPDIR=str(work))  # the harness's input file goes with the work folder
    replay = [a for a in args if not a.startswith("-")]
    if replay:  # rerun findings: libFuzzer runs the files given, then compare them
        fz = subprocess.run([str(harness), *args], cwd=here, capture_output=True, text=True, env=henv)
        print(fz.stderr[-4000:], end="")
        files = [Path(a) for a in replay]
        _n, dis = compare(c_exe, rust_exe, files, work, here)
        print(f"inputs {len(files)}, crashes {int(fz.returncode != 0)}, disagreements {dis}")
        return 1 if fz.returncode or dis else 0
    corpus = keep or work / "corpus"
    corpus.mkdir(parents=True, exist_ok=True)
    for f in CORPUS.iterdir():
        shutil.copyfile(f, corpus / f.name)
    # -timeout: an input that takes over 2 s is a hang; -rss_limit_mb: a leak or a runaway allocation.
    cmd = [str(harness), "-timeout=2", "-rss_limit_mb=1024", "-max_len=4096", "-print_final_stats=1",
           *args, str(corpus)]
    fz = subprocess.run(cmd, cwd=here, capture_output=True, text=True, env=henv)
    log = fz.stderr
    print(log[-6000:] if fz.returncode else log[-1500:], end="")
    m = re.search(r"Done (\d+) runs", log) or re.search(r"stat::number_of_executed_units:\s*(\d+)", log)
    runs = int(m.group(1)) if m else 0
    cov = max((int(n) for n in re.findall(r"cov: (\d+)", log)), default=0)
    crashes = int(fz.returncode != 0)
    if rust:
        r_runs, r_crashes, r_cov = rust_fuzz(work, corpus, args, here, plant_bug)
        print(f"rust: inputs {r_runs}, crashes {r_crashes}, cov {r_cov}")
        runs, crashes = runs + r_runs, crashes + r_crashes
    findings = [p for p in here.iterdir() if re.match(r"(rust-)?(crash|timeout|oom|leak)-", p.name)]
    crashes = max(crashes, len(findings))
    files = sorted(corpus.iterdir())
    n, dis = compare(c_exe, rust_exe, files, work, here)
    print(f"inputs {runs}, corpus {n}, crashes {crashes}, disagreements {dis}, cov {cov}")
    return 1 if crashes or dis else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
