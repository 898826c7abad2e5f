"""Generated code that cannot silently differ from the checked design: literals,
comments, empty things.

- tests/edge/edge.rcs and tests/bare/bare.rcs are in the conformance list
  (c_build.CONFORMANCE: every C configuration and both Rust profiles give
  `rcsc sim`'s trace byte for byte; clippy and rustfmt are clean on their
  crates).  Here their scenarios' expectations are checked in the simulator, so
  the traces the targets must equal are the intended ones.
- Every integer literal has its exact type in both targets: in C the literal
  of each type is checked with `_Generic` (C11, compiled by gcc and clang);
  in Rust each carries its type suffix.
- The comment sanitisers: whatever the design text, the result is one line of
  printable ASCII that cannot end the comment, open a nested one, form a
  trigraph or splice lines; a design file whose name holds such characters
  builds clean in both targets.
"""

from __future__ import annotations

import contextlib
import io
import shutil
import subprocess
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from c_build import ROOT, compile_c, generate, reference_trace, run_main
from rcsc import cli
from rcsc.backends.c.target import CTarget, c_comment
from rcsc.backends.rust.target import RustTarget, rust_comment
from rcsc.driver import check_path
from rcsc.semantics.types import DURATION, I32, I64, U32

EDGE = ROOT / "tests/edge/edge.rcs"
NASTY = [
    'c /* a note */ and l',
    "x */ y",
    "a /*/ b",
    "// a line comment \\\n next line",
    "ends with a backslash \\",
    "??/ ??= ??( ??) ??! ??< ??> ??- ??' ???/",
    "30 \u00b0C \u00fc",
    "\u202e reversed \u2066 isolate \u200f",
    "tab\there\r\ncrlf\x0cform feed\x00nul\x7fdel",
    "`code` /// doc //! inner",
    "",
]


def test_edge_scenarios_meet_their_expectations() -> None:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()) as out, contextlib.redirect_stderr(err):
        rc = cli.main(["test", str(ROOT / "tests/edge"), str(ROOT / "tests/bare")])
    assert rc == 0, out.getvalue() + err.getvalue()
    assert "2 passed, 0 failed" in out.getvalue()


# ---- literals -------------------------------------------------------------------------------

INT_CASES = [
    (I32, [0, 1, -1, 2147483647, -2147483647, -2147483648]),
    (U32, [0, 1, 2147483648, 4294967295]),
    (I64, [0, -1, 2147483648, -3000000000, 9223372036854775807, -9223372036854775808]),
    (DURATION, [0, 1000, 3000000000, -9223372036854775808]),
]
C_TYPE = {"i32": "int32_t", "u32": "uint32_t", "i64": "int64_t", "duration": "int64_t"}


