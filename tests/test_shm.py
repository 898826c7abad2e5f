"""The multi-CPU transport of the C runtime (backends/c/runtime/rcs_shm.c).

tests/c/shm_hammer.c writes samples from one CPU and reads them from
another at full speed: no copy may be torn or older than the one before,
and in lockstep every sample arrives exactly once.  Built under the strict
warning flags with gcc and clang, run as two processes (plain and under
ASan/UBSan) and as two threads under TSan.  Every run must leave no segment
in /dev/shm.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

# Real-time runs and machine-wide resources: these tests run alone, after the
# others (the README's test command, `-m serial`).
pytestmark = pytest.mark.serial

ROOT = Path(__file__).resolve().parents[1]
RUNTIME = ROOT / "backends" / "c" / "runtime"
HAMMER = ROOT / "tests" / "c" / "shm_hammer.c"
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wshadow", "-Wsign-conversion", "-Werror"]

BUILDS = {
    "gcc": ("gcc", ["-O2"]),
    "clang": ("clang", ["-O2"]),
    "asan": ("gcc", ["-O1", "-g", "-fsanitize=address,undefined", "-fno-sanitize-recover=all"]),
    "tsan": ("clang", ["-O1", "-g", "-fsanitize=thread"]),
}


@pytest.fixture(scope="module")
def hammer(tmp_path_factory):
    out = tmp_path_factory.mktemp("shm")
    exes = {}
    for name, (cc, flags) in BUILDS.items():
        exe = out / f"hammer_{name}"
        cmd = [cc, *STRICT, *flags, f"-I{RUNTIME}", str(RUNTIME / "rcs_shm.c"), str(HAMMER), "-o", str(exe), "-lpthread"]
        r = subprocess.run(cmd, capture_output=True, text=True)
        assert r.returncode == 0 and r.stderr == "", r.stderr
        exes[name] = exe
    return exes


def _leftovers(tag: str) -> list[str]:
    return [n for n in os.listdir("/dev/shm") if tag in n]


@pytest.mark.parametrize(
    "build,mode,how,n",
    [
        ("gcc", "proc", "free", 1_000_000),
        ("clang", "proc", "free", 1_000_000),
        ("gcc", "proc", "lockstep", 100_000),
        ("asan", "proc", "free", 200_000),
        ("asan", "proc", "lockstep", 20_000),
        ("tsan", "thread", "free", 200_000),
        ("tsan", "thread", "lockstep", 20_000),
        ("gcc", "thread", "free", 1_000_000),
    ],
)
def test_hammer(hammer, build, mode, how, n):
    tag = f"rcs-hammer-{os.getpid()}-{build}-{mode}-{how}"
    r = subprocess.run([str(hammer[build]), mode, how, str(n), "/" + tag], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""
    reads = int(r.stdout.split()[1])
    # Lockstep sees every sample; a free-running reader at least several.
    assert reads == n if how == "lockstep" else reads >= 2
    assert _leftovers(tag) == []


def test_torn_reads_are_caught(hammer, tmp_path):
    """Without the seqlock's second check the hammer reports a torn copy (the test can fail)."""
    src = (RUNTIME / "rcs_shm.c").read_text()
    check = "if (ld(&best_slot[S_SEQ], __ATOMIC_RELAXED) != s1) continue;"
    assert check in src
    (tmp_path / "rcs_shm.c").write_text(src.replace(check, "(void)s1;"))
    (tmp_path / "rcs_shm.h").write_text((RUNTIME / "rcs_shm.h").read_text())
    exe = tmp_path / "broken"
    subprocess.run(["gcc", "-O2", f"-I{tmp_path}", str(tmp_path / "rcs_shm.c"), str(HAMMER), "-o", str(exe), "-lpthread"], check=True)
    tag = f"rcs-hammer-{os.getpid()}-broken"
    # A race: on a busy machine one run may not interleave; a few runs do.
    for _ in range(5):
        r = subprocess.run([str(exe), "thread", "free", "3000000", "/" + tag], capture_output=True, text=True, timeout=120)
        if r.returncode != 0:
            break
    assert r.returncode == 1 and "torn" in r.stderr
    assert _leftovers(tag) == []


# ---- the Rust twin (backends/rust/runtime/host/shm.rs) ------------------------------

RUST_HOST = ROOT / "backends" / "rust" / "runtime" / "host"
RUST_HAMMER = ROOT / "tests" / "rust_shm"


@pytest.fixture(scope="module")
def rust_hammer(tmp_path_factory):
    root = tmp_path_factory.mktemp("rust_shm")
    crate = root / "hammer"
    shutil.copytree(RUST_HAMMER, crate, ignore=shutil.ignore_patterns("target", "Cargo.lock"))
    shutil.copytree(RUST_HOST, crate / "host")
    env = dict(os.environ, CARGO_TARGET_DIR=str(root / "target"), CARGO_TERM_COLOR="never")
    for cmd in (["cargo", "build", "--offline", "--release"], ["cargo", "clippy", "--offline", "--release", "--", "-D", "warnings"]):
        r = subprocess.run(cmd, cwd=crate, env=env, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        assert "warning" not in r.stderr, r.stderr
    r = subprocess.run(["rustfmt", "--check", "--edition", "2021", str(crate / "src" / "main.rs")], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout
    return root / "target" / "release" / "shm_hammer"


@pytest.mark.parametrize("mode,how,n", [("proc", "free", 500_000), ("proc", "lockstep", 50_000), ("thread", "free", 500_000), ("thread", "lockstep", 50_000)])
def test_rust_hammer(rust_hammer, mode, how, n):
    tag = f"rcs-rhammer-{os.getpid()}-{mode}-{how}"
    r = subprocess.run([str(rust_hammer), mode, how, str(n), "/" + tag], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""
    reads = int(r.stdout.split()[1])
    assert reads == n if how == "lockstep" else reads >= 2
    assert _leftovers(tag) == []
