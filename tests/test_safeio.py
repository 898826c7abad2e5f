"""Files rcsc reads and writes: no link followed, no person's file touched, no half build.

The write phase of `rcsc build` is a transaction (rcsc.outputs.safeio): these tests
plant links and files in the output folder, interrupt the write phase at every
step (an exception standing for Ctrl-C, an I/O error, a kill), and send real
SIGINTs to a running build, and each time find the complete old build or the
complete new one, never a mix that a build tool would accept.
"""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rcsc.outputs import safeio
from rcsc.cli import main

ROOT = Path(__file__).resolve().parent.parent
SUBMARINE = ROOT / "examples" / "submarine" / "submarine.rcs"


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def two_designs(tmp_path_factory) -> tuple[Path, Path]:
    """The submarine and a variant whose build differs in several files."""
    d = tmp_path_factory.mktemp("designs")
    old = d / "old" / "submarine.rcs"
    new = d / "new" / "submarine.rcs"
    old.parent.mkdir()
    new.parent.mkdir()
    text = SUBMARINE.read_text()
    old.write_text(text)
    assert "const RPM_STEP: f64 = 2.0" in text
    new.write_text(text.replace("const RPM_STEP: f64 = 2.0", "const RPM_STEP: f64 = 3.0").replace("heartbeat 30 ms", "heartbeat 20 ms"))
    return old, new


@pytest.fixture(scope="module")
def builds(two_designs, tmp_path_factory) -> tuple[dict, dict]:
    """What a clean build of each design writes."""
    out = {}
    for name, design in zip(("old", "new"), two_designs):
        folder = tmp_path_factory.mktemp(f"ref-{name}")
        assert main(["build", str(design), "--target", "c", "-o", str(folder)]) == 0
        out[name] = _snapshot(folder)
    assert out["old"] != out["new"]
    assert out["old"].keys() == out["new"].keys()
    return out["old"], out["new"]


