"""Fuzzing `rcsc check`: no input, however broken, may crash the compiler.

Three families of generated inputs are written to a file and checked in
process with `rcsc.cli.main(['check', FILE, '--format', 'json'])`:

(a) random text: arbitrary Unicode (NUL included), text over the language's
    own characters, soups of the grammar's keywords and punctuation, random
    text after a valid header, and a few raw byte strings (not always UTF-8);
(b) grammar-derived designs: `DesignGen` writes syntactically plausible
    designs from the grammar's constructs (controllers, plans, rules,
    expressions, types, durations, CPUs, imports of std.math,
    std.lifecycle, missing modules and local files) with names drawn from a
    small pool, so that names sometimes resolve and sometimes do not;
(c) mutated real files: every examples/**/*.rcs and stdlib/std/*.rcs with
    random token and line mutations (delete, duplicate, swap, replace names,
    flip operators, extreme numbers, truncate).

For every input: `main` returns (no exception escapes), the exit code is 0, 1
(never 2, and never an "internal compiler error"; a file that is not UTF-8
is one E0010 finding), stdout is one JSON document whose summary matches its
diagnostics and the exit code, and every diagnostic (and every secondary
label) has a file, a line and a column inside that file.

The runs are reproducible: hypothesis is derandomized (fixed seed per test,
no example database), the generators of (b) and (c) are driven by a seed that
hypothesis draws, and a failure prints the family, the seed and the input.
To see the input of a seed: `python tests/test_fuzz.py grammar SEED` or
`python tests/test_fuzz.py mutate SEED FILE`.

The families run MIN_RUNS inputs together (each family asserts its own share,
and `test_zz_total_inputs` the sum when all three ran in this session).
Deeply nested expressions and blocks are explicit cases (`test_deep_nesting`)
rather than part of a family, so that one known crash there does not stop a
family from exploring the rest.  The whole file takes 50-70 s on two cores.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import random
import re
import shutil
import sys
import tempfile
import traceback
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, note, settings
from hypothesis import strategies as st
from hypothesis.errors import InvalidArgument

ROOT = Path(__file__).resolve().parents[1]
MIN_RUNS = 5_000

# Inputs per family; their sum is above MIN_RUNS.  (c) runs whole example
# files, so each of its inputs costs ~10x one of (a).
N_TEXT = 3_200
N_GRAMMAR = 1_400
N_MUTATE = 450

RUNS: dict[str, int] = {"text": 0, "grammar": 0, "mutate": 0}
FAMILIES_DONE: set[str] = set()


def _settings(n: int):
    return settings(
        max_examples=n,
        deadline=None,
        derandomize=True,  # the same inputs on every run and machine
        database=None,
        print_blob=True,
        phases=(Phase.explicit, Phase.generate, Phase.shrink),
        suppress_health_check=list(HealthCheck),
    )


# ---------------------------------------------------------------------------
# running rcsc and the invariants of its answer
# ---------------------------------------------------------------------------

_WORKDIR: Path | None = None


def _workdir() -> Path:
    """A folder for the inputs, with a local module to import (`helper.rcs`)."""
    global _WORKDIR
    if _WORKDIR is None:
        d = Path(tempfile.mkdtemp(prefix="rcsc-fuzz-"))
        (d / "helper.rcs").write_text(
            "module helper\nconst HK: f64 = 2.5\nenum HMode { ON, OFF }\n"
            "fn hscale(x: f64) -> f64 = x * HK\ngm hvar: f64 = 0.0 from env\n",
            encoding="utf-8",
        )
        (d / "sub").mkdir()
        (d / "sub" / "broken.rcs").write_text("module sub.broken\nconst : = \n", encoding="utf-8")
        (d / "sub" / "design2.rcs").write_text("design two\nconst Z: i32 = 1\n", encoding="utf-8")
        _WORKDIR = d
    return _WORKDIR


@pytest.fixture(scope="module", autouse=True)
def _fuzz_session():
    """Build `rcsc`'s argparse parser once for this module, and remove the
    input folder at the end.  `main()` is still the entry point of every run;
    only the ~3 ms of rebuilding the same parser (argparse's gettext
    look-ups) per input is saved, a quarter of the fuzz budget.  argparse
    parsers are reusable: parse_args does not change them."""
    global _WORKDIR
    from rcsc import cli

    original = cli.build_parser
    cached = original()
    cli.build_parser = lambda only=None: cached  # the full parser serves every command
    try:
        yield
    finally:
        cli.build_parser = original
        if _WORKDIR is not None:
            shutil.rmtree(_WORKDIR, ignore_errors=True)
            _WORKDIR = None


def run_check(path: Path) -> tuple[object, str, str]:
    """`rcsc check PATH --format json` in process: (exit code, stdout, stderr)."""
    from rcsc import cli

    out, err = io.StringIO(), io.StringIO()
    old = os.environ.get("RCSC_BACKTRACE")
    os.environ["RCSC_BACKTRACE"] = "1"  # an internal error then carries its traceback
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                rc = cli.main(["check", str(path), "--format", "json"])
            except BaseException:  # noqa: BLE001 - reported as the failure itself
                return "escaped", out.getvalue(), traceback.format_exc()
    finally:
        if old is None:
            os.environ.pop("RCSC_BACKTRACE", None)
        else:
            os.environ["RCSC_BACKTRACE"] = old
    return rc, out.getvalue(), err.getvalue()


def _is_utf8(data: bytes) -> bool:
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return False
    return True


def _check_position(d: dict, texts: dict[str, str], where: str) -> None:
    assert isinstance(d.get("file"), str) and d["file"], f"{where}: no file"
    line, col = d.get("line"), d.get("column")
    assert isinstance(line, int) and line >= 1, f"{where}: bad line {line!r}"
    assert isinstance(col, int) and col >= 1, f"{where}: bad column {col!r}"
    text = texts.get(d["file"])
    if text is not None:
        # A line ends at LF, CRLF or a lone CR; a byte-order mark is not text.
        lines = re.sub("\r(?!\n)", "\n", text.removeprefix("\ufeff")).split("\n")
        assert line <= len(lines), f"{where}: line {line} beyond the file's {len(lines)} lines"
        assert col <= len(lines[line - 1]) + 1, f"{where}: column {col} beyond line {line} ({len(lines[line - 1])} chars)"


def check_input(family: str, data: str | bytes, name: str = "fuzz.rcs", describe: str = "") -> None:
    """Write `data`, run `rcsc check` on it and assert the invariants."""
    RUNS[family] += 1
    path = _workdir() / name
    raw = data.encode("utf-8") if isinstance(data, str) else data
    path.write_bytes(raw)
    with contextlib.suppress(InvalidArgument):  # outside a hypothesis test there is nothing to note
        note(f"family {family} {describe}\n--- input ({len(raw)} bytes) ---\n{raw.decode('utf-8', 'replace')}\n--- end ---")
    rc, out, err = run_check(path)
    context = f"[{family} {describe}] rcsc check on {path}"
    assert rc != "escaped", f"{context}: an exception escaped main():\n{err}"
    assert "internal compiler error" not in err, f"{context}: crashed (exit {rc}):\n{err}"
    assert rc in (0, 1, 2), f"{context}: exit code {rc!r}\n{err}"
    # A readable file is never a usage error: one that is not UTF-8 is E0010 at its first bad byte.
    assert rc != 2, f"{context}: exit 2 for a readable file:\n{err}"
    try:
        doc = json.loads(out)
    except ValueError as exc:
        raise AssertionError(f"{context}: stdout is not JSON ({exc}):\n{out[:2000]}\n{err}") from exc
    assert isinstance(doc, dict) and isinstance(doc.get("diagnostics"), list), f"{context}: bad document {out[:500]}"
    texts = {str(path): raw.decode("utf-8", "replace")}
    if not _is_utf8(raw):
        codes = [d.get("code") for d in doc["diagnostics"]]
        assert codes == ["E0010"], f"{context}: not UTF-8, found {codes}"
    errors = warnings = 0
    for i, d in enumerate(doc["diagnostics"]):
        where = f"{context}: diagnostic {i} {d.get('code')} {d.get('message')!r}"
        assert isinstance(d.get("code"), str) and d["code"], where
        _check_position(d, texts, where)
        for j, label in enumerate(d.get("labels", [])):
            _check_position(label, texts, f"{where} label {j}")
        errors += d.get("severity") == "error"
        warnings += d.get("severity") == "warning"
    assert doc["summary"] == {"errors": errors, "warnings": warnings}, f"{context}: summary {doc['summary']}"
    assert rc == (1 if errors else 0), f"{context}: exit {rc} with {errors} errors"


# ---------------------------------------------------------------------------
# (a) random text
# ---------------------------------------------------------------------------

KEYWORDS = [
    "design", "module", "import", "const", "enum", "record", "gm", "from", "env", "fn", "extern",
    "budget", "verbset", "verb", "verbs", "controller", "simulator", "level", "cpu", "heartbeat",
    "overhead", "schedule", "subordinates", "reads", "writes", "reports", "status", "local", "pre",
    "post", "plan", "continuous", "otherwise", "new", "done", "error", "report", "if", "then", "else",
    "elif", "and", "or", "not", "true", "false", "in", "cmd", "in_state", "std", "math", "lifecycle",
    "f64", "i32", "i64", "u32", "bool", "duration", "abs", "min", "max", "S1", "TB", "x", "E0",
    "period", "age", "stop", "freeze",
]
PUNCT = [
    "{", "}", "(", ")", "|", ";", ":", ",", ".", "..", "->", "=", "+=", "-=", "*=", "==", "!=", "<",
    "<=", ">", ">=", "+", "-", "*", "/", "%", "*", '"', '"a.rcs"', "//", "/*", "*/", "\n",
    "1", "0x1F", "1_000", "2.5", "1e3", "30 ms", "500 us", "2 s", "1.5 ms", "99999999999999999999",
]
LANG_CHARS = "abcdefxyzSTE0123456789_ {}()|;:,.-><=*/%+\"\n\t#@$!?\\'`~^&[]"


def _soup(tokens: list[str]) -> str:
    return " ".join(tokens)


TEXT_STRATEGY = st.one_of(
    st.text(max_size=300),  # any Unicode (no surrogates), NUL included
    st.text(alphabet=LANG_CHARS, max_size=400),
    st.lists(st.sampled_from(KEYWORDS + PUNCT), max_size=120).map(_soup),
    st.tuples(
        st.sampled_from(["design d\n", "module m\n", "design d\ncontroller C level 1 budget 1 ms {\n", ""]),
        st.lists(st.sampled_from(KEYWORDS + PUNCT), max_size=80).map(_soup),
    ).map("".join),
    st.binary(max_size=200),  # may or may not be UTF-8
)


@_settings(N_TEXT)
@given(TEXT_STRATEGY)
def test_fuzz_random_text(data):
    check_input("text", data)


def test_fuzz_random_text_count():
    # runs right after the family's own test: the family really ran its share
    if RUNS["text"] == 0:
        pytest.skip("test_fuzz_random_text did not run in this session")
    assert RUNS["text"] >= N_TEXT
    FAMILIES_DONE.add("text")


# ---------------------------------------------------------------------------
# (b) grammar-derived designs
# ---------------------------------------------------------------------------

class DesignGen:
    """Random designs built from the grammar's constructs (rcs.lark).

    Names come from small pools so that references sometimes resolve and
    sometimes do not; most output parses, and a small share is deliberately
    slightly off (a missing `;`, an unknown keyword) to reach the error paths
    of sema after a partial success elsewhere.
    """

    TYPE_NAMES = ["bool", "i32", "i64", "u32", "f64", "duration", "Mode", "Pt", "Phase", "Nope", "HMode"]
    VALUE_NAMES = ["x", "y", "speed", "K", "LIMIT", "count", "target", "hvar", "HK", "gm1", "gm2", "p", "q", "level", "done", "cmd", "in_state"]
    CTRL_NAMES = ["TOP", "MID", "TB", "LOW", "SIM", "PR", "X"]
    FN_NAMES = ["f", "g", "clamp", "lerp", "hscale", "ext", "abs", "min", "max", "f64", "i32", "u32", "i64", "Pt", "nothing", "sign_i32", "approx_eq"]
    VERB_NAMES = ["INIT", "HALT", "ABORT", "MOVE", "GO", "STOP"]
    STATE_NAMES = ["S1", "S2", "S3", "WAIT", "new", "done", "error"]
    ATTRS = ["done", "error", "executing", "error_code", "age", "AT_GOAL", "progress", "x", "y", "A", "IDLE", "RUN", "target", "nope", "ON"]
    STD = ["std.math", "std.lifecycle", "std.missing", "std.math.extra", "std", "std._x", "helper"]
    FILES = ["helper.rcs", "missing.rcs", "../outside.rcs", "/etc/hostname", "sub/broken.rcs", "sub/design2.rcs", "sub/../helper.rcs", "fuzz.rcs", "", "sub"]
    INTS = ["0", "1", "2", "3", "7", "10", "42", "0x2A", "1_000", "255", "2147483647", "2147483648", "4294967296", "9223372036854775808", "99999999999999999999999", "0x_", "0_0"]
    FLOATS = ["0.0", "1.0", "2.5", "0.5", "1e3", "2.5e-3", "1e308", "1e309", "1e-400", "3.0E+2", "0.1"]
    DURS = ["0 ms", "1 ms", "30 ms", "500 us", "2 s", "1.5 ms", "0.0001 us", "1e-9 s", "60 ms", "90 ms", "1 us", "99999999999 s", "0.5 us", "15 ms"]

    def __init__(self, seed: int) -> None:
        self.r = random.Random(seed)
        self.depth = 0

    # -- small helpers ---------------------------------------------------------

    def pick(self, seq):
        return self.r.choice(seq)

    def chance(self, p: float) -> bool:
        return self.r.random() < p

    def some(self, gen, lo: int, hi: int, sep: str = ", ") -> str:
        return sep.join(gen() for _ in range(self.r.randint(lo, hi)))

    def name(self) -> str:
        pool = self.pick([self.VALUE_NAMES, self.CTRL_NAMES, self.TYPE_NAMES, self.VERB_NAMES, self.STATE_NAMES])
        return self.pick(pool) if self.chance(0.95) else self.pick(["_", "a1", "Z_9", "otherwise", "plan", "verb", "if", "true"])

    def vname(self) -> str:
        return self.pick(self.VALUE_NAMES) if self.chance(0.9) else self.name()

    # -- types and literals ----------------------------------------------------

    def type_(self) -> str:
        t = self.pick(self.TYPE_NAMES)
        if self.chance(0.2):
            lo, hi = self.r.choice([("0", "10"), ("0.0", "30.0"), ("-5", "5"), ("10", "0"), ("0", "3000"), ("K", "LIMIT"), ("1 ms", "2 s"), ("Mode.A", "Mode.B"), ("-1.0", "x")])
            t += f" in {lo}..{hi}"
        return t

    def literal(self) -> str:
        k = self.r.randint(0, 5)
        if k <= 1:
            return self.pick(self.INTS)
        if k == 2:
            return self.pick(self.FLOATS)
        if k == 3:
            return self.pick(self.DURS)
        if k == 4:
            return self.pick(["true", "false"])
        return "(-" + self.pick(self.INTS + self.FLOATS) + ")"

    # -- expressions -------------------------------------------------------------

    def expr(self, max_depth: int = 3) -> str:
        """An expression that follows the grammar's precedence levels (so it
        parses), with random operators, names, calls and attributes."""
        if max_depth > 0 and self.chance(0.08):
            d = max_depth - 1
            return f"if {self.expr(d)} then {self.expr(d)} else {self.expr(d)}"
        return self.or_expr(max_depth)

    def _chain(self, item, ops: list[str], max_depth: int, p_more: float) -> str:
        out = item(max_depth)
        while max_depth > 0 and self.chance(p_more):
            out += f" {self.pick(ops)} {item(max_depth - 1)}"
            p_more /= 2
        return out

    def or_expr(self, d: int) -> str:
        return self._chain(self.and_expr, ["or"], d, 0.2)

    def and_expr(self, d: int) -> str:
        return self._chain(self.not_expr, ["and"], d, 0.25)

    def not_expr(self, d: int) -> str:
        if d > 0 and self.chance(0.1):
            return "not " + self.not_expr(d - 1)
        if self.chance(0.08):
            return f"in_state {self.pick(['>=', '>', '<', '=='])} {self.pick(self.DURS)}"
        left = self.sum_expr(d)
        if d > 0 and self.chance(0.35):
            return f"{left} {self.pick(['==', '!=', '<', '<=', '>', '>='])} {self.sum_expr(d - 1)}"
        return left

    def sum_expr(self, d: int) -> str:
        return self._chain(self.prod_expr, ["+", "-"], d, 0.3)

    def prod_expr(self, d: int) -> str:
        return self._chain(self.unary, ["*", "/", "%"], d, 0.25)

    def unary(self, d: int) -> str:
        if d > 0 and self.chance(0.1):
            return "-" + self.unary(d - 1)
        return self.postfix(d)

    def postfix(self, d: int) -> str:
        k = self.r.randint(0, 9)
        if d <= 0 or k <= 3:
            out = self.atom()
        elif k == 4:
            out = f"({self.expr(d - 1)})"
        elif k in (5, 6):
            out = self.call(d - 1)
        elif k == 7:
            out = f"{self.pick(self.CTRL_NAMES + ['cmd', 'Mode', 'Phase', 'p', 'HMode'])}.{self.pick(self.ATTRS)}"
        elif k == 8:
            out = f"cmd.{self.pick(['speed', 'x', 'target', 'n', 'mode', 'nope', 'rpm'])}"
        else:
            return f"(in_state {self.pick(['>=', '>', '<'])} {self.pick(self.DURS)})"
        while self.chance(0.08):
            out += f".{self.pick(self.ATTRS)}"
        return out

    def atom(self) -> str:
        k = self.r.randint(0, 4)
        if k <= 1:
            return self.literal()
        if k <= 3:
            return self.vname()
        return f"{self.pick(['Mode', 'Phase', 'HMode', 'Pt', 'x'])}.{self.pick(['A', 'B', 'C', 'IDLE', 'RUN', 'ON', 'x', 'nope'])}"

    def args(self, max_depth: int) -> str:
        def arg() -> str:
            if self.chance(0.4):
                return f"{self.pick(['x', 'y', 'a', 'b', 'rpm', 'target', 'n', 'lo', 'hi', 't'])} = {self.expr(max_depth)}"
            return self.expr(max_depth)

        return self.some(arg, 0, 4)

    def call(self, max_depth: int) -> str:
        return f"{self.pick(self.FN_NAMES)}({self.args(max_depth)})"

    # -- statements ----------------------------------------------------------------

    def lvalue(self) -> str:
        base = self.vname()
        return base if self.chance(0.85) else f"{base}.{self.pick(self.ATTRS)}"

    def stmt(self, depth: int = 2) -> str:
        k = self.r.randint(0, 5)
        if k <= 2:
            return f"{self.lvalue()} {self.pick(['=', '+=', '-=', '*='])} {self.expr(3)};"
        if k == 3:
            return f"{self.call(2)};"
        if depth <= 0:
            return f"{self.lvalue()} = {self.expr(2)};"
        out = f"if {self.expr(3)} {{ {self.some(lambda: self.stmt(depth - 1), 0, 3, ' ')} }}"
        for _ in range(self.r.randint(0, 2)):
            out += f" elif {self.expr(2)} {{ {self.some(lambda: self.stmt(depth - 1), 0, 2, ' ')} }}"
        if self.chance(0.5):
            out += f" else {{ {self.some(lambda: self.stmt(depth - 1), 0, 2, ' ')} }}"
        return out

    def job(self) -> str:
        k = self.r.randint(0, 5)
        if k <= 1:
            return f"{self.lvalue()} {self.pick(['=', '+=', '-=', '*='])} {self.expr(2)}"
        if k <= 3:
            return f"{self.pick(self.CTRL_NAMES)}.{self.pick(self.VERB_NAMES)}({self.args(2)})"
        if k == 4:
            return f"report {self.pick(['AT_GOAL', 'AT_LIMIT', 'DONE', 'nope'])}"
        return self.call(2)

    # -- plans ---------------------------------------------------------------------

    def rule(self, i: int) -> str:
        label = f"E{i}" if self.chance(0.85) else self.pick(["E0", "E1", "E9", "X"])
        guard = "otherwise" if self.chance(0.15) else self.expr(2)
        state = self.pick(["new", "new", "*", "S1", "S2", "S3", "WAIT", "done", "error"])
        nxt = self.pick(["S1", "S2", "S3", "WAIT", "done", "done", "*", "new"] + [f"error({self.expr(1)})"] * 2)
        out = f"{label}: {guard} | {state} -> {nxt}"
        if self.chance(0.7):
            out += " | " + self.some(self.job, 0 if self.chance(0.1) else 1, 3)
        return out + ";"

    def plan(self) -> str:
        mod = " continuous" if self.chance(0.2) else ""
        rules = "\n        ".join(self.rule(i) for i in range(self.r.randint(0, 11 if self.chance(0.1) else 4)))
        return f"plan {self.pick(self.VERB_NAMES)}{mod} {{\n        {rules}\n    }}"

    # -- controllers and other items -------------------------------------------------

    def params(self) -> str:
        return self.some(lambda: f"{self.pick(['x', 'y', 'a', 'b', 'rpm', 'target', 'n', 'lo', 'hi', 'x'])}: {self.type_()}", 0, 3)

    def verb(self) -> str:
        name = self.pick(self.VERB_NAMES)
        return f"verb {name}" if self.chance(0.4) else f"verb {name}({self.params()})"

    def ctrl_item(self) -> str:
        k = self.r.randint(0, 11)
        names = lambda pool: self.some(lambda: self.pick(pool), 1, 4)  # noqa: E731
        if k == 0:
            return f"subordinates {names(self.CTRL_NAMES)}"
        if k == 1:
            return f"reads {names(self.VALUE_NAMES)}"
        if k == 2:
            return f"writes {names(self.VALUE_NAMES)}"
        if k == 3:
            return self.verb()
        if k == 4:
            return f"verbs {self.pick(['Lifecycle', 'Basic', 'Mine', 'Nope'])}"
        if k == 5:
            return f"reports {names(['AT_GOAL', 'AT_LIMIT', 'DONE', 'EXEC', 'AT_GOAL'])}"
        if k == 6:
            return f"status {self.vname()}: {self.type_()} = {self.expr(2)}"
        if k == 7:
            return f"local {self.vname()}: {self.type_()} = {self.expr(2)}"
        if k == 8:
            return f"{self.pick(['pre', 'post'])} {{ {self.some(self.stmt, 0, 4, ' ')} }}"
        return self.plan()

    def controller(self) -> str:
        kind = "simulator" if self.chance(0.2) else "controller"
        attrs = []
        for _ in range(self.r.randint(0, 3)):
            attrs.append(
                f"level {self.pick(['0', '1', '2', '3', '4', '99999999999'])}" if self.chance(0.5)
                else f"{self.pick(['budget', 'budget', 'period'])} {self.pick(self.DURS)}"
            )
        body = "\n    ".join(self.ctrl_item() for _ in range(self.r.randint(0, 6)))
        return f"{kind} {self.pick(self.CTRL_NAMES)} {' '.join(attrs)} {{\n    {body}\n}}"

    def item(self) -> str:
        k = self.r.randint(0, 12)
        if k == 0:
            return f"const {self.vname()}: {self.type_()} = {self.expr(3)}"
        if k == 1:
            return f"enum {self.pick(['Mode', 'Phase', 'Pt', 'E'])} {{ {self.some(lambda: self.pick(['A', 'B', 'C', 'IDLE', 'RUN', 'A']), 0, 4)} }}"
        if k == 2:
            return f"record {self.pick(['Pt', 'Mode', 'R'])} {{ {self.some(lambda: self.pick(['x', 'y', 'z', 'x']) + ': ' + self.type_(), 0, 3)} }}"
        if k == 3:
            init = f" = {self.expr(2)}" if self.chance(0.85) else ""
            env = " from env" if self.chance(0.3) else ""
            return f"gm {self.vname()}: {self.type_()}{init}{env}"
        if k == 4:
            return f"fn {self.pick(self.FN_NAMES)}({self.params()}) -> {self.type_()} = {self.expr(4)}"
        if k == 5:
            return f"extern fn {self.pick(self.FN_NAMES)}({self.params()}) -> {self.type_()} budget {self.pick(self.DURS)}"
        if k == 6:
            return f"verbset {self.pick(['Mine', 'Lifecycle', 'Basic'])} {{ {self.some(self.verb, 0, 3, ' ')} }}"
        if k in (7, 8, 9, 10):
            return self.controller()
        if k == 11:
            items = [f"heartbeat {self.pick(self.DURS)}", f"overhead {self.pick(self.DURS)}", f"schedule {self.some(lambda: self.pick(self.CTRL_NAMES), 1, 5)}"]
            chosen = [self.pick(items) for _ in range(self.r.randint(0, 4))]
            return f"cpu {self.pick(['main', 'CPU2', 'TOP'])} {{ {' '.join(chosen)} }}"
        return self.import_()

    def import_(self) -> str:
        if self.chance(0.5):
            return f"import {self.pick(self.STD)}"
        return f'import "{self.pick(self.FILES)}"'

    # -- coherent designs: declared names are mostly the ones used -------------------

    def coherent(self) -> str:
        """A design whose controllers, GM variables, verbs and subordinates are\n        mostly consistent, so that the plan, ownership, hierarchy and timing\n        checks see plausible models (and the odd inconsistency)."""
        r = self.r
        n = r.randint(1, 4)
        ctrls = r.sample(self.CTRL_NAMES, n)
        level = {c: 0 for c in ctrls}
        subs: dict[str, list[str]] = {c: [] for c in ctrls}
        for i, c in enumerate(ctrls[1:], 1):
            boss = ctrls[r.randrange(i)] if self.chance(0.9) else r.choice(ctrls)
            if boss != c or self.chance(0.3):
                subs[boss].append(c)
        for c in reversed(ctrls):  # levels from the leaves up (a few wrong on purpose)
            level[c] = 1 + max([level[s] for s in subs[c] if s != c] or [0])
            if self.chance(0.05):
                level[c] = r.randint(0, 3)
        gms = {f"g{k}": r.choice(["f64", "i32", "bool", "f64 in 0.0..100.0", "Mode"]) for k in range(r.randint(0, 5))}
        writer = {g: (r.choice(ctrls) if self.chance(0.85) else None) for g in gms}
        verbs = {c: r.sample(["INIT", "HALT", "MOVE", "GO", "STOP"], r.randint(1, 3)) for c in ctrls}
        params = {v: r.choice(["", "(x: f64)", "(x: f64, n: i32)", "(m: Mode)"]) for v in ["INIT", "HALT", "MOVE", "GO", "STOP"]}
        init = {"f64": "0.0", "i32": "0", "bool": "false", "f64 in 0.0..100.0": "50.0", "Mode": "Mode.A"}
        out = ["design coherent\n"]
        if self.chance(0.25):
            out.append("import std.math\n")
        if self.chance(0.25):
            out.append("import std.lifecycle\n")
        out.append("enum Mode { A, B, C }\nrecord Pt { x: f64, y: f64 }\nconst K: f64 = 2.0\nconst N: i32 = 3\n")
        if self.chance(0.5):
            out.append(f"fn f(a: f64) -> f64 = {self.num(2, ['a'])}\n")
        for g, t in gms.items():
            env = " from env" if writer[g] is None and self.chance(0.8) else ""
            out.append(f"gm {g}: {t} = {init[t]}{env}\n")
        for c in ctrls:
            kind = "simulator" if self.chance(0.1) else "controller"
            mine = [g for g in gms if writer[g] == c]
            seen = [g for g in gms if g not in mine and self.chance(0.5)]
            numeric = [g for g in mine + seen if gms[g].startswith(("f64", "i32"))]
            body = []
            if subs[c]:
                body.append(f"subordinates {', '.join(subs[c])}")
            if seen:
                body.append(f"reads {', '.join(seen)}")
            if mine:
                body.append(f"writes {', '.join(mine)}")
            for v in verbs[c]:
                body.append(f"verb {v}{params[v]}")
            if self.chance(0.3):
                body.append("reports AT_GOAL")
            body.append(f"local t: f64 = {self.pick(['0.0', '1.5', '-1'])}")
            body.append("status progress: f64 = 0.0")
            if self.chance(0.4):
                fvars = [g for g in mine if gms[g].startswith("f64")] + ["t", "progress"]
                body.append(f"pre {{ {self.pick(fvars)} = {self.num(2, numeric + ['t'])}; }}")
            for v in verbs[c] if self.chance(0.9) else verbs[c][:-1]:
                body.append(self.coherent_plan(v, params[v], subs[c], verbs, numeric, [g for g in mine if gms[g].startswith("f64")]))
            budget = self.pick(["1 ms", "2 ms", "500 us", "10 ms"])
            # Divided rates, sometimes not a whole number of heartbeats (E0607).
            period = f" period {self.pick(['20 ms', '30 ms', '60 ms', '90 ms'])}" if self.chance(0.2) else ""
            out.append(f"{kind} {c} level {level[c]} budget {budget}{period} {{\n    " + "\n    ".join(body) + "\n}\n")
        cpus = r.randint(1, 2)
        groups: list[list[str]] = [[] for _ in range(cpus)]
        for c in ctrls:
            if self.chance(0.95):
                groups[r.randrange(cpus)].append(c)
        for k, g in enumerate(groups):
            hb = self.pick(["30 ms", "10 ms", "20 ms", "15 ms", "1 ms"])
            sched = f" schedule {', '.join(g)}" if g else ""
            out.append(f"cpu cpu{k} {{ heartbeat {hb}{' overhead 1 ms' if self.chance(0.5) else ''}{sched} }}\n")
        return "".join(out)

    def num(self, d: int, names: list[str]) -> str:
        """An f64-ish expression over `names`."""
        if d <= 0 or self.chance(0.3):
            return self.pick(names + ["1.0", "K", "0.5", "2", "cmd.x"]) if names else self.pick(["1.0", "K", "0.5"])
        k = self.r.randint(0, 4)
        if k == 0:
            return f"{self.num(d - 1, names)} {self.pick(['+', '-', '*', '/'])} {self.num(d - 1, names)}"
        if k == 1:
            return f"clamp({self.num(d - 1, names)}, 0.0, {self.num(d - 1, names)})"
        if k == 2:
            return f"f64({self.pick(['N', '1', 'cmd.n'])})"
        if k == 3:
            return f"({self.num(d - 1, names)})"
        return f"min({self.num(d - 1, names)}, {self.num(d - 1, names)})"

    def cond(self, subs: list[str], numeric: list[str]) -> str:
        k = self.r.randint(0, 6)
        if subs and k <= 2:
            s = self.pick(subs)
            return f"{s}.{self.pick(['done', 'done', 'error', 'executing', 'AT_GOAL', 'progress > 0.5', 'error_code != 0', 'age > 60 ms'])}"
        if k == 3:
            return f"in_state >= {self.pick(['30 ms', '60 ms', '45 ms', '2 s', '1 ms'])}"
        if k == 4:
            return self.pick(["true", "false", "cmd.m == Mode.B", "not (t > 1.0)"])
        if k == 5 and self.chance(0.5):
            return f"{self.cond(subs, numeric)} {self.pick(['and', 'or'])} {self.cond(subs, numeric)}"
        return f"{self.num(2, numeric + ['t'])} {self.pick(['<', '>=', '==', '!='])} {self.num(1, numeric + ['t'])}"

    def coherent_plan(self, verb: str, params: str, subs: list[str], verbs: dict, numeric: list[str], fwrites: list[str]) -> str:
        r = self.r
        states = ["S1", "S2", "S3"][: r.randint(1, 3)]
        rules = []
        for i in range(r.randint(1, 11 if self.chance(0.1) else 5)):
            src = self.pick(["new"] * 2 + states + ["*"]) if i else "new"
            if self.chance(0.8) and src != "*":
                nxt = self.pick(states + ["done", "done", "*"] + ([f"error({r.randint(0, 9)})"]))
            else:
                nxt = f"error({self.pick(['1', '2', 'N', '1.5', '-1'])})"
            guard = "otherwise" if self.chance(0.1) else self.cond(subs, numeric)
            jobs = []
            for _ in range(r.randint(0, 3)):
                k = r.randint(0, 3)
                if subs and k <= 1:
                    s = self.pick(subs)
                    v = self.pick(verbs.get(s, ["INIT"]))
                    jobs.append(f"{s}.{v}({self.pick(['', 'x = 1.0', '1.0', 'x = t, n = 2', 'm = Mode.C', 'cmd.x'])})")
                elif k == 2:
                    jobs.append(f"{self.pick(fwrites + ['t', 'progress'])} {self.pick(['=', '+='])} {self.num(2, numeric + ['t'])}")
                else:
                    jobs.append(self.pick(["report AT_GOAL", "t = 0.0", "progress = 1.0"]))
            tail = f" | {', '.join(jobs)}" if jobs else ""
            rules.append(f"E{i}: {guard} | {src} -> {nxt}{tail};")
        mod = " continuous" if self.chance(0.15) else ""
        return f"plan {verb}{mod} {{\n        " + "\n        ".join(rules) + "\n    }"

    def design(self) -> str:
        if self.chance(0.35):
            return self.coherent()
        header = self.r.choices(["design fuzz\n", "module fuzz.mod\n", "", "design level\n"], weights=[85, 5, 5, 5])[0]
        parts = [header]
        for _ in range(self.r.randint(0, 2)):
            parts.append(self.import_() + "\n")
        for _ in range(self.r.randint(0, 7)):
            parts.append(self.item() + "\n")
        if self.chance(0.7):  # most designs get a plausible CPU, so the timing checks run
            parts.append(f"cpu main {{ heartbeat 30 ms overhead 1 ms schedule {', '.join(self.r.sample(self.CTRL_NAMES, 3))} }}\n")
        text = "".join(parts)
        if self.chance(0.08):  # a small slip somewhere
            pos = self.r.randint(0, len(text))
            text = text[:pos] + self.pick([";", "", "}", "{", "|", " foo ", "\n//", "/*"]) + text[pos:]
        return text


def grammar_input(seed: int) -> str:
    return DesignGen(seed).design()


@_settings(N_GRAMMAR)
@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_fuzz_grammar_designs(seed):
    check_input("grammar", grammar_input(seed), describe=f"seed={seed}")


def test_fuzz_grammar_designs_count():
    if RUNS["grammar"] == 0:
        pytest.skip("test_fuzz_grammar_designs did not run in this session")
    assert RUNS["grammar"] >= N_GRAMMAR
    FAMILIES_DONE.add("grammar")


def test_grammar_generator_reaches_sema():
    """The generator is worth its time only if much of its output parses, and
    the checker then finds semantic errors (not only syntax errors)."""
    from rcsc.diagnostics import Diagnostics
    from rcsc.front.parse import text_to_ast
    from rcsc.front.source import SourceFile

    parsed = 0
    for seed in range(200):
        try:
            tree = text_to_ast(SourceFile("g.rcs", grammar_input(seed)), Diagnostics())
        except Exception:  # noqa: BLE001 - crashes are test_fuzz_grammar_designs' business
            continue
        parsed += tree is not None
    assert parsed >= 100, f"only {parsed}/200 generated designs parse"


# ---------------------------------------------------------------------------
# (c) mutated example and standard-library files
# ---------------------------------------------------------------------------

def corpus_files() -> list[Path]:
    files = sorted(ROOT.glob("examples/**/*.rcs")) + sorted(ROOT.glob("stdlib/std/*.rcs"))
    return [f for f in files if f.is_file()]


_TOKEN_RE = re.compile(
    r"//[^\n]*|/\*.*?\*/|\"[^\"\n]*\"|[0-9][0-9_]*(?:\.[0-9_]+)?(?:[eE][+-]?[0-9]+)?|0x[0-9A-Fa-f_]+"
    r"|[A-Za-z_][A-Za-z0-9_]*|->|\.\.|[=!<>+\-*]=|\s+|.",
    re.S,
)
FLIPS = {
    "<": "<=", "<=": ">", ">": ">=", ">=": "<", "==": "!=", "!=": "==", "and": "or", "or": "and",
    "+": "-", "-": "+", "/": "%", "%": "*", "->": "|", "|": "->", "done": "error(1)",
    "new": "*", "*": "new", "true": "false", "false": "true", "=": "==", "+=": "-=", "{": "(", "}": ")",
    "(": "{", ")": "}", "ms": "us", "us": "s", "s": "ms", "f64": "i32", "i32": "u32", "u32": "f64",
    "controller": "simulator", "simulator": "controller", ",": ";", ";": ",", ".": "..", "..": ".",
}
EXTREMES = ["0", "-1", "2147483648", "1e309", "0x", "99999999999999999999", "0.0", "1e-12", "4294967296", "1_"]


def mutate(text: str, seed: int) -> str:
    """1-4 random mutations of `text` (tokens, lines or a truncation)."""
    r = random.Random(seed)
    for _ in range(r.randint(1, 4)):
        toks = _TOKEN_RE.findall(text)
        idx = [i for i, t in enumerate(toks) if not t.isspace()]
        if not idx:
            return text + r.choice(PUNCT)
        names = sorted({t for t in toks if re.fullmatch(r"[A-Za-z_]\w*", t)}) or ["x"]
        op = r.randint(0, 11)
        i = r.choice(idx)
        if op == 0:  # delete a token
            toks[i] = ""
        elif op == 1:  # duplicate a token
            toks[i] = toks[i] + " " + toks[i]
        elif op == 2:  # swap two tokens
            j = r.choice(idx)
            toks[i], toks[j] = toks[j], toks[i]
        elif op in (3, 4):  # replace a name by another name of the file (or the pool)
            named = [k for k in idx if re.fullmatch(r"[A-Za-z_]\w*", toks[k])]
            if named:
                k = r.choice(named)
                toks[k] = r.choice(names) if r.random() < 0.8 else r.choice(KEYWORDS)
        elif op == 5:  # flip an operator / keyword
            flippable = [k for k in idx if toks[k] in FLIPS]
            if flippable:
                k = r.choice(flippable)
                toks[k] = FLIPS[toks[k]]
        elif op == 6:  # extreme number
            nums = [k for k in idx if toks[k][:1].isdigit()]
            if nums:
                toks[r.choice(nums)] = r.choice(EXTREMES)
        elif op == 7:  # insert a random token
            toks[i] = r.choice(KEYWORDS + PUNCT) + " " + toks[i]
        if op <= 7:
            text = "".join(toks)
            continue
        # A line ends at LF, CRLF or a lone CR; a byte-order mark is not text.
        lines = re.sub("\r(?!\n)", "\n", text.removeprefix("\ufeff")).split("\n")
        a, b = r.randrange(len(lines)), r.randrange(len(lines))
        if op == 8:  # delete lines
            del lines[a:a + r.randint(1, 3)]
        elif op == 9:  # duplicate a line
            lines.insert(b, lines[a])
        elif op == 10:  # swap two lines
            lines[a], lines[b] = lines[b], lines[a]
        else:  # truncate
            text = text[: r.randint(0, len(text))]
            continue
        text = "\n".join(lines)
    return text


_CORPUS: dict[str, str] = {}


def _corpus_text(path: Path) -> str:
    key = str(path)
    if key not in _CORPUS:
        text = path.read_text(encoding="utf-8")
        if "stdlib" in path.parts and not text.lstrip().startswith("design"):
            # a stdlib module becomes a design (the root must be one); the rest is unchanged
            text = re.sub(r"^module [\w.]+", "design mutated", text, count=1, flags=re.M)
        _CORPUS[key] = text
    return _CORPUS[key]


def test_corpus_is_present():
    files = corpus_files()
    assert any("stdlib" in f.parts for f in files), files


@_settings(N_MUTATE)
@given(st.integers(min_value=0, max_value=10**6), st.integers(min_value=0, max_value=2**32 - 1))
def test_fuzz_mutated_files(which, seed):
    files = corpus_files()
    path = files[which % len(files)]
    rel = path.relative_to(ROOT)
    check_input("mutate", mutate(_corpus_text(path), seed), describe=f"file={rel} seed={seed}")


def test_fuzz_mutated_files_count():
    if RUNS["mutate"] == 0:
        pytest.skip("test_fuzz_mutated_files did not run in this session")
    assert RUNS["mutate"] >= N_MUTATE
    FAMILIES_DONE.add("mutate")


@pytest.mark.parametrize("path", corpus_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_unmutated_corpus_files(path):
    """Every corpus file itself goes through the same invariants."""
    check_input("mutate", _corpus_text(path), describe=f"file={path.relative_to(ROOT)} unmutated")


# ---------------------------------------------------------------------------
# known deep-nesting inputs (explicit, so that one crash does not hide the
# families' other findings)
# ---------------------------------------------------------------------------

DEEP = {
    "sum-chain-600": "design d\nconst K: i32 = " + " + ".join(["1"] * 600) + "\n",
    "and-chain-600": "design d\nconst K: bool = " + " and ".join(["true"] * 600) + "\n",
    "negation-600": "design d\nconst K: i32 = " + "-" * 600 + "1\n",
    "not-600": "design d\nconst K: bool = " + "not " * 600 + "true\n",
    "parens-600": "design d\nconst K: i32 = " + "(" * 600 + "1" + ")" * 600 + "\n",
    "if-chain-300": "design d\nconst K: i32 = " + "if true then 1 else " * 300 + "0\n",
    "elif-chain-400": "design d\ncontroller C level 1 budget 1 ms {\n local x: i32 = 0\n pre { if x > 0 { x = 1; }"
    + " elif x > 1 { x = 2; }" * 400 + " }\n}\ncpu m { heartbeat 10 ms schedule C }\n",
    "nested-if-300": "design d\ncontroller C level 1 budget 1 ms {\n local x: i32 = 0\n pre { "
    + "if x > 0 { " * 300 + "x = 1;" + " }" * 300 + " }\n}\ncpu m { heartbeat 10 ms schedule C }\n",
}


@pytest.mark.parametrize("name", sorted(DEEP))
def test_deep_nesting(name):
    check_input("text", DEEP[name], describe=name)


def test_zz_total_inputs():
    """At least MIN_RUNS generated inputs ran (when the three families ran)."""
    if FAMILIES_DONE != {"text", "grammar", "mutate"}:
        pytest.skip(f"only {sorted(FAMILIES_DONE)} ran in this session")
    total = sum(RUNS.values())
    assert total >= MIN_RUNS, f"{total} inputs ({RUNS}), expected at least {MIN_RUNS}"


if __name__ == "__main__":  # reproduce one input: python tests/test_fuzz.py grammar SEED | mutate SEED FILE
    kind, seed = sys.argv[1], int(sys.argv[2])
    if kind == "grammar":
        sys.stdout.write(grammar_input(seed))
    else:
        sys.stdout.write(mutate(_corpus_text(ROOT / sys.argv[3]), seed))
