"""Coverage-guided fuzzing of rcsc's front end with atheris (libFuzzer for Python).

The hypothesis families of tests/test_fuzz.py draw inputs blindly; this harness
lets libFuzzer's coverage feedback steer the inputs into the branches the
random families miss.  Four targets, each with an oracle that can fail:

  parsers   the fast parser (rcsc.front.rdparse) against the reference grammar
            (grammar/rcs.lark): the same tree, span for span, and the same
            findings, byte for byte (tests/test_fastparse.py's comparison);
  check     the whole of `rcsc check` on the text (parse, model, every check
            family with z3): no exception escapes, every finding has a code and
            a span inside the file;
  scenario  a scenario text against the submarine design through the one
            scenario parser: no exception, every finding has a span inside it;
  fmt       `rcsc fmt` on a text that parses: the formatted text parses to the
            same tree (spans aside), keeps every comment in order, and
            formatting it again changes nothing (tests/test_fmt.py's oracle).

The corpus starts from every .rcs (or .scn) file of the repository, and a
dictionary of the language's keywords and punctuation helps the mutator.

    python bench/fuzz_front.py parsers -max_total_time=600      # ten minutes
    python bench/fuzz_front.py check -runs=20000 -jobs=2

Any further arguments are libFuzzer's (-runs, -max_total_time, -seed, ...).
A failure writes `crash-<hash>` in the working folder and exits non-zero;
rerun it with `python bench/fuzz_front.py TARGET crash-<hash>`.  The suite
runs a bounded slice of each target (tests/test_fuzz_coverage.py).
`--plant-bug` makes the parsers oracle fail on a valid `period` attribute: the
suite uses it to show that the harness really reports what it finds.
"""

from __future__ import annotations

import ctypes
import fnmatch
import os
import sys
import tempfile
from pathlib import Path

import atheris

ROOT = Path(__file__).resolve().parents[1]


def _keeps_results(native) -> bool:
    """Whether `native` (atheris's `_trace_cmp`) keeps a reference to the
    result of the comparison it traces: asked of the installed atheris, so
    that a version without the defect is not given references back that
    it does not hold."""
    token = object()

    class Left:
        def __lt__(self, other):
            return token

    before = sys.getrefcount(token)
    native(Left(), Left(), 0, 0, False)  # 0: `<`, the comparison's index in dis.cmp_op
    return sys.getrefcount(token) > before


def _release_comparison_results() -> None:
    """Stop atheris from keeping the result of every comparison it traces.

    The instrumented code calls `atheris._trace_cmp(left, right, op, ...)`
    for each comparison, and the native function hands back the result
    with one reference too many (pybind11 adds one to the `py::handle` it
    returns, and the new reference from the comparison is never dropped).
    For `True` and `False` that only inflates a count, but z3's `a == b`
    makes a new term, and every such term kept alive keeps the z3 context
    it was made in: with a context per analysed plan (rcsc.checks.smt,
    `own_context`) the fuzzer grew past 2 GB in 150 inputs.  The wrapper
    gives the extra reference back; instrumented code finds it because it
    looks `_trace_cmp` up on the module at each call.  `atheris.Fuzz` puts
    the fuzzing version there when it starts, so this runs at the first
    input, and after any later swap.  Checked by
    tests/test_fuzz_coverage.py (the memory of a bounded run)."""
    native = atheris._trace_cmp
    if getattr(native, "releases_results", False) or native is _SOUND[0]:
        return
    if not _keeps_results(native):
        _SOUND[0] = native
        return
    decref = ctypes.pythonapi.Py_DecRef
    decref.argtypes = [ctypes.py_object]
    decref.restype = None

    def trace_cmp(*args):
        result = native(*args)
        decref(result)
        return result

    trace_cmp.releases_results = True  # type: ignore[attr-defined]
    atheris._trace_cmp = trace_cmp


def _report_memory() -> None:
    """Print the process's peak memory when it has grown by 25 MB since
    last printed (`peak memory N MB`; tests/test_fuzz_coverage.py reads it).

    libFuzzer's own `rss:` figures come from getrusage, whose peak Linux
    carries over `exec` from the process that started this one: under a
    test suite that has grown, they say the suite's size.  The high-water
    mark of /proc/self/status (VmHWM) is this process's own."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            kib = next(int(line.split()[1]) for line in status if line.startswith("VmHWM:"))
    except (OSError, StopIteration, ValueError):
        return
    if kib >= _PEAK[0] + 25 * 1024:
        _PEAK[0] = kib
        print(f"peak memory {kib // 1024} MB", flush=True)


_PEAK = [0]

# The `_trace_cmp` last found to keep no results (`_keeps_results`).
_SOUND: list = [None]

sys.path.insert(0, str(ROOT / "tests"))

# Instrument rcsc (and lark, whose parser is half of the parsers oracle) so
# that libFuzzer sees their branches; the rest of the import graph is not
# worth the slowdown.
with atheris.instrument_imports(include=["rcsc", "lark"]):
    from rcsc.diagnostics import Diagnostics
    from rcsc.driver import check_path
    from rcsc.front.parse import text_to_ast, text_to_ast_lark
    from rcsc.front.scenario import text_to_scenario
    from rcsc.front.source import SourceFile
    from rcsc.editor import fmt as _fmt  # noqa: F401  (instrumented before test_fmt imports it)

import test_fastparse  # noqa: E402  (tree_difference and the findings view)
import test_fmt  # noqa: E402  (the formatter's round-trip oracle)
import test_fuzz  # noqa: E402  (KEYWORDS and PUNCT of the language)

PLANT_BUG = False
SUBMARINE = ROOT / "examples" / "submarine" / "submarine.rcs"


def _text(data: bytes) -> str | None:
    """The input as text; rcsc refuses non-UTF-8 files before parsing (E0001)."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def _assert_spans(diags) -> None:
    for d in diags:
        assert d.code and d.code[0] in "EW", f"finding without a code: {d}"
        for span in [d.span, *(label.span for label in d.labels)]:
            if span is not None:
                n = len(span.file.text)
                assert 0 <= span.start <= span.end <= n, f"{d.code} span {span.start}-{span.end} outside 0-{n}"


