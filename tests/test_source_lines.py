"""Lines and columns of a large file found without its line table (`SourceFile._probe`).

A check that reports a few findings in a large file counts the line breaks
up to them instead of making the table of every line; the answers must be
the table's, whatever the order of the questions, and the counting must give
way to the table once it has cost as much.
"""

import random

from hypothesis import given, settings
from hypothesis import strategies as st

from rcsc.front import source as S


@settings(max_examples=300, deadline=None)
@given(st.data())
def test_lines_found_by_counting_are_the_tables(data):
    size = data.draw(st.integers(0, 3000))
    rnd = random.Random(data.draw(st.integers(0, 10**6)))
    text = "".join(rnd.choice("ab\n") for _ in range(size))
    old = S._REUSE_ABOVE
    S._REUSE_ABOVE = 10  # every text of more than 10 characters is "large"
    try:
        probed, table = S.SourceFile("a.rcs", text), S.SourceFile("b.rcs", text)
        table._line_starts  # noqa: B018  (made now)
        for _ in range(data.draw(st.integers(1, 40))):
            if data.draw(st.booleans()):
                offset = data.draw(st.integers(-2, size + 2))
                assert probed.line_col(offset) == table.line_col(offset)
            else:
                line = data.draw(st.integers(0, table.line_count + 1))
                assert probed.line_text(line) == table.line_text(line)
        assert probed._counted <= len(text)
    finally:
        S._REUSE_ABOVE = old


def test_a_few_lines_of_a_large_file_need_no_table():
    text = "".join(f"line {i}\n" for i in range(100_000))
    f = S.SourceFile("big.rcs", text)
    at = text.index("line 50000\n") + 5
    assert f.line_col(at) == (50_001, 6)
    assert f.line_text(50_001) == "line 50000"
    assert f.line_col(at + 11) == (50_002, 6)  # "line 50000\n" is 11 characters
    assert f._starts is None  # counted, not tabled
    # Counting the whole file again would cost more than the table: it is made.
    f.line_col(len(text) - 1)
    f.line_col(len(text) - 1)
    assert f._starts is not None
    assert f.line_col(at) == (50_001, 6)


def test_many_lines_asked_make_the_table():
    """The lines found by counting are kept in a sorted list: past a
    thousand of them (lines asked in any order) the table is made."""
    text = "x\n" * 200_000
    f = S.SourceFile("many.rcs", text)
    order = list(range(0, len(text), 2))
    random.Random(1).shuffle(order)
    for offset in order[:3000]:
        assert f.line_col(offset) == (offset // 2 + 1, 1)
    assert f._starts is not None and len(f._known or ()) <= S._KNOWN_LINES + 1
