"""The fast front end: tokens (`rcsc.front.lexer`) to AST (`rcsc.front.ast`) by recursive descent.

`grammar/rcs.lark` stays the reference grammar and `rcsc.front.lark_parse` its
reference parser.  This parser accepts the same language and builds the same
tree, span for span, without a parse tree in between; a test
(tests/test_fastparse.py) holds the two together on every design in the
repository and on generated ones.

It handles well-formed files, which is what large designs and re-checks
are.  On the first token it does not expect, or when the input nests
deeper than it is willing to recurse, it gives up (`Fallback`) and the
caller re-parses the file with the reference parser, which writes the
syntax diagnostic (E0001/E0002, with the expected tokens) or the E0007 for
deep nesting.  So the fast path never has to agree with Lark on error
messages, only on what is valid.

Keywords are words the grammar expects at a given point: `level` is a name
in an expression and a keyword after `controller X`.  Each method below
checks the keywords that the reference parser accepts at its position
before it reads a word as a name; the expression levels differ (`if` starts
an expression only at the top level of one, `not` only at the `not` level,
so `-not` is the name `not`, as in the reference parser).

Adding a construct to the grammar (`grammar/rcs.lark`) means, besides the
Lark transformer method in `rcsc.front.lark_parse` and the field in `rcsc.front.ast`:

- one method here and one entry in a dispatch table: `_ITEMS` (top-level
  items), `_CTRL_ATTRS` (`controller X level 1 budget 2 ms ...`),
  `_CTRL_ITEMS` (controller body) or `_CPU_ITEMS` (cpu body); a controller
  attribute such as `period 10 ms` is `("period", self.duration())`;
- if the construct makes a word a keyword where a name may also stand
  (expression start: `expr`/`binary`/`postfix`; block statements: `stmt`;
  jobs: `job`; guards, states and next states: `rule`, `state_pat`,
  `next_state`), the check of that word before the name is read;
- a new operator or punctuation character in `rcsc.front.lexer._TOKEN` (longer
  operators before their prefixes, as Lark orders them);
- an example in tests/test_fastparse.py (CORNERS), which compares both
  parsers on it.

A construct the fast parser does not know yet is not wrong, only slow: the
file falls back to the reference parser.
"""

from __future__ import annotations

import math

from rcsc.front import ast
from rcsc.diagnostics import Diagnostics
from rcsc.front.lexer import DIGITS, NAME_START, is_float, tokenize
from rcsc.front.parse import MAX_NESTING, UNIT_NANOS, literal_fraction, literal_int, nest
from rcsc.front.source import SourceFile, Span


class Fallback(Exception):
    """The fast parser does not handle this input: use the reference parser."""


# Recursion the fast parser allows itself (parentheses, unary operators and
# `if`s inside each other) before it leaves the file to the reference
# parser, which is not recursive.  Each level costs about ten Python frames.
_MAX_RECURSION = 48

_CMP_OPS = frozenset(("==", "!=", "<=", ">=", "<", ">"))
# Precedence levels of the binary operators (and of the prefix `not`).
_OR, _AND, _NOT, _CMP, _SUM, _PROD = range(1, 7)
_LEVELS = {"or": _OR, "and": _AND, "+": _SUM, "-": _SUM, "*": _PROD, "/": _PROD, "%": _PROD}
_LEVELS.update(dict.fromkeys(_CMP_OPS, _CMP))
_ASSIGN_OPS = frozenset(("=", "+=", "-=", "*="))
_UNITS = frozenset(UNIT_NANOS)
# Words that start an expression as keywords where a full `expr` may start
# (so `f(if = 1)` is not a named argument, as in the reference parser).
_EXPR_KEYWORDS = frozenset(("if", "not", "true", "false"))


