"""Start-up: `rcsc --version` and `rcsc explain` load only what they use.

The import set is asserted, not timings (bench/bench_startup.py measures
those): a command that needs no design must not load the checks, the SMT
solver, the graph library, the template engine or the parser generator.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

HEAVY = ("z3", "networkx", "jinja2", "lark", "rcsc.checks", "rcsc.outputs.graph", "rcsc.checks.smt", "rcsc.outputs.backend", "rcsc.driver", "rcsc.front.parse")

_PROBE = """
import io, json, sys, contextlib
from rcsc.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    code = main(json.loads(sys.argv[1]))
print(json.dumps({"code": code, "modules": sorted(sys.modules)}))
"""


def _modules(argv: list[str]) -> tuple[int, set[str]]:
    out = subprocess.run([sys.executable, "-c", _PROBE, json.dumps(argv)], capture_output=True, text=True, check=True).stdout
    data = json.loads(out.splitlines()[-1])
    return data["code"], set(data["modules"])


@pytest.mark.parametrize("argv", [["--version"], ["-V"], ["explain", "E0505"], ["explain", "--list"], ["--help"]])
def test_light_commands_do_not_import_heavy_modules(argv: list[str]) -> None:
    code, modules = _modules(argv)
    assert code == 0
    loaded = sorted(m for m in modules if any(m == h or m.startswith(h + ".") for h in HEAVY))
    assert loaded == []


def test_check_does_load_the_front_end() -> None:
    """The probe can see heavy modules: `check` of a missing file still imports the driver."""
    code, modules = _modules(["check", "no-such-file.rcs"])
    assert code == 2
    assert "rcsc.driver" in modules


def test_grammar_cache_is_private_and_reused(tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    probe = (
        "from rcsc.front.parse import text_to_ast\nfrom rcsc.front.source import SourceFile\nfrom rcsc.diagnostics import Diagnostics\n"
        "d = Diagnostics()\nt = text_to_ast(SourceFile('x.rcs', 'design x\\n'), d)\nprint(t.kind, len(d))\n"
    )
    for _ in range(2):  # the second run loads the file the first one wrote
        out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True, env=dict(os.environ, RCSC_PARSER="lark"))  # the fast parser needs no grammar
        assert out.stdout.strip() == "design 0"
    files = list((tmp_path / "rcsc").iterdir())
    assert len(files) == 1 and files[0].name.startswith("rcs-lark")
    assert (tmp_path / "rcsc").stat().st_mode & 0o077 == 0


def test_check_of_valid_files_does_not_load_the_parser_generator(tmp_path) -> None:
    """Lark is the reference parser for the files the fast parser gives up on
    (syntax errors); a check of valid files (here an example with imports)
    never imports it, a file with a syntax error does."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    example = os.path.join(here, "examples", "machining_cell", "machining_cell.rcs")
    code, modules = _modules(["check", example, "--no-cache", "--format", "short"])
    assert code in (0, 1)
    assert "rcsc.driver" in modules and "rcsc.front.rdparse" in modules
    assert not any(m == "lark" or m.startswith("lark.") for m in modules)
    bad = tmp_path / "bad.rcs"
    bad.write_text("design bad\ncontroller C {\n", encoding="utf-8")
    code, modules = _modules(["check", str(bad), "--no-cache", "--format", "short"])
    assert code == 1
    assert "lark" in modules
