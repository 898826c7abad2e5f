"""Controller types and function blocks, instantiated into ordinary controllers.

A `controller type Axis(max: f64, out: gm) level 1 budget 1 ms { ... }` is a
template; `controller XAX: Axis(max = 2.0, out = x_cmd)` makes a controller
`XAX` whose body is a copy of the template's, with every value parameter
replaced by its argument (a compile-time constant, checked by the semantic
pass with the parameter's type) and every `gm` parameter by the Global
Memory variable or field it is bound to (in expressions, in assignment
targets and in `reads`/`writes` lists).

A `block PID(kp: f64, ...) { input e: f64 = 0.0  state i: f64 = 0.0
output y: f64 = 0.0  step { ... } }` is a function block.  `block pid: PID(kp
= 1.0)` in a controller gives it one instance: each input becomes a local
`pid__e`, each state and output a status field `pid__i`, `pid__y` (so they
are in the trace, among the controller's fields); the statement `pid(e =
x)` (in `pre`, `post` or a job list) becomes `pid__e = x` followed by a copy of
the step's assignments, and `pid.y` reads the output `pid__y`.

So the checks, the simulator and every backend see ordinary controllers.
Each copy's spans point into the template, in a per-instance copy of its
source file (`InstanceSource`): `Diagnostics.add` maps them back to the real
file and adds a label at the instance ("in instance `XAX` of `Axis`"), so a
finding inside a type names the instance it was found in.
"""

from __future__ import annotations

import dataclasses

from rcsc.front import ast
from rcsc.diagnostics import Diagnostics, closest
from rcsc.front.source import SourceFile, Span

SEP = "__"  # between a block instance's name and its member's


class InstanceSource(SourceFile):
    """A source file seen through one instance: same path and text as
    `origin`; `instance` is (label message, span of the instance)."""

    origin: SourceFile
    instance: tuple[str, Span]


def instance_source(origin: SourceFile, message: str, where: Span) -> InstanceSource:
    src = object.__new__(InstanceSource)
    src.path, src.text, src._line_starts = origin.path, origin.text, origin._line_starts
    src.origin, src.instance = origin, (message, where)
    return src


class _Copier:
    """A deep copy of AST nodes with spans in `origin` moved to `clone` and
    names substituted by `name_of` (Name -> Expr or None: unchanged)."""

    def __init__(self, origin: SourceFile, clone: SourceFile) -> None:
        self.origin, self.clone = origin, clone

    def name(self, node: ast.Name):  # overridden
        return None

    def attr(self, node: ast.Attr):  # overridden
        return None

    def assign(self, node: ast.Assign):  # overridden
        return None

    def copy(self, x):
        if isinstance(x, Span):
            return Span(self.clone, x.start, x.end) if x.file is self.origin else x
        if isinstance(x, list):
            return [self.copy(i) for i in x]
        if isinstance(x, tuple):
            return tuple(self.copy(i) for i in x)
        if isinstance(x, ast.Name):
            got = self.name(x)
            if got is not None:
                return got
        elif isinstance(x, ast.Attr):
            got = self.attr(x)
            if got is not None:
                return got
        elif isinstance(x, ast.Assign):
            got = self.assign(x)
            if got is not None:
                return got
        if isinstance(x, ast.Node):
            new = object.__new__(type(x))
            for f in dataclasses.fields(x):
                setattr(new, f.name, self.copy(getattr(x, f.name)))
            depth = getattr(x, "depth", None)
            if depth is not None:
                new.depth = depth
            return new
        return x