class _Parser:
    def __init__(self, source: SourceFile, diags: Diagnostics, holes: list[tuple[int, int]] | None = None) -> None:
        self.src = source
        self.diags = diags
        self.toks, self.starts, self.ends = tokenize(source.text, holes)
        self.i = 0
        self.recursion = 0
        self.too_deep = False

    # ---- tokens and spans ------------------------------------------------------

    def fail(self):
        raise Fallback

    def expect(self, tok: str) -> None:
        if self.toks[self.i] != tok:
            raise Fallback
        self.i += 1

    def span(self, first: int) -> Span:
        """The span from token `first` to the last token read."""
        return Span(self.src, self.starts[first], self.ends[self.i - 1])

    def tspan(self, i: int) -> Span:
        return Span(self.src, self.starts[i], self.ends[i])

    def name(self) -> ast.Ident:
        """A NAME where the grammar expects nothing else (any word)."""
        i = self.i
        tok = self.toks[i]
        if tok[0] not in NAME_START:
            raise Fallback
        self.i = i + 1
        return ast.Ident(Span(self.src, self.starts[i], self.ends[i]), tok)

    def enter(self) -> None:
        self.recursion += 1
        if self.recursion > _MAX_RECURSION:
            raise Fallback

    def nest(self, node, *children):
        return nest(self, node, children)

    def nest1(self, node, child):
        """`nest` for one child (no generator: this is the hot path)."""
        depth = node.depth = getattr(child, "depth", 1) + 1
        if depth > MAX_NESTING and not self.too_deep:
            self.nest(node, child)
        return node

    def nest2(self, node, left, right):
        """`nest` for two children."""
        a, b = getattr(left, "depth", 1), getattr(right, "depth", 1)
        depth = node.depth = (a if a > b else b) + 1
        if depth > MAX_NESTING and not self.too_deep:
            self.nest(node, left, right)
        return node

    # ---- file and top-level items ------------------------------------------------

    def file(self) -> ast.File:
        kind, name = "", None
        tok = self.toks[0]
        if tok == "design":
            self.i = 1
            kind, name = "design", self.name()
        elif tok == "module":
            self.i = 1
            kind, name = "module", self.dotted_name()
        items = []
        toks = self.toks
        while toks[self.i] != " ":
            item = _ITEMS.get(toks[self.i])
            if item is None:
                raise Fallback
            items.append(item(self))
        return ast.File(Span(self.src, 0, len(self.src.text)), kind, name, items)

    def dotted_name(self) -> ast.Ident:
        first = self.i
        parts = [self.name().name]
        while self.toks[self.i] == ".":
            self.i += 1
            parts.append(self.name().name)
        return ast.Ident(self.span(first), ".".join(parts))

    def import_decl(self) -> ast.Import:
        first = self.i
        self.i += 1
        tok = self.toks[self.i]
        if tok[0] == '"' and len(tok) > 1:
            self.i += 1
            return ast.Import(self.span(first), tok[1:-1], True)
        target = self.dotted_name().name
        return ast.Import(self.span(first), target, False)

    def type_ref(self) -> ast.TypeRef:
        first = self.i
        if self.toks[first] == "[":
            self.i += 1
            elem = self.type_ref()
            self.expect(";")
            size = self.expr()
            self.expect("]")
            span = self.span(first)
            return ast.TypeRef(span, ast.Ident(span, "[]"), None, None, elem, size)
        name = self.name()
        lo = hi = None
        if self.toks[self.i] == "in":
            self.i += 1
            lo = self.expr()
            self.expect("..")
            hi = self.expr()
        return ast.TypeRef(self.span(first), name, lo, hi)

    def const_decl(self) -> ast.Const:
        first = self.i
        self.i += 1
        name = self.name()
        self.expect(":")
        type_ = self.type_ref()
        self.expect("=")
        value = self.expr()
        return ast.Const(self.span(first), name, type_, value)

    def enum_decl(self) -> ast.Enum:
        first = self.i
        self.i += 1
        name = self.name()
        self.expect("{")
        members = []
        if self.toks[self.i] != "}":
            members.append(self.name())
            while self.toks[self.i] == ",":
                self.i += 1
                if self.toks[self.i] == "}":
                    break
                members.append(self.name())
        self.expect("}")
        return ast.Enum(self.span(first), name, members)

    def param(self) -> ast.Param:
        """`NAME: type`, a record field or a parameter."""
        first = self.i
        name = self.name()
        self.expect(":")
        type_ = self.type_ref()
        return ast.Param(self.span(first), name, type_)

    def params(self, close: str) -> list[ast.Param]:
        """`param ("," param)* ","?`, possibly empty, up to (not including) `close`."""
        out = []
        if self.toks[self.i] != close:
            out.append(self.param())
            while self.toks[self.i] == ",":
                self.i += 1
                if self.toks[self.i] == close:
                    break
                out.append(self.param())
        return out

    def record_decl(self) -> ast.Record:
        first = self.i
        self.i += 1
        name = self.name()
        self.expect("{")
        fields = self.params("}")
        self.expect("}")
        return ast.Record(self.span(first), name, fields)

    def gm_decl(self) -> ast.GmVar:
        first = self.i
        self.i += 1
        name = self.name()
        self.expect(":")
        type_ = self.type_ref()
        init = None
        if self.toks[self.i] == "=":
            self.i += 1
            init = self.expr()
        from_env = to_env = False
        if self.toks[self.i] in ("from", "to"):
            from_env, to_env = self.toks[self.i] == "from", self.toks[self.i] == "to"
            self.i += 1
            self.expect("env")
        return ast.GmVar(self.span(first), name, type_, init, from_env, to_env)

    def signature(self) -> tuple[ast.Ident, list[ast.Param], ast.TypeRef]:
        """`NAME "(" [params] ")" "->" type` of a function or an extern."""
        name = self.name()
        self.expect("(")
        params = self.params(")")
        self.expect(")")
        self.expect("->")
        return name, params, self.type_ref()

    def fn_decl(self) -> ast.Function:
        first = self.i
        self.i += 1
        name, params, ret = self.signature()
        self.expect("=")
        body = self.expr()
        return ast.Function(self.span(first), name, params, ret, body)

    def extern_decl(self) -> ast.Extern:
        first = self.i
        self.i += 1
        self.expect("fn")
        name, params, ret = self.signature()
        self.expect("budget")
        budget = self.duration()
        return ast.Extern(self.span(first), name, params, ret, budget)

    def verb_decl(self) -> ast.Verb:
        first = self.i
        self.i += 1
        name = self.name()
        params = []
        if self.toks[self.i] == "(":
            self.i += 1
            params = self.params(")")
            self.expect(")")
        return ast.Verb(self.span(first), name, params)

    def verbset_decl(self) -> ast.VerbSet:
        first = self.i
        self.i += 1
        name = self.name()
        self.expect("{")
        verbs = []
        while self.toks[self.i] == "verb":
            verbs.append(self.verb_decl())
        self.expect("}")
        return ast.VerbSet(self.span(first), name, verbs)

    def name_list(self) -> ast.NameList:
        first = self.i
        names = [self.name()]
        while self.toks[self.i] == ",":
            self.i += 1
            names.append(self.name())
        return ast.NameList(self.span(first), names)

    # ---- controllers -------------------------------------------------------------

    def controller_decl(self) -> ast.Node:
        first = self.i
        simulator = self.toks[self.i] == "simulator"
        self.i += 1
        if self.toks[self.i] == "type":
            self.i += 1
            name = self.name()
            self.expect("(")
            params = self.type_params()
            self.expect(")")
            body = self.controller_rest(first, name, simulator)
            return ast.ControllerType(self.span(first), name, params, body)
        name = self.name()
        if self.toks[self.i] == ":":
            self.i += 1
            type_name = self.name()
            self.expect("(")
            args = self.args()
            return ast.ControllerInstance(self.span(first), name, simulator, type_name, args)
        return self.controller_rest(first, name, simulator)

    def type_params(self) -> list[ast.TypeParam]:
        out = []
        while self.toks[self.i] != ")":
            first = self.i
            name = self.name()
            self.expect(":")
            if self.toks[self.i] == "gm":
                self.i += 1
                out.append(ast.TypeParam(self.span(first), name, None))
            else:
                type_ = self.type_ref()
                out.append(ast.TypeParam(self.span(first), name, type_))
            if self.toks[self.i] != ",":
                break
            self.i += 1
        return out

    def block_use(self):
        first = self.i
        self.i += 1
        name = self.name()
        self.expect(":")
        type_name = self.name()
        self.expect("(")
        args = self.args()
        return "blocks", ast.BlockUse(self.span(first), name, type_name, args)

    def fblock_decl(self) -> ast.BlockType:
        first = self.i
        self.i += 1
        name = self.name()
        self.expect("(")
        params = self.params(")")
        self.expect(")")
        self.expect("{")
        members, steps = [], []
        toks = self.toks
        while toks[self.i] != "}":
            start = self.i
            kind = toks[start]
            if kind == "step":
                self.i += 1
                body = self.block()
                steps.append((self.span(start), body))
                continue
            if kind not in ("input", "state", "output"):
                raise Fallback
            self.i += 1
            mname = self.name()
            self.expect(":")
            type_ = self.type_ref()
            self.expect("=")
            init = self.expr()
            members.append(ast.BlockMember(self.span(start), kind, mname, type_, init))
        self.i += 1
        return ast.BlockType(self.span(first), name, params, members, steps)

    def controller_rest(self, first: int, name: ast.Ident, simulator: bool) -> ast.Controller:
        found: list[tuple[str, object]] = []
        toks = self.toks
        while True:
            attr = _CTRL_ATTRS.get(toks[self.i])
            if attr is None:
                break
            found.append(attr(self))
        self.expect("{")
        while toks[self.i] != "}":
            item = _CTRL_ITEMS.get(toks[self.i])
            if item is None:
                raise Fallback
            found.append(item(self))
        self.i += 1
        ctrl = ast.Controller(self.span(first), name, simulator)
        for key, value in found:
            getattr(ctrl, key).append(value)
        return ctrl

    def level_attr(self):
        first = self.i
        self.i += 1
        tok = self.toks[self.i]
        if tok[0] not in DIGITS or is_float(tok):
            raise Fallback
        self.i += 1
        return "level", (int(tok.replace("_", ""), 0 if tok.startswith("0x") else 10), self.span(first))

    def budget_attr(self):
        self.i += 1
        return "budget", self.duration()

    def period_attr(self):
        self.i += 1
        return "period", self.duration()

    def _list_item(self, key: str):
        self.i += 1
        return key, self.name_list()

    def subordinates_decl(self):
        return self._list_item("subordinates")

    def reads_decl(self):
        return self._list_item("reads")

    def writes_decl(self):
        return self._list_item("writes")

    def reports_decl(self):
        return self._list_item("reports")

    def verb_item(self):
        return "verbs", self.verb_decl()

    def verbs_use(self):
        self.i += 1
        return "verb_sets", self.name()

    def _member(self, key: str):
        first = self.i
        self.i += 1
        name = self.name()
        self.expect(":")
        type_ = self.type_ref()
        self.expect("=")
        init = self.expr()
        return key, ast.Decl(self.span(first), name, type_, init)

    def status_field(self):
        return self._member("status_fields")

    def local_decl(self):
        return self._member("locals")

    def _hook(self, key: str):
        first = self.i
        self.i += 1
        body = self.block()
        return key, (self.span(first), body)

    def pre_block(self):
        return self._hook("pre")

    def post_block(self):
        return self._hook("post")

    def plan_item(self):
        return "plans", self.plan_decl()

    # ---- plans and rules ---------------------------------------------------------

    def plan_decl(self) -> ast.Plan:
        first = self.i
        self.i += 1
        name = self.name()
        toks = self.toks
        mods = []
        while toks[self.i] in ("continuous", "ordered"):
            mods.append(ast.Ident(self.tspan(self.i), toks[self.i]))
            self.i += 1
        self.expect("{")
        rules = []
        while toks[self.i] != "}":
            rules.append(self.rule())
        self.i += 1
        return ast.Plan(self.span(first), name, any(m.name == "continuous" for m in mods), rules, mods)

    def rule(self) -> ast.Rule:
        """`LABEL: guard | state -> next [| [jobs]] ;`"""
        first = self.i
        label = self.name()
        self.expect(":")
        toks = self.toks
        if toks[self.i] == "otherwise":
            guard, guard_span = None, self.tspan(self.i)
            self.i += 1
        else:
            guard = self.expr()
            guard_span = guard.span
        self.expect("|")
        state = self.state_pat()
        self.expect("->")
        next_ = self.next_state()
        jobs = []
        if toks[self.i] == "|":
            self.i += 1
            if toks[self.i] != ";":
                jobs.append(self.job())
                while toks[self.i] == ",":
                    self.i += 1
                    jobs.append(self.job())
        self.expect(";")
        return ast.Rule(self.span(first), label, guard, guard_span, state, next_, jobs)

    def state_pat(self) -> ast.StatePat:
        i = self.i
        tok = self.toks[i]
        if tok == "new":
            kind, name = "new", None
        elif tok == "*":
            kind, name = "any", None
        elif tok[0] in NAME_START:
            kind, name = "named", tok
        else:
            raise Fallback
        self.i = i + 1
        return ast.StatePat(self.tspan(i), kind, name)

    def next_state(self) -> ast.NextState:
        i = self.i
        tok = self.toks[i]
        if tok == "error":
            self.i += 1
            self.expect("(")
            code = self.expr()
            self.expect(")")
            return ast.NextState(self.span(i), "error", code=code)
        if tok == "done":
            kind, name = "done", None
        elif tok == "*":
            kind, name = "same", None
        elif tok == "new":
            kind, name = "new", None
        elif tok[0] in NAME_START:
            kind, name = "named", tok
        else:
            raise Fallback
        self.i = i + 1
        return ast.NextState(self.tspan(i), kind, name)

    def job(self) -> ast.Stmt:
        first = self.i
        toks = self.toks
        if toks[first] == "report":
            self.i += 1
            status = self.name()
            return ast.Report(self.span(first), status)
        if toks[first + 1] == "(":
            return self.call_stmt(first, end=None)
        target = self.lvalue()
        tok = toks[self.i]
        if tok == "[":
            return self.assign(first, target, end=None, index=self.lvalue_index())
        if tok == "(" and len(target) == 2:
            self.i += 1
            args = self.args()
            return self.nest(ast.Command(self.span(first), target[0], target[1], args), *[a.value for a in args])
        return self.assign(first, target, end=None)

    def lvalue(self) -> list[ast.Ident]:
        names = [self.name()]
        while self.toks[self.i] == ".":
            self.i += 1
            names.append(self.name())
        return names

    def lvalue_index(self) -> ast.Expr:
        """`"[" expr "]"` after an lvalue's names."""
        self.i += 1
        index = self.expr()
        self.expect("]")
        return index

    def assign(self, first: int, target: list[ast.Ident], end: str | None, index: ast.Expr | None = None) -> ast.Assign:
        op = self.toks[self.i]
        if op not in _ASSIGN_OPS:
            raise Fallback
        self.i += 1
        value = self.expr()
        if end is not None:
            self.expect(end)
        if index is not None:
            return self.nest(ast.Assign(self.span(first), target, op, value, index), value, index)
        return self.nest1(ast.Assign(self.span(first), target, op, value), value)

    def call_stmt(self, first: int, end: str | None) -> ast.CallStmt:
        """`NAME "(" [args] ")"`, then `end` (`;` in a block); the Call and
        the statement share the span of the whole statement."""
        func = self.name()
        self.i += 1  # "("
        args = self.args()
        if end is not None:
            self.expect(end)
        span = self.span(first)
        call = self.nest(ast.Call(span, func, args), *[a.value for a in args])
        return self.nest1(ast.CallStmt(span, call), call)

    # ---- blocks (pre/post) ---------------------------------------------------------

    def block(self) -> list[ast.Stmt]:
        self.expect("{")
        toks = self.toks
        stmts = []
        while toks[self.i] != "}":
            stmts.append(self.stmt())
        self.i += 1
        return stmts

    def stmt(self) -> ast.Stmt:
        first = self.i
        toks = self.toks
        tok = toks[first]
        if tok == "if":
            return self.if_stmt()
        if toks[first + 1] == "(":
            return self.call_stmt(first, end=";")
        target = self.lvalue()
        index = self.lvalue_index() if toks[self.i] == "[" else None
        return self.assign(first, target, end=";", index=index)

    def if_stmt(self) -> ast.If:
        first = self.i
        self.enter()
        self.i += 1
        toks = self.toks
        branches = [(self.expr(), self.block())]
        while toks[self.i] == "elif":
            self.i += 1
            branches.append((self.expr(), self.block()))
        else_body = None
        if toks[self.i] == "else":
            self.i += 1
            else_body = self.block()
        self.recursion -= 1
        inner = [c for c, _ in branches] + [st for _, b in branches for st in b] + list(else_body or [])
        return self.nest(ast.If(self.span(first), branches, else_body), *inner)

    # ---- CPUs ----------------------------------------------------------------------

    def cpu_decl(self) -> ast.Cpu:
        first = self.i
        self.i += 1
        name = self.name()
        self.expect("{")
        items = []
        toks = self.toks
        while toks[self.i] != "}":
            item = _CPU_ITEMS.get(toks[self.i])
            if item is None:
                raise Fallback
            items.append(item(self))
        self.i += 1
        cpu = ast.Cpu(self.span(first), name)
        for key, value in items:
            getattr(cpu, key).append(value)
        return cpu

    def heartbeat(self):
        self.i += 1
        return "heartbeat", self.duration()

    def overhead(self):
        self.i += 1
        return "overhead", self.duration()

    def schedule(self):
        self.i += 1
        return "schedule", self.name_list()

    # ---- expressions -----------------------------------------------------------------

    def expr(self) -> ast.Expr:
        """`if c then a else b`, or an `or` chain."""
        if self.toks[self.i] != "if":
            return self.or_expr()
        first = self.i
        self.enter()
        self.i += 1
        cond = self.expr()
        self.expect("then")
        then = self.expr()
        self.expect("else")
        else_ = self.expr()
        self.recursion -= 1
        return self.nest(ast.IfExpr(self.span(first), cond, then, else_), cond, then, else_)

    def or_expr(self) -> ast.Expr:
        return self.binary(_OR)

    def binary(self, min_level: int) -> ast.Expr:
        """Operators of precedence `min_level` and above, by precedence
        climbing (one call per operand, not one per grammar level): the
        grammar's or_expr (_OR), and_expr (_AND), not_expr (_NOT),
        cmp_expr (_CMP), sum_expr (_SUM) and prod_expr (_PROD)."""
        first = self.i
        toks = self.toks
        if min_level <= _NOT and toks[first] == "not":
            self.enter()
            self.i += 1
            operand = self.binary(_NOT)
            self.recursion -= 1
            left = self.nest1(ast.Unary(self.span(first), "not", operand), operand)
        else:
            left = self.unary()
        while True:
            op_i = self.i
            op = toks[op_i]
            level = _LEVELS.get(op)
            if level is None or level < min_level:
                return left
            self.i = op_i + 1
            if level == _PROD:
                right = self.unary()
            else:
                right = self.binary(level + 1)
            if level <= _AND:
                op_span = Span(self.src, left.span.end, right.span.start)
            else:
                op_span = Span(self.src, self.starts[op_i], self.ends[op_i])
            left = self.nest2(ast.Binary(self.span(first), op, left, right, op_span), left, right)
            if level == _CMP and toks[self.i] in _CMP_OPS:
                raise Fallback  # comparisons do not chain

    def unary(self) -> ast.Expr:
        if self.toks[self.i] != "-":
            return self.postfix()
        first = self.i
        self.enter()
        self.i += 1
        operand = self.unary()
        self.recursion -= 1
        return self.nest1(ast.Unary(self.span(first), "-", operand), operand)

    def postfix(self) -> ast.Expr:
        first = self.i
        toks = self.toks
        tok = toks[first]
        if tok[0] in NAME_START and tok != "true" and tok != "false":
            if toks[first + 1] == "(":
                func = ast.Ident(self.tspan(first), tok)
                self.i = first + 2
                args = self.args()
                node = self.nest(ast.Call(self.span(first), func, args), *[a.value for a in args])
            else:
                self.i = first + 1
                node = ast.Name(self.tspan(first), tok)
        else:
            node = self.atom()
        while True:
            tok = toks[self.i]
            if tok == ".":
                self.i += 1
                attr = self.name()
                node = self.nest1(ast.Attr(self.span(first), node, attr), node)
            elif tok == "[":
                self.enter()
                self.i += 1
                index = self.expr()
                self.expect("]")
                self.recursion -= 1
                node = self.nest2(ast.Index(self.span(first), node, index), node, index)
            else:
                return node

    def atom(self) -> ast.Expr:
        i = self.i
        tok = self.toks[i]
        if tok[0] in DIGITS:
            if self.toks[i + 1] in _UNITS:
                return self.duration()
            self.i = i + 1
            if is_float(tok):
                return self.float_lit(i)
            return ast.IntLit(self.tspan(i), literal_int(tok))
        if tok == "true" or tok == "false":
            self.i = i + 1
            return ast.BoolLit(self.tspan(i), tok == "true")
        if tok == "(":
            self.enter()
            self.i += 1
            inner = self.expr()
            self.expect(")")
            self.recursion -= 1
            return inner
        if tok == "[":
            return self.array_lit()
        raise Fallback

    def array_lit(self) -> ast.Expr:
        """`[a, b, ...]` or `[value; count]`."""
        first = self.i
        toks = self.toks
        self.enter()
        self.i += 1
        items: list[ast.Expr] = []
        if toks[self.i] != "]":
            items.append(self.expr())
            if toks[self.i] == ";":
                self.i += 1
                count = self.expr()
                self.expect("]")
                self.recursion -= 1
                return self.nest2(ast.ArrayRepeat(self.span(first), items[0], count), items[0], count)
            while toks[self.i] == ",":
                self.i += 1
                if toks[self.i] == "]":
                    break
                items.append(self.expr())
        self.expect("]")
        self.recursion -= 1
        return self.nest(ast.ArrayLit(self.span(first), items), *items)

    def float_lit(self, i: int) -> ast.FloatLit:
        span = self.tspan(i)
        value = float(self.toks[i].replace("_", ""))
        if math.isinf(value):
            self.diags.add("E0212", span, "float literal out of range for `f64`", "larger than 1.8e308").with_help(
                "f64 holds magnitudes up to about 1.8e308; a larger literal would silently become infinity"
            )
            value = 0.0
        return ast.FloatLit(span, value)

    def duration(self) -> ast.DurationLit:
        """`(INT | FLOAT) UNIT`."""
        first = self.i
        number, unit = self.toks[first], self.toks[first + 1]
        if number[0] not in DIGITS or unit not in _UNITS:
            raise Fallback
        self.i = first + 2
        span = self.span(first)
        if number.isdigit() and number.isascii() and len(number) <= 18:
            # A plain integer (the usual `10 ms`): exact without fractions.
            return ast.DurationLit(span, int(number) * UNIT_NANOS[unit], f"{number} {unit}")
        nanos = literal_fraction(number) * UNIT_NANOS[unit]
        if nanos.denominator != 1:
            self.diags.add("E0210", span, "duration is not a whole number of nanoseconds", "finer than 1 ns")
        return ast.DurationLit(span, int(nanos), f"{number} {unit}")

    def args(self) -> list[ast.Arg]:
        """`[arg ("," arg)* ","?] ")"` after a `(`."""
        out = []
        toks = self.toks
        self.enter()
        while toks[self.i] != ")":
            first = self.i
            tok = toks[first]
            if toks[first + 1] == "=" and tok[0] in NAME_START and tok not in _EXPR_KEYWORDS:
                name = self.name()
                self.i += 1
                value = self.expr()
                out.append(ast.Arg(self.span(first), name, value))
            else:
                value = self.expr()
                out.append(ast.Arg(self.span(first), None, value))
            if toks[self.i] != ",":
                break
            self.i += 1
        self.expect(")")
        self.recursion -= 1
        return out


