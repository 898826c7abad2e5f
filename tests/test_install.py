"""An installed rcsc works outside the checkout.

Builds a wheel, installs it (without dependencies: they come from the test
environment) into a fresh virtual environment, and runs the installed `rcsc`
from a temporary folder on a copy of an example, so the grammar and the
standard library must come from inside the installed package.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

# `pip wheel` builds in the checkout's build/ folder, which other tests' walks
# of the checkout would see appear and vanish: this file runs alone, after
# the others (the README's test command, `-m serial`).
pytestmark = pytest.mark.serial

ROOT = Path(__file__).resolve().parent.parent


def test_installed_wheel_checks_a_design_from_another_folder(tmp_path: Path) -> None:
    wheel_dir = tmp_path / "wheel"
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(wheel_dir), str(ROOT)],
        check=True,
        cwd=tmp_path,
    )
    (wheel,) = wheel_dir.glob("rcsc-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert "rcsc/grammar/rcs.lark" in names
    assert "rcsc/stdlib/std/math.rcs" in names
    assert "rcsc/stdlib/std/lifecycle.rcs" in names

    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    py = venv / "bin" / "python"
    # The dependencies come from the environment running the tests, which may
    # itself be a virtual environment (then `--system-site-packages` would
    # reach the base interpreter, not it).  A .pth line adds its library
    # folders as plain paths: their own .pth files (the checkout's editable
    # install among them) are not processed, so `rcsc` comes from the wheel.
    purelib = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             check=True, capture_output=True, text=True).stdout.strip()
    outer = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    Path(purelib, "rcsc_test_outer.pth").write_text("".join(f"{d}\n" for d in sorted(outer)))
    subprocess.run([str(py), "-m", "pip", "install", "-q", "--no-deps", "--force-reinstall", str(wheel)], check=True)

    work = tmp_path / "elsewhere"
    shutil.copytree(ROOT / "examples" / "submarine", work)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    where = subprocess.run(
        [str(py), "-c", "import rcsc, rcsc.front.parse; print(rcsc.__file__)"], check=True, cwd=work, env=env, capture_output=True, text=True
    ).stdout.strip()
    assert where.startswith(str(venv)), f"imported rcsc from {where}, not from the installed wheel"

    result = subprocess.run(
        [str(venv / "bin" / "rcsc"), "check", "submarine.rcs"], cwd=work, env=env, capture_output=True, text=True
    )
    assert result.returncode == 0, result.stdout + result.stderr
    result = subprocess.run([str(py), "-m", "rcsc", "check", "submarine.rcs", "--format", "short"], cwd=work, env=env, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr

    # Code generation from the installed package: templates and runtime files
    # come from inside the wheel, and the C output compiles and runs.
    assert "rcsc/backends/c/templates/ctrl.c.j2" in names
    assert "rcsc/backends/c/runtime/rcs_runtime.c" in names
    result = subprocess.run([str(venv / "bin" / "rcsc"), "targets"], cwd=work, env=env, capture_output=True, text=True)
    assert result.returncode == 0 and [x.split()[0] for x in result.stdout.splitlines()] == ["ada", "c", "rust"], result.stdout + result.stderr
    assert "rcsc/backends/ada/runtime/rcs_num.ads" in names and "rcsc/backends/ada/templates/ctrl.adb.j2" in names
    result = subprocess.run(
        [str(venv / "bin" / "rcsc"), "build", "submarine.rcs", "--target", "c", "-o", "out"], cwd=work, env=env, capture_output=True, text=True
    )
    assert result.returncode == 0, result.stdout + result.stderr
    subprocess.run(["make", "-s", "-C", str(work / "out"), "CC=gcc"], check=True, capture_output=True)
    run = subprocess.run(
        [str(work / "out" / "submarine_MAIN"), "--fast", "--no-console", "--no-timing", "--cycles", "3", "--trace", "-"],
        capture_output=True, text=True,
    )
    assert run.returncode == 0 and len(run.stdout.splitlines()) == 3, run.stderr

    # The Rust target too: its templates and runtime (num.rs, host/) come from the wheel.
    assert "rcsc/backends/rust/templates/ctrl.rs.j2" in names
    assert "rcsc/backends/rust/runtime/num.rs" in names and "rcsc/backends/rust/runtime/host/mod.rs" in names
    result = subprocess.run(
        [str(venv / "bin" / "rcsc"), "build", "submarine.rcs", "--target", "rust", "-o", "rs"], cwd=work, env=env, capture_output=True, text=True
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert (work / "rs" / "src" / "num.rs").is_file() and (work / "rs" / "host" / "mod.rs").is_file()
