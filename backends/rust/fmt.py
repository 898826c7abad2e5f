"""Rust expression trees and their layout, as rustfmt lays them out.

The Rust target builds each expression as a small tree (`Atom`, `Call`,
`Bin`, ...) instead of a string, so that a statement is written the way
`rustfmt --edition 2021` with the default configuration would write it: on
one line when it fits, else broken where rustfmt breaks it.  The functions
below are a port of the parts of rustfmt the generated code needs (rustfmt's
shape.rs, pairs.rs, overflow.rs, lists.rs and the expression, struct
literal, `if`/`else` and assignment code of expr.rs), limited to the nodes
defined here.  A rewrite returns the text or `None` when it cannot fit,
exactly like rustfmt's `Rewrite::rewrite`, so that the callers' fallbacks
are rustfmt's.

Parentheses are decided when a tree is built (`Bin.make`, `Unary.make`,
`Cast.make`), so that rustc's `unused_parens` never fires and precedence is
always right.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

MAX_WIDTH = 100
TAB = 4
FN_CALL_WIDTH = 60
ARRAY_WIDTH = 60
CHAIN_WIDTH = 60
STRUCT_LIT_WIDTH = 18
SINGLE_LINE_IF_ELSE_MAX_WIDTH = 50
SHORT_ARRAY_ELEMENT_WIDTH_THRESHOLD = 10

# Rust operator precedence (higher binds tighter).
P_IF = 0  # `if c { a } else { b }`: needs parentheses as an operand
P_OR, P_AND, P_CMP = 1, 2, 3
P_ADD, P_MUL = 8, 9
P_CAST = 10
P_UNARY = 11
P_POSTFIX = 12

BIN_PREC = {
    "||": P_OR, "&&": P_AND,
    "==": P_CMP, "!=": P_CMP, "<": P_CMP, "<=": P_CMP, ">": P_CMP, ">=": P_CMP,
    "+": P_ADD, "-": P_ADD, "*": P_MUL, "/": P_MUL, "%": P_MUL,
}


# ---- shapes (rustfmt's shape.rs) ------------------------------------------------------


@dataclass(frozen=True)
class Shape:
    """The room for a rewrite: `width` on its first line, at `indent` (block + alignment),
    `offset` characters already used on the current line beyond the block indent."""

    width: int
    block: int
    align: int
    offset: int

    @staticmethod
    def indented(block: int, align: int = 0) -> "Shape":
        return Shape(max(0, MAX_WIDTH - (block + align)), block, align, align)

    def indent_width(self) -> int:
        return self.block + self.align

    def with_max_width(self) -> "Shape":
        return Shape(max(0, MAX_WIDTH - self.indent_width()), self.block, self.align, self.offset)

    def block_indent(self, delta: int) -> "Shape":
        if self.align == 0:
            return Shape(self.width, self.block + delta, 0, 0)
        return Shape(self.width, self.block, self.align + delta, self.align + delta)

    def block_only(self) -> "Shape":
        return Shape(self.width, self.block, 0, self.offset)

    def add_offset(self, delta: int) -> "Shape":
        return Shape(self.width, self.block, self.align, self.offset + delta)

    def sub_width(self, n: int) -> "Shape | None":
        if self.width < n:
            return None
        return Shape(self.width - n, self.block, self.align, self.offset)

    def offset_left(self, delta: int) -> "Shape | None":
        return self.add_offset(delta).sub_width(delta)

    def used_width(self) -> int:
        return self.block + self.offset

    def rhs_overhead(self) -> int:
        return max(0, MAX_WIDTH - (self.used_width() + self.width))

    def with_width(self, width: int) -> "Shape":
        return Shape(width, self.block, self.align, self.offset)


def _nl(width: int) -> str:
    return "\n" + " " * width


def budget(used: int) -> int:
    return max(0, MAX_WIDTH - used)


def first_line_width(s: str) -> int:
    return len(s.split("\n", 1)[0])


def last_line_width(s: str) -> int:
    return len(s.rsplit("\n", 1)[-1])


def trimmed_last_line_width(s: str) -> int:
    return len(s.rsplit("\n", 1)[-1].strip())


def single_line(s: str) -> bool:
    return "\n" not in s


def first_line_ends_with(s: str, c: str) -> bool:
    return s.split("\n", 1)[0].endswith(c)


def last_line_extendable(s: str) -> bool:
    for c in reversed(s):
        if c in "()]}?>":
            continue
        if c == "\n":
            break
        if c.isspace():
            continue
        return False
    return True


def fits(s: str, shape: Shape) -> bool:
    """rustfmt's `wrap_str` test: the first line within the width, the others within
    the maximum, the last one within the shape."""
    if not s:
        return True
    if first_line_width(s) > shape.width:
        return False
    if single_line(s):
        return True
    if any(len(line) > MAX_WIDTH for line in s.split("\n")[1:]):
        return False
    return last_line_width(s) <= shape.used_width() + shape.width


# ---- nodes ------------------------------------------------------------------------------


class Node:
    prec = P_POSTFIX

    def flat(self) -> str:
        raise NotImplementedError

    def rewrite(self, shape: Shape) -> str | None:
        raise NotImplementedError

    def __str__(self) -> str:
        return self.flat()


_FIELD_CHAIN = re.compile(r"[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+")
_SIMPLE = re.compile(r'-?[A-Za-z0-9_.]+(?:[eE][+-]?[0-9]+)?|"(?:[^"\\]|\\.)*"')


@dataclass
class Atom(Node):
    """A literal, a path or a field access: never broken."""

    text: str
    prec: int = P_POSTFIX

    @property
    def simple(self) -> bool:
        """rustfmt's `is_simple_expr`: a literal, a one-segment path or a field of one."""
        return "::" not in self.text and _SIMPLE.fullmatch(self.text) is not None

    def flat(self) -> str:
        return self.text

    def rewrite(self, shape: Shape) -> str | None:
        if _FIELD_CHAIN.fullmatch(self.text):
            root, *fields = self.text.split(".")
            return _rewrite_chain(Atom(root), ["." + f for f in fields], shape)
        return self.text if len(self.text) <= shape.width else None