@pytest.mark.parametrize("cc", ["gcc", "clang"])
def test_c_integer_literals_have_their_exact_type_and_value(tmp_path: Path, cc: str) -> None:
    design = check_path(str(EDGE)).model
    assert design is not None
    tg = CTarget(design)
    lines = ["#include <inttypes.h>", "#include <stdio.h>", "int main(void)", "{"]
    expected = []
    for t, values in INT_CASES:
        for v in values:
            lit, ctype = tg.literal(v, t), C_TYPE[t.name]
            lines.append(f'    _Static_assert(_Generic({lit}, {ctype}: 1, default: 0), "{lit} is not {ctype}");')
            lines.append(f'    printf("%lld\\n", (long long){lit});')
            expected.append(str(v))
    lines += ["    return 0;", "}"]
    src = tmp_path / "lits.c"
    src.write_text("\n".join(lines) + "\n", encoding="utf-8")
    exe = tmp_path / "lits"
    proc = subprocess.run([cc, "-std=c11", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Werror", "-o", str(exe), str(src)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    assert out.split() == expected


def test_rust_literals_carry_their_type() -> None:
    design = check_path(str(EDGE)).model
    assert design is not None
    tg = RustTarget(design)
    for t, values in INT_CASES:
        name = "i64" if t == DURATION else t.name
        for v in values:
            text = tg.literal(v, t).flat()
            assert text == f"{name}::MIN" if v == (I64.min if name == "i64" else I32.min) else text == f"{v}_{name}", text
    for x, text in ((0.5, "0.5_f64"), (-0.0, "-0.0_f64"), (1e300, "1e+300_f64"), (5e-324, "5e-324_f64"), (3.0, "3.0_f64")):
        assert tg.literal(x, design.consts["TINY"].type).flat() == text


def test_generated_rust_has_no_unsuffixed_design_literal(tmp_path: Path) -> None:
    """In the edge crate every number the design wrote carries its suffix."""
    import re

    generate(EDGE, "rust", tmp_path)
    text = (tmp_path / "src/ctrl_TOP.rs").read_text(encoding="utf-8")
    for lit in ("3000000000", "4294967295", "2147483648", "4000000000", "4294967296"):
        found = re.findall(rf"\b{lit}(?:_\w+)?\b", text)
        assert found and all(f.endswith(("_i64", "_u32")) for f in found), (lit, found)


# ---- comments -------------------------------------------------------------------------------


def _c_safe(text: str) -> None:
    assert all(" " <= ch <= "~" for ch in text), repr(text)
    for bad in ("/*", "*/", "??", "\\"):
        assert bad not in text, (bad, text)


def _rust_safe(text: str) -> None:
    assert all(" " <= ch <= "~" for ch in text), repr(text)
    for bad in ("/*", "*/", "`"):
        assert bad not in text, (bad, text)


@pytest.mark.parametrize("text", NASTY)
def test_comment_sanitisers_on_known_troublemakers(text: str) -> None:
    _c_safe(c_comment(text))
    _rust_safe(rust_comment(text))
    assert c_comment("c /* a note */ and l") == "c / * a note * / and l"
    assert rust_comment("x > 1 // why\n   and y") == "x > 1 // why and y"


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet=st.characters(codec="utf-8") | st.sampled_from(list("/*?\\`\n\r\t !=()<>-'")), max_size=40))
def test_comment_sanitisers_on_any_text(text: str) -> None:
    _c_safe(c_comment(text))
    _rust_safe(rust_comment(text))
    # Sanitising is idempotent: a safe text stays as it is.
    assert c_comment(c_comment(text)) == c_comment(text)
    assert rust_comment(rust_comment(text)) == rust_comment(text)


def test_a_design_file_name_with_odd_characters_builds_clean(tmp_path: Path) -> None:
    """The file name reaches every `file.rcs:LINE` comment; it can hold anything but `/`."""
    folder = tmp_path / "odd"
    folder.mkdir()
    design = folder / "e\u00b0 ??) *\\\n`x`.rcs"
    shutil.copy(EDGE, design)
    scn = ROOT / "tests/edge/edge.scn"
    c_out = tmp_path / "c"
    generate(design, "c", c_out)
    for cc in ("gcc", "clang"):
        exe = tmp_path / f"odd-{cc}"
        compile_c(c_out, cc, ["-O0"], exe)
        trace = tmp_path / f"{cc}.jsonl"
        assert run_main(exe, design, scn, trace).returncode == 0
        assert trace.read_bytes() == reference_trace(EDGE, scn)
    rust_out = tmp_path / "rust"
    generate(design, "rust", rust_out)
    files = sorted(str(p) for p in rust_out.rglob("*.rs"))
    proc = subprocess.run(["rustfmt", "--check", "--edition", "2021", *files], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    for p in list(c_out.iterdir()) + [Path(f) for f in files]:
        text = p.read_text(encoding="utf-8")
        assert text.isascii(), p.name
    assert "(e? ? ?) *? `x`.rcs:" in (c_out / "edge_TOP.c").read_text(encoding="utf-8")
    assert "(e? ??) *\\ 'x'.rcs:" in (rust_out / "src/ctrl_TOP.rs").read_text(encoding="utf-8")