def _bind(params, args: list[ast.Arg], what: str, site: ast.Ident, diags: Diagnostics) -> dict[str, ast.Arg] | None:
    """Arguments matched to parameters by name (or position); None after a finding."""
    bound: dict[str, ast.Arg] = {}
    names = [p.name.name for p in params]
    ok = True
    for i, a in enumerate(args):
        if a.name is None:
            if i >= len(names):
                diags.add("E0262", a.span, f"too many arguments for {what}", "extra argument").with_note(
                    f"{what} has {len(names)} parameter{'s' if len(names) != 1 else ''}"
                )
                ok = False
                continue
            key = names[i]
        else:
            key = a.name.name
            if key not in names:
                diag = diags.add("E0262", a.name.span, f"{what} has no parameter `{key}`", "unknown parameter")
                diag.with_note("parameters: " + (", ".join(f"`{n}`" for n in names) or "none"))
                # A misspelt parameter that no other argument names stands
                # for it (not also "needs `lo`", and the instance is made).
                given = {b.name.name for b in args if b.name is not None} | set(bound)
                meant = diag.guess(key, [n for n in names if n not in given])
                if meant is None:
                    ok = False
                    continue
                key = meant
        if key in bound:
            diags.add("E0262", a.span, f"parameter `{key}` is given more than once", "repeated argument")
            ok = False
            continue
        bound[key] = a
    missing = [n for n in names if n not in bound]
    if missing:
        diags.add("E0261", site.span, f"{what} needs " + ", ".join(f"`{n}`" for n in missing), "missing argument" + ("s" if len(missing) > 1 else "")).with_help(
            "give every parameter a value: " + ", ".join(f"{n} = ..." for n in missing)
        )
        ok = False
    return bound if ok else None


def _gm_path(e: ast.Expr) -> list[ast.Ident] | None:
    """`a.b.c` as identifiers (what a `gm` parameter may be bound to)."""
    if isinstance(e, ast.Name):
        return [ast.Ident(e.span, e.name)]
    if isinstance(e, ast.Attr):
        head = _gm_path(e.obj)
        return None if head is None else head + [e.attr]
    return None


def _walk(x):
    """The syntax nodes in `x` (a node or a list of them), in order, `x` first."""
    if isinstance(x, list):
        for y in x:
            yield from _walk(y)
    elif isinstance(x, ast.Node):
        yield x
        for f in dataclasses.fields(x):
            if f.name != "span":
                yield from _walk(getattr(x, f.name))


def _memory_read(value: ast.Expr, gm) -> ast.Name | None:
    """The first name of a variable (`gm`: its names) in a value parameter's argument."""
    return next((n for n in _walk(value) if isinstance(n, ast.Name) and n.name in gm), None)


def _memory_argument(p: ast.Param, value: ast.Expr, variables: dict[str, str], what: str, diags: Diagnostics) -> bool:
    """E0204 for a value parameter given a variable (`variables`: name -> what
    it is, "a Global Memory variable", "a local of `C`"): a value parameter
    is a constant of the instance.  Reported once, here, instead of as a read
    the body does not declare and again as a non-constant."""
    name = _memory_read(value, variables)
    if name is None:
        return False
    diag = diags.add("E0204", name.span, f"`{name.name}` is {variables[name.name]}: value parameter `{p.name.name}` of {what} takes a constant",
                     "a variable").with_label(p.name.span, "a value parameter")
    if what.startswith("controller type"):
        diag.with_help(f"to give each instance a variable, declare `{p.name.name}: gm` and read it with `reads {p.name.name}` in the type")
    else:
        diag.with_help(f"to pass a variable on every step, declare `{p.name.name}` as an `input` of the block and give it in the call")
    return True


def _has_int_literal(x) -> bool:
    return any(isinstance(n, ast.IntLit) for n in _walk(x))


def _typed(value: ast.Expr, t: ast.TypeRef | None) -> ast.Expr:
    """A value parameter's argument where the parameter is used.  Integer
    literals take their type from where they stand (docs/language.md §4), so an
    argument made with them is converted to the parameter's declared type:
    with `k: u32 = 4294967295`, `-k` wraps as a u32 (not an out-of-range
    literal), and with `g: f64 = 2`, `g / 4` is 0.5 wherever it stands (not an
    i32 division) -- as with a typed constant.  An array written out
    (`[4294967295, 2]`, `[2; 4]`) for a `[u32; 2]` parameter has each element
    converted to the element type, at any depth."""
    if t is None or not _has_int_literal(value):
        return value
    if t.elem is not None:
        if isinstance(value, ast.ArrayLit):
            items = [_typed(x, t.elem) for x in value.items]
            out: ast.Expr = ast.ArrayLit(value.span, items)
        elif isinstance(value, ast.ArrayRepeat):
            out = ast.ArrayRepeat(value.span, _typed(value.value, t.elem), value.count)
        else:
            return value
        depth = getattr(value, "depth", None)
        if depth is not None:
            out.depth = depth + 1
        return out
    if t.name.name not in ("i32", "i64", "u32", "f64"):
        return value
    call = ast.Call(value.span, ast.Ident(value.span, t.name.name), [ast.Arg(value.span, None, value)])
    depth = getattr(value, "depth", None)
    if depth is not None:
        call.depth = depth + 1
    return call