@dataclass
class Call(Node):
    """`callee(args)`: the callee is a path (never a method call: rustfmt lays those out
    as chains)."""

    callee: str
    args: list[Node] = field(default_factory=list)
    prec = P_POSTFIX

    def flat(self) -> str:
        return f"{self.callee}({', '.join(a.flat() for a in self.args)})"

    def rewrite(self, shape: Shape) -> str | None:
        if len(self.callee) > shape.width:
            return None
        return rewrite_list(self.callee, self.args, shape, "(", ")", FN_CALL_WIDTH)


@dataclass
class Array(Node):
    """`[a, b]`, or a bracketed macro call such as `vec![a, b]` (`name` = `vec!`)."""

    items: list[Node]
    name: str = ""
    prec = P_POSTFIX

    def flat(self) -> str:
        return f"{self.name}[{', '.join(a.flat() for a in self.items)}]"

    def rewrite(self, shape: Shape) -> str | None:
        return rewrite_list(self.name, self.items, shape, "[", "]", ARRAY_WIDTH)


@dataclass
class Paren(Node):
    inner: Node
    prec = P_POSTFIX

    def flat(self) -> str:
        return f"({self.inner.flat()})"

    def rewrite(self, shape: Shape) -> str | None:
        sub = shape.offset_left(1)
        sub = sub.sub_width(1) if sub else None
        if sub is None:
            return None
        inner = self.inner.rewrite(sub)
        return None if inner is None else f"({inner})"


@dataclass
class Bin(Node):
    op: str
    left: Node
    right: Node

    @property
    def prec(self) -> int:  # type: ignore[override]
        return BIN_PREC[self.op]

    @staticmethod
    def make(op: str, left: Node, right: Node) -> "Bin":
        if op in ("&&", "||") and isinstance(right, Bin) and right.op == op:
            # `a && (b && c)` is `a && b && c` (also when evaluated): written without
            # parentheses, as the left-nested tree that Rust parses it into.
            return Bin.make(op, Bin.make(op, left, right.left), right.right)
        p = BIN_PREC[op]
        if left.prec < p or (left.prec == p and p == P_CMP):
            left = Paren(left)
        elif op == "<" and _ends_in_cast(left):
            # `x as i32 < y` (also `a + x as i32 < y`) would start generic arguments.
            left = Paren(left)
        if right.prec <= p:
            right = Paren(right)
        return Bin(op, left, right)

    def flat(self) -> str:
        return f"{self.left.flat()} {self.op} {self.right.flat()}"

    def rewrite(self, shape: Shape) -> str | None:
        r = _rewrite_all_pairs(self, shape)
        if r is None:
            r = _rewrite_pair(self.left, self.right, f" {self.op} ", shape)
        return r


