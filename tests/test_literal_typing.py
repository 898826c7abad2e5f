"""The typing of integer literals is one rule, the same on either side of an operator.

An expression made of integer literals only (`5`, `5 + 1`, `abs(5)`,
`max(5, 1)`, `if c then 5 else 1`, `-(2 * 3)`) has no type of its own: it
takes the type of the other operand (docs/language.md section 4).  So
`5 + 1 < A`, `A > 5 + 1` and `abs(5) == A` are accepted or refused alike, for
every operator, for A a typed constant or a variable of every type, and a
comparison gives the same value whichever side the literal is on.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rcsc.semantics import model as m
from rcsc.driver import check_path

TYPES = {"i32": "7", "i64": "7", "u32": "7", "f64": "7.5", "duration": "7 ms"}
UNTYPED = ["5", "5 + 1", "abs(5)", "max(5, 1)", "(if c then 5 else 1)", "-(2 * 3)", "(5 + 1) * 2"]
COMPARE = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "==": "==", "!=": "!="}
ARITH = ["+", "-", "*", "/", "%"]


def _design(t: str, a_kind: str, body: list[tuple[str, str]]) -> str:
    """A design whose controller N computes each `(target, expr)` of `body` in `pre`."""
    a_decl = f"const A: {t} = {TYPES[t]}" if a_kind == "const" else f"gm A: {t} = {TYPES[t]} from env"
    statuses = "".join(f"    status {name}: {'bool' if name.startswith('b') else t} = {'false' if name.startswith('b') else TYPES[t]}\n" for name, _ in body)
    jobs = "".join(f"        {name} = {expr};\n" for name, expr in body)
    reads = "A, c" if a_kind == "gm" else "c"
    return (
        f"design lit\n{a_decl}\ngm c: bool = false from env\n"
        f"controller N level 1 budget 1 ms {{\n    reads {reads}\n{statuses}    pre {{\n{jobs}    }}\n}}\n"
        "cpu MAIN {\n    heartbeat 10 ms\n    schedule N\n}\n"
    )


def _check(tmp_path: Path, name: str, text: str):
    path = tmp_path / f"{name}.rcs"
    path.write_text(text, encoding="utf-8")
    return check_path(str(path))


def _outcome(tmp_path: Path, name: str, t: str, a_kind: str, target: str, expr: str):
    """(sorted error codes, the typed value expression or None)."""
    result = _check(tmp_path, name, _design(t, a_kind, [(target, expr)]))
    codes = sorted(d.code for d in result.diags.errors)
    if codes:
        return codes, None
    assert result.model is not None
    (stmt,) = result.model.controllers["N"].pre
    assert isinstance(stmt, m.Assign)
    return codes, stmt.value


@pytest.mark.parametrize("a_kind", ["const", "gm"])
@pytest.mark.parametrize("op", list(COMPARE))
@pytest.mark.parametrize("t", list(TYPES))
def test_comparison_with_a_literal_expression_is_symmetric(tmp_path: Path, t: str, op: str, a_kind: str) -> None:
    for i, lit in enumerate(UNTYPED):
        left = _outcome(tmp_path, f"l{i}", t, a_kind, "b", f"{lit} {op} A")
        right = _outcome(tmp_path, f"r{i}", t, a_kind, "b", f"A {COMPARE[op]} {lit}")
        assert left[0] == right[0], f"`{lit} {op} A` gives {left[0]}, `A {COMPARE[op]} {lit}` gives {right[0]} ({t})"
        if t == "duration":
            # An integer is not a duration, on either side.
            assert left[0] == ["E0200"], f"`{lit} {op} A` with A: duration gives {left[0]}"
            continue
        assert left[0] == [], f"`{lit} {op} A` with A: {t} is refused: {left[0]}"
        if a_kind == "const" and "c" not in lit:
            # Both fold to a constant, and the value does not depend on the side.
            assert isinstance(left[1], m.Const) and isinstance(right[1], m.Const)
            assert left[1].value == right[1].value, f"`{lit} {op} A` and `A {COMPARE[op]} {lit}` differ ({t})"
        else:
            for value in (left[1], right[1]):
                assert isinstance(value, m.Binary) and value.left.type.name == t and value.right.type.name == t


@pytest.mark.parametrize("a_kind", ["const", "gm"])
@pytest.mark.parametrize("op", ARITH)
@pytest.mark.parametrize("t", list(TYPES))
def test_arithmetic_with_a_literal_expression_is_symmetric(tmp_path: Path, t: str, op: str, a_kind: str) -> None:
    for i, lit in enumerate(UNTYPED):
        for order, expr in (("l", f"{lit} {op} A"), ("r", f"A {op} {lit}")):
            codes, value = _outcome(tmp_path, f"{order}{i}", t, a_kind, "v", f"({expr}) + A")
            if t == "duration":
                assert codes == ["E0200"], f"`{expr}` with A: duration gives {codes}"
            elif t == "f64" and op == "%":
                assert codes == ["E0208"], f"`{expr}` with A: f64 gives {codes}"
            else:
                assert codes == [], f"`{expr}` with A: {t} is refused: {codes}"
                assert value is not None and value.type.name == t


@pytest.mark.parametrize("t", ["i32", "i64", "u32", "f64"])
def test_builtin_arguments_take_the_typed_arguments_type_in_any_position(tmp_path: Path, t: str) -> None:
    for i, (a, b) in enumerate((("A", "5 + 1"), ("5 + 1", "A"), ("abs(5)", "A"), ("A", "-(2 * 3)"))):
        lit = b if a == "A" else a
        if t == "u32" and lit.startswith("-"):
            continue  # -6 is out of range for u32 (E0207) on either side; covered below
        codes, value = _outcome(tmp_path, f"m{i}", t, "gm", "v", f"max({a}, {b})")
        assert codes == [], f"`max({a}, {b})` with A: {t} is refused: {codes}"
        assert value is not None and value.type.name == t
    for i, expr in enumerate(("max(A, -1)", "max(-1, A)")):
        codes, _ = _outcome(tmp_path, f"n{i}", "u32", "gm", "v", expr)
        assert codes == ["E0207"], f"`{expr}` with A: u32 gives {codes}"


def test_a_literal_expression_without_context_is_i32_or_i64(tmp_path: Path) -> None:
    """Nothing to take a type from: the literal's own default (i32, i64 if it does not fit)."""
    codes, value = _outcome(tmp_path, "d", "i64", "gm", "b", "5 + 1 < 7")
    assert codes == [] and isinstance(value, m.Const) and value.value is True
    for i, expr in enumerate(("(5 + 1) < 3000000000", "3000000000 > 5 + 1", "(if c then 1 else 3000000000) == 1")):
        codes, value = _outcome(tmp_path, f"e{i}", "i64", "gm", "b", expr)
        assert codes == [], f"`{expr}` is refused: {codes}"
        assert isinstance(value, m.Binary) or value.value is True
        operands = [value.left, value.right] if isinstance(value, m.Binary) else []
        assert all(x.type.name == "i64" for x in operands)