class _TypeCopier(_Copier):
    def __init__(self, origin, clone, values: dict[str, ast.Expr], gms: dict[str, list[ast.Ident]], diags: Diagnostics) -> None:
        super().__init__(origin, clone)
        self.values, self.gms, self.d = values, gms, diags

    def name(self, node):
        if node.name in self.values:
            return self.values[node.name]
        if node.name in self.gms:
            path = self.gms[node.name]
            e: ast.Expr = ast.Name(path[0].span, path[0].name)
            for part in path[1:]:
                e = ast.Attr(path[0].span.to(part.span), e, part)
                e.depth = 1
            return e
        return None

    def copy(self, x):
        # `age(p)` of a `gm` parameter: the age of the variable it is bound
        # to, its whole variable for a field (stamps belong to variables), as
        # in `reads` and `writes`; the field itself would not be a name.
        if (isinstance(x, ast.Call) and x.func.name == "age" and len(x.args) == 1 and x.args[0].name is None
                and isinstance(x.args[0].value, ast.Name) and x.args[0].value.name in self.gms):
            head = self.gms[x.args[0].value.name][0]
            new = self.copy_node(x)
            new.args = [ast.Arg(new.args[0].span, None, ast.Name(head.span, head.name))]
            return new
        return super().copy(x)

    def assign(self, node):
        head = node.target[0].name
        if head in self.values:
            self.d.add("E0264", Span(self.clone, node.target[0].span.start, node.target[0].span.end),
                       f"`{head}` is a parameter of the controller type, a constant", "assigned here").with_help(
                "declare a `local` or `status` field for a value that changes")
            return None
        if head in self.gms:
            new = self.copy_node(node)
            new.target = list(self.gms[head]) + new.target[1:]
            return new
        return None

    def copy_node(self, node):
        new = object.__new__(type(node))
        for f in dataclasses.fields(node):
            setattr(new, f.name, self.copy(getattr(node, f.name)))
        depth = getattr(node, "depth", None)
        if depth is not None:
            new.depth = depth
        return new


def expand(files, diags: Diagnostics) -> list[list[ast.Node]]:
    """The top-level items of each loaded file (`rcsc.front.loader.LoadedFile`),
    with controller instances made into controllers and block instances lowered."""
    ctypes: dict[str, ast.ControllerType] = {}
    btypes: dict[str, ast.BlockType] = {}
    broken: set[str] = set()  # types with repeated parameters: reported once, not instantiated
    gm: dict[str, str] = {}  # Global Memory names (a value parameter given one is E0204)
    for f in files:
        if f.tree is None:
            continue
        for item in f.tree.items:
            if isinstance(item, ast.ControllerType):
                ctypes.setdefault(item.name.name, item)
            elif isinstance(item, ast.BlockType):
                btypes.setdefault(item.name.name, item)
            elif isinstance(item, ast.GmVar):
                gm[item.name.name] = "a Global Memory variable"
    used: set[str] = set()
    for t in [*ctypes.values(), *btypes.values()]:
        seen: set[str] = set()
        for p in t.params:
            if p.name.name in seen:
                diags.add("E0101", p.name.span, f"parameter `{p.name.name}` is defined more than once", "repeated parameter")
                used.add(t.name.name)
                broken.add(t.name.name)
            seen.add(p.name.name)
    for t in ctypes.values():  # a block a type uses is used (its findings come with the type's instances)
        used.update(u.type_name.name for u in t.body.blocks)
    out: list[list[ast.Node]] = []
    for f in files:
        items: list[ast.Node] = []
        out.append(items)
        if f.tree is None:
            continue
        for item in f.tree.items:
            if isinstance(item, ast.ControllerInstance):
                ctrl = None if item.type_name.name in broken else _instantiate(item, ctypes, used, diags, gm)
                if ctrl is None:
                    items.append(_placeholder(item))
                    continue
                _lower_blocks(ctrl, btypes, used, diags, broken, gm)
                items.append(ctrl)
            elif isinstance(item, ast.Controller) and item.blocks:
                ctrl = _Copier(None, None).copy(item)  # the tree stays what was written
                _lower_blocks(ctrl, btypes, used, diags, broken, gm)
                items.append(ctrl)
            else:
                items.append(item)
    for f in files:
        if f.tree is None or not f.is_root:
            continue
        for item in f.tree.items:
            if isinstance(item, (ast.ControllerType, ast.BlockType)) and item.name.name not in used:
                what = "controller type" if isinstance(item, ast.ControllerType) else "block"
                diags.add("W0260", item.name.span, f"{what} `{item.name.name}` is never instantiated", "never used").with_note(
                    "the body of a type is checked in each of its instances; with none, it is not checked at all"
                )
    return out


