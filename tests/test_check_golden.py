"""`rcsc check --format json` of every example and every tests/cases input, byte for byte.

The golden files under tests/golden/check/ were written by rcsc as it was
before the fast front end, the caches and the faster checks came in (with
the reference Lark parser); they pin the findings users see (codes, spans,
messages, notes, witnesses).  `--update-golden` rewrites them through the
reference parser (RCSC_PARSER=lark), so a regeneration cannot hide a
difference of the fast path.

Each check runs as a fresh command does: z3's state carries over between
checks in one process and can change which witness a later check shows, so
every input is checked in its own child process (forked from one helper
process that has imported rcsc and done nothing else).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rcsc.sim.testrun import is_design_file

ROOT = Path(__file__).resolve().parents[1]

_RUNNER = r"""
import io, json, os, sys, traceback
from rcsc.cli import main
out = {}
for path in json.loads(sys.stdin.read()):
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        buf = io.StringIO()
        sys.stdout, sys.stderr = buf, io.StringIO()
        try:
            main(["check", path, "--format", "json", "--no-cache"])
        except BaseException:
            buf.write(traceback.format_exc())
        finally:
            os.write(w, buf.getvalue().encode())
            os._exit(0)
    os.close(w)
    chunks = []
    while True:
        data = os.read(r, 1 << 16)
        if not data:
            break
        chunks.append(data)
    os.close(r)
    os.waitpid(pid, 0)
    out[path] = b"".join(chunks).decode()
sys.__stdout__.write(json.dumps(out))
"""


def _roots() -> list[str]:
    roots = [p for p in sorted(ROOT.glob("examples/**/*.rcs")) if is_design_file(str(p))]
    cases = ROOT / "tests" / "cases"
    roots += sorted(cases.glob("*.rcs"))
    roots += sorted(d / "main.rcs" for d in cases.iterdir() if d.is_dir() and (d / "main.rcs").is_file())
    return [str(p.relative_to(ROOT)) for p in roots]


ROOTS = _roots()


def check_outputs(paths: list[str], lark: bool) -> dict[str, str]:
    """The JSON report of `rcsc check` for each path, each in a fresh process."""
    env = dict(os.environ, RCSC_NO_CACHE="1")
    if lark:
        env["RCSC_PARSER"] = "lark"
    proc = subprocess.run(
        [sys.executable, "-c", _RUNNER], input=json.dumps(paths), cwd=ROOT, env=env,
        capture_output=True, text=True, check=True,
    )
    return json.loads(proc.stdout)


@pytest.fixture(scope="module")
def outputs(request) -> dict[str, str]:
    return check_outputs(ROOTS, lark=bool(request.config.getoption("--update-golden")))


@pytest.mark.parametrize("path", ROOTS)
def test_check_output_is_unchanged(path: str, outputs, golden) -> None:
    assert outputs[path].startswith("{")
    golden("check/" + path.removesuffix(".rcs").replace("/", "__") + ".json", outputs[path])


def test_every_example_and_case_is_covered() -> None:
    assert any(p.startswith("examples/") for p in ROOTS)
    assert len(ROOTS) > 90
