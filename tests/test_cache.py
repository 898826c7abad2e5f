"""The on-disk cache of `rcsc check` (rcsc.checks.cache, `.rcsc-cache/` next to the design).

A second run reads the guard analysis from the cache and reports the same
bytes; corrupt, stale or foreign entries are ignored and rewritten, never a
crash; `--no-cache` and RCSC_NO_CACHE=1 leave no trace; a folder that cannot
be written only means no caching.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from rcsc.checks import cache
from rcsc.cli import main

ROOT = Path(__file__).resolve().parents[1]
CASES = ROOT / "tests" / "cases"
# Designs with guard findings (witnesses, externs, records) and without.
DESIGNS = ["W0515_order_dependent.rcs", "W0515_records_and_externs.rcs", "E0506_dead_rule.rcs", "W0517_waits_forever.rcs", "E0516_new_unanswered.rcs",
           "W0524_range_flow.rcs", "W0525_overflow_division.rcs"]


@pytest.fixture(autouse=True)
def _cache_on(monkeypatch):
    monkeypatch.delenv("RCSC_NO_CACHE", raising=False)


def _check(path: Path, capsys, *extra: str) -> str:
    main(["check", str(path), "--format", "json", *extra])
    return capsys.readouterr().out


def _entries(folder: Path) -> list[Path]:
    return sorted(folder.glob("guards-*.json"))


def _forget_findings(folder: Path) -> None:
    """Delete the replayed checks (rcsc.checks.replay), so that the next run reads the guard entries."""
    for p in folder.glob("result-*.json"):
        p.unlink()


def _fresh_check(path: Path, *extra: str) -> str:
    """`rcsc check` in a fresh process, as users run it (z3's state carries
    over between analyses in one process and can change which witness a
    later analysis finds, so in-process runs are not comparable)."""
    env = {k: v for k, v in os.environ.items() if k != "RCSC_NO_CACHE"}
    proc = subprocess.run([sys.executable, "-m", "rcsc", "check", str(path), "--format", "json", *extra], capture_output=True, text=True, env=env)
    assert proc.returncode in (0, 1), proc.stderr
    return proc.stdout


@pytest.mark.parametrize("name", DESIGNS)
def test_second_run_reads_the_cache_and_says_the_same(tmp_path: Path, name: str) -> None:
    design = tmp_path / name
    shutil.copy(CASES / name, design)
    reference = _fresh_check(design, "--no-cache")
    assert not (tmp_path / cache.FOLDER).exists()
    first = _fresh_check(design)
    entries = _entries(tmp_path / cache.FOLDER)
    assert entries, "nothing was cached"
    second = _fresh_check(design)
    assert reference == first == second
    assert '"code"' in reference  # the case has findings


def _empty_entries(folder: Path) -> None:
    """Rewrite every guard entry (with a valid checksum) to hold no findings."""
    for path in _entries(folder):
        doc = json.loads(path.read_text())
        doc["payload"] = "[]"
        doc["checksum"] = __import__("hashlib").sha256(b"[]").hexdigest()
        path.write_text(json.dumps(doc))


def test_the_cache_is_really_read(tmp_path: Path, capsys) -> None:
    """An entry rewritten (with a valid checksum) to hold no findings is believed:
    proof that the second run answers from the cache, not from the solver."""
    design = tmp_path / "d.rcs"
    shutil.copy(CASES / "W0515_order_dependent.rcs", design)
    assert "W0515" in _check(design, capsys)
    _empty_entries(tmp_path / cache.FOLDER)
    _forget_findings(tmp_path / cache.FOLDER)
    assert "W0515" not in _check(design, capsys)


def test_build_reads_the_cache_of_check(tmp_path: Path, capsys, monkeypatch) -> None:
    """`rcsc build` checks first, with the same cache as `rcsc check`: with an
    entry rewritten to hold no findings, a build that denies warnings goes
    through (it believed the cache), and with RCSC_NO_CACHE=1 it is refused
    (the solver finds the warning again)."""
    design = tmp_path / "d.rcs"
    shutil.copy(CASES / "W0515_order_dependent.rcs", design)
    assert "W0515" in _check(design, capsys)
    _empty_entries(tmp_path / cache.FOLDER)
    build = ["build", str(design), "--target", "c", "--deny-warnings", "-o", str(tmp_path / "out")]
    assert main(build) == 0, capsys.readouterr().err
    monkeypatch.setenv("RCSC_NO_CACHE", "1")
    assert main(build[:-1] + [str(tmp_path / "out2")]) == 1
    assert "W0515" in capsys.readouterr().err


@pytest.mark.parametrize(
    "damage",
    [
        lambda text: "",
        lambda text: text[: len(text) // 2],
        lambda text: "\x00\xff garbage",
        lambda text: text.replace('"format": 1', '"format": 999'),
        lambda text: text.replace('"code": "', '"code": "0'),
        lambda text: text.replace('[', '[{"d": 5}, ', 1),  # checksum no longer matches
        lambda text: json.dumps({**json.loads(text), "payload": '[{"d": [["code", 1]]}]',
                                 "checksum": __import__("hashlib").sha256(b'[{"d": [["code", 1]]}]').hexdigest()}),
        lambda text: json.dumps({**json.loads(text), "payload": '[{"ty": "NoSuchType"}]',
                                 "checksum": __import__("hashlib").sha256(b'[{"ty": "NoSuchType"}]').hexdigest()}),
        lambda text: "[]",
    ],
)
def test_corrupt_entries_are_ignored_and_rewritten(tmp_path: Path, damage) -> None:
    design = tmp_path / "d.rcs"
    shutil.copy(CASES / "W0515_records_and_externs.rcs", design)
    reference = _fresh_check(design)
    entries = _entries(tmp_path / cache.FOLDER)
    good = {p: p.read_text() for p in entries}
    for p in entries:
        p.write_text(damage(good[p]), encoding="utf-8", errors="surrogateescape")
    _forget_findings(tmp_path / cache.FOLDER)
    assert _fresh_check(design) == reference
    for p in entries:  # rewritten: the same bytes as a clean run writes
        assert p.read_text() == good[p]


def test_no_cache_flag_and_environment_leave_no_trace(tmp_path: Path, capsys, monkeypatch) -> None:
    design = tmp_path / "d.rcs"
    shutil.copy(CASES / "E0506_dead_rule.rcs", design)
    _check(design, capsys, "--no-cache")
    monkeypatch.setenv("RCSC_NO_CACHE", "1")
    _check(design, capsys)
    assert not (tmp_path / cache.FOLDER).exists()


def test_a_cache_folder_that_cannot_be_written_means_no_cache(tmp_path: Path, capsys) -> None:
    design = tmp_path / "d.rcs"
    shutil.copy(CASES / "E0506_dead_rule.rcs", design)
    (tmp_path / cache.FOLDER).write_text("a file where the folder would be")
    first = _check(design, capsys)
    assert "E0506" in first and _check(design, capsys) == first


def test_the_folder_tells_tools_it_is_a_cache(tmp_path: Path, capsys) -> None:
    design = tmp_path / "d.rcs"
    shutil.copy(CASES / "E0506_dead_rule.rcs", design)
    _check(design, capsys)
    folder = tmp_path / cache.FOLDER
    assert (folder / ".gitignore").read_text().splitlines()[-1] == "*"
    assert (folder / "CACHEDIR.TAG").read_text().startswith("Signature: 8a477f597d28d172789f06886806bc55")


def test_tagged_json_round_trip() -> None:
    from rcsc.semantics.types import F64, I32

    value = {("gm", "x"): (1, 2.5, float("nan"), float("-inf"), True, None, "s"), "k": [F64, I32, {"a": -0.0}]}
    back = cache.decode(json.loads(json.dumps(cache.encode(value))), {})
    assert repr(back) == repr(value)
    with pytest.raises(cache.NotStorable):
        cache.encode(object())


def test_value_findings_come_from_the_cache_at_their_new_place(tmp_path: Path, capsys) -> None:
    """The value analysis (W0524/W0525) keeps each plan's findings too: a design
    edited above the plans reads them back where the plans now are, with the
    bytes of a check without cache; an entry emptied (valid checksum) is believed."""
    design = tmp_path / "d.rcs"
    text = (CASES / "W0524_range_flow.rcs").read_text(encoding="utf-8")
    design.write_text(text, encoding="utf-8")
    _fresh_check(design)  # fills the cache
    design.write_text("// moved down\n\n" + text, encoding="utf-8")
    scratch = _fresh_check(design, "--no-cache")
    assert "W0524" in scratch
    assert _fresh_check(design) == scratch
    folder = tmp_path / cache.FOLDER
    emptied = 0
    for path in sorted(folder.glob("values-*.json")):
        doc = json.loads(path.read_text())
        payload = json.loads(doc["payload"])
        if payload and payload[0][0] == "W0524":
            doc["payload"] = "[]"
            doc["checksum"] = __import__("hashlib").sha256(b"[]").hexdigest()
            path.write_text(json.dumps(doc))
            emptied += 1
    assert emptied
    _forget_findings(folder)
    assert "W0524" not in _check(design, capsys)