def test_a_planted_symlink_is_refused_and_its_target_untouched(tmp_path: Path, capsys) -> None:
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    out = tmp_path / "out"
    out.mkdir()
    os.symlink(victim, out / "submarine.h")
    assert main(["build", str(SUBMARINE), "--target", "c", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "submarine.h: it is a symbolic link" in err and "Nothing was written" in err
    assert victim.read_text() == "precious\n"
    assert os.path.islink(out / "submarine.h")
    assert sorted(p.name for p in out.iterdir()) == ["submarine.h"]


def test_a_persons_externs_file_linked_into_the_build_is_kept(tmp_path: Path, capsys) -> None:
    """The externs file is the person's (written only when missing); kept
    in another folder and linked in, it is kept as it is, not refused."""
    design = ROOT / "tests" / "mc" / "extern_cpu.rcs"
    mine = tmp_path / "mine" / "extern_cpu_externs.c"
    mine.parent.mkdir()
    mine.write_text("/* my externs */\n")
    out = tmp_path / "out"
    out.mkdir()
    os.symlink(mine, out / "extern_cpu_externs.c")
    assert main(["build", str(design), "--target", "c", "-o", str(out)]) == 0, capsys.readouterr().err
    assert os.path.islink(out / "extern_cpu_externs.c") and mine.read_text() == "/* my externs */\n"
    assert (out / "Makefile").exists()
    capsys.readouterr()
    # A link to nothing (or to a folder) would only fail later, in make: refused now.
    os.unlink(out / "extern_cpu_externs.c")
    os.symlink(tmp_path / "nowhere.c", out / "extern_cpu_externs.c")
    assert main(["build", str(design), "--target", "c", "-o", str(out)]) == 2
    assert "it is a symbolic link to no file" in capsys.readouterr().err


def test_a_symlinked_subfolder_is_refused(tmp_path: Path, capsys) -> None:
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = tmp_path / "out"
    out.mkdir()
    os.symlink(elsewhere, out / "src")
    assert main(["build", str(SUBMARINE), "--target", "rust", "-o", str(out)]) == 2
    assert "`src` is not a plain folder" in capsys.readouterr().err
    assert list(elsewhere.iterdir()) == []


def test_old_temporary_names_of_a_person_are_left_alone(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    mine = out / "submarine.c.rcsc-tmp"
    mine.write_text("mine\n")
    assert main(["build", str(SUBMARINE), "--target", "c", "-o", str(out)]) == 0
    assert mine.read_text() == "mine\n"
    assert not (out / safeio.TXN).exists()


def test_doc_does_not_follow_a_dangling_link(tmp_path: Path, capsys) -> None:
    site = tmp_path / "site"
    site.mkdir()
    outside = tmp_path / "outside.html"
    os.symlink(outside, site / "index.html")
    assert main(["doc", str(SUBMARINE), "-o", str(site)]) == 2
    assert "not a regular file" in capsys.readouterr().err
    assert not outside.exists()


def test_a_report_to_a_device_or_link_writes_through_it(tmp_path: Path) -> None:
    """`-o /dev/null` must leave /dev/null a device: renaming a file over it
    would break the machine for every other program."""
    before = os.stat(os.devnull)
    assert main(["graph", str(SUBMARINE), "--format", "dot", "-o", os.devnull]) == 0
    after = os.lstat(os.devnull)
    assert stat.S_ISCHR(after.st_mode) and after.st_rdev == before.st_rdev
    fifo = tmp_path / "pipe.dot"
    os.mkfifo(fifo)
    reader = subprocess.Popen(["cat", str(fifo)], stdout=subprocess.PIPE)
    assert main(["graph", str(SUBMARINE), "-o", str(fifo)]) == 0
    assert reader.communicate(timeout=30)[0].startswith(b"//")
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    target = tmp_path / "target.dot"
    target.write_text("old\n")
    link = tmp_path / "graph.dot"
    os.symlink(target, link)
    assert main(["graph", str(SUBMARINE), "-o", str(link)]) == 0
    assert link.is_symlink() and target.read_text().startswith("//")
    plain = tmp_path / "plain.dot"
    plain.write_text("old\n")
    assert main(["graph", str(SUBMARINE), "-o", str(plain)]) == 0
    assert plain.read_text().startswith("//") and sorted(p.name for p in tmp_path.iterdir()) == ["graph.dot", "pipe.dot", "plain.dot", "target.dot"]


class _Interrupt(BaseException):
    """Stands for a signal or a kill arriving at one point of the write phase."""


def _count_steps(monkeypatch, two_designs, tmp_path) -> int:
    """How many file-system steps (exclusive writes and renames) a rebuild takes."""
    old, new = two_designs
    out = tmp_path / "count"
    assert main(["build", str(old), "--target", "c", "-o", str(out)]) == 0
    calls = []
    real_rename, real_write = os.rename, safeio._write_exclusive
    monkeypatch.setattr(safeio.os, "rename", lambda a, b: (calls.append("r"), real_rename(a, b)))
    monkeypatch.setattr(safeio, "_write_exclusive", lambda p, d: (calls.append("w"), real_write(p, d)))
    assert main(["build", str(new), "--target", "c", "-o", str(out)]) == 0
    monkeypatch.undo()
    return len(calls)


@pytest.mark.parametrize("kind", ["interrupt", "oserror", "kill"])
def test_an_interruption_at_every_step_leaves_old_or_new(kind, monkeypatch, two_designs, builds, tmp_path) -> None:
    old_design, new_design = two_designs
    old_files, new_files = builds
    steps = _count_steps(monkeypatch, two_designs, tmp_path)
    assert steps > 8
    for k in range(steps):
        out = tmp_path / f"{kind}-{k}"
        assert main(["build", str(old_design), "--target", "c", "-o", str(out)]) == 0
        n = [0]
        real_rename, real_write = os.rename, safeio._write_exclusive

        def step(real, *a):
            n[0] += 1
            if n[0] == k + 1:
                if kind == "interrupt":
                    raise _Interrupt()
                if kind == "oserror":
                    raise OSError(28, "No space left on device")
                raise _Interrupt()  # a kill: nothing after this point runs ...
            return real(*a)

        monkeypatch.setattr(safeio.os, "rename", lambda a, b: step(real_rename, a, b))
        monkeypatch.setattr(safeio, "_write_exclusive", lambda p, d: step(real_write, p, d))
        if kind == "kill":
            # ... not even the clean-up: a kill skips `except` and `finally`.
            monkeypatch.setattr(safeio.shutil, "rmtree", lambda *a, **k: None)
        try:
            main(["build", str(new_design), "--target", "c", "-o", str(out)])
        except _Interrupt:
            pass
        monkeypatch.undo()
        files = {k2: v for k2, v in _snapshot(out).items() if not k2.startswith(safeio.TXN)}
        if kind == "kill" and (out / safeio.TXN).exists():
            # Killed inside the transaction: the folder may hold a mix, but
            # then it has no Makefile, so make refuses it ...
            if files not in (old_files, new_files):
                assert "Makefile" not in files and "CMakeLists.txt" not in files, f"step {k}: a mixed build with a Makefile"
            # ... and the next build finishes or discards the transaction.
            assert main(["build", str(new_design), "--target", "c", "-o", str(out)]) == 0
            assert _snapshot(out) == new_files, f"step {k}: recovery did not give the new build"
            continue
        assert not (out / safeio.TXN).exists(), f"step {k}: transaction folder left behind"
        assert files in (old_files, new_files), f"step {k} ({kind}): a mixed build"


def test_sigint_during_real_builds_leaves_old_or_new(two_designs, builds, tmp_path) -> None:
    """Real Ctrl-Cs at spread-out moments of a running `rcsc build`."""
    old_design, new_design = two_designs
    old_files, new_files = builds
    seen = set()
    for i, delay in enumerate([0.05 * j for j in range(12)]):
        out = tmp_path / f"sig-{i}"
        assert main(["build", str(old_design), "--target", "c", "-o", str(out)]) == 0
        proc = subprocess.Popen([sys.executable, "-m", "rcsc", "build", str(new_design), "--target", "c", "-o", str(out)],
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        time.sleep(0.3 + delay)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        assert b"Traceback" not in err, err.decode()
        files = _snapshot(out)
        assert files in (old_files, new_files), f"SIGINT after {0.3 + delay:.2f} s: a mixed build"
        seen.add("new" if files == new_files else "old")
    assert seen  # which of the two depends on the machine's speed; both are correct


def test_read_input_refuses_special_files_and_huge_files(tmp_path: Path) -> None:
    fifo = tmp_path / "d.rcs"
    os.mkfifo(fifo)
    start = time.monotonic()
    with pytest.raises(safeio.InputError, match="not a regular file"):
        safeio.read_input(str(fifo))
    with pytest.raises(safeio.InputError, match="not a regular file"):
        safeio.read_input("/dev/zero")
    big = tmp_path / "big.rcs"
    big.write_bytes(b"x" * 2000)
    with pytest.raises(safeio.InputError, match="limit is 1000 bytes"):
        safeio.read_input(str(big), limit=1000)
    assert time.monotonic() - start < 1.0


def test_check_and_test_do_not_block_on_a_fifo(tmp_path: Path, capsys) -> None:
    folder = tmp_path / "d"
    folder.mkdir()
    (folder / "ok.rcs").write_text(SUBMARINE.read_text())
    os.mkfifo(folder / "pipe.rcs")
    os.mkfifo(folder / "pipe.scn")
    start = time.monotonic()
    assert main(["check", str(folder / "pipe.rcs")]) == 2
    assert "not a regular file" in capsys.readouterr().err
    assert main(["check", "/dev/zero"]) == 2
    main(["test", str(folder)])
    assert time.monotonic() - start < 30.0


def test_no_report_replaces_an_input_of_the_same_command(tmp_path: Path, capsys) -> None:
    """`-o`, `--step-log` and `--junit` name files the user chose, but never
    the design, one of its imports or the scenario the command reads, under
    any spelling (a link, `./`), nor another report of the same command."""
    folder = tmp_path / "sub"
    (folder / "scenarios").mkdir(parents=True)
    design = folder / "submarine.rcs"
    design.write_text(SUBMARINE.read_text())
    scn = folder / "scenarios" / "init.scn"
    scn.write_text("cycles 12\nat 1: SM.INIT()\nexpect within 1..12: SM.done\n")
    (folder / "link.rcs").symlink_to("submarine.rcs")
    before = _snapshot(folder)
    d, s = str(design), str(scn)
    attempts = [
        ["check", d, "-o", d],
        ["check", d, "-o", str(folder / "link.rcs")],
        ["sim", d, "--scenario", s, "-o", s],
        ["sim", d, "--scenario", s, "-o", str(folder / "scenarios" / ".." / "submarine.rcs")],
        ["sim", d, "--scenario", s, "--step-log", d],
        ["events", d, s, "-o", s],
        ["graph", d, "--format", "dot", "-o", d],
        ["test", d, "--junit", d],
        ["test", s, "--junit", s],  # fails before it reads the scenario (no design beside it)
    ]
    for argv in attempts:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert "it is an input of this command" in err or "no design for it" in err, (argv, err)
        assert _snapshot(folder) == before, argv
    # A design with errors stops before its scenarios are read: they are
    # inputs all the same.
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "b.rcs").write_text("design b\ncontroller {\n")
    (broken / "b_run.scn").write_text("cycles 2\n")
    assert main(["test", str(broken / "b.rcs"), "--junit", str(broken / "b_run.scn")]) == 2
    assert "it is an input of this command" in capsys.readouterr().err
    assert (broken / "b_run.scn").read_text() == "cycles 2\n"
    # Two reports of one command to one file: the second is refused.
    trace = tmp_path / "t.jsonl"
    assert main(["sim", d, "--scenario", s, "-o", str(trace), "--step-log", str(trace)]) == 2
    assert "already wrote another report to it" in capsys.readouterr().err
    # Writing the same report again in another command is what -o is for,
    # and a device takes any number of reports.
    assert main(["sim", d, "--scenario", s, "-o", str(trace)]) == 0
    assert main(["sim", d, "--scenario", s, "-o", str(trace)]) == 0
    assert main(["sim", d, "--scenario", s, "-o", os.devnull, "--step-log", os.devnull]) == 0