@dataclass
class Unary(Node):
    op: str  # "-", "!", "&"
    operand: Node
    prec = P_UNARY

    @staticmethod
    def make(op: str, operand: Node) -> "Unary":
        if operand.prec < P_UNARY or (op == "-" and operand.flat().startswith("-")):
            operand = Paren(operand)
        return Unary(op, operand)

    def flat(self) -> str:
        return f"{self.op}{self.operand.flat()}"

    def rewrite(self, shape: Shape) -> str | None:
        sub = shape.offset_left(len(self.op))
        if sub is None:
            return None
        r = self.operand.rewrite(sub)
        return None if r is None else self.op + r


def _ends_in_cast(node: "Node") -> bool:
    """Whether `node` written flat ends in `... as T`, the type a following `<` would open."""
    while isinstance(node, Bin):
        node = node.right
    return isinstance(node, Cast)


@dataclass
class Cast(Node):
    operand: Node
    ty: str
    prec = P_CAST

    @staticmethod
    def make(operand: Node, ty: str) -> "Cast":
        if operand.prec < P_CAST:
            operand = Paren(operand)
        return Cast(operand, ty)

    def flat(self) -> str:
        return f"{self.operand.flat()} as {self.ty}"

    def rewrite(self, shape: Shape) -> str | None:
        return _rewrite_pair(self.operand, Atom(self.ty), " as ", shape)


@dataclass
class FieldOf(Node):
    """A field of a computed value: `f(x).y`."""

    obj: Node
    name: str
    prec = P_POSTFIX

    def flat(self) -> str:
        return f"{self.obj.flat()}.{self.name}"

    def rewrite(self, shape: Shape) -> str | None:
        fields = ["." + self.name]
        obj = self.obj
        while isinstance(obj, FieldOf):
            fields.insert(0, "." + obj.name)
            obj = obj.obj
        return _rewrite_chain(obj, fields, shape)


def _is_block_like(parent: Node, text: str) -> bool:
    """rustfmt's `is_block_expr` for a chain's parent."""
    if isinstance(parent, (Call, Array, Struct, If)):
        return "\n" in text
    if isinstance(parent, Paren):
        return _is_block_like(parent.inner, text)
    return False


def _rewrite_chain(parent: Node, children: list[str], shape: Shape) -> str | None:
    """rustfmt's chains.rs (block indent) for a parent and field accesses `.x`."""
    root = parent.rewrite(shape)
    if root is None:
        return None
    ends_with_block = _is_block_like(parent, root)
    child_count = len(children)
    rest = list(children)
    tab_width = max(0, TAB - shape.offset)
    while len(root) <= tab_width and "\n" not in root:
        if shape.offset_left(len(root)) is None:
            return None
        root += rest.pop(0)
        ends_with_block = last_line_extendable(root)
        if not rest:
            break
    if not rest:
        return root if fits(root, shape) else None
    child_shape = (shape.block_indent(0) if ends_with_block else shape.block_indent(TAB)).with_max_width()
    rewrites = [root] + rest[:-1]
    last = rest[-1]
    extendable = last_line_extendable(root)
    almost_total = last_line_width(root) if extendable else sum(len(r) for r in rewrites)
    limit = shape.width if child_count == 1 else min(shape.width, CHAIN_WIDTH)
    one_line_budget = max(0, limit - almost_total)
    all_in_one_line = all("\n" not in r for r in rewrites) and one_line_budget > 0
    fits_single_line = False
    if all_in_one_line or extendable:
        last_shape = shape if all_in_one_line else child_shape
        if last_shape.offset_left(almost_total) is not None:
            could_fit = len(last) <= one_line_budget
            if child_shape.sub_width(shape.rhs_overhead()) is None:
                return None
            if could_fit:
                fits_single_line = all_in_one_line
    elif child_shape.sub_width(shape.rhs_overhead()) is None:
        return None
    rewrites.append(last)
    connector = "" if fits_single_line else _nl(child_shape.indent_width())
    result = rewrites[0] + "".join(connector + r for r in rewrites[1:])
    return result if fits(result, shape) else None