def _placeholder(item: ast.ControllerInstance) -> ast.Controller:
    """A controller with nothing in it, so that uses of the name are not also unknown."""
    ctrl = ast.Controller(item.span, item.name, item.simulator)
    ctrl.placeholder = True
    return ctrl


def _instantiate(item: ast.ControllerInstance, ctypes: dict[str, ast.ControllerType], used: set[str], diags: Diagnostics,
                 gm: dict[str, str]) -> ast.Controller | None:
    t = ctypes.get(item.type_name.name)
    if t is None:
        diag = diags.add("E0260", item.type_name.span, f"no controller type named `{item.type_name.name}`", "unknown controller type")
        diag.with_note("controller types: " + (", ".join(f"`{n}`" for n in sorted(ctypes)) or "none declared"))
        meant = diag.guess(item.type_name.name, ctypes)
        if meant is not None:  # not also "never instantiated" (W0260)
            used.add(meant)
        return None
    used.add(t.name.name)
    what = f"controller type `{t.name.name}`"
    bound = _bind(t.params, item.args, what, item.type_name, diags)
    if bound is None:
        return None
    values: dict[str, ast.Expr] = {}
    gms: dict[str, list[ast.Ident]] = {}
    ok = True
    for p in t.params:
        arg = bound[p.name.name]
        if p.type is None:
            path = _gm_path(arg.value)
            if path is None:
                diags.add("E0263", arg.value.span, f"`{p.name.name}` is a `gm` parameter: bind it to a Global Memory variable or field",
                          "not a Global Memory name").with_label(p.span, "declared `gm` here")
                ok = False
                continue
            root = path[0].name
            if root not in gm and closest(root, gm) is None:
                # A constant or another name that is no Global Memory (a
                # misspelt variable is reported, with its guess, where the
                # instance `reads` or `writes` it).
                diags.add("E0263", path[0].span, f"`{p.name.name}` is a `gm` parameter: `{root}` is not a Global Memory variable",
                          "not a Global Memory name").with_label(p.span, "declared `gm` here")
                ok = False
                continue
            gms[p.name.name] = path
        elif _memory_argument(p, arg.value, gm, what, diags):
            ok = False
        else:
            values[p.name.name] = _typed(arg.value, p.type)
    if not ok:
        return None
    origin = t.span.file
    clone = instance_source(origin, f"in instance `{item.name.name}` of `{t.name.name}` declared here", item.name.span)
    cp = _TypeCopier(origin, clone, values, gms, diags)
    body = t.body
    ctrl = ast.Controller(Span(clone, body.span.start, body.span.end), item.name, item.simulator)
    for f in dataclasses.fields(ast.Controller):
        if f.name in ("span", "name", "simulator"):
            continue
        setattr(ctrl, f.name, cp.copy(getattr(body, f.name)))
    # `reads`/`writes` of a `gm` parameter: the bound variable's name, once:
    # two parameters bound to two fields of one variable (`x = pos.x, y =
    # pos.y`) read or write that variable, which is not listed twice.
    for lists in (ctrl.reads, ctrl.writes):
        bound_here: set[str] = set()
        for nl in lists:
            names = []
            for i in nl.names:
                if i.name in gms:
                    head = gms[i.name][0]
                    if head.name in bound_here:
                        continue
                    bound_here.add(head.name)
                    i = head
                names.append(i)
            nl.names = names
    for decl in ctrl.status_fields + ctrl.locals:
        if decl.name.name in values or decl.name.name in gms:
            diags.add("E0264", decl.name.span, f"`{decl.name.name}` is also a parameter of `{t.name.name}`", "hides the parameter")
    ctrl.param_args = [(p, bound[p.name.name].value) for p in t.params if p.type is not None]
    if item.doc is not None:  # the instance's own doc comment, else the type's (copied with the template)
        ctrl.doc = item.doc
    return ctrl


