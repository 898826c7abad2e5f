"""The math built-ins, `cycle` and `///` doc comments.

tests/mathfn (in c_build.CONFORMANCE) is their conformance design: every
built-in at its edges in the simulator, C (every configuration) and Rust,
trace byte for byte.  Here: the reference definitions at their edges, the
targets' integer sqrt algorithm (as numeric.sqrt_bits) against math.sqrt,
and doc comments in both parsers, in the model and in generated comments.
"""

from __future__ import annotations

import math
import random

from rcsc.diagnostics import Diagnostics
from rcsc.front.parse import text_to_ast, text_to_ast_lark
from rcsc.front.source import SourceFile
from rcsc.semantics import numeric as n


def bits(x: float) -> int:
    return n.f64_bits(x)


def test_edges_of_every_builtin() -> None:
    assert bits(n.f64_sqrt(-0.0)) == bits(-0.0) and math.isnan(n.f64_sqrt(-1.0)) and n.f64_sqrt(math.inf) == math.inf
    assert bits(n.f64_ceil(-0.5)) == bits(-0.0) and bits(n.f64_trunc(-0.5)) == bits(-0.0) and bits(n.f64_floor(0.5)) == bits(0.0)
    assert [n.f64_round_even(x) for x in (0.5, 1.5, 2.5, -2.5, -3.5, 0.49999999999999994)] == [0.0, 2.0, 2.0, -2.0, -4.0, 0.0]
    assert bits(n.f64_round_even(-0.5)) == bits(-0.0)
    assert n.f64_round_even(4503599627370495.5) == 4503599627370496.0 and n.f64_floor(1e300) == 1e300
    for f in (n.f64_floor, n.f64_ceil, n.f64_trunc, n.f64_round_even):
        assert f(math.inf) == math.inf and f(-math.inf) == -math.inf and math.isnan(f(math.nan))
    assert n.f64_copysign(1.5, -0.0) == -1.5 and n.f64_copysign(-1.5, math.nan) == 1.5
    for a, b in ((-0.0, 0.0), (0.0, -0.0)):
        assert bits(n.f64_min(a, b)) == bits(-0.0) and bits(n.f64_max(a, b)) == bits(0.0)
    assert math.isnan(n.f64_min(math.nan, 1.0)) and math.isnan(n.f64_max(1.0, math.nan))


def test_the_targets_sqrt_algorithm_is_correctly_rounded() -> None:
    rng = random.Random(19)
    values = [5e-324, 1e-310, 2.2250738585072014e-308, 1.7976931348623157e308, 2.0, 3.0, 0.5]
    values += [n.f64_from_bits(rng.getrandbits(63)) for _ in range(20000)]
    for x in values:
        if not math.isnan(x):
            assert bits(n.sqrt_bits(x)) == bits(math.sqrt(x)), x


DOCS = """design d
/// The top.
/// Second line.
controller A level 1 budget 1 ms {
    /// A verb.
    verb GO
    /// A field.
    status s: i32 = 0
    //// not a doc comment
    plan GO {
        /// The only rule. */ /* tries to break out
        R: true | new -> done;
    }
    /// documents nothing
    pre { s = 1; }
}
cpu C { heartbeat 10 ms
 schedule A }
"""


def test_doc_comments_are_the_same_in_both_parsers_and_documents_nothing_is_w0240() -> None:
    src = SourceFile("d.rcs", DOCS)
    d1, d2 = Diagnostics(), Diagnostics()
    fast, ref = text_to_ast(src, d1), text_to_ast_lark(src, d2)
    assert fast == ref
    ctrl = fast.items[0]
    assert ctrl.doc.text == "The top.\nSecond line." and ctrl.doc.span.text.startswith("/// The top.")
    assert ctrl.verbs[0].doc.text == "A verb." and ctrl.status_fields[0].doc.text == "A field."
    assert ctrl.plans[0].doc is None  # `////` is a plain comment
    assert ctrl.plans[0].rules[0].doc.text == "The only rule. */ /* tries to break out"
    for d in (d1, d2):
        codes = [x.code for x in d]
        assert codes == ["W0240"], codes


