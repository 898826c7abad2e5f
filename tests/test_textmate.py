"""The TextMate grammar (editors/vscode/syntaxes/rcs.tmLanguage.json).

A small tokenizer applies the grammar's patterns the way a TextMate engine
does (at each point the match that starts first wins, ties to the earlier
pattern; `begin`/`end` spans) with Python regular expressions, which agree
with Oniguruma on the constructs the grammar uses.  Every keyword of
grammar/rcs.lark and every built-in type must get a scope, comments must be
comments in the examples, and the keywords in the examples must be scoped."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from rcsc.semantics.types import BUILTIN_TYPES

ROOT = Path(__file__).resolve().parent.parent
GRAMMAR = json.loads((ROOT / "editors" / "vscode" / "syntaxes" / "rcs.tmLanguage.json").read_text())
KEYWORDS = sorted(set(re.findall(r'"([a-z_]+)"', (ROOT / "grammar" / "rcs.lark").read_text())))
EXAMPLES = sorted((ROOT / "examples").glob("*/*.rcs")) + sorted((ROOT / "stdlib").glob("*/*.rcs"))


def _flatten(patterns: list[dict]) -> list[dict]:
    out = []
    for p in patterns:
        if "include" in p:
            out.extend(_flatten(GRAMMAR["repository"][p["include"][1:]].get("patterns", [GRAMMAR["repository"][p["include"][1:]]])))
        elif "patterns" in p and "match" not in p and "begin" not in p:
            out.extend(_flatten(p["patterns"]))
        else:
            out.append(p)
    return out


PATTERNS = _flatten(GRAMMAR["patterns"])


def tokenize(text: str) -> list[tuple[str, str]]:
    """(text, scope) pieces; text outside every pattern has scope ""."""
    out: list[tuple[str, str]] = []
    compiled = [(p, re.compile(p.get("match") or p["begin"], re.M)) for p in PATTERNS]
    pos = 0
    while pos < len(text):
        best = None
        for p, rx in compiled:
            m = rx.search(text, pos)
            if m and m.end() > m.start() and (best is None or m.start() < best[1].start()):
                best = (p, m)
        if best is None:
            out.append((text[pos:], ""))
            break
        p, m = best
        if m.start() > pos:
            out.append((text[pos:m.start()], ""))
        if "begin" in p:
            end = re.compile(p["end"]).search(text, m.end())
            stop = end.end() if end else len(text)
            out.append((text[m.start():stop], p["name"]))
            pos = stop
            continue
        if "captures" in p:
            last = m.start()
            for k in sorted(p["captures"], key=int):
                if m.group(int(k)) is None:
                    continue
                if m.start(int(k)) > last:
                    out.append((text[last:m.start(int(k))], ""))
                out.append((m.group(int(k)), p["captures"][k]["name"]))
                last = m.end(int(k))
            if m.end() > last:
                out.append((text[last:m.end()], ""))
        else:
            out.append((m.group(0), p["name"]))
        pos = m.end()
    return out


def _scope_of(text: str, word: str) -> str:
    return next(scope for piece, scope in tokenize(text) if piece == word)


def test_grammar_is_a_textmate_grammar() -> None:
    assert GRAMMAR["scopeName"] == "source.rcs" and GRAMMAR["fileTypes"] == ["rcs"]
    for p in PATTERNS:
        assert ("match" in p) != ("begin" in p)
        assert "name" in p or "captures" in p


@pytest.mark.parametrize("keyword", KEYWORDS)
def test_every_keyword_of_the_language_is_scoped(keyword: str) -> None:
    scope = _scope_of(f"x {keyword} y\n", keyword)
    assert scope.startswith(("keyword.", "storage.", "constant.language.")), (keyword, scope)


@pytest.mark.parametrize("name", sorted(BUILTIN_TYPES))
def test_builtin_types_are_scoped(name: str) -> None:
    assert _scope_of(f"gm v: {name} = 0\n", name) == "support.type.primitive.rcs"


def test_rule_parts() -> None:
    tokens = [t for t in tokenize("        E0: x >= 1.0 | new -> S1 | TB.AHEAD(rpm = 2 ms);\n") if t[1]]
    assert tokens[:2] == [("E0", "entity.name.label.rcs"), (":", "punctuation.separator.rcs")]
    assert ("->", "keyword.operator.transition.rcs") in tokens and ("|", "punctuation.separator.column.rcs") in tokens
    assert ("new", "keyword.other.state.rcs") in tokens and ("AHEAD", "entity.name.function.rcs") in tokens
    assert ("2 ms", "constant.numeric.duration.rcs") in tokens and ("1.0", "constant.numeric.float.rcs") in tokens
    # `name: type` in a declaration is not a rule label.
    assert not any(s == "entity.name.label.rcs" for _, s in tokenize("    local prop_rpm: i32 = 0\n"))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_examples_comments_and_keywords(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    tokens = tokenize(text)
    comments = "".join(t for t, s in tokens if s.startswith("comment."))
    for m in re.finditer(r"//[^\n]*", text):
        line_start = text.rfind("\n", 0, m.start()) + 1
        if '"' in text[line_start:m.start()]:
            continue
        assert m.group(0) in comments
    # Outside comments and strings, no keyword of the language is left unscoped.
    for piece, scope in tokens:
        if scope:
            continue
        for word in re.findall(r"[A-Za-z_][A-Za-z0-9_]*", piece):
            assert word not in KEYWORDS, (path.name, word, piece)
