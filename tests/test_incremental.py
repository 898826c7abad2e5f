"""The incremental re-check (rcsc.checks.incremental): after an edit inside
the plans of some controllers, `rcsc check` parses and checks only those
controllers again, and answers what a full check answers.

The scan that finds controllers and plan bodies without parsing agrees with
the parser on every design of the repository; an edit inside a plan takes
the incremental path and gives the full check's report; an edit that
changes what other controllers see (outside a plan, a verb that can now
fail, names or types that no longer check, controller types) is checked in
full; and random edits of random designs (bench/incremental_fuzz.py, a
bounded slice) give the same reports both ways.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rcsc.checks import incremental
from rcsc.diagnostics import Diagnostics
from rcsc.front import ast
from rcsc.front import items as it
from rcsc.front.loader import path_to_files
from rcsc.front.source import SourceFile

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))

import incremental_fuzz  # noqa: E402  (bench/incremental_fuzz.py)
import synthetic  # noqa: E402  (bench/synthetic.py)


@pytest.fixture(autouse=True)
def _cache_on(monkeypatch):
    monkeypatch.delenv("RCSC_NO_CACHE", raising=False)
    monkeypatch.delenv("RCSC_INCREMENTAL", raising=False)


def _designs() -> list[Path]:
    """Every .rcs file of the checkout.  Folders that builds make and delete
    (build/, cargo's target/) are not entered: another test's build running
    at the same time would pull a folder from under the walk."""
    out = []
    for folder, dirs, files in os.walk(ROOT):
        dirs[:] = [d for d in dirs if d not in ("build", "target", ".rcsc-cache", ".git") and not d.startswith(".venv")]
        out.extend(Path(folder) / f for f in files if f.endswith(".rcs"))
    return sorted(out)


def test_the_scan_finds_what_the_parser_finds_in_every_design() -> None:
    compared = 0
    for path in _designs():
        text = SourceFile(str(path), path.read_text(encoding="utf-8", errors="replace")).text
        files = path_to_files(str(path), Diagnostics(), as_module=True)
        tree = files[0].tree
        if tree is None:
            continue
        found = it.controller_items(text)
        assert found is not None, path
        parsed = {x.name.name: x for x in tree.items if type(x) is ast.Controller}
        assert [x.name for x in found] == list(parsed), path
        for x in found:
            c = parsed[x.name]
            assert (c.span.start, c.span.end) == (x.start, x.end), (path, x.name)
            assert [(p.name.name, p.span.end - 1) for p in c.plans] == [(v, e) for v, _, e in x.bodies], (path, x.name)
            compared += 1
    assert compared > 300


def test_the_scan_is_not_fooled_by_comments_strings_and_names() -> None:
    text = (
        'design d\n// controller X { plan Y {\n/* } */\nconst plan: i32 = 1\n'
        'controller A level 1 budget 1 ms {\n    local plan: i32 = 0\n    verbs plan\n'
        '    plan GO ordered {\n        R1: true | new -> done | x = "}";  // }\n    }\n}\n'
    )
    found = it.controller_items(text)
    assert found is not None and [x.name for x in found] == ["A"]
    (verb, s, e), = found[0].bodies
    assert verb == "GO" and text[s:e].strip().startswith("R1:") and text[e] == "}"
    blanked = it.blank(text, [(s, e)])
    assert len(blanked) == len(text) and blanked.count("\n") == text.count("\n") and "R1" not in blanked
    assert it.controller_items("controller A { plan B {") is None  # unbalanced: no guess


# Pieces that matter to the scan: braces, strings, comments, divisions,
# line breaks and the words that open controllers and plans.
_PIECES = ["{", "}", '"', "/", "*", "\n", " ", "x", "//", "/*", "*/", "a = 1 / 2", "controller C1 ", "controller X level 2 ",
           " budget 10 us ", "plan p ", "plan q ordered ", '"}"']


def _design_text(n: int, plans: int) -> str:
    out = []
    for k in range(n):
        out.append(["", "// c\n", "/* x */", "gm a: f64 = 1.0 / 2.0\n", '/// "doc\n'][k % 5])
        out.append(f"controller C{k} level {k} {{\n")
        for j in range((k + plans) % 5):
            out.append(f'  plan P{j} {{ a: {{ x }} "s}}" // }}\n }}\n')
        out.append("}\n")
    return "".join(out)


def _as_found(items):
    return None if items is None else [(x.name, x.start, x.end, x.bodies, x.scan_from) for x in items]


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.integers(0, 6), st.integers(0, 4),
       st.lists(st.tuples(st.floats(0, 1), st.integers(0, 8), st.lists(st.sampled_from(_PIECES), max_size=4)), min_size=1, max_size=8))
def test_the_scan_after_an_edit_finds_what_a_whole_scan_finds(n, plans, edits) -> None:
    """A language server scans text after text, each an edit of the one
    before; the scan then reads only the controllers around the edit
    (`items._rescan`) and must find what scanning the whole text finds, and
    `digests` must give what digesting it whole gives."""
    it._memo[:] = [None, None, None, None]
    text = _design_text(n, plans)
    it.digests(text)
    for where, length, pieces in edits:
        at = int(where * len(text))
        text = text[:at] + "".join(pieces) + text[at + length:]
        found = it.controller_items(text)
        whole = it._scan(text)
        assert _as_found(found) == _as_found(whole), text
        sums = it.digests(text)
        assert sums == (None if whole is None else (it.gaps(text, whole),
                                                    [(it.digest(x.outline(text)), it.digest(x.body_text(text))) for x in whole]))


@pytest.mark.parametrize("old, new", [
    ('controller C level 1{"}', 'controller C level 1{"}"'),
    ('controller A { a " }\ncontroller B { }\n', 'controller A { a " }"\ncontroller B { }\n'),
    ('controller C{"}\n"', 'controller C{"}"'),
])
def test_a_quote_written_after_a_closing_brace_on_its_line_is_read_again(old: str, new: str) -> None:
    """A lone `"` before a `}` is a string only when a `"` follows on the
    line: an edit later on that line changes what the `}` is, so the scan
    after the edit must start before that line."""
    it._memo[:] = [None, None, None, None]
    it.controller_items(old)
    assert _as_found(it.controller_items(new)) == _as_found(it._scan(new))


def test_the_scan_after_an_edit_reads_only_the_edited_controller() -> None:
    text = _design_text(40, 3)
    it._memo[:] = [None, None, None, None]
    it.controller_items(text)
    at = text.index("a: { x }", text.index("controller C20 "))
    edited = text[:at] + "b" + text[at + 1:]
    found = it.controller_items(edited)
    assert it._memo[2] is not None and it._memo[2].count(None) == 1  # C20 alone was scanned again
    assert _as_found(found) == _as_found(it._scan(edited))


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.integers(0, 1000), st.lists(st.tuples(st.floats(0, 1), st.integers(0, 40), st.lists(st.sampled_from(["\n", "a", "\n\n", "bc"]), max_size=6)),
                                      min_size=1, max_size=6))
def test_the_line_table_after_an_edit_is_the_line_table(seed, edits) -> None:
    """The line table of a large text that is an edit of the last one is made
    from the last one's (`source._line_starts_of`); it must be the table."""
    import itertools
    import random

    from rcsc.front import source

    def table(t: str) -> list[int]:
        return [0, *itertools.accumulate(map((1).__add__, map(len, t.split("\n")[:-1])))]

    r = random.Random(seed)
    text = "".join(r.choice(["ab", "\n", "x\n\n", "yyyy"]) for _ in range(40_000))
    assert len(text) > source._REUSE_ABOVE
    source._last_lines[:] = [None, None]
    assert SourceFile("a.rcs", text)._line_starts == table(text)
    for where, length, pieces in edits:
        at = int(where * len(text))
        text = text[:at] + "".join(pieces) + text[at + length:]
        before = source._last_lines[1]
        assert SourceFile("a.rcs", text)._line_starts == table(text)
        assert source._last_lines[0] is not None and source._last_lines[1] is not before


def _edit(path: Path, old: str, new: str, after: str = "") -> None:
    text = path.read_text(encoding="utf-8")
    at = text.index(old, text.index(after) if after else 0)
    path.write_text(text[:at] + new + text[at + len(old):], encoding="utf-8")


def _check(folder: Path, *extra: str, incremental_on: bool = True) -> str:
    env = {k: v for k, v in os.environ.items() if k != "RCSC_NO_CACHE"}
    env["PYTHONPATH"] = str(ROOT)
    if not incremental_on:
        env["RCSC_INCREMENTAL"] = "0"
    proc = subprocess.run([sys.executable, "-m", "rcsc", "check", "d.rcs", "--format", "json", *extra], capture_output=True,
                          text=True, env=env, cwd=folder, timeout=600)
    assert proc.returncode in (0, 1) and "Traceback" not in proc.stderr, proc.stderr
    return proc.stdout


@pytest.fixture
def checked(tmp_path: Path) -> Path:
    """A synthetic design of six controllers, checked once (the cache holds its findings and outline)."""
    folder = tmp_path / "a"
    folder.mkdir()
    (folder / "d.rcs").write_text(synthetic.generate(6, 3, 6), encoding="utf-8")
    _check(folder)
    return folder


# The controllers the first re-check of the last `_both_ways` checked again.
_rechecked: list[frozenset] = [frozenset()]


def _both_ways(folder: Path) -> tuple[bool, str, str]:
    """Whether the re-check of `folder/d.rcs` is incremental, its report and
    that of a full check with a copy of the same cache."""
    copy = folder.parent / (folder.name + "-full")
    shutil.copytree(folder, copy)
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        used = incremental.recheck("d.rcs", False, ".rcsc-cache") is not None
        why = incremental.last_miss
        _rechecked[:] = [incremental.last_rechecked]
    finally:
        os.chdir(cwd)
    os.chdir(copy)
    try:
        incremental.recheck("d.rcs", False, ".rcsc-cache")  # the same solver questions on both sides
    finally:
        os.chdir(cwd)
    inc, full = _check(folder), _check(copy, incremental_on=False)
    assert incremental_fuzz.normalized(inc) == incremental_fuzz.normalized(full), why
    return used, why, inc


def test_an_edit_inside_a_plan_is_rechecked_in_part_and_gives_the_full_report(checked: Path) -> None:
    # One rule of C1 now leaves a gap in `new` (E0516), below C0 and above C2..C5.
    _edit(checked / "d.rcs", "<= 1000.0", "<= 999.0", after="controller C1 ")
    used, why, report = _both_ways(checked)
    assert used, why
    assert '"code": "E0516"' in report


def test_findings_of_unchanged_controllers_move_with_the_lines_above_them(checked: Path) -> None:
    # A finding in C4 first, then three lines more in a plan of C1 (above it).
    _edit(checked / "d.rcs", "<= 1000.0", "<= 999.0", after="controller C4 ")
    _check(checked)
    text = (checked / "d.rcs").read_text(encoding="utf-8")
    at = text.index("plan", text.index("controller C1 "))
    at = text.index("{", at) + 1
    (checked / "d.rcs").write_text(text[:at] + "\n\n    // three lines more\n" + text[at:], encoding="utf-8")
    used, why, report = _both_ways(checked)
    assert used, why
    assert '"code": "E0516"' in report


@pytest.mark.parametrize(
    "old, new",
    [
        ("local count: i32 in 0..1000 = 0", "local count: i32 in 0..1000 = 1"),  # a local's initial value
        ("local count: i32 in 0..1000 = 0", "local count: i32 in 0..10 = 0"),  # a local's range
        ("reports AT_GOAL", "reports AT_GOAL, SLOW"),  # a status value its supervisor can read
        ("status progress: f64 = 0.0", "status progress: f64 in 0.0..50.0 = 0.0"),  # a status field's range
        ("post { if count > MAX_COUNT", "post { if count >= MAX_COUNT"),  # `post`
    ],
)
def test_an_edit_of_a_header_is_rechecked_in_part_with_the_supervisor(checked: Path, old: str, new: str) -> None:
    """C2's header changes: C2 and its supervisor C0 are checked again, the
    others keep their findings; the report is the full check's."""
    _edit(checked / "d.rcs", old, new, after="controller C2 ")
    used, why, _ = _both_ways(checked)
    assert used, why


@pytest.mark.parametrize(
    "old, new, why",
    [
        ("budget 100 us {\n    reads c2_raw", "budget 90 us {\n    reads c2_raw",
         "a controller's level, budget, period, subordinates or Global Memory changed"),
        ("reads c2_raw, c0_sp", "reads c2_raw", "a controller's level, budget, period, subordinates or Global Memory changed"),
        ("-> error(10)", "-> error(11)", "an edited controller's summary changed"),
        ("<= 1000.0", "<= true", "errors of names or types came or went"),
    ],
)
def test_edits_that_change_what_others_see_are_checked_in_full(checked: Path, old: str, new: str, why: str) -> None:
    _edit(checked / "d.rcs", old, new, after="controller C2 ")
    used, reason, _ = _both_ways(checked)
    assert not used and reason == why


def test_designs_with_controller_types_are_checked_in_full(tmp_path: Path) -> None:
    import difftest_gen

    for seed in range(40):
        text = difftest_gen.draw(seed, 0).design
        if "controller type" in text or "simulator type" in text:
            break
    else:
        pytest.fail("no draw with a controller type")
    (tmp_path / "d.rcs").write_text(text, encoding="utf-8")
    _check(tmp_path)
    edited = incremental_fuzz.edit(text, __import__("random").Random(seed))
    assert edited is not None
    (tmp_path / "d.rcs").write_text(edited[0], encoding="utf-8")
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        assert incremental.recheck("d.rcs", False, ".rcsc-cache") is None
    finally:
        os.chdir(cwd)
    # (A controller type lies outside the controllers the scan finds: an
    # edit of a declaration it names is "the text outside the controllers".)
    assert incremental.last_miss in ("controller types", "an edited controller's summary changed", "the text outside the controllers changed")


def test_random_edits_of_random_designs_give_the_full_report(capsys) -> None:
    """A bounded slice of `python bench/incremental_fuzz.py --seeds A..B`."""
    assert incremental_fuzz.main(["--seeds", "30..33"]) == 0, capsys.readouterr().out
    out = capsys.readouterr().out
    assert " 0 disagreements" in out and "re-checked incrementally" in out


@pytest.mark.parametrize("form", ["crlf", "bom", "tabs"])
def test_line_ends_byte_order_marks_and_tabs_keep_every_place(tmp_path: Path, form: str) -> None:
    """The scan, the blanking and the moved findings work on the text as the
    checker sees it (a byte-order mark dropped, CRLF kept, tabs counted as
    one column): the report equals the full check's."""
    text = synthetic.generate(4, 2, 5)
    # A finding in C3 that must move when C1 grows.
    at = text.index("<= 1000.0", text.index("controller C3 "))
    text = text[:at] + "<= 999.0" + text[at + len("<= 1000.0"):]
    if form == "crlf":
        text = text.replace("\n", "\r\n")
    elif form == "bom":
        text = "\ufeff" + text
    else:
        text = text.replace("    ", "\t")
    folder = tmp_path / "a"
    folder.mkdir()
    (folder / "d.rcs").write_bytes(text.encode("utf-8"))
    _check(folder)
    nl = "\r\n" if form == "crlf" else "\n"
    at = text.index("{", text.index("plan", text.index("controller C1 "))) + 1
    (folder / "d.rcs").write_bytes((text[:at] + nl + nl + "    // more lines" + nl + text[at:]).encode("utf-8"))
    used, why, report = _both_ways(folder)
    assert used, why
    assert '"code": "E0516"' in report


@pytest.mark.parametrize("seed", [8, 18, 38, 3])
def test_a_language_server_keeps_unchanged_controllers_trees_between_edits(tmp_path: Path, seed: int) -> None:
    """In a long-lived process (`memory_stores`), the syntax trees of the
    unchanged controllers are kept from one re-check to the next and moved
    to their new offsets instead of being parsed again.  Successive random
    edits (which change lengths above other controllers, and sometimes
    write a doc comment before one) give the places of a full check,
    finding for finding and label for label."""
    r = incremental_fuzz.run_seed_in_memory(seed, tmp_path)
    assert r["ok"], r["edits"]
    if seed % 10 == 8:  # the synthetic designs: edits inside plans, re-checked in part
        assert r["used"] >= 2 and r["kept"] > 0


def test_a_doc_comment_written_before_a_controller_is_not_lost_by_a_kept_tree(tmp_path: Path) -> None:
    """A tree kept while a controller had no doc comment must not be used
    after one was written before it (that edit is checked in full, and the
    next edit inside a plan is re-checked in part): the comment documents
    the controller (no W0240 "documents nothing"), as in a full check."""
    from rcsc.checks import cache
    from rcsc.driver import check_path

    path = tmp_path / "d.rcs"
    text = synthetic.generate(3, 2, 1)
    path.write_text(text, encoding="utf-8")
    real = os.path.realpath(path)
    memory = incremental.memory_stores(cache.MemoryStore())
    check_path(str(path), memory=memory)
    steps = [
        lambda t: t.replace("count = 0, c0_sp", "count = 1, c0_sp", 1),  # inside a plan of C0: C1, C2 kept
        lambda t: t.replace("controller C1 ", "/// the second\ncontroller C1 ", 1),  # outside: a full check
        lambda t: t.replace("count = 1, c0_sp", "count = 2, c0_sp", 1),  # inside again: in part
    ]
    for step in steps:
        new = step(text)
        assert new != text
        text = new
        result = check_path(str(path), overlay={real: text}, memory=memory)
        full = check_path(str(path), overlay={real: text}, guard_store=memory["guards"])
        assert incremental_fuzz.places(result) == incremental_fuzz.places(full)
    assert result.partial and "W0240" not in {d.code for d in result.diags.items}
    assert result.model.controllers["C1"].doc == "the second"


def test_an_edit_of_a_local_reanalyses_only_that_controllers_plans(tmp_path: Path, monkeypatch) -> None:
    """The value analysis keys each plan by its controller's header and what
    it sees of its subordinates (verbs, status), not by every header: after
    an edit of C2's local, the supervisor C0 is checked again but its plans'
    value findings come from the store; only C2's plans are analysed."""
    from rcsc.checks import cache, values
    from rcsc.driver import check_path

    path = tmp_path / "d.rcs"
    text = synthetic.generate(6, 3, 6)
    path.write_text(text, encoding="utf-8")
    memory = incremental.memory_stores(cache.MemoryStore())
    check_path(str(path), memory=memory)
    analysed: list[str] = []
    run = values._Plan.run

    def counting(self) -> None:
        analysed.append(self.c.name)
        run(self)

    monkeypatch.setattr(values._Plan, "run", counting)
    at = text.index("local count: i32 in 0..1000 = 0", text.index("controller C2 "))
    edited = text[:at] + "local count: i32 in 0..1000 = 5" + text[at + len("local count: i32 in 0..1000 = 0"):]
    result = check_path(str(path), overlay={os.path.realpath(path): edited}, memory=memory)
    assert result.partial, incremental.last_miss
    assert analysed and set(analysed) == {"C2"}
    full = check_path(str(path), overlay={os.path.realpath(path): edited}, guard_store=memory["guards"])
    assert incremental_fuzz.places(result) == incremental_fuzz.places(full)


_HINTED = """design d

controller TOP level 2 budget 1 ms {
    subordinates A, B
    verb RUN
    plan RUN {
        E0: true | new -> S1 | A.GO(), B.GO();
        E1: A.done and B.done | S1 -> done;
        E2: A.error or B.error | S1 -> error(1);
    }
}

controller A level 1 budget 1 ms {
    verb GO
    local count: i32 in 0..9 = 0
    plan GO {
        E0: speedlimit > 3 | new -> done;
    }
}

controller B level 1 budget 1 ms {
    verb GO
    local other: i32 in 0..9 = 0
    plan GO {
        E0: true | new -> done;
    }
}

cpu main {
    heartbeat 10 ms
    schedule TOP, A, B
}
"""


@pytest.mark.parametrize("first, then", [("other", "speedlimt"), ("speedlimt", "other")])
def test_a_header_edit_that_changes_a_did_you_mean_elsewhere_is_checked_in_full(tmp_path: Path, first: str, then: str) -> None:
    """A's unknown name `speedlimit` (E0100) gets a "did you mean" chosen
    among the names declared in every header: renaming B's local (B is not
    A's supervisor) changes the help of a finding in A, kept from the last
    check by a re-check in part (found by a second read of the change)."""
    from rcsc.checks import cache
    from rcsc.driver import check_path

    path = tmp_path / "d.rcs"
    text = _HINTED.replace("local other", f"local {first}")
    path.write_text(text, encoding="utf-8")
    memory = incremental.memory_stores(cache.MemoryStore())
    check_path(str(path), memory=memory)
    edited = text.replace(f"local {first}", f"local {then}")
    result = check_path(str(path), overlay={os.path.realpath(path): edited}, memory=memory)
    full = check_path(str(path), overlay={os.path.realpath(path): edited})
    assert incremental_fuzz.places(result) == incremental_fuzz.places(full)
    assert not getattr(result, "partial", False) and incremental.last_miss == "the names a hint can suggest changed"
    helps = [h for d in result.diags.items if d.code == "E0100" for h in d.helps]
    assert ("did you mean `speedlimt`?" in helps) == (then == "speedlimt")


@pytest.mark.parametrize(
    "old, new, rechecked",
    [
        # A Global Memory variable that only C3 reads: C3 and its supervisor C0.
        ("gm c3_raw: f64 = 0.0 from env", "gm c3_raw: f64 in -500.0..500.0 = 0.0 from env", {"C0", "C3"}),
        # A function every controller's `pre` calls (through `within`'s record type too).
        ("clamp(x * k, -1000.0, 1000.0)", "clamp(x * k, -900.0, 900.0)", None),
        ("enum Mode { IDLE, RUN, SERVICE }", "enum Mode { IDLE, RUN, SERVICE, MAINT }", None),
        ("const MAX_COUNT: i32 = 100", "const MAX_COUNT: i32 = 90", None),
        # A constant that nothing names: no controller is checked again.
        ("const GAIN: f64 = 0.5", "const GAIN: f64 = 0.5\nconst UNUSED: i32 = 3", set()),
    ],
)
def test_an_edit_of_a_declaration_rechecks_the_controllers_that_name_it(checked: Path, old: str, new: str, rechecked) -> None:
    """An edit of declarations outside the controllers checks again the
    controllers whose text names what changed (and their supervisors);
    the report is the full check's."""
    _edit(checked / "d.rcs", old, new)
    used, why, _ = _both_ways(checked)
    assert used, why
    if rechecked is not None:
        assert _rechecked[0] == rechecked


@pytest.mark.parametrize(
    "old, new",
    [
        ("const GAIN: f64 = 0.5", "// tuned by hand\nconst GAIN: f64 = 0.5"),  # a comment outside the controllers
        ("import std.math\n", "import std.math\nimport std.lifecycle\n"),  # an import
        ("design synthetic_6_3_6", "design synthetic_six"),  # the design's name
    ],
)
def test_an_edit_outside_the_controllers_and_their_declarations_is_checked_in_full(checked: Path, old: str, new: str) -> None:
    _edit(checked / "d.rcs", old, new)
    used, why, _ = _both_ways(checked)
    assert not used and why == "the text outside the controllers changed"


IMPORTING = """design t1

import std.lifecycle
import "lib.rcs"

const HI: f64 = 10.0

gm x: f64 in 0.0..100.0 = 0.0 from env

controller TOP level 2 budget 1 ms {
    subordinates A
    verbs Lifecycle
    plan INIT {
        E0: true | new -> S1 | A.INIT();
        E1: A.done | S1 -> done;
        E2: A.error | S1 -> error(1);
    }
    plan HALT { E0: true | new -> done; }
    plan ABORT { E0: true | new -> done; }
}

controller A level 1 budget 1 ms {
    reads x
    verbs Lifecycle
    plan INIT {
        E0: x <= lim_hi() | new -> done;
        E1: x > 10.0 | new -> error(2);
    }
    plan HALT { E0: true | new -> done; }
    plan ABORT { E0: true | new -> done; }
}

cpu MAIN { heartbeat 10 ms schedule TOP, A }
"""


def test_a_declaration_an_imported_file_names_is_checked_in_full(tmp_path: Path) -> None:
    """The names of a design are shared by all its files: `A` reaches `HI`
    only through a function of the imported file, which its text does not
    name.  After `HI` drops to 9.0, a value of `x` in 9..10 makes no rule
    of `new` true (E0516): the full check's finding, not the last one's."""
    folder = tmp_path / "a"
    folder.mkdir()
    (folder / "lib.rcs").write_text("module lib\nfn lim_hi() -> f64 = HI\n", encoding="utf-8")
    (folder / "d.rcs").write_text(IMPORTING, encoding="utf-8")
    assert '"code": "E0516"' not in _check(folder)
    _edit(folder / "d.rcs", "const HI: f64 = 10.0", "const HI: f64 = 9.0")
    used, why, report = _both_ways(folder)
    assert not used and why == "an imported file names an edited declaration"
    assert '"code": "E0516"' in report


def test_a_damaged_list_of_declarations_is_a_miss_not_a_crash() -> None:
    text = IMPORTING
    items = it.controller_items(text)
    outline = {"declarations": {"frame": "x", "digests": {"Junk": "y"}}}
    with pytest.raises(incremental._Miss, match="a corrupt entry"):
        incremental._edited_declarations("d.rcs", text, items, outline, [])


def test_a_comment_moved_past_a_controller_is_an_edit_of_the_text_outside() -> None:
    """The frame compared after an edit of declarations keeps the places of
    the controllers: a comment before C1 is C1's doc comment, after it not."""
    from rcsc.front.declarations import declarations
    from rcsc.front.rdparse import parse_fast

    def frame(text: str) -> str:
        found = it.controller_items(text)
        tree, _ = parse_fast(SourceFile("d.rcs", text), [(x.start, x.end) for x in found])
        decls = declarations(text, tree.items, found)
        assert decls is not None
        return decls.frame

    base = synthetic.generate(3, 1, 2)
    before_c1 = base.replace("controller C1 ", "// a note\ncontroller C1 ", 1)
    before_c2 = base.replace("controller C2 ", "// a note\ncontroller C2 ", 1)
    assert frame(before_c1) != frame(before_c2)
    # Blank lines, and a declaration added between two others, leave it as it was.
    assert frame(base.replace("const GAIN", "\n\nconst NEW: i32 = 1\nconst GAIN", 1)) == frame(base)