@dataclass
class If(Node):
    """`if cond { then } else { else_ }`; `else_` may be another `If` (an `else if`)."""

    cond: Node
    then: Node
    else_: Node
    prec = P_IF

    def flat(self) -> str:
        e = self.else_.flat() if isinstance(self.else_, If) else f"{{ {self.else_.flat()} }}"
        return f"if {self.cond.flat()} {{ {self.then.flat()} }} else {e}"

    def rewrite(self, shape: Shape) -> str | None:
        return self.rewrite_as(shape, statement=False)

    def rewrite_as(self, shape: Shape, statement: bool, nested: bool = False) -> str | None:
        """rustfmt's `ControlFlow::rewrite`: `statement` (a statement or a block's last
        expression) never goes on one line; `nested`: the `if` of an `else if`."""
        head = self.head(shape, allow_single_line=not statement and not nested, nested=nested)
        if head is None:
            return None
        cond_str, used = head
        if used == 0:
            return cond_str
        result = cond_str + _block([self.then], shape.indent_width())
        else_shape = Shape.indented(shape.block, shape.align)
        if isinstance(self.else_, If):
            rest = self.else_.rewrite_as(else_shape, statement=True, nested=True)
        else:
            rest = _block([self.else_], else_shape.indent_width())
        if rest is None:
            return None
        return result + " else " + rest

    def head(self, shape: Shape, allow_single_line: bool, nested: bool) -> tuple[str, int] | None:
        """rustfmt's `ControlFlow::rewrite_cond`: (`if cond` plus the separator before the
        block, the width used), or (the whole one-line `if`, 0)."""
        fresh = shape.with_width(budget(shape.used_width()))
        constr = fresh.offset_left(7) if nested else fresh  # 7 = "} else "
        if constr is None:
            return None
        cond_shape = constr.offset_left(3)  # 3 = "if "
        pat = self.cond.rewrite(cond_shape) if cond_shape else None
        if pat is None:
            return None
        one_line_budget = budget(constr.used_width() + 3 + 2)
        force_newline_brace = ("\n" in pat or len(pat) > one_line_budget) and (
            not last_line_extendable(pat) or _last_line_offsetted(shape.used_width(), pat)
        )
        if allow_single_line:
            trial = self._single_line(pat, shape.width)
            if trial is not None and len(trial) <= SINGLE_LINE_IF_ELSE_MAX_WIDTH:
                return trial, 0
        sep = _nl(shape.indent_width()) if force_newline_brace else " "
        used = last_line_width(pat) if "\n" in pat else 2 + len(pat) + 2
        return "if " + pat + sep, used

    def _single_line(self, pat: str, width: int) -> str | None:
        if isinstance(self.else_, If) or "\n" in pat:
            return None
        new_width = width - (len(pat) + 2 + len("  {  } else {  }"))
        if new_width < 0:
            return None
        if_str = _stmt_rewrite(self.then, Shape(new_width, 0, 0, 0))
        if if_str is None:
            return None
        new_width -= len(if_str)
        if new_width < 0:
            return None
        else_str = _stmt_rewrite(self.else_, Shape(new_width, 0, 0, 0))
        if else_str is None or "\n" in if_str or "\n" in else_str:
            return None
        result = f"if {pat} {{ {if_str} }} else {{ {else_str} }}"
        return result if len(result) <= width else None


def _last_line_offsetted(start_column: int, s: str) -> bool:
    leading = 0
    for c in reversed(s):
        if c == "\n":
            break
        if c.isspace():
            leading += 1
        else:
            leading = 0
    return leading > start_column


def _stmt_rewrite(e: Node, shape: Shape) -> str | None:
    """A block's last expression (rustfmt's style 2015: formatted as a statement)."""
    if isinstance(e, If):
        return e.rewrite_as(shape, statement=True)
    return e.rewrite(shape)


def _block(exprs: list[Node], indent: int) -> str:
    """`{` + each expression on its own line one level deeper + `}` (a block of an `if`)."""
    inner = indent + TAB
    lines = []
    for e in exprs:
        r = _stmt_rewrite(e, Shape.indented(inner))
        if r is None:
            r = e.flat()
        lines.append(" " * inner + r)
    return "{\n" + "\n".join(lines) + _nl(indent) + "}"


