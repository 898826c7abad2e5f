"""The fast parser (rcsc.front.rdparse) against the reference parser (Lark, grammar/rcs.lark).

For every input both must give the same tree, node for node and span for
span (nesting depths included), and the same findings, byte for byte.  The
inputs are every .rcs file in the repository, the fuzz families of
tests/test_fuzz.py (grammar-derived designs, mutated example and library
files, keyword soups), synthetic designs of bench/synthetic.py and a list
of corner cases where a word is a keyword in one place and a name in
another.  The test also checks that the fast path really answers (does not
leave everything to Lark).
"""

from __future__ import annotations

import dataclasses
import importlib.util
import random
import sys
from pathlib import Path

import pytest

from rcsc.diagnostics import Diagnostics
from rcsc.front.parse import text_to_ast, text_to_ast_lark
from rcsc.front.rdparse import Fallback, parse_fast
from rcsc.front.source import SourceFile, Span

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
import test_fuzz  # noqa: E402  (the generators of the fuzz families)


def _synthetic():
    spec = importlib.util.spec_from_file_location("bench_synthetic", ROOT / "bench" / "synthetic.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def tree_difference(a, b, path: str = "file") -> str | None:
    """Where two ASTs differ (types, fields, spans, nesting depth), or None."""
    if type(a) is not type(b):
        return f"{path}: {type(a).__name__} vs {type(b).__name__}"
    if isinstance(a, Span):
        return None if (a.start, a.end) == (b.start, b.end) else f"{path}: span {a.start}-{a.end} vs {b.start}-{b.end}"
    if dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            found = tree_difference(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
            if found:
                return found
        if getattr(a, "depth", None) != getattr(b, "depth", None):
            return f"{path}: depth {getattr(a, 'depth', None)} vs {getattr(b, 'depth', None)}"
        return None
    if isinstance(a, (list, tuple)):
        if len(a) != len(b):
            return f"{path}: {len(a)} vs {len(b)} elements"
        for k, (x, y) in enumerate(zip(a, b)):
            found = tree_difference(x, y, f"{path}[{k}]")
            if found:
                return found
        return None
    return None if a == b else f"{path}: {a!r} vs {b!r}"


def _findings(diags: Diagnostics) -> list[tuple]:
    return [
        (d.code, d.severity.value, d.message, d.span and (d.span.start, d.span.end), d.label,
         [(lb.span.start, lb.span.end, lb.message) for lb in d.labels], d.notes, d.helps)
        for d in diags
    ]


STATS = {"fast": 0, "fallback": 0}


def assert_same(text: str, name: str = "t.rcs") -> bool:
    """Parse `text` both ways and compare; True when the fast path answered."""
    source = SourceFile(name, text)
    ref_diags, got_diags = Diagnostics(), Diagnostics()
    ref = text_to_ast_lark(source, ref_diags)
    got = text_to_ast(source, got_diags)
    difference = tree_difference(ref, got)
    assert difference is None, f"trees differ at {difference}\n--- input ---\n{text}"
    assert _findings(ref_diags) == _findings(got_diags), f"findings differ\n--- input ---\n{text}"
    try:
        parse_fast(source)
    except Fallback:
        STATS["fallback"] += 1
        return False
    STATS["fast"] += 1
    return True


def repo_files() -> list[Path]:
    files = []
    for pattern in ("examples/**/*.rcs", "tests/cases/**/*.rcs", "stdlib/**/*.rcs", "tests/stress/**/*.rcs", "tests/sim/**/*.rcs"):
        files += sorted(ROOT.glob(pattern))
    # A file that is not UTF-8 is never parsed (E0010, tests/cases/E0010_not_utf8).
    return [f for f in files if test_fuzz._is_utf8(f.read_bytes())]


def test_repo_files_parse_the_same() -> None:
    files = repo_files()
    assert len(files) > 80
    fast = sum(assert_same(f.read_text(encoding="utf-8"), str(f)) for f in files)
    # Only the files written to show a syntax error go to the reference parser.
    assert fast >= len(files) - 10


def test_grammar_designs_parse_the_same() -> None:
    fast = sum(assert_same(test_fuzz.grammar_input(seed)) for seed in range(400))
    assert fast >= 150, f"only {fast}/400 generated designs took the fast path"


def test_mutated_files_parse_the_same() -> None:
    files = test_fuzz.corpus_files()
    fast = 0
    for seed in range(300):
        path = files[seed % len(files)]
        fast += assert_same(test_fuzz.mutate(test_fuzz._corpus_text(path), seed), path.name)
    assert fast >= 30


def test_keyword_soups_parse_the_same() -> None:
    r = random.Random(18)
    words = test_fuzz.KEYWORDS + test_fuzz.PUNCT
    for _ in range(400):
        soup = " ".join(r.choice(words) for _ in range(r.randint(0, 60)))
        assert_same(r.choice(["design d\n", "design d\ncontroller C level 1 budget 1 ms {\n", ""]) + soup)


def test_synthetic_designs_parse_the_same() -> None:
    synthetic = _synthetic()
    for n, p, r in ((1, 1, 1), (3, 3, 4), (6, 5, 6)):
        assert assert_same(synthetic.generate(n, p, r))


# A word is a keyword only where the grammar expects it; elsewhere it is a name.
CORNERS = [
    # controller types, instances and function blocks
    "design d\ncontroller type T(a: f64 in 0.0..1.0, b: gm, c: i32,) level 1 budget 1 ms {\n block f: LP(k = a)\n}\ncontroller X: T(a = 1.0, b = g.x, c = 2)\n",
    "design d\nsimulator type S() level 0 budget 1 ms { }\nsimulator P: S()\ncontroller Q: T(1.0, x)\n",
    "design d\nblock B(k: f64) {\n input x: f64 = 0.0\n state s: bool = false\n output y: f64 = k\n step { y = x; s = not s; }\n step { }\n}\nblock E() { }\n",
    "design d\ncontroller C level 1 budget 1 ms {\n block f: B()\n post { f(x = 1.0); f(2.0); }\n plan P { P0: f.y > 0.0 | new -> done | f(); }\n}\n",
    "design d\nconst type: i32 = 1\nconst step: i32 = type\nconst input: i32 = state\n",  # new keywords are names elsewhere
    # Arrays: types (nested, a constant length), literals (empty, trailing
    # comma, repeat), indexing after names, calls, fields, parentheses and
    # literals, and indexed assignment in a block and in a job list.
    "design d\nconst A: [[f64; 2]; N] = [[1.0, 2.0,], [0.0; 2]]\ngm g: [i32; 3] = []\n",
    "design d\nconst B: i32 = f(x)[1] + r.xs[i + 1][j] + (a)[0] + [1, 2][k] - -a[0]\n",
    "design d\ncontroller C level 1 budget 1 ms {\n    pre { a[i] = 1; r.xs[k + 1] += 2; }\n"
    "    plan P { R: a[0] > 1 | new -> done | a[i] = [x; 2], S.V(p = [1, 2]), r.b[0] -= 1; }\n}\n",
    "design d\nfn f(a: [bool; 2], b: [[E; 1]; 3]) -> [i64; 2] = [a[0]; 2]\n",
    "design d\ngm x: f64 = 0.0 to env\ngm y: f64 = 0.0 from env\ngm to: i32 = 0\n",  # `to env` and `from env`
    "design d\ncontroller C level 1 budget 1 ms period 20 ms {\n}\n",  # the `period` attribute
    "design d\nconst A: i32 = and\n",  # `and` cannot start an expression: a name
    "design d\nconst A: bool = not if\n",  # after `not`, `if` is a name
    "design d\nconst A: i32 = -not\n",
    "design d\nconst A: i32 = 1 + if(2)\n",
    "design d\nconst A: i32 = if (a) then (b) else -(c.d)\n",
    "design d\nconst A: i32 = f(if = 1)\n",
    "design d\nconst A: i32 = f(x = 1, (y), z,)\n",
    "design d\nconst A: i32 = ((1 + 2)) * (3) and (x) or y\n",
    "design d\nconst A: i32 = a < b < c\n",
    "design d\nconst A: i32 = 1.e5\n",
    "design d\nconst A: i32 = 10ms.x\n",
    "design d\nconst A: i32 = 0x1F + 1_000 + 1e400 + 0.5e-3 s + 1.0000000001 ns\n",
    "design d\nconst A: i32 = 1e-12 s\n",
    "design d\nconst A: i32 = a->b\n",
    "design d\nconst A: i32 = x /* unterminated\n",
    "design d\nconst A: i32 = x // comment at the end",
    "design d\nconstX: i32 = 1\n",
    "design d\ncontrollerX level 1 {}\n",
    "design d\ncontroller X level5 {}\n",
    "design d\ncontroller X level 0x1_0 budget 1.5 ms budget 2 s {}\n",
    "design d\ncontroller X level 3.0 {}\n",
    "design d\ngm g: f64 in 0 .. 10 = 1 from env\n",
    "design d\ngm g: f64 from environment\n",
    "module a.b.c\nimport std.math\nimport \"x.rcs\"\nimport \"unterminated\n",
    "design d\nenum E { A, B, }\nrecord R { a: f64, b: i32 in -1..1, }\nenum F {}\nrecord G {}\n",
    "design d\nfn f(a: f64, b: f64,) -> f64 = a\nextern fn g() -> f64 budget 10 us\n",
    "design d\nverbset V { verb A verb B(x: f64) verb C() }\n",
    "design d\ncpu c { heartbeat 10 ms overhead 1 us schedule A, B }\n",
    "design d\ncontroller C level 1 {\n verb if\n local x: i32 = 0\n status s: i32 = 0\n"
    " reads a, b writes c reports d subordinates S verbs V\n"
    " pre { if x { else = 1; } elif y { f(); } else { x.y += 1; } if z { } else { } }\n"
    " post { x *= 2; g(a = 1); }\n"
    " plan if ordered continuous {\n"
    "  if: otherwise | new -> done;\n"
    "  plan: x and not y | * -> *;\n"
    "  new: true | S1 -> new | ;\n"
    "  L: (x) | new -> error(1 + 2) | report s, S.GO(a = 1), x.y = 3, f(1), z -= 1;\n"
    "  M: x | level -> level;\n"
    "  N: x | new -> S2 | report;\n"
    "  O: otherwise and x | new -> done;\n"
    " }\n}\n",
    "design d\ncontroller C { pre { else = 1; } post { x = 1 } }\n",
    "design d\ncontroller C { plan P { A: x | new -> done | a.b.c(1); } }\n",
    "design d\nconst A: i32 = " + "(" * 60 + "1" + ")" * 60 + "\n",
    "design d\nconst A: i32 = " + "-" * 200 + "1\n",
    "design d\nconst A: i32 = " + " + ".join(["1"] * 200) + "\n",
    "design d\nconst A: i32 = " + " + ".join(["1"] * 200) + "\nconst B: i32 = 1e999\n",
    "design d\nconst A: i32 = 1\u202e\n",
    "design d\r\nconst A: i32 = 1\rconst B: i32 = 2\n",
    "\ufeffdesign d\nconst A: i32 = 1\n",
    # `///` doc comments: attached by one pass after either parser (W0240 for a stray one).
    "design d\n/// A.\n///B\n//// plain\nconst A: i32 = 1\n/// dangling\n",
    "design d\n/// c\ncontroller C level 1 budget 1 ms {\n /// v\n verb GO(x: f64)\n /// s\n status s: i32 = 0\n"
    " /// p\n plan GO ordered {\n  /// r\n  R: true | new -> done;\n }\n /// nothing\n pre { }\n}\n"
    "/// rec\nrecord R {\n /// f\n a: f64 }\n/// e\nenum E { A }\n/// cpu\ncpu M { heartbeat 10 ms }\n",
    "design d\n/// cut off by /* c */\n/* x */ const A: i32 = 1\n/// */ /* \\ ??/\nfn f() -> i32 = 1\n",
    "design d\n/// a doc comment before a syntax error\ncontroller {\n",
    "design d\n/// \u202e reversed\nconst A: i32 = 1\n",
    "",
    "design d",
    "design",
]


@pytest.mark.parametrize("text", CORNERS, ids=range(len(CORNERS)))
def test_corner_cases_parse_the_same(text: str) -> None:
    assert_same(text)


def test_the_fast_path_answers_well_formed_designs() -> None:
    text = (ROOT / "examples" / "submarine" / "submarine.rcs").read_text(encoding="utf-8")
    tree, found = parse_fast(SourceFile("s.rcs", text))
    assert tree is not None and len(found) == 0
    with pytest.raises(Fallback):
        parse_fast(SourceFile("s.rcs", text + "\ncontroller {"))