TYPED_DOCS = """design d
gm a: f64 = 0.0 to env
gm b: f64 = 0.0 to env
/// One output.
controller type T(out: gm) level 1 budget 1 ms {
    writes out
    /// Its verb.
    verb GO
    block k: B(g = 2.0)
    post { k(x = 1.0); out = k.y; }
    plan GO { R: true | new -> done; }
}
/// The first.
controller X: T(out = a)
controller Y: T(out = b)
/// Scales its input.
block B(g: f64) {
    /// What comes in.
    input x: f64 = 0.0
    /// What goes out.
    output y: f64 = 0.0
    step { y = g * x; }
}
controller TOP level 2 budget 1 ms { subordinates X, Y }
cpu C { heartbeat 10 ms
 schedule TOP, X, Y }
"""


def test_doc_comments_on_controller_types_instances_and_blocks(tmp_path) -> None:
    """`///` before a controller type, an instance, a block and its members
    documents them (it was W0240 "documents nothing"): an instance shows its
    own text, or else its type's, and a block's members reach the fields."""
    from rcsc.driver import check_path

    src = SourceFile("d.rcs", TYPED_DOCS)
    d1, d2 = Diagnostics(), Diagnostics()
    assert text_to_ast(src, d1) == text_to_ast_lark(src, d2)
    assert [x.code for x in d1] == [] and [x.code for x in d2] == []
    (tmp_path / "d.rcs").write_text(TYPED_DOCS)
    result = check_path(str(tmp_path / "d.rcs"))
    assert "W0240" not in {x.code for x in result.diags}
    ctrls = result.model.controllers
    assert ctrls["X"].doc == "The first." and ctrls["Y"].doc == "One output."
    assert ctrls["Y"].verbs["GO"].doc == "Its verb."
    assert ctrls["X"].status_fields["k__y"].doc == "What goes out." and ctrls["X"].locals["k__x"].doc == "What comes in."
    from rcsc.editor import symbols

    idx = symbols.build([text_to_ast(src, Diagnostics())])
    assert symbols.hover_text(idx.controllers["X"]).endswith("\n\nThe first.")
    assert symbols.hover_text(idx.controllers["Y"]).endswith("\n\nOne output.")


def test_doc_comments_reach_the_generated_code_sanitised(tmp_path) -> None:
    from c_build import ROOT, generate

    design = ROOT / "tests/mathfn/mathfn.rcs"
    generate(design, "c", tmp_path / "c")
    generate(design, "rust", tmp_path / "rs")
    c_text = "\n".join(p.read_text() for p in (tmp_path / "c").glob("*.[ch]"))
    rs_text = "\n".join(p.read_text() for p in (tmp_path / "rs" / "src").glob("*.rs"))
    assert "Every built-in of `x`, * / / * a doc comment" in c_text and "Done at once. * /" in c_text
    assert "//! Every built-in of 'x'," in rs_text and "// Done at once. * /" in rs_text
    for line in c_text.splitlines():
        if "Done at once" in line or "a doc comment that tries" in line:
            assert line.count("*/") <= 1 and "\\" not in line and line.isascii()


def test_doc_comments_in_hover_and_in_rcsc_doc() -> None:
    from rcsc.driver import check_path
    from rcsc.editor import symbols
    from rcsc.outputs.doc import render_html

    src = SourceFile("d.rcs", DOCS)
    idx = symbols.build([text_to_ast(src, Diagnostics())])
    assert symbols.hover_text(idx.controllers["A"]).endswith("\n\nThe top.\nSecond line.")
    verb = idx.members["A"]["GO"]
    assert symbols.hover_text(verb).endswith("A verb.")

    from c_build import ROOT

    result = check_path(str(ROOT / "tests/mathfn/mathfn.rcs"))
    assert result.model is not None
    html = render_html(result.model, list(result.diags))
    assert '<p class="doc">Steps every third cycle of its CPU.' in html
    assert "Done at once. */ // \\ ??/ newline follows" in html  # autoescaped text, nothing to escape here
    assert "<span class=\"doc\">Done at once." in html


def test_cycle_is_not_available_outside_controllers_and_builtins_are_reserved(tmp_path) -> None:
    from rcsc.driver import check_path

    def codes(text: str, name: str) -> list[str]:
        (tmp_path / name).write_text(text)
        return [d.code for d in check_path(str(tmp_path / name)).diags]

    assert "E0100" in codes("design d\nfn f(x: i64) -> i64 = x + cycle\ncpu C { heartbeat 10 ms }\n", "f.rcs")
    assert "E0101" in codes("design d\nfn sqrt(x: f64) -> f64 = x\ncpu C { heartbeat 10 ms }\n", "g.rcs")
    assert "E0101" in codes("design d\nconst cycle: i32 = 1\ncpu C { heartbeat 10 ms }\n", "h.rcs")