@dataclass
class Struct(Node):
    name: str
    fields: list[tuple[str, Node]]
    prec = P_POSTFIX

    def flat(self) -> str:
        if not self.fields:
            return f"{self.name} {{}}"
        return f"{self.name} {{ {', '.join(_field_flat(n, v) for n, v in self.fields)} }}"

    def rewrite(self, shape: Shape) -> str | None:
        path_shape = shape.sub_width(2)
        if path_shape is None or len(self.name) > path_shape.width:
            return None
        path = self.name
        if not self.fields:
            return f"{path} {{}}"
        # rustfmt's struct_lit_shape: prefix `Foo {` + space, suffix ` }`.
        v = shape.block_indent(TAB)
        v_shape = v.with_width(budget(v.indent_width()))
        w = shape.width - (len(path) + 3 + 2)
        h_shape = Shape(min(w, STRUCT_LIT_WIDTH), shape.block, shape.align, shape.align) if w >= 0 else None
        one_line_width = h_shape.width if h_shape else 0
        item_shape = v_shape.sub_width(1)
        if item_shape is None:
            return None
        items = []
        for n, e in self.fields:
            r = _rewrite_field(n, e, item_shape)
            if r is None:
                return None
            items.append(r)
        if h_shape is not None:
            horizontal = _definitive_horizontal(items, h_shape.width)
        else:
            horizontal = False
        if horizontal:
            fields_str = ", ".join(items)
        else:
            fields_str = (",\n" + " " * v_shape.indent_width()).join(items) + ","
        if "\n" in fields_str or len(fields_str) > one_line_width:
            body = _nl(v_shape.indent_width()) + fields_str + _nl(shape.indent_width())
        else:
            body = f" {fields_str} "
        return f"{path} {{{body}}}"


def _shorthand(name: str, value: Node) -> bool:
    """`Foo { x }` for `Foo { x: x }` (clippy::redundant_field_names; rustfmt keeps either)."""
    return isinstance(value, Atom) and value.text == name


def _field_flat(name: str, value: Node) -> str:
    return name if _shorthand(name, value) else f"{name}: {value.flat()}"


def _rewrite_field(name: str, e: Node, shape: Shape) -> str | None:
    expr_shape = shape.offset_left(len(name) + 2)
    r = e.rewrite(expr_shape) if expr_shape else None
    if r is not None:
        return name if _shorthand(name, e) else f"{name}: {r}"
    inner = Shape.indented(shape.block + TAB, shape.align)
    r = e.rewrite(inner)
    return None if r is None else f"{name}:\n{' ' * inner.indent_width()}{r}"


# ---- binary operators (rustfmt's pairs.rs) ---------------------------------------------


def _flatten(node: Bin, shape: Shape) -> tuple[list[tuple[Node, str | None]], list[str]]:
    top = node.op
    stack: list[Bin] = []
    items: list[tuple[Node, str | None]] = []
    seps: list[str] = []
    cur: Node = node
    while True:
        if isinstance(cur, Bin) and cur.op == top:
            stack.append(cur)
            cur = cur.left
            continue
        if not items:
            rw = cur.rewrite(shape)
        else:
            nested = shape.block_indent(TAB).with_max_width().sub_width(shape.rhs_overhead())
            d = nested.offset_left(len(seps[-1]) + 1) if nested else None
            rw = cur.rewrite(d) if d else None
        items.append((cur, rw))
        if not stack:
            break
        b = stack.pop()
        seps.append(b.op)
        cur = b.right
    return items, seps


def _rewrite_all_pairs(node: Bin, shape: Shape) -> str | None:
    items, seps = _flatten(node, shape)
    r = _pairs_one_line(items, seps, shape)
    if r is None:
        r = _pairs_multiline(items, seps, shape)
    return r


def _pairs_one_line(items, seps, shape: Shape) -> str | None:
    result = ""
    base = shape.block_only()
    for (_, rw), s in zip(items, seps):
        if rw is None or not single_line(rw) or len(result) > shape.width:
            return None
        result += f"{rw} {s} "
    prefix_len = len(result)
    cur = base.offset_left(last_line_width(result))
    if cur is None:
        return None
    last = items[-1][0].rewrite(cur)
    if last is None:
        return None
    result += last
    if first_line_width(result) > shape.width:
        return None
    if not (single_line(result) or last.startswith("{")) and (last.startswith("(") or prefix_len > TAB):
        return None
    return result if fits(result, shape) else None


def _pairs_multiline(items, seps, shape: Shape) -> str | None:
    nested = shape.block_indent(TAB).with_max_width().sub_width(shape.rhs_overhead())
    if nested is None:
        return None
    indent_str = _nl(nested.indent_width())
    result = items[0][1]
    if result is None:
        return None
    for (e, default_rw), s in zip(items[1:], seps):
        offset = 0 if "\n" in result else shape.used_width()
        if last_line_width(result) + offset <= nested.used_width():
            line_shape = shape.offset_left(len(s) + 2 + trimmed_last_line_width(result))
            if line_shape is not None:
                rw = e.rewrite(line_shape)
                if rw is not None:
                    result += f" {s} {rw}"
                    continue
        result += indent_str + s + " "
        if default_rw is None:
            return None
        result += default_rw
    return result


