"""The reference parser: `grammar/rcs.lark` with Lark, and its tree turned into the AST.

Lark builds a parse tree with positions; a Transformer turns it into
`rcsc.front.ast` nodes whose spans cover exactly the text they came from.  A
syntax error becomes one diagnostic (E0001/E0002) with the expected tokens
spelled out the way an engineer reads them.  `rcsc.front.parse.text_to_ast`
uses it for the files the fast parser (`rcsc.front.rdparse`) leaves to it;
the scenario language (`rcsc.front.scenario`) is parsed with it.
"""

from __future__ import annotations

import re

import math
from functools import lru_cache
from importlib import resources

from lark import Lark, Token, Transformer_NonRecursive, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from rcsc.front import ast
from rcsc.diagnostics import Diagnostics
from rcsc.front.parse import UNIT_NANOS, check_bidi, literal_fraction, literal_int, nest
from rcsc.front.source import BIDI_CONTROLS, SourceFile, Span

# How expected terminals are shown in a syntax error.
_TOKEN_WORDS = {
    "NAME": "a name",
    "INT": "an integer",
    "FLOAT": "a number",
    "STRING": "a quoted path",
    "UNIT": "a time unit (`us`, `ms` or `s`)",
    "CMP_OP": "a comparison",
    "ADD_OP": "`+` or `-`",
    "MUL_OP": "`*`, `/` or `%`",
    "ASSIGN_OP": "`=`",
    "CONTROLLER_KIND": "`controller` or `simulator`",
    "PLAN_MOD": "`continuous` or `ordered`",
    "OTHERWISE": "`otherwise`",
    "NEW": "`new`",
    "RANGE_IN": "`in`",
    "$END": "end of file",
}


@lru_cache(maxsize=1)
def _parser() -> Lark:
    text = resources.files("rcsc.grammar").joinpath("rcs.lark").read_text(encoding="utf-8")
    from rcsc.front.grammar_cache import lark_cache

    return Lark(text, parser="lalr", propagate_positions=True, maybe_placeholders=True, cache=lark_cache("rcs", text))


def _describe_expected(parser: Lark, names: set[str]) -> list[str]:
    words = set()
    for name in names:
        if name in _TOKEN_WORDS:
            words.add(_TOKEN_WORDS[name])
            continue
        try:
            term = parser.get_terminal(name)
        except KeyError:
            words.add(name.lower())
            continue
        pattern = term.pattern
        if pattern.type == "str":
            words.add(f"`{pattern.value}`")
        else:
            words.add(name.lower())
    return sorted(words)