# ---- function blocks ---------------------------------------------------------------


class _Inst:
    """One block instance of a controller."""

    def __init__(self, use: ast.BlockUse, t: ast.BlockType, args: dict[str, ast.Arg], clone: SourceFile) -> None:
        self.use, self.t, self.args, self.clone = use, t, args, clone
        self.members = {mb.name.name: mb for mb in t.members}

    def mangled(self, member: str) -> str:
        return self.use.name.name + SEP + member


class _StepCopier(_Copier):
    """A block's step or member initial value, inside one instance."""

    def __init__(self, inst: _Inst, diags: Diagnostics) -> None:
        super().__init__(inst.t.span.file, inst.clone)
        self.inst, self.d = inst, diags

    def name(self, node):
        arg = self.inst.args.get(node.name)
        if arg is not None:
            return _typed(arg.value, next((p.type for p in self.inst.t.params if p.name.name == node.name), None))
        if node.name in self.inst.members:
            return ast.Name(self.copy(node.span), self.inst.mangled(node.name))
        return None

    def assign(self, node):
        head = node.target[0]
        mb = self.inst.members.get(head.name)
        if mb is None or mb.kind == "input":
            what = "a parameter" if head.name in self.inst.args else "an input" if mb is not None else "not a member of the block"
            self.d.add("E0265", self.copy(head.span), f"a block's step assigns only its `state` and `output` members; `{head.name}` is {what}",
                       "assigned here").with_help("declare it in the block: `state NAME: TYPE = VALUE`")
            return None
        new = object.__new__(ast.Assign)
        new.span = self.copy(node.span)
        new.target = [ast.Ident(self.copy(head.span), self.inst.mangled(head.name)), *self.copy(node.target[1:])]
        new.op = node.op
        new.value = self.copy(node.value)
        new.index = self.copy(node.index)  # `s[i] = v` in a step: an element of an array member
        depth = getattr(node, "depth", None)
        if depth is not None:
            new.depth = depth
        return new


