"""A whole check kept between runs (rcsc.checks.replay): `rcsc check` of an
unchanged design replays the stored findings; any change to any file it read
makes it check again; the answer is always the bytes a check without cache
gives, which a property test holds over random sequences of edits.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rcsc.checks import cache
from rcsc.cli import main

ROOT = Path(__file__).resolve().parents[1]
CASES = ROOT / "tests" / "cases"

# A design over two files with findings (W0515 and W0524 with witnesses) and clean plans.
MAIN = (CASES / "W0515_order_dependent.rcs").read_text(encoding="utf-8").replace(
    "gm level: i32 in 0..100 = 0 from env\n", 'import "lib/limits.rcs"\n\ngm level: i32 in 0..100 = 0 from env\n'
)
LIB = "module d.limits\n\nconst HIGH: i32 = 90\nconst LOW: i32 = 50\n"
MAIN = MAIN.replace("level > 90 ", "level > HIGH").replace("level < 50 ", "level < LOW")
# A value finding too (W0524: `level - LOW` leaves 0..10).
MAIN = MAIN.replace("    reads level\n", "    reads level\n    local n: i32 in 0..10 = 0\n", 1)
MAIN = MAIN.replace("E3: true         | S2  -> done;", "E3: true         | S2  -> done | n = level - LOW;", 1)


@pytest.fixture(autouse=True)
def _cache_on(monkeypatch):
    monkeypatch.delenv("RCSC_NO_CACHE", raising=False)


def _write(folder: Path, main_text: str, lib_text: str) -> Path:
    (folder / "lib").mkdir(exist_ok=True)
    (folder / "lib" / "limits.rcs").write_text(lib_text, encoding="utf-8")
    (folder / "d.rcs").write_text(main_text, encoding="utf-8")
    return folder / "d.rcs"


def _fresh(path: Path, *extra: str) -> tuple[int, str]:
    """`rcsc check --format json` in a fresh process (z3's state carries over within one)."""
    env = {k: v for k, v in os.environ.items() if k != "RCSC_NO_CACHE"}
    proc = subprocess.run([sys.executable, "-m", "rcsc", "check", str(path), "--format", "json", *extra],
                          capture_output=True, text=True, env=env, cwd=path.parent)
    assert proc.returncode in (0, 1), proc.stderr
    return proc.returncode, proc.stdout


def _results(folder: Path) -> list[Path]:
    return sorted((folder / cache.FOLDER).glob("result-*.json"))


def test_an_unchanged_design_is_replayed_without_the_front_end(tmp_path: Path) -> None:
    design = _write(tmp_path, MAIN, LIB)
    reference = _fresh(design, "--no-cache")
    assert "W0515" in reference[1] and "W0524" in reference[1]
    assert _fresh(design) == reference  # checks and stores
    assert len(_results(tmp_path)) == 1
    script = (
        f"import sys; from rcsc.cli import main; code = main(['check', {str(design)!r}, '--format', 'json']); "
        "sys.stdout.flush(); print('LOADED', sorted(m for m in ('lark', 'rcsc.front.parse', 'rcsc.semantics.sema', 'rcsc.checks.guards') if m in sys.modules)); "
        "sys.exit(code)"
    )
    env = {k: v for k, v in os.environ.items() if k != "RCSC_NO_CACHE"}
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, cwd=tmp_path)
    out, loaded = proc.stdout.rsplit("LOADED", 1)
    assert (proc.returncode, out) == reference
    assert loaded.strip() == "[]"


def test_the_findings_of_each_instance_of_a_type_are_replayed(tmp_path: Path) -> None:
    """A finding in a controller type's body is reported once per instance,
    at the same place with the same message (the instances told apart by a
    label): a replayed check must keep each of them, not merge them."""
    design = tmp_path / "d.rcs"
    design.write_text(
        "design d\n\nimport std.blocks\n\ngm a: f64 = 0.0 to env\ngm b: f64 = 0.0 to env\n\n"
        "controller type T(out: gm) level 1 budget 1 ms {\n    writes out\n    block filt: LOWPASS(tau = 0.5, dt = 0.01)\n"
        "    post { out = 1.0; }\n}\n\ncontroller A: T(out = a)\ncontroller B: T(out = b)\n\n"
        "cpu main {\n    heartbeat 10 ms\n    schedule A, B\n}\n", encoding="utf-8")
    reference = _fresh(design, "--no-cache")
    found = [d for d in json.loads(reference[1])["diagnostics"] if d["code"] == "W0261"]
    assert len(found) == 2 and found[0]["line"] == found[1]["line"] and found[0]["labels"] != found[1]["labels"]
    assert _fresh(design) == reference  # checks and stores
    assert len(_results(tmp_path)) == 1
    assert _fresh(design) == reference  # replays