class _ToAst(Transformer_NonRecursive):
    """Lark tree -> rcsc.front.ast.  Every method receives the node's meta."""

    def __init__(self, source: SourceFile, diags: Diagnostics) -> None:
        super().__init__(visit_tokens=False)
        self.too_deep = False
        self.src = source
        self.diags = diags

    # -- helpers ---------------------------------------------------------------

    def span(self, meta) -> Span:
        if getattr(meta, "empty", False):
            return Span(self.src, 0, 0)
        return Span(self.src, meta.start_pos, meta.end_pos)

    def tspan(self, tok: Token) -> Span:
        return Span(self.src, tok.start_pos, tok.end_pos)

    def ident(self, tok: Token) -> ast.Ident:
        return ast.Ident(self.tspan(tok), str(tok))

    def nest(self, node, *children):
        return nest(self, node, children)

    def node_span(self, node) -> Span:
        return node.span if isinstance(node, ast.Node) else self.tspan(node)

    # -- file ------------------------------------------------------------------

    @v_args(meta=True)
    def start(self, meta, children):
        kind, name, items = "", None, []
        for c in children:
            if isinstance(c, tuple) and c[0] == "header":
                kind, name = c[1], c[2]
            elif c is not None:
                items.append(c)
        return ast.File(Span(self.src, 0, len(self.src.text)), kind, name, items)

    @v_args(meta=True)
    def design_header(self, meta, children):
        return ("header", "design", self.ident(children[0]))

    @v_args(meta=True)
    def module_header(self, meta, children):
        return ("header", "module", children[0])

    @v_args(meta=True)
    def dotted_name(self, meta, children):
        return ast.Ident(self.span(meta), ".".join(str(c) for c in children))

    @v_args(meta=True)
    def import_std(self, meta, children):
        return ast.Import(self.span(meta), children[0].name, False)

    @v_args(meta=True)
    def import_file(self, meta, children):
        return ast.Import(self.span(meta), str(children[0])[1:-1], True)

    # -- declarations ------------------------------------------------------------

    @v_args(meta=True)
    def type(self, meta, children):
        name, _in, lo, hi = children
        return ast.TypeRef(self.span(meta), self.ident(name), lo, hi)

    @v_args(meta=True)
    def array_type(self, meta, children):
        elem, size = children
        span = self.span(meta)
        return ast.TypeRef(span, ast.Ident(span, "[]"), None, None, elem, size)

    @v_args(meta=True)
    def const_decl(self, meta, children):
        name, type_, value = children
        return ast.Const(self.span(meta), self.ident(name), type_, value)

    @v_args(meta=True)
    def enum_decl(self, meta, children):
        name, *members = children
        return ast.Enum(self.span(meta), self.ident(name), [self.ident(m) for m in members if m is not None])

    @v_args(meta=True)
    def field(self, meta, children):
        return ast.Param(self.span(meta), self.ident(children[0]), children[1])

    param = field

    @v_args(meta=True)
    def record_decl(self, meta, children):
        name, *fields = children
        return ast.Record(self.span(meta), self.ident(name), [f for f in fields if f is not None])

    @v_args(meta=True)
    def env_writer(self, meta, children):
        return "from"

    @v_args(meta=True)
    def env_reader(self, meta, children):
        return "to"

    @v_args(meta=True)
    def gm_decl(self, meta, children):
        name, type_, init, env = children
        return ast.GmVar(self.span(meta), self.ident(name), type_, init, env == "from", env == "to")

    @v_args(meta=True)
    def params(self, meta, children):
        return list(children)

    @v_args(meta=True)
    def fn_decl(self, meta, children):
        name, params, ret, body = children
        return ast.Function(self.span(meta), self.ident(name), params or [], ret, body)

    @v_args(meta=True)
    def extern_decl(self, meta, children):
        name, params, ret, budget = children
        return ast.Extern(self.span(meta), self.ident(name), params or [], ret, budget)

    @v_args(meta=True)
    def verb_decl(self, meta, children):
        name, params = children
        return ast.Verb(self.span(meta), self.ident(name), params or [])

    @v_args(meta=True)
    def verbset_decl(self, meta, children):
        name, *verbs = children
        return ast.VerbSet(self.span(meta), self.ident(name), list(verbs))

    @v_args(meta=True)
    def name_list(self, meta, children):
        return ast.NameList(self.span(meta), [self.ident(c) for c in children])

    # -- controllers -------------------------------------------------------------

    @v_args(meta=True)
    def level_attr(self, meta, children):
        return ("level", (int(str(children[0]).replace("_", ""), 0 if str(children[0]).startswith("0x") else 10), self.span(meta)))

    @v_args(meta=True)
    def budget_attr(self, meta, children):
        return ("budget", children[0])

    @v_args(meta=True)
    def period_attr(self, meta, children):
        return ("period", children[0])

    @v_args(meta=True)
    def subordinates_decl(self, meta, children):
        return ("subordinates", children[0])

    @v_args(meta=True)
    def reads_decl(self, meta, children):
        return ("reads", children[0])

    @v_args(meta=True)
    def writes_decl(self, meta, children):
        return ("writes", children[0])

    @v_args(meta=True)
    def verbs_use(self, meta, children):
        return ("verb_sets", self.ident(children[0]))

    @v_args(meta=True)
    def reports_decl(self, meta, children):
        return ("reports", children[0])

    @v_args(meta=True)
    def status_field(self, meta, children):
        name, type_, init = children
        return ("status_fields", ast.Decl(self.span(meta), self.ident(name), type_, init))

    @v_args(meta=True)
    def local_decl(self, meta, children):
        name, type_, init = children
        return ("locals", ast.Decl(self.span(meta), self.ident(name), type_, init))

    @v_args(meta=True)
    def pre_block(self, meta, children):
        return ("pre", (self.span(meta), children[0]))

    @v_args(meta=True)
    def post_block(self, meta, children):
        return ("post", (self.span(meta), children[0]))

    @v_args(meta=True)
    def controller_decl(self, meta, children):
        kind, name, *rest = children
        ctrl = ast.Controller(self.span(meta), self.ident(name), str(kind) == "simulator")
        for item in rest:
            if isinstance(item, ast.Verb):
                ctrl.verbs.append(item)
            elif isinstance(item, ast.Plan):
                ctrl.plans.append(item)
            else:
                key, value = item
                getattr(ctrl, key).append(value)
        return ctrl

    # -- controller types and function blocks ---------------------------------

    @v_args(meta=True)
    def ctype_decl(self, meta, children):
        kind, name, params, *rest = children
        body = self.controller_decl(meta, [kind, name, *rest])
        return ast.ControllerType(self.span(meta), self.ident(name), params or [], body)

    @v_args(meta=True)
    def tparams(self, meta, children):
        return list(children)

    @v_args(meta=True)
    def tparam_value(self, meta, children):
        return ast.TypeParam(self.span(meta), self.ident(children[0]), children[1])

    @v_args(meta=True)
    def tparam_gm(self, meta, children):
        return ast.TypeParam(self.span(meta), self.ident(children[0]), None)

    @v_args(meta=True)
    def cinst_decl(self, meta, children):
        kind, name, type_name, args = children
        return ast.ControllerInstance(self.span(meta), self.ident(name), str(kind) == "simulator", self.ident(type_name), args or [])

    @v_args(meta=True)
    def block_use(self, meta, children):
        name, type_name, args = children
        return ("blocks", ast.BlockUse(self.span(meta), self.ident(name), self.ident(type_name), args or []))

    @v_args(meta=True)
    def fblock_decl(self, meta, children):
        name, params, *items = children
        members = [i for i in items if isinstance(i, ast.BlockMember)]
        steps = [i for i in items if isinstance(i, tuple)]
        return ast.BlockType(self.span(meta), self.ident(name), params or [], members, steps)

    @v_args(meta=True)
    def block_input(self, meta, children):
        return ast.BlockMember(self.span(meta), "input", self.ident(children[0]), children[1], children[2])

    @v_args(meta=True)
    def block_state(self, meta, children):
        return ast.BlockMember(self.span(meta), "state", self.ident(children[0]), children[1], children[2])

    @v_args(meta=True)
    def block_output(self, meta, children):
        return ast.BlockMember(self.span(meta), "output", self.ident(children[0]), children[1], children[2])

    @v_args(meta=True)
    def block_step(self, meta, children):
        return (self.span(meta), children[0])

    # -- plans -----------------------------------------------------------------

    @v_args(meta=True)
    def plan_decl(self, meta, children):
        name, *rest = children
        mods = [self.ident(r) for r in rest if isinstance(r, Token)]
        rules = [r for r in rest if isinstance(r, ast.Rule)]
        return ast.Plan(self.span(meta), self.ident(name), any(m.name == "continuous" for m in mods), rules, mods)

    @v_args(meta=True)
    def rule(self, meta, children):
        label, guard, state, next_, jobs = children
        guard_expr, guard_span = guard
        return ast.Rule(self.span(meta), self.ident(label), guard_expr, guard_span, state, next_, jobs or [])

    @v_args(meta=True)
    def guard(self, meta, children):
        return (children[0], children[0].span)

    @v_args(meta=True)
    def otherwise_guard(self, meta, children):
        return (None, self.tspan(children[0]))

    @v_args(meta=True)
    def state_new(self, meta, children):
        return ast.StatePat(self.span(meta), "new")

    @v_args(meta=True)
    def state_any(self, meta, children):
        return ast.StatePat(self.span(meta), "any")

    @v_args(meta=True)
    def state_named(self, meta, children):
        return ast.StatePat(self.span(meta), "named", str(children[0]))

    @v_args(meta=True)
    def next_named(self, meta, children):
        return ast.NextState(self.span(meta), "named", str(children[0]))

    @v_args(meta=True)
    def next_done(self, meta, children):
        return ast.NextState(self.span(meta), "done")

    @v_args(meta=True)
    def next_error(self, meta, children):
        return ast.NextState(self.span(meta), "error", code=children[0])

    @v_args(meta=True)
    def next_same(self, meta, children):
        return ast.NextState(self.span(meta), "same")

    @v_args(meta=True)
    def next_new(self, meta, children):
        return ast.NextState(self.span(meta), "new")

    @v_args(meta=True)
    def job_list(self, meta, children):
        return list(children)

    # -- statements --------------------------------------------------------------

    @v_args(meta=True)
    def lvalue(self, meta, children):
        index = children[-1] if isinstance(children[-1], ast.Expr) else None
        return [self.ident(c) for c in children if isinstance(c, Token)], index

    @v_args(meta=True)
    def assign(self, meta, children):
        (target, index), op, value = children
        if index is None:
            return self.nest(ast.Assign(self.span(meta), target, str(op), value), value)
        return self.nest(ast.Assign(self.span(meta), target, str(op), value, index), value, index)

    @v_args(meta=True)
    def command(self, meta, children):
        sub, verb, args = children
        return self.nest(ast.Command(self.span(meta), self.ident(sub), self.ident(verb), args or []), *[a.value for a in args or []])

    @v_args(meta=True)
    def call_stmt(self, meta, children):
        func, args = children
        span = self.span(meta)
        call = self.nest(ast.Call(span, self.ident(func), args or []), *[a.value for a in args or []])
        return self.nest(ast.CallStmt(span, call), call)

    @v_args(meta=True)
    def report(self, meta, children):
        return ast.Report(self.span(meta), self.ident(children[0]))

    @v_args(meta=True)
    def block(self, meta, children):
        return list(children)

    @v_args(meta=True)
    def elif_clause(self, meta, children):
        return (children[0], children[1])

    @v_args(meta=True)
    def if_stmt(self, meta, children):
        cond, body, *rest = children
        else_body = rest.pop() if rest else None
        branches = [(cond, body)] + [c for c in rest if c is not None]
        inner = [c for c, _ in branches] + [st for _, b in branches for st in b] + list(else_body or [])
        return self.nest(ast.If(self.span(meta), branches, else_body), *inner)

    @v_args(meta=True)
    def args(self, meta, children):
        return list(children)

    @v_args(meta=True)
    def pos_arg(self, meta, children):
        return ast.Arg(self.span(meta), None, children[0])

    @v_args(meta=True)
    def named_arg(self, meta, children):
        return ast.Arg(self.span(meta), self.ident(children[0]), children[1])

    # -- CPUs ------------------------------------------------------------------

    @v_args(meta=True)
    def heartbeat(self, meta, children):
        return ("heartbeat", children[0])

    @v_args(meta=True)
    def overhead(self, meta, children):
        return ("overhead", children[0])

    @v_args(meta=True)
    def schedule(self, meta, children):
        return ("schedule", children[0])

    @v_args(meta=True)
    def cpu_decl(self, meta, children):
        name, *items = children
        cpu = ast.Cpu(self.span(meta), self.ident(name))
        for key, value in items:
            getattr(cpu, key).append(value)
        return cpu

    # -- expressions -------------------------------------------------------------

    def _int(self, tok: Token) -> int:
        return literal_int(str(tok))

    @v_args(meta=True)
    def int_lit(self, meta, children):
        return ast.IntLit(self.span(meta), self._int(children[0]))

    @v_args(meta=True)
    def float_lit(self, meta, children):
        value = float(str(children[0]).replace("_", ""))
        if math.isinf(value):
            self.diags.add("E0212", self.span(meta), "float literal out of range for `f64`", "larger than 1.8e308").with_help(
                "f64 holds magnitudes up to about 1.8e308; a larger literal would silently become infinity"
            )
            value = 0.0
        return ast.FloatLit(self.span(meta), value)

    @v_args(meta=True)
    def true_lit(self, meta, children):
        return ast.BoolLit(self.span(meta), True)

    @v_args(meta=True)
    def false_lit(self, meta, children):
        return ast.BoolLit(self.span(meta), False)

    @v_args(meta=True)
    def name(self, meta, children):
        return ast.Name(self.span(meta), str(children[0]))

    @v_args(meta=True)
    def duration(self, meta, children):
        number, unit = children
        span = self.span(meta)
        value = literal_fraction(str(number))
        nanos = value * UNIT_NANOS[str(unit)]
        if nanos.denominator != 1:
            self.diags.add("E0210", span, "duration is not a whole number of nanoseconds", "finer than 1 ns")
        return ast.DurationLit(span, int(nanos), f"{number} {unit}")

    @v_args(meta=True)
    def attr(self, meta, children):
        return self.nest(ast.Attr(self.span(meta), children[0], self.ident(children[1])), children[0])

    @v_args(meta=True)
    def index(self, meta, children):
        obj, idx = children
        return self.nest(ast.Index(self.span(meta), obj, idx), obj, idx)

    @v_args(meta=True)
    def array_lit(self, meta, children):
        items = [c for c in children if c is not None]
        return self.nest(ast.ArrayLit(self.span(meta), items), *items)

    @v_args(meta=True)
    def array_repeat(self, meta, children):
        value, count = children
        return self.nest(ast.ArrayRepeat(self.span(meta), value, count), value, count)

    @v_args(meta=True)
    def call(self, meta, children):
        func, args = children
        return self.nest(ast.Call(self.span(meta), self.ident(func), args or []), *[a.value for a in args or []])

    @v_args(meta=True)
    def neg(self, meta, children):
        return self.nest(ast.Unary(self.span(meta), "-", children[0]), children[0])

    @v_args(meta=True)
    def not_(self, meta, children):
        return self.nest(ast.Unary(self.span(meta), "not", children[0]), children[0])

    def _bin(self, meta, left, op, right, op_span):
        return self.nest(ast.Binary(self.span(meta), op, left, right, op_span), left, right)

    @v_args(meta=True)
    def binop(self, meta, children):
        left, op, right = children
        return self._bin(meta, left, str(op), right, self.tspan(op))

    compare = binop

    @v_args(meta=True)
    def and_(self, meta, children):
        left, right = children
        return self._bin(meta, left, "and", right, Span(self.src, left.span.end, right.span.start))

    @v_args(meta=True)
    def or_(self, meta, children):
        left, right = children
        return self._bin(meta, left, "or", right, Span(self.src, left.span.end, right.span.start))

    @v_args(meta=True)
    def if_expr(self, meta, children):
        return self.nest(ast.IfExpr(self.span(meta), *children), *children)