def _lower_blocks(ctrl: ast.Controller, btypes: dict[str, ast.BlockType], used: set[str], diags: Diagnostics, broken: set[str],
                 gm: dict[str, str]) -> None:
    insts: dict[str, _Inst] = {}
    # What a block's value parameter may not be given: a variable of the design or of this controller.
    variables = gm | {d.name.name: f"a local of `{ctrl.name.name}`" for d in ctrl.locals} | {
        d.name.name: f"a status field of `{ctrl.name.name}`" for d in ctrl.status_fields}
    taken = {d.name.name for d in ctrl.status_fields + ctrl.locals}
    for use in ctrl.blocks:
        if use.type_name.name in broken:
            ctrl.poisoned.append(use.name.name)
            continue
        t = btypes.get(use.type_name.name)
        if t is None:
            diag = diags.add("E0260", use.type_name.span, f"no block named `{use.type_name.name}`", "unknown block")
            diag.with_note("blocks: " + (", ".join(f"`{n}`" for n in sorted(btypes)) or "none declared") + " (`import std.blocks` for the standard ones)")
            meant = diag.guess(use.type_name.name, btypes)
            if meant is not None:  # not also "never instantiated" (W0260)
                used.add(meant)
            ctrl.poisoned.append(use.name.name)
            continue
        used.add(t.name.name)
        ctrl.poisoned.append(use.name.name)
        if use.name.name in insts or use.name.name in taken:
            diags.add("E0267", use.name.span, f"`{use.name.name}` is defined more than once in `{ctrl.name.name}`", "second definition")
            continue
        args = _bind(t.params, use.args, f"block `{t.name.name}`", use.type_name, diags)
        if args is None:
            continue
        memory = [_memory_argument(p, args[p.name.name].value, variables, f"block `{t.name.name}`", diags) for p in t.params if p.name.name in args]
        if any(memory):
            continue
        if not t.steps:
            diags.add("E0265", t.name.span, f"block `{t.name.name}` has no `step`", "no step").with_help("add `step { NAME = EXPR; }`")
        for extra in t.steps[1:]:
            diags.add("E0265", extra[0], f"block `{t.name.name}` has more than one `step`", "second step")
        clone = instance_source(t.span.file, f"in block `{use.name.name}` of `{ctrl.name.name}` declared here", use.name.span)
        inst = _Inst(use, t, args, clone)
        # Checked as constants of their parameters' types (E0204, E0206), as a
        # controller type's are: their uses are converted to those types (`_typed`).
        ctrl.param_args = ctrl.param_args + [(p, args[p.name.name].value) for p in t.params if p.name.name in args]
        insts[use.name.name] = inst
        cp = _StepCopier(inst, diags)
        for _, body in t.steps[:1]:
            cp.copy(body)  # reports assignments to inputs and parameters, once per instance
        for mb in t.members:
            if mb.name.name in args:
                diags.add("E0264", cp.copy(mb.name.span), f"`{mb.name.name}` is also a parameter of block `{t.name.name}`", "hides the parameter")
            decl = ast.Decl(cp.copy(mb.span), ast.Ident(cp.copy(mb.name.span), inst.mangled(mb.name.name)), cp.copy(mb.type), cp.copy(mb.init),
                            mb.doc)
            (ctrl.locals if mb.kind == "input" else ctrl.status_fields).append(decl)
        for _, body in t.steps[:1]:
            for st in body:
                if not isinstance(st, ast.Assign):
                    diags.add("E0265", cp.copy(st.span), "a block's step is a list of assignments", "not an assignment").with_help(
                        "write a choice as an expression: `y = if c then a else b;`")
    if not insts and not ctrl.blocks:
        return
    lower = _UseCopier(ctrl, insts, diags)
    ctrl.pre = [(sp, lower.stmts(body)) for sp, body in ctrl.pre]
    ctrl.post = [(sp, lower.stmts(body)) for sp, body in ctrl.post]
    for plan in ctrl.plans:
        for r in plan.rules:
            if r.guard is not None:
                r.guard = lower.copy(r.guard)
            r.jobs = lower.stmts(r.jobs)
    for d in ctrl.status_fields + ctrl.locals:
        d.init = lower.copy(d.init)
    for name, inst in insts.items():
        if name not in lower.called:
            diags.add("W0261", inst.use.name.span, f"block instance `{name}` is never called", "never called").with_help(
                f"run one step of it each cycle: `pre {{ {name}(...); }}`, or remove it"
            ).with_note("its outputs keep their initial values, and its step is not checked")