def _rewrite_pair(lhs: Node, rhs: Node, infix: str, shape: Shape) -> str | None:
    """rustfmt's `rewrite_pair` with the separator in front (binop_separator = Front)."""
    lhs_shape = shape.with_width(budget(shape.used_width()))
    lhs_result = lhs.rewrite(lhs_shape)
    if lhs_result is None:
        return None
    rs = shape.offset_left(last_line_width(lhs_result) + len(infix))
    rhs_orig = rhs.rewrite(rs) if rs else None
    if rhs_orig is not None:
        allow_same_line = len(lhs_result) <= TAB or first_line_ends_with(rhs_orig, "{")
        if "\n" not in rhs_orig or allow_same_line:
            one = last_line_width(lhs_result) + len(infix) + first_line_width(rhs_orig)
            if one <= shape.width:
                return lhs_result + infix + rhs_orig
    base = Shape.indented(shape.block + TAB, shape.align).sub_width(shape.rhs_overhead())
    if base is None:
        return None
    op = infix.lstrip()
    rhs_shape = base.offset_left(len(op))
    if rhs_shape is None:
        return None
    rhs_result = rhs.rewrite(rhs_shape)
    if rhs_result is None:
        return None
    return lhs_result + _nl(rhs_shape.indent_width()) + op + rhs_result


# ---- lists: calls and arrays (rustfmt's overflow.rs and lists.rs) ------------------------


def _is_simple(e: Node) -> bool:
    if isinstance(e, Atom):
        return e.simple
    if isinstance(e, (Unary, Cast)):
        return _is_simple(e.operand)
    return False


def _can_be_overflowed(e: Node, n_args: int) -> bool:
    if isinstance(e, If):
        return n_args == 1
    if isinstance(e, (Call, Array, Struct)):
        return n_args == 1
    if isinstance(e, (Unary, Cast)):
        return _can_be_overflowed(e.operand, n_args)
    return False


def _is_nested_call(e: Node) -> bool:
    if isinstance(e, Call) or (isinstance(e, Array) and e.name):
        return True
    if isinstance(e, (Unary, Cast)):
        return _is_nested_call(e.operand)
    return False


def _definitive_horizontal(items: list[str], limit: int) -> bool:
    total = sum(len(i) for i in items) + 2 * max(0, len(items) - 1)
    return total <= limit and not any("\n" in i for i in items)


def rewrite_list(ident: str, args: list[Node], shape: Shape, opener: str, closer: str, item_max_width: int) -> str | None:
    """rustfmt's overflow `Context::rewrite` for `ident(args)` / `ident[args]` (block indent)."""
    used_width = len(ident)
    one_line_width = max(0, shape.width - (used_width + 2))
    ol = shape.offset_left(len(ident) + 1)
    ol = ol.sub_width(1) if ol else None
    one_line_shape = ol if ol is not None else shape.with_width(0)
    nested = shape.block_only().block_indent(TAB).with_max_width()
    nested_shape = nested.with_width(max(0, nested.width - 1))
    items: list[str | None] = [a.rewrite(nested_shape) for a in args]
    tactic = _try_overflow_last_item(ident, args, items, one_line_shape, nested_shape, one_line_width, item_max_width)
    if tactic is None or any(i is None for i in items):
        return None
    strs: list[str] = items  # type: ignore[assignment]
    if tactic == "horizontal":
        items_str = ", ".join(strs)
    elif tactic == "vertical":
        items_str = (",\n" + " " * nested_shape.indent_width()).join(strs) + ("," if strs else "")
    else:  # mixed
        items_str = _write_mixed(strs, nested_shape)
    return _wrap_items(ident, items_str, shape, nested_shape, tactic == "horizontal", opener, closer)


def _write_mixed(items: list[str], shape: Shape) -> str:
    indent = " " * shape.indent_width()
    out = ""
    line_len = 0
    for i, item in enumerate(items):
        total = len(item) + 1  # with its separator (the last one gets a trailing comma)
        if line_len > 0 and line_len + 1 + total > shape.width:
            out += "\n" + indent
            line_len = 0
        elif line_len > 0:
            out += " "
            line_len += 1
        line_len += total
        out += item + ","
    return out


def _wrap_items(ident: str, items_str: str, shape: Shape, nested_shape: Shape, extendable: bool, opener: str, closer: str) -> str:
    width = max(0, shape.width - last_line_width(ident))
    extend_width = 2 if not items_str else first_line_width(items_str) + 1
    if extendable and extend_width <= width:
        return ident + opener + items_str + closer
    result = ident + opener
    if items_str:
        result += _nl(nested_shape.indent_width()) + items_str
    return result + _nl(shape.block) + closer