def text_to_ast_lark(source: SourceFile, diags: Diagnostics) -> ast.File | None:
    """Parse one file with the reference (Lark) parser."""
    from rcsc.front.doccomment import attach

    tree = parse_with(_parser(), _ToAst, source, diags)
    attach(tree, source, diags)
    return tree


def parse_with(parser: Lark, builder_class: type, source: SourceFile, diags: Diagnostics):
    """Parse `source` with `parser` and build the result with `builder_class`
    (a `_ToAst`); None after a syntax error or a too-deep nesting (E0007).
    Bidirectional control characters are reported (E0008) before parsing."""
    check_bidi(source, diags)
    try:
        tree = parser.parse(source.text)
    except UnexpectedInput as exc:
        _syntax_error(parser, source, exc, diags)
        return None
    builder = builder_class(source, diags)
    try:
        result = builder.transform(tree)
    except VisitError as exc:  # pragma: no cover - a bug in the transformer
        raise exc.orig_exc from exc
    # Too deep to analyse safely: report it (E0007) like a syntax error.
    return None if builder.too_deep else result


# The help of a syntax error where a `;` could stand: most often a rule's `;` was forgotten.
RULE_END_HELP = "a rule ends with `;`: `LABEL: condition | state -> next | jobs;`"


def _syntax_error(parser: Lark, source: SourceFile, exc: UnexpectedInput, diags: Diagnostics) -> None:
    text = source.text
    if isinstance(exc, UnexpectedCharacters):
        pos = exc.pos_in_stream
        ch = text[pos] if pos < len(text) else ""
        if ch == '"':
            diags.add("E0002", Span(source, pos, min(len(text), pos + 1)), "unterminated string", "this quote is never closed")
            return
        if ch in BIDI_CONTROLS:
            return  # already reported (E0008)
        shown = repr(ch)[1:-1] if ch.isprintable() else f"\\u{ord(ch):04x}"
        diag = diags.add("E0002", Span(source, pos, pos + 1), f"unexpected character `{shown}`", "not part of the language")
        expected = _describe_expected(parser, set(exc.allowed or ()))
        if expected:
            diag.with_note("expected " + _join(expected))
        return
    if isinstance(exc, UnexpectedEOF):
        end = len(text)
        diag = diags.add("E0001", Span(source, end, end), "unexpected end of file", "the file ends here")
        expected = _describe_expected(parser, set(exc.expected or ()))
        if expected:
            diag.with_note("expected " + _join(expected))
        return
    assert isinstance(exc, UnexpectedToken)
    tok = exc.token
    if tok.type == "$END":
        start = end = len(text)
        found = "end of file"
    else:
        start, end = tok.start_pos, tok.end_pos
        found = f"`{tok}`"
    expected = _describe_expected(parser, set(exc.expected or ()))
    diag = diags.add("E0001", Span(source, start, end), f"syntax error: unexpected {found}", "unexpected here")
    if expected:
        diag.with_note("expected " + _join(expected))
    before = re.search(r"\b(period|budget|heartbeat|overhead)\s*$", text[:start])
    if before and tok.type != "$END" and str(tok).isidentifier():
        # `period STALE`: these take a duration literal, read before any
        # constant is known (the schedule and the budgets are fixed first).
        diag.with_help(f"`{before.group(1)}` takes a duration literal such as `100 ms` or `2 us`, not a named constant")
        return
    if tok.type != "$END" and str(tok).isidentifier():
        # A misspelt keyword (`report` for `reports`, `overheed`): the word
        # the grammar expected there.
        words = re.findall(r"`([A-Za-z_]\w*)`", " ".join(expected))
        if diag.guess(str(tok), words) is not None:
            return
    if str(tok) == "(" and _COMMAND_BEFORE.search(text, 0, start) and not _in_plan(text, start):
        # `SUB.VERB()` in `pre`, `post` or a block's step: only a rule sends commands.
        diag.with_help("a command is a job of a plan's rule (`E1: condition | S1 -> S2 | SUB.VERB();`), not a statement")
        return
    # A rule whose `;` is missing: the next line's start is unexpected.
    if "`;`" in expected and tok.type != "$END" and "\n" in text[:start][len(text[:start].rstrip()):] and _in_plan(text, start):
        diag.with_help(RULE_END_HELP)


_PLAN_HEADER = re.compile(r"\s*plan\b")
_COMMAND_BEFORE = re.compile(r"\b[A-Za-z_]\w*\s*\.\s*[A-Za-z_]\w*\s*\Z")


def _in_plan(text: str, pos: int) -> bool:
    """Whether `pos` lies inside the braces of a `plan` (where a rule ends
    with `;`): the innermost brace open before it belongs to a line that
    starts with `plan`.  Braces in comments can mislead it; it only chooses
    a help."""
    depth = 0
    for i in range(pos - 1, -1, -1):
        ch = text[i]
        if ch == "}":
            depth += 1
        elif ch == "{":
            if depth == 0:
                line_start = text.rfind("\n", 0, i) + 1
                return bool(_PLAN_HEADER.match(text, line_start))
            depth -= 1
    return False


def _join(words: list[str]) -> str:
    if len(words) <= 1:
        return "".join(words)
    if len(words) > 8:
        words = words[:8] + ["..."]
    return ", ".join(words[:-1]) + " or " + words[-1]