def fuzz_parsers(data: bytes) -> None:
    text = _text(data)
    if text is None:
        return
    source = SourceFile("fuzz.rcs", text)
    ref_diags, got_diags = Diagnostics(), Diagnostics()
    ref = text_to_ast_lark(source, ref_diags)
    got = text_to_ast(source, got_diags)
    difference = test_fastparse.tree_difference(ref, got)
    if PLANT_BUG and got is not None and ref is not None and " period " in text:
        difference = "planted"
    assert difference is None, f"trees differ at {difference}"
    assert test_fastparse._findings(ref_diags) == test_fastparse._findings(got_diags), "findings differ"


_WORK = Path(tempfile.mkdtemp(prefix="rcsc-fuzz-"))


def fuzz_check(data: bytes) -> None:
    text = _text(data)
    if text is None:
        return
    path = str(_WORK / "fuzz.rcs")
    # The overlay gives the text without touching the disk for every input;
    # imports of local modules resolve against the empty work folder.
    _assert_spans(check_path(path, overlay={path: text}).diags)


_DESIGN = None


def fuzz_scenario(data: bytes) -> None:
    global _DESIGN
    text = _text(data)
    if text is None:
        return
    if _DESIGN is None:
        _DESIGN = check_path(str(SUBMARINE)).model
    diags = Diagnostics()
    text_to_scenario(SourceFile("fuzz.scn", text), _DESIGN, diags)
    _assert_spans(diags)


def fuzz_fmt(data: bytes) -> None:
    text = _text(data)
    if text is None:
        return
    test_fmt._assert_round_trip(text, "the input")


TARGETS = {
    "parsers": (fuzz_parsers, "*.rcs"),
    "check": (fuzz_check, "*.rcs"),
    "scenario": (fuzz_scenario, "*.scn"),
    "fmt": (fuzz_fmt, "*.rcs"),
}


def _seed_corpus(pattern: str) -> Path:
    """A fresh corpus folder holding the repository's files of one kind.

    libFuzzer adds what it finds to the first corpus folder; a temporary one
    keeps the checkout clean."""
    folder = Path(tempfile.mkdtemp(prefix="rcsc-corpus-"))
    # build/, cargo's target/ and the virtual environments are not entered:
    # a build running at the same time would pull a folder from under the walk.
    paths = []
    for where, dirs, files in os.walk(ROOT):
        dirs[:] = [d for d in dirs if d not in ("build", "target", ".git") and not d.startswith(".venv")]
        paths.extend(Path(where) / f for f in fnmatch.filter(files, pattern))
    for k, path in enumerate(sorted(paths)):
        (folder / f"{k:04d}-{path.name}").write_bytes(path.read_bytes()[:20000])
    return folder


def _dictionary() -> Path:
    """A libFuzzer dictionary: every keyword and punctuation mark, quoted."""
    path = _WORK / "rcs.dict"
    words = sorted(set(test_fuzz.KEYWORDS) | set(test_fuzz.PUNCT))
    def quote(word: str) -> str:
        # libFuzzer's dictionary syntax: printable ASCII as is, the rest,
        # quotes and backslashes as \xNN escapes of the UTF-8 bytes.
        return "".join(chr(b) if 32 <= b < 127 and b not in (34, 92) else f"\\x{b:02X}" for b in word.encode())

    path.write_text("".join(f'"{quote(w)}"\n' for w in words))
    return path


def main(argv: list[str]) -> None:
    global PLANT_BUG
    if len(argv) < 2 or argv[1] not in TARGETS:
        sys.exit(f"usage: {argv[0]} {{{'|'.join(TARGETS)}}} [--plant-bug] [libFuzzer options or crash files]")
    target, pattern = TARGETS[argv[1]]
    rest = argv[2:]
    if "--plant-bug" in rest:
        PLANT_BUG = True
        rest.remove("--plant-bug")
    replay = [a for a in rest if not a.startswith("-")]
    extra = [] if replay else [str(_seed_corpus(pattern)), f"-dict={_dictionary()}"]
    os.environ.setdefault("RCSC_NO_CACHE", "1")

    def one_input(data: bytes) -> None:
        _release_comparison_results()
        target(data)
        _report_memory()

    atheris.Setup([argv[0], *rest, *extra], one_input)
    atheris.Fuzz()


if __name__ == "__main__":
    main(sys.argv)