_ITEMS = {
    "import": _Parser.import_decl,
    "const": _Parser.const_decl,
    "enum": _Parser.enum_decl,
    "record": _Parser.record_decl,
    "gm": _Parser.gm_decl,
    "fn": _Parser.fn_decl,
    "extern": _Parser.extern_decl,
    "verbset": _Parser.verbset_decl,
    "controller": _Parser.controller_decl,
    "simulator": _Parser.controller_decl,
    "block": _Parser.fblock_decl,
    "cpu": _Parser.cpu_decl,
}

# Controller attributes (`controller X level 1 budget 2 ms {`): each returns
# (attribute list of ast.Controller, value).
_CTRL_ATTRS = {
    "level": _Parser.level_attr,
    "budget": _Parser.budget_attr,
    "period": _Parser.period_attr,
}

# Controller body items: each returns (attribute list of ast.Controller, value).
_CTRL_ITEMS = {
    "subordinates": _Parser.subordinates_decl,
    "reads": _Parser.reads_decl,
    "writes": _Parser.writes_decl,
    "verb": _Parser.verb_item,
    "verbs": _Parser.verbs_use,
    "reports": _Parser.reports_decl,
    "status": _Parser.status_field,
    "local": _Parser.local_decl,
    "pre": _Parser.pre_block,
    "post": _Parser.post_block,
    "plan": _Parser.plan_item,
    "block": _Parser.block_use,
}

_CPU_ITEMS = {
    "heartbeat": _Parser.heartbeat,
    "overhead": _Parser.overhead,
    "schedule": _Parser.schedule,
}


def parse_fast(source: SourceFile, holes: list[tuple[int, int]] | None = None) -> tuple[ast.File | None, Diagnostics]:
    """Parse `source`: (tree or None after E0007, findings of literals and
    nesting).  Raises Fallback where the reference parser must answer.
    `holes`: ranges read as blanks (see `rcsc.front.lexer.tokenize`)."""
    diags = Diagnostics()
    parser = _Parser(source, diags, holes)
    try:
        tree = parser.file()
    except (RecursionError, IndexError) as exc:
        raise Fallback from exc
    if parser.too_deep:
        return None, diags
    from rcsc.front.doccomment import attach

    attach(tree, source, diags, holes)
    return tree, diags