class _UseCopier(_Copier):
    """The controller's own code: block calls expanded, outputs read by name."""

    def __init__(self, ctrl: ast.Controller, insts: dict[str, _Inst], diags: Diagnostics) -> None:
        super().__init__(None, None)
        self.ctrl, self.insts, self.d = ctrl, insts, diags
        self.blocks = {u.name.name for u in ctrl.blocks}
        self.called: set[str] = set()

    def stmts(self, body: list[ast.Stmt]) -> list[ast.Stmt]:
        out: list[ast.Stmt] = []
        for st in body:
            if isinstance(st, ast.CallStmt) and st.call.func.name in self.blocks:
                inst = self.insts.get(st.call.func.name)
                if inst is not None:
                    self.called.add(inst.use.name.name)
                    out.extend(self.call(inst, st))
                continue
            if isinstance(st, ast.If):
                new = self.copy(st)
                new.branches = [(self.copy(c), self.stmts(b)) for c, b in st.branches]
                new.else_body = None if st.else_body is None else self.stmts(st.else_body)
                out.append(new)
                continue
            out.append(self.copy(st))
        return out

    def call(self, inst: _Inst, st: ast.CallStmt) -> list[ast.Stmt]:
        inputs = [mb for mb in inst.t.members if mb.kind == "input"]
        out: list[ast.Stmt] = []
        ranks: list[int] = []
        seen: set[str] = set()
        for i, a in enumerate(st.call.args):
            if a.name is None:
                mb = inputs[i] if i < len(inputs) else None
                if mb is None:
                    self.d.add("E0262", a.span, f"too many inputs for block `{inst.use.name.name}`", "extra input").with_note(
                        f"block `{inst.t.name.name}` has {len(inputs)} input{'s' if len(inputs) != 1 else ''}")
                    continue
            else:
                mb = inst.members.get(a.name.name)
                if mb is None or mb.kind != "input":
                    diag = self.d.add("E0262", a.name.span, f"block `{inst.t.name.name}` has no input `{a.name.name}`", "not an input")
                    diag.with_note("inputs: " + (", ".join(f"`{m.name.name}`" for m in inputs) or "none"))
                    given = {b.name.name for b in st.call.args if b.name is not None}
                    diag.guess(a.name.name, [m.name.name for m in inputs if m.name.name not in given])
                    continue
            if mb.name.name in seen:
                self.d.add("E0262", a.span, f"input `{mb.name.name}` is given more than once", "repeated input")
                continue
            seen.add(mb.name.name)
            target = ast.Ident(a.span, inst.mangled(mb.name.name))
            assign = ast.Assign(a.span, [target], "=", self.copy(a.value))
            assign.depth = getattr(a.value, "depth", 1) + 1
            out.append(assign)
            ranks.append(inputs.index(mb))
        # Inputs are evaluated in the order of the block's inputs, as the
        # arguments of any call are in the order of its parameters
        # (docs/language.md, "Order of evaluation"), whatever order names them.
        out = [x for _, x in sorted(zip(ranks, out), key=lambda pair: pair[0])]
        cp = _StepCopier(inst, Diagnostics())  # the step's own findings were reported once, at the instance
        for _, body in inst.t.steps[:1]:
            out.extend(cp.copy(s) for s in body if isinstance(s, ast.Assign) and _assignable(inst, s))
        return out

    def name(self, node):
        if node.name in self.blocks:
            self.d.add("E0266", node.span, f"`{node.name}` is a block instance, not a value", "block instance").with_help(
                f"read one of its outputs: `{node.name}.OUTPUT`; run it with `{node.name}(INPUT = ...)`")
            return None
        return None

    def attr(self, node):
        if isinstance(node.obj, ast.Name) and node.obj.name in self.insts:
            inst = self.insts[node.obj.name]
            mb = inst.members.get(node.attr.name)
            if mb is None or mb.kind != "output":
                what = f"the {mb.kind} `{mb.name.name}`" if mb is not None else f"`{node.attr.name}`, which it does not have"
                diag = self.d.add("E0266", node.span, f"`{node.obj.name}.{node.attr.name}` reads {what} of block `{inst.t.name.name}`; only outputs can be read",
                                  "not an output")
                outs = [m.name.name for m in inst.t.members if m.kind == "output"]
                diag.with_note("outputs: " + (", ".join(f"`{o}`" for o in outs) or "none"))
                return node  # as written: not copied further (one finding)
            return ast.Name(node.span, inst.mangled(mb.name.name))
        if isinstance(node.obj, ast.Name) and node.obj.name in self.blocks:
            return node  # an instance that could not be made (reported): its outputs are unknown, not a second finding
        return None

    def assign(self, node):
        head = node.target[0].name
        if head in self.blocks:
            self.d.add("E0266", node.target[0].span.to(node.target[-1].span), f"the members of block `{head}` are written only by its step",
                       "assigned here").with_help(f"pass a value as an input: `{head}(INPUT = VALUE)`")
            return None
        return None


def _assignable(inst: _Inst, st: ast.Assign) -> bool:
    mb = inst.members.get(st.target[0].name)
    return mb is not None and mb.kind != "input"