def _last_item_shape(args: list[Node], items: list[str | None], shape: Shape, args_max_width: int) -> Shape | None:
    if len(items) == 1 and not _is_nested_call(args[0]):
        return shape
    offset = sum(2 + len(i or "") for i in items[:-1])
    return shape.with_width(min(args_max_width, shape.width)).offset_left(offset)


def _rewrite_last_with_overflow(e: Node, shape: Shape) -> str | None:
    if isinstance(e, If):
        head = e.head(shape, allow_single_line=True, nested=False)
        if head is None or "\n" in head[0]:
            return None
    return e.rewrite(shape)


def _try_overflow_last_item(ident, args, items, one_line_shape, nested_shape, one_line_width, item_max_width) -> str | None:
    if not args:
        return "horizontal"
    n = len(args)
    combine_with_callee = n == 1 and len(ident) < TAB
    overflow_last = combine_with_callee or _can_be_overflowed(args[-1], n)
    placeholder = None
    if overflow_last:
        s = _last_item_shape(args, items, one_line_shape, item_max_width)
        if s is not None:
            placeholder = _rewrite_last_with_overflow(args[-1], s)
            if placeholder is not None:
                items[-1] = placeholder.split("\n", 1)[0]
    tactic = "horizontal" if _definitive_horizontal([i or "" for i in items], min(one_line_width, item_max_width)) else "vertical"
    if overflow_last and tactic == "horizontal" and placeholder is not None and n == 1:
        if placeholder.count("\n") == 1:
            rw = args[-1].rewrite(nested_shape)
            items[-1] = rw if rw is not None and "\n" not in rw else placeholder
        else:
            items[-1] = placeholder
        return tactic
    if overflow_last and tactic == "horizontal" and placeholder is not None:
        items[-1] = placeholder
        return tactic
    items[-1] = args[-1].rewrite(nested_shape)
    last = items[-1] or ""
    if n == 1 and one_line_width != 0 and "\n" not in last and len(last) <= one_line_width:
        return "horizontal"
    if _definitive_horizontal([i or "" for i in items], min(one_line_width, item_max_width)):
        return "horizontal"
    if all(_is_simple(a) for a in args) and all(len(i or "") <= SHORT_ARRAY_ELEMENT_WIDTH_THRESHOLD for i in items):
        return "mixed"
    return "vertical"


# ---- statements (rustfmt's stmt.rs, the assignment code of expr.rs) ---------------------


def pad(indent: int) -> str:
    return " " * (TAB * indent)


def fn_head(indent: int, prefix: str, name: str, params: list[str], ret: str | None, end: str = " {") -> list[str]:
    """A function's signature as rustfmt writes it: on one line when it fits, else
    one parameter per line."""
    arrow = f" -> {ret}" if ret else ""
    one = f"{pad(indent)}{prefix}fn {name}({', '.join(params)}){arrow}{end}"
    if len(one) <= MAX_WIDTH or not params:
        return [one]
    return [f"{pad(indent)}{prefix}fn {name}("] + [f"{pad(indent + 1)}{p}," for p in params] + [f"{pad(indent)}){arrow}{end}"]


def field_decl(decl: str, indent: int) -> list[str]:
    """A struct field `pub name: Type,`: the type on the next line when it does not fit."""
    one = f"{pad(indent)}{decl},"
    if len(one) <= MAX_WIDTH or ": " not in decl:
        return [one]
    name, ty = decl.split(": ", 1)
    return [f"{pad(indent)}{name}:", f"{pad(indent + 1)}{ty},"]


def _can_flatten(e: Node) -> bool:
    if isinstance(e, (Call, Array, Struct)):
        return True
    if isinstance(e, (Unary, Cast)):
        return _can_flatten(e.operand)
    return False