def test_the_stored_findings_are_really_read(tmp_path: Path, capsys) -> None:
    """An entry rewritten (with a valid checksum) to hold no findings is believed."""
    design = _write(tmp_path, MAIN, LIB)
    main(["check", str(design), "--format", "json"])
    assert "W0515" in capsys.readouterr().out
    (entry,) = _results(tmp_path)
    doc = json.loads(entry.read_text())
    payload = json.loads(doc["payload"])
    payload["items"] = []
    doc["payload"] = json.dumps(payload, separators=(",", ":"))
    doc["checksum"] = hashlib.sha256(doc["payload"].encode()).hexdigest()
    entry.write_text(json.dumps(doc))
    assert main(["check", str(design), "--format", "json"]) == 0
    assert "W0515" not in capsys.readouterr().out


def test_a_changed_import_is_checked_again(tmp_path: Path, capsys) -> None:
    design = _write(tmp_path, MAIN, LIB)
    main(["check", str(design), "--format", "short"])
    first = capsys.readouterr().out
    (tmp_path / "lib" / "limits.rcs").write_text(LIB.replace("const LOW: i32 = 50", "const LOW: bool = 50"), encoding="utf-8")
    assert main(["check", str(design), "--format", "short"]) == 1
    second = capsys.readouterr().out
    assert "E0200" in second and second != first
    (tmp_path / "lib" / "limits.rcs").unlink()
    main(["check", str(design), "--format", "short"])
    assert "E0003" in capsys.readouterr().out  # a missing import: checked, and never stored
    assert all("E0003" not in p.read_text() for p in _results(tmp_path))


@pytest.mark.parametrize("damage", [lambda t: "", lambda t: t[: len(t) // 2], lambda t: "\x00 garbage",
                                    lambda t: t.replace('"format": 1', '"format": 7')])
def test_corrupt_stored_findings_are_ignored(tmp_path: Path, capsys, damage) -> None:
    design = _write(tmp_path, MAIN, LIB)
    main(["check", str(design), "--format", "json"])
    reference = capsys.readouterr().out
    for p in _results(tmp_path):
        p.write_text(damage(p.read_text()), encoding="utf-8")
    main(["check", str(design), "--format", "json"])
    assert capsys.readouterr().out == reference


# ---- the property: incremental == from scratch -------------------------------------------

# Edits of the kind a user makes between two checks: a number changed, a
# comparison turned round, a rule deleted, a stray character (a syntax
# error), a change to the imported module, and going back to an earlier text
# (which the cache has seen).
_NUMBERS = ["0", "1", "49", "50", "60", "90", "101", "-3", "2147483648"]


def _edit(texts: tuple[str, str], choice: int, pick: int, history: list[tuple[str, str]]) -> tuple[str, str]:
    main_text, lib_text = texts
    kind = choice % 6
    if kind == 5 and history:
        return history[pick % len(history)]
    if kind == 4:
        numbers = [i for i, ch in enumerate(lib_text) if ch.isdigit() and not lib_text[i - 1].isdigit()]
        i = numbers[pick % len(numbers)]
        j = i
        while j < len(lib_text) and lib_text[j].isdigit():
            j += 1
        return main_text, lib_text[:i] + _NUMBERS[pick % len(_NUMBERS)] + lib_text[j:]
    lines = main_text.split("\n")
    rules = [i for i, line in enumerate(lines) if "|" in line and ":" in line]
    k = rules[pick % len(rules)] if rules else 0
    line = lines[k]
    if kind == 0:
        digits = [i for i, ch in enumerate(line) if ch.isdigit() and (i == 0 or not line[i - 1].isalnum())]
        if digits:
            i = digits[pick % len(digits)]
            j = i
            while j < len(line) and line[j].isdigit():
                j += 1
            line = line[:i] + _NUMBERS[(pick // 3) % len(_NUMBERS)] + line[j:]
    elif kind == 1:
        for a, b in ((">=", "<="), ("<=", ">="), ("> ", "< "), ("< ", "> ")):
            if a in line:
                line = line.replace(a, b, 1)
                break
    elif kind == 2 and len(rules) > 1:
        line = ""
    elif kind == 3:
        line = line + "#"
    lines[k] = line
    return "\n".join(lines), lib_text


@settings(max_examples=6, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.integers(0, 5), st.integers(0, 1000)), min_size=2, max_size=4))
def test_incremental_check_equals_a_check_from_scratch(tmp_path_factory, edits) -> None:
    folder = tmp_path_factory.mktemp("replay")
    texts = (MAIN, LIB)
    history: list[tuple[str, str]] = []
    for choice, pick in [(5, 0)] + edits:  # the first check fills the cache
        texts = _edit(texts, choice, pick, history) if history else texts
        history.append(texts)
        design = _write(folder, *texts)
        incremental = _fresh(design)
        scratch = _fresh(design, "--no-cache")
        assert incremental == scratch, f"texts: {texts!r}"
    assert _results(folder), "nothing was stored"
    shutil.rmtree(folder)