def arm(pattern: str, body: Node, indent: int) -> list[str]:
    """A match arm `pattern => body,` as rustfmt's `rewrite_match_body` writes it: on one
    line, with the body broken after the arrow, or in a block."""
    shape = Shape.indented(TAB * indent).offset_left(len(pattern) + 4)
    body_shape = shape.sub_width(1) if shape else None
    orig = _stmt_rewrite(body, body_shape) if body_shape else None
    head = f"{pad(indent)}{pattern} =>"
    if orig is not None and "\n" not in orig and len(orig) <= body_shape.width:  # type: ignore[union-attr]
        return _lines(f"{pattern} => {orig},", indent)
    nxt = _stmt_rewrite(body, Shape.indented(TAB * (indent + 1)))

    def block(text: str) -> list[str]:
        return [head + " {"] + _lines(text, indent + 1) + [pad(indent) + "}"]

    if orig is not None and nxt is not None and _prefer_next_line(orig, nxt):
        return block(nxt)
    if orig is not None and _can_flatten(body) and first_line_width(orig) <= body_shape.width:  # type: ignore[union-attr]
        return _lines(f"{pattern} => {orig},", indent)
    if orig is not None and nxt is not None and "\n" in orig:
        return block(nxt)
    if orig is None and nxt is not None:
        return block(nxt)
    return _lines(f"{pattern} => {orig if orig is not None else body.flat()},", indent)


def _prefer_next_line(orig: str, new: str) -> bool:
    return (
        "\n" not in new
        or orig.count("\n") > new.count("\n") + 1
        or (first_line_ends_with(orig, "(") and not first_line_ends_with(new, "("))
        or (first_line_ends_with(orig, "{") and not first_line_ends_with(new, "{"))
        or (first_line_ends_with(orig, "[") and not first_line_ends_with(new, "["))
    )


def rhs(lhs: str, e: Node, shape: Shape) -> str | None:
    """rustfmt's `rewrite_assign_rhs`: `lhs` ends with the operator (`x =`, `let y =`)."""
    llw = last_line_width(lhs) - (shape.indent_width() if "\n" in lhs else 0)
    orig_shape = shape.offset_left(llw + 1) or Shape(0, shape.block, shape.align, shape.offset + llw + 1)
    orig = e.rewrite(orig_shape)
    if orig is not None and "\n" not in orig and len(orig) <= orig_shape.width:
        return f"{lhs} {orig}"
    ind = Shape.indented(orig_shape.block + TAB, orig_shape.align)
    new_shape = ind.sub_width(orig_shape.rhs_overhead())
    if new_shape is None:
        return None
    new = e.rewrite(new_shape)
    new_indent = _nl(orig_shape.block + TAB + orig_shape.align)
    if orig is not None and new is not None:
        if not fits(new, new_shape):
            return f"{lhs} {orig}"
        if _prefer_next_line(orig, new):
            return lhs + new_indent + new
        return f"{lhs} {orig}"
    if new is not None:
        return lhs + new_indent + new
    if orig is not None:
        return f"{lhs} {orig}"
    return None


def _lines(text: str, indent: int) -> list[str]:
    return (pad(indent) + text).split("\n")


def assign(lhs: str, op: str, value: Node, indent: int) -> list[str]:
    """`lhs op value;` (op: `=`, `+=`, ...); also `let x = value;` and
    `const X: T = value;` (give the whole left-hand side in `lhs`)."""
    shape = Shape.indented(TAB * indent).sub_width(1)
    assert shape is not None
    lhs_shape = shape.sub_width(len(op) + 1)
    target = Atom(lhs).rewrite(lhs_shape) if lhs_shape is not None else None
    text = rhs(f"{target or lhs} {op}", value, shape)
    if text is None:
        text = f"{lhs} {op} {value.flat()}"
    return _lines(text + ";", indent)


def let(name: str, value: Node, indent: int) -> list[str]:
    return assign(f"let {name}", "=", value, indent)


def expr_stmt(e: Node, indent: int) -> list[str]:
    """`e;`"""
    shape = Shape.indented(TAB * indent).sub_width(1)
    assert shape is not None
    text = _stmt_rewrite(e, shape) or e.flat()
    return _lines(text + ";", indent)


def tail(e: Node, indent: int) -> list[str]:
    """`e` as a block's last expression."""
    text = _stmt_rewrite(e, Shape.indented(TAB * indent)) or e.flat()
    return _lines(text, indent)


def if_open(cond: Node, indent: int, keyword: str = "if") -> list[str]:
    """The head of an `if` statement (keyword `if`) or of an `} else if` (keyword
    `} else if`), ending in `{` (on its own line when rustfmt puts it there)."""
    shape = Shape.indented(TAB * indent)
    nested = keyword != "if"
    head = If(cond, Atom(""), Atom("")).head(shape, allow_single_line=False, nested=nested)
    text = head[0] if head is not None else f"if {cond.flat()} "
    prefix = "} else " if nested else ""
    return _lines(prefix + text + "{", indent)
