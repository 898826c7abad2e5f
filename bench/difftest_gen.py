"""Random valid designs and scenarios for the differential tester (bench/difftest.py).

`generate(seed)` returns a `Case`: the text of a design that `rcsc check`
accepts without errors and the text of a scenario for it.  The same seed gives
the same bytes.  The generator covers the whole language: every scalar type
and every conversion between them, numeric edges (wrap-around, division by
zero, MIN / -1, saturating float-to-int, NaN, infinities, -0.0), enums,
nested records, constants, pure functions, std.math, `pre`/`post` blocks with
`if`/`elif`/`else`, plans with `new`, `*`, `otherwise`, `in_state`, `done`,
the math built-ins and `cycle` (from a stream of their own, around the
values assigned),
`error(c)`, `report`, subordinates commanded with arguments, status fields,
simulators and `from env` inputs; the scenario sends commands with arguments
to the root, sets the inputs to edge values and runs a number of cycles.

Heavy arithmetic is put in statements (whose results reach the trace through
status fields and Global Memory), conditions of rules stay small, so that the
guard analysis of `rcsc check` stays fast.  A design that still does not check
clean (a condition that happens to be always false, say) is drawn again from
the next sub-seed; `Case.attempt` says how many draws it took.

Integer `if` expressions whose branches are both constants are drawn where
the context gives them no type (`i32(if c then u32(1) else u32(4294967295))`,
`(if c then u32(4294967295) else u32(3)) == 2147483648`): the Rust target
once left such literals to rustc's inference.  Extern functions (declared,
called from controllers, never from a pure `fn`) come from a random stream
of their own.

Arrays, controller types and function blocks come from streams of their own
(a seed that draws none of them keeps its design).  About half the seeds
declare arrays `[T; N]` of every element type (f64 with NaN and -0.0
elements, arrays of arrays and of records, N a literal or an integer
constant) as constants, inputs (the scenario sets them), Global Memory,
status fields, locals, a record field and function parameters, and read
them with constant indices, indices out of range and indices from inputs
and `cycle` (out of range at run time), `len`, `sum`, `min_of` and
`max_of`; they assign elements and whole arrays.  In about a third, one
subordinate is a controller type instantiated two or three times under the
same supervisor with its own value parameters and `gm` bindings; in about
a third, controllers hold function blocks (`std.blocks`, and a block of the
design's own with an array state) that they step in `pre`/`post` and job
lists and whose outputs they read.

Verbs take array parameters (the supervisor passes a whole array, a
literal or a function's result; the scenario passes literals to the root),
functions return arrays, a simulator may be a `simulator type` with
instances, and a supervisor reads its subordinates' block outputs
(`SUB.INSTANCE__OUTPUT`).  Rates and CPUs come from a stream of their own:
in about half the seeds the controllers are placed on one to three CPUs
with harmonic heartbeats (5 to 500 ms), a third of them run at a divided
rate (`period`), conditions and statements read `age(...)` of Global Memory
and of subordinates, and the scenario (counting base ticks) freezes a
controller or stops a CPU.

Eight more streams of their own (29 November 2026, later), each decided
once per seed, so that a seed that draws none of them keeps its design and
scenario byte for byte: ranges `T in lo..hi` (on constants, Global Memory,
status fields, locals, record fields, verb parameters, value parameters of
controller types, and the parameters and results of functions and externs;
every constant, initial value and command argument of the scenario inside
its range, values assigned at run time and the scenario's inputs not);
verb sets of the design's own and std.lifecycle's (`verbs NAME`);
simulators with verbs, commanded by a supervisor or, outside the command
tree, by the scenario; `gm` parameters of controller types bound to a field
of a record in Global Memory, `gm` parameters that are read (each instance
binds its own variable or field) and a controller type's `period`; extern
calls as statements and as jobs (their results unused, their calls in the
journal); arguments by name out of order, after positional ones (commands,
functions, externs, records, blocks, instances: the language evaluates them
in the order of the parameters); the scenario's `expect` lines (`at`,
`within`, `always`, `final`, over statuses, states, verbs, status fields
and Global Memory), which the harness evaluates again on each program's
trace; and stub plans (a continuous plan with one entry rule into a state
with no rules).

`hostile=True` draws names that are reserved words or well-known macros of C
and Rust, names that collide once joined with `_`, and very long names:
problems of the targets' naming, found behind that option only.
"""

from __future__ import annotations

import contextlib
import random
import re
from dataclasses import dataclass, field

INT_TYPES = ("i32", "i64", "u32")
NUM_TYPES = ("i32", "i64", "u32", "f64")
SCALARS = ("bool", "i32", "i64", "u32", "f64", "duration")
HEARTBEAT_MS = 10
INT_BOUNDS = {"i32": (-2**31, 2**31 - 1), "i64": (-2**63, 2**63 - 1), "u32": (0, 2**32 - 1)}
# Bounds of f64 and duration ranges (the range stream), besides the values a range must hold.
FLOAT_BOUNDS = ["-1.7976931348623157e308", "-1e300", "-1000.0", "-1", "-0.5", "0", "0.0", "-0.0", "0.5", "1.0", "30",
                "1e16", "1e300", "1.7976931348623157e308"]
DURATION_BOUNDS = ["(-9223372036 s)", "(-1 s)", "0 ms", "1 us", "10 ms", "1 s", "100 s", "9223372036 s"]
INT_LITERAL = re.compile(r"\(?-?(0x[0-9A-Fa-f_]+|[0-9_]+)\)?")

INT_EDGES = {
    "i32": ["0", "1", "-1", "7", "-7", "3", "2147483647", "-2147483648", "0x7fff_ffff", "1_000", "65536", "46341"],
    "i64": ["0", "1", "-1", "-7", "9223372036854775807", "-9223372036854775808", "4294967296", "3037000500", "100_000"],
    "u32": ["0", "1", "7", "4294967295", "2147483648", "0xFFFF_FFFF", "65536", "3"],
}
FLOAT_EDGES = ["0.0", "-0.0", "1.0", "-1.0", "0.5", "0.1", "2.5e3", "1e300", "-1e300", "5e-324", "2147483647.5",
               "-2147483648.9", "4294967295.5", "9.3e18", "-9.3e18", "1e-7", "3.0", "123.456"]
# Operands of the math built-ins: signed zeros, halves (round_even), NaN,
# infinities, subnormals, huge values, the largest halves below 2^52.
MATH_EDGES = ["0.0", "(-0.0)", "0.5", "(-0.5)", "1.5", "2.5", "(-2.5)", "(-3.5)", "0.49999999999999994",
              "4503599627370495.5", "(-4503599627370495.5)", "1e300", "(-1e300)", "5e-324", "1.7976931348623157e308",
              "(0.0 / 0.0)", "(1.0 / 0.0)", "(-1.0 / 0.0)", "2.0", "(-2.0)", "1e16"]
MATH_FUNCS = ("sqrt", "floor", "ceil", "trunc", "round_even", "copysign", "min", "max")
DURATIONS = ["0 ms", "10 ms", "20 ms", "30 ms", "50 ms", "100 ms", "1 s", "500 us", "1.5 ms", "2 s"]
# The "more" stream's edges (DesignGen.more): integer literals where an f64
# is expected (2^53 + 1 is not a double), durations near the ends of i64
# nanoseconds, NaN and infinities as scalar values.
F64_INT_LITERALS = ["2", "0", "(-3)", "7", "1000000", "9007199254740993", "(-2147483648)", "4294967296"]
BIG_DURATIONS = ["9223372036 s", "(-9223372036 s)", "1000000 s", "9223372036854 ms", "(-1 us)", "1 us"]
F64_SPECIALS = ["(0.0 / 0.0)", "(1.0 / 0.0)", "(-1.0 / 0.0)", "(-(0.0 / 0.0))"]
# Doc comments, which every target copies into a comment of its own: the
# ends and openings of C, Rust and Ada comments, a line-continuing
# backslash, a trigraph, format and markup characters, non-ASCII text.
DOC_TEXTS = ["ends with a backslash \\", "closes */ a C comment", "opens /* one", "a trigraph ??/", "an Ada -- comment",
             "a Rust //! doc and #[attr]", "units: µs, °C, ±0.5 — done", "tab\tinside", "`code`, *stars* and %d %s {}",
             "quotes \" and ' and \\n", "}}} {{{ {% raw %}", "ends with a slash /"]

# std.lifecycle's verb sets (`verbs NAME`).
STD_VERBSETS = {"Lifecycle": [("INIT", []), ("HALT", []), ("ABORT", [])], "Basic": [("INIT", []), ("HALT", [])]}

# std.math functions by result type: (name, parameter types).
STD_MATH = {
    "f64": [("clamp", ("f64", "f64", "f64")), ("clamp_abs", ("f64", "f64")), ("sign", ("f64",)),
            ("signed_square", ("f64",)), ("deadband", ("f64", "f64")), ("dead_zone", ("f64", "f64")),
            ("safe_div", ("f64", "f64", "f64")), ("percent_of", ("f64", "f64")), ("lerp", ("f64", "f64", "f64")),
            ("interpolate", ("f64",) * 5), ("interpolate_clamped", ("f64",) * 5),
            ("ramp_toward", ("f64", "f64", "f64")), ("lowpass", ("f64", "f64", "f64")),
            ("lowpass_alpha", ("f64", "f64")), ("lag_step", ("f64",) * 4), ("angle_diff_deg", ("f64", "f64")),
            ("wrap_deg_360", ("f64",))],
    "i32": [("clamp_i32", ("i32", "i32", "i32")), ("sign_i32", ("i32",))],
    "i64": [("clamp_i64", ("i64", "i64", "i64"))],
    "bool": [("in_range", ("f64", "f64", "f64")), ("in_range_i32", ("i32", "i32", "i32")),
             ("hysteresis", ("f64", "bool", "f64", "f64")), ("approx_eq", ("f64", "f64", "f64")),
             ("within_pct", ("f64", "f64", "f64"))],
}

# std.blocks: name -> (parameters with values to draw from, inputs, outputs).
_F = ["0.5", "0.01", "2.0", "0.0", "(-1.0)", "1e300", "0.1"]
_D = ["10 ms", "20 ms", "50 ms", "0 ms", "1 s"]
STD_BLOCKS = {
    "PID": ([("kp", _F), ("ki", _F), ("kd", _F), ("lo", _F), ("hi", _F), ("dt", _F)], [("err", "f64")], [("y", "f64")]),
    "LOWPASS": ([("tau", _F), ("dt", _F)], [("x", "f64")], [("y", "f64")]),
    "RATE_LIMIT": ([("rise", _F), ("fall", _F), ("dt", _F)], [("x", "f64")], [("y", "f64")]),
    "DEBOUNCE": ([("n", ["0", "1", "3", "(-1)"])], [("x", "bool")], [("q", "bool")]),
    "TON": ([("pt", _D), ("dt", _D)], [("x", "bool")], [("et", "duration"), ("q", "bool")]),
    "TOF": ([("pt", _D), ("dt", _D)], [("x", "bool")], [("et", "duration"), ("q", "bool")]),
    "TP": ([("pt", _D), ("dt", _D)], [("x", "bool")], [("et", "duration"), ("q", "bool")]),
    "R_TRIG": ([], [("x", "bool")], [("q", "bool")]),
    "F_TRIG": ([], [("x", "bool")], [("q", "bool")]),
}
# f64 elements of array literals in the design (not the scenario): NaN, -0.0, infinity.
ARRAY_FLOAT_EDGES = FLOAT_EDGES + ["(0.0 / 0.0)", "(-0.0)", "(1.0 / 0.0)", "(-(0.0 / 0.0))"]

# Names that are fine in the language but reserved, predefined or macros in C
# or Rust (or in the generated code's own vocabulary).
HOSTILE_WORDS = [
    "int", "char", "float", "double", "long", "short", "signed", "unsigned", "static", "extern", "const_", "volatile",
    "register", "auto", "struct", "union", "typedef", "sizeof", "switch", "case", "default", "goto", "break",
    "continue", "return", "while", "for", "do", "else_", "enum_", "void", "inline", "restrict", "_Bool", "bool_",
    "NULL", "EOF", "errno", "stdin", "stdout", "printf", "main", "exit", "abort", "INT32_MAX", "INT32_MIN",
    "UINT32_MAX", "INT64_MIN", "NAN", "INFINITY", "assert", "isnan", "fabs", "memcpy", "size_t", "int32_t",
    "uint32_t", "bool_t", "true_", "self", "Self_", "crate", "super", "mod", "impl", "trait", "type", "match", "loop",
    "move", "mut", "ref", "pub", "use", "where", "async", "await", "dyn", "box", "yield", "unsafe", "let", "fn_",
    "as", "in", "macro", "priv", "try", "virtual", "final", "override", "abstract", "become", "typeof", "unsized",
    "Option", "Some", "None", "Ok", "Err", "Result", "Vec", "String", "Default", "Clone", "Copy", "u8", "i8",
    "usize", "f32", "core", "std", "alloc", "step", "init", "buf", "cmd_", "status_", "gm_", "new_", "state",
    "ST_NEW", "RULE", "serial", "echo", "rcs", "num", "Externs", "host", "lib", "types", "functions",
    # the language's own contextual keywords
    "level", "status", "done", "error", "from", "budget", "verb", "plan", "otherwise", "continuous", "ordered",
    "report", "reads", "writes", "local", "pre", "post", "then", "elif", "heartbeat", "schedule", "env",
]


@dataclass
class Case:
    seed: int
    design: str
    scenario: str
    attempt: int = 0
    name: str = ""


@dataclass
class Record:
    name: str
    fields: list[tuple[str, str]]


@dataclass
class Var:
    name: str
    type: str
    # A declared range `lo..hi` (the range stream): the texts of its bounds.
    range: tuple[str, str] | None = None


@dataclass
class Ctrl:
    name: str
    level: int
    simulator: bool = False
    subs: list["Ctrl"] = field(default_factory=list)
    verbs: list[tuple[str, list[tuple[str, str]]]] = field(default_factory=list)
    reports: list[str] = field(default_factory=list)
    status: list[Var] = field(default_factory=list)
    locals: list[Var] = field(default_factory=list)
    writes: list[Var] = field(default_factory=list)
    reads: list[Var] = field(default_factory=list)
    # Arrays (drawn from a stream of their own; the main stream never sees them).
    alocals: list[Var] = field(default_factory=list)
    astatus: list[Var] = field(default_factory=list)
    awrites: list[Var] = field(default_factory=list)
    areads: list[Var] = field(default_factory=list)
    arecs: list[Var] = field(default_factory=list)  # locals of a record with an array field
    # Function block instances: (instance, block, arguments, inputs, outputs).
    blocks: list[tuple[str, str, str, list[tuple[str, str]], list[tuple[str, str]]]] = field(default_factory=list)
    # A controller type: its name, value parameters, and its instances (name, arguments).
    type_name: str = ""
    tparams: list[tuple[str, str]] = field(default_factory=list)
    atparams: list[tuple[str, str]] = field(default_factory=list)  # array value parameters
    instances: list[tuple[str, str]] = field(default_factory=list)
    instance_of: "Ctrl | None" = None
    # The values of the value parameters, one list per instance (for their ranges).
    inst_values: list[list[str]] = field(default_factory=list)
    vsets: list[str] = field(default_factory=list)  # `verbs NAME` (the verb set stream)
    gm_reads: list[tuple[str, str]] = field(default_factory=list)  # `gm` parameters read: (name, type)


class Names:
    """Fresh names: plain (`in0`, `C1`, ...) or hostile."""

    def __init__(self, rng: random.Random, hostile: bool) -> None:
        self.rng = rng
        self.hostile = hostile
        self.used: set[str] = set()
        self.counter = 0
        self.words = list(HOSTILE_WORDS)
        rng.shuffle(self.words)

    def fresh(self, prefix: str, upper: bool = False) -> str:
        self.counter += 1
        if self.hostile and self.rng.random() < 0.6:
            choice = self.rng.random()
            if choice < 0.5 and self.words:
                name = self.words.pop()
            elif choice < 0.75:
                # Pieces that collide once joined with `_` by the targets.
                name = self.rng.choice(["A_B", "A", "B_C", "x_y", "x", "y_z", "MAIN_C", "s_t", "ctrl_A"]) + (
                    "" if self.rng.random() < 0.5 else "_" + self.rng.choice(["B", "C", "y", "z", "t"]))
            else:
                name = (prefix + "_very_long_name_" * self.rng.randint(4, 16))[:250] + str(self.counter)
            if name not in self.used:
                self.used.add(name)
                return name
        name = f"{prefix}{self.counter}"
        if upper:
            name = name.upper()
        self.used.add(name)
        return name


class DesignGen:
    """One draw of a design and its scenario from a seed."""

    def __init__(self, seed: int, hostile: bool = False, features: bool = True) -> None:
        self.rng = random.Random(seed)
        self.seed = seed
        self.names = Names(self.rng, hostile)
        self.hostile = hostile
        self.enums: dict[str, list[str]] = {}
        self.records: dict[str, Record] = {}
        self.consts: list[Var] = []
        self.fns: list[tuple[str, list[tuple[str, str]], str]] = []
        self.env: list[Var] = []
        self.gm_out: list[Var] = []
        self.ctrls: list[Ctrl] = []
        self.std_math = self.rng.random() < 0.8
        self.budget = 0  # expression nodes left in the current expression
        # Extern functions are drawn from a stream of their own, so that adding
        # them changed a seed's design only where an extern is declared or called.
        self.ext_rng = random.Random(seed ^ 0x5EED)
        self.externs: list[tuple[str, list[tuple[str, str]], str]] = []
        self.in_fn = False  # a pure `fn` cannot call an extern (E0211)
        # The math built-ins and `cycle` likewise: they wrap what the main
        # stream drew for an assignment, so a seed keeps its design otherwise.
        self.math_rng = random.Random(seed ^ 0xF10A7)
        # Arrays, controller types and function blocks: streams of their own,
        # so that a seed that draws none of them keeps its design.
        self.arr_rng = random.Random(seed ^ 0xA77A1)
        self.use_arrays = self.arr_rng.random() < 0.55 and features
        self.features = features
        self.arrays: dict[str, tuple[str, int]] = {}  # "[f64; 3]" -> (element type, length)
        self.arecords: dict[str, Record] = {}  # records with an array field (outside the main stream)
        self.aconsts: list[Var] = []
        self.aenv: list[Var] = []
        self.agm: list[Var] = []
        self.afns: list[tuple[str, str, str, str]] = []  # (name, array type, index type, result)
        self.arfns: list[tuple[str, str, str, str]] = []  # functions returning an array: (name, array type, element, body)
        self.len_consts: list[tuple[str, int]] = []
        self.actx: list[tuple[str, str]] | None = None  # readable arrays of the current controller
        self.atargets: list[tuple[str, str]] = []  # assignable arrays of the current controller
        self.aidx: list[str] = []  # extra integer index variables (`w.k`)
        self.ct_rng = random.Random(seed ^ 0xC7C7)
        self.blk_rng = random.Random(seed ^ 0xB10C)
        self.use_blocks = self.blk_rng.random() < 0.4 and features
        self.user_blocks: list[str] = []
        self.bcalls: list[tuple[str, list[tuple[str, str]]]] = []  # callable instances of the current controller
        # Rates and CPUs (a stream of its own): divided rates, several CPUs
        # with harmonic heartbeats, `age(...)` reads and `stop`/`freeze` faults.
        self.mc_rng = random.Random(seed ^ 0x3C9D)
        self.use_rates = self.mc_rng.random() < 0.45 and features
        self.cpus: list[tuple[str, int, list[Ctrl]]] = []  # (name, heartbeat ms, schedule)
        self.periods: dict[str, int] = {}  # controller -> its period in ms (a divided rate)
        # More shapes of the language (a stream of its own, so a seed that
        # draws none keeps its design): subordinates' status read as values,
        # `in_state` as a value, any condition in a rule, `*` rules of every
        # kind, integer literals typed f64, constants built from constants,
        # named and non-positive error codes, math inside expressions, NaN and
        # infinities as values, durations near the ends of their range.
        self.x_rng = random.Random(seed ^ 0x7E57)
        self.more = features and self.x_rng.random() < 0.6
        # Array value parameters of controller types and blocks, their
        # arguments written out with integer literals (a stream of its own):
        # each element takes the parameter's element type, as in a typed
        # constant (`[u32; 2]` given `[4294967295, 2]` wraps as u32).
        self.tp_rng = random.Random(seed ^ 0x7A9A)
        self.acc_wrap = features and self.tp_rng.random() < 0.5  # the user block ACC has `w: [u32; 2]`
        self.sub_values: set[str] = set()  # the names of those status values
        # The shapes below come each from a stream of its own, decided once
        # per seed: a seed that draws none of them keeps its design byte for
        # byte (one that draws one may change elsewhere too).
        self.rg_rng = random.Random(seed ^ 0x4A2E)  # ranges `T in lo..hi`
        self.use_ranges = features and self.rg_rng.random() < 0.4
        self.vs_rng = random.Random(seed ^ 0x5E75)  # verb sets, own and std.lifecycle's
        self.use_verbsets = features and self.vs_rng.random() < 0.3
        self.sv_rng = random.Random(seed ^ 0x51F7)  # simulators that accept commands
        self.use_sim_verbs = features and self.sv_rng.random() < 0.5
        # `gm` parameters bound to record fields, `gm` parameters read, a controller type's `period`.
        self.tb_rng = random.Random(seed ^ 0x6B1D)
        self.use_bindings = features and self.tb_rng.random() < 0.6
        self.es_rng = random.Random(seed ^ 0xE5CA)  # extern calls as statements
        self.use_ext_stmts = features and self.es_rng.random() < 0.5
        self.na_rng = random.Random(seed ^ 0xA4A3)  # arguments by name out of order, positional ones first
        self.use_reorder = features and self.na_rng.random() < 0.5
        self.ex_rng = random.Random(seed ^ 0xE4EC)  # the scenario's `expect` lines
        self.use_expects = features and self.ex_rng.random() < 0.5
        self.stub_rng = random.Random(seed ^ 0x5702)  # stub plans (docs/language.md section 9.5)
        self.use_stubs = features and self.stub_rng.random() < 0.25
        self.field_ranges: dict[tuple[str, str], tuple[str, str]] = {}  # (record, field) -> bounds
        self.param_ranges: dict[tuple[str, str], tuple[str, str]] = {}  # (verb, parameter) -> bounds
        self.verbsets: dict[str, list[tuple[str, list[tuple[str, str]]]]] = {}  # name -> its verbs
        self.type_periods: dict[str, int] = {}  # controller type -> its period in ms

    # ---- streams of their own -------------------------------------------------------

    STREAMS = ("rng", "x_rng", "math_rng", "arr_rng", "ext_rng", "blk_rng", "mc_rng", "tp_rng", "ct_rng")

    @contextlib.contextmanager
    def drawing_from(self, rng: random.Random):
        """Draw expressions from `rng` alone: every stream the expression
        drawing reads is replaced, for the time of the block, by one seeded
        from `rng`, so that what is drawn inside leaves every stream (and
        the expression budget) where it was."""
        saved = {a: getattr(self, a) for a in self.STREAMS}
        budget = self.budget
        for a in self.STREAMS:
            setattr(self, a, random.Random(rng.getrandbits(64)))
        try:
            yield
        finally:
            for a, v in saved.items():
                setattr(self, a, v)
            self.budget = budget

    def arglist(self, params: list[str], values: list[str], named: bool) -> str:
        """Arguments as written.  The reordering stream sometimes gives
        positional ones by name, and named ones out of order, after some
        positional ones: the language evaluates them in the order of the
        parameters, whatever order they are written in."""
        na = self.na_rng
        if not named:
            if not (self.use_reorder and params and na.random() < 0.3):
                return ", ".join(values)
        pairs = [f"{p} = {v}" for p, v in zip(params, values)]
        if self.use_reorder and len(pairs) > 1 and na.random() < 0.7:
            k = 0 if na.random() < 0.5 else na.randrange(len(pairs))
            rest = pairs[k:]
            na.shuffle(rest)
            return ", ".join(values[:k] + rest)
        return ", ".join(pairs)

    # ---- ranges ---------------------------------------------------------------------

    def number(self, text: str, t: str):
        """The value of a literal of type t (an int, a float, nanoseconds), or
        None for anything else (an expression, NaN, an infinity)."""
        text = text.strip()
        while text.startswith("(") and text.endswith(")"):
            text = text[1:-1].strip()
        try:
            if t in INT_TYPES:
                v = int(text.replace("_", ""), 0)
                # `-3` of a u32 is a negation that wraps, not a literal.
                return v if INT_BOUNDS[t][0] <= v <= INT_BOUNDS[t][1] else None
            if t == "f64":
                v = float(text.replace("_", ""))
                return v if v == v and abs(v) != float("inf") else None
            if t == "duration":
                from decimal import Decimal

                num, unit = text.split()
                return int(Decimal(num.replace("_", "")) * {"us": 10**3, "ms": 10**6, "s": 10**9}[unit])
        except (ValueError, KeyError, ArithmeticError):
            return None
        return None

    def draw_range(self, t: str, values: list[str]) -> tuple[str, str] | None:
        """Bounds `lo..hi` for type t that hold every one of `values` (none
        when one of them is not a literal); from the range stream."""
        g = self.rg_rng
        if t not in NUM_TYPES and t != "duration":
            return None
        nums = [self.number(v, t) for v in values]
        if any(v is None for v in nums):
            return None

        def paren(text: str) -> str:
            return f"({text})" if text.startswith("-") and g.random() < 0.5 else text

        if t in INT_TYPES:
            tlo, thi = INT_BOUNDS[t]
            lo = min(nums) if nums else max(tlo, g.randint(-100, 100))
            hi = max(nums) if nums else lo
            lo = max(tlo, lo - g.choice([0, 0, 1, 3, 100, 70000, 2**40]))
            hi = min(thi, hi + g.choice([0, 1, 3, 100, 70000, 2**40]))
            return paren(str(lo)), paren(str(hi))
        if t == "f64":
            lo_v = min(nums) if nums else 0.0
            hi_v = max(nums) if nums else 1.0
            los = [b for b in FLOAT_BOUNDS if float(b) <= lo_v] + [values[nums.index(lo_v)] if nums else "0.0"]
            his = [b for b in FLOAT_BOUNDS if float(b) >= hi_v] + [values[nums.index(hi_v)] if nums else "1.0"]
            return paren(g.choice(los)), paren(g.choice(his))
        lo_v = min(nums) if nums else 0
        hi_v = max(nums) if nums else 10**7
        los = [b for b in DURATION_BOUNDS if self.number(b, t) <= lo_v] + ([values[nums.index(lo_v)]] if nums else [])
        his = [b for b in DURATION_BOUNDS if self.number(b, t) >= hi_v] + ([values[nums.index(hi_v)]] if nums else [])
        return g.choice(los), g.choice(his)

    def ranged(self, t: str, values: list[str], p: float = 0.35) -> tuple[str, tuple[str, str] | None]:
        """A declared type: sometimes (the range stream) with a range that holds `values`."""
        if not self.use_ranges or self.rg_rng.random() >= p:
            return t, None
        bounds = self.draw_range(t, values)
        return (f"{t} in {bounds[0]}..{bounds[1]}", bounds) if bounds else (t, None)

    def fit(self, text: str, t: str, bounds: tuple[str, str] | None) -> str:
        """`text` if it lies in `bounds`, else the lower bound (a constant in a ranged slot must)."""
        if bounds is None:
            return text
        v = self.number(text, t)
        if v is not None and self.number(bounds[0], t) <= v <= self.number(bounds[1], t):
            return text
        return bounds[0]

    # ---- types and values ------------------------------------------------------------

    def rtype(self, allow_record: bool = True, scalar_weight: int = 6) -> str:
        pool = list(SCALARS) * scalar_weight + list(self.enums) * 2
        if allow_record:
            pool += list(self.records) * 2
        return self.rng.choice(pool)

    def literal(self, t: str, rng: random.Random | None = None) -> str:
        """A constant expression of type t (literals, constants, constructors)."""
        r = rng or self.rng
        if t in self.arrays:
            return self.array_literal(t, r)
        if t == "bool":
            return r.choice(["true", "false"])
        if t in INT_TYPES:
            return r.choice(INT_EDGES[t])
        if t == "f64":
            if self.more and self.x_rng.random() < 0.1:
                return self.x_rng.choice(F64_SPECIALS)
            return r.choice(FLOAT_EDGES)
        if t == "duration":
            if self.more and self.x_rng.random() < 0.1:
                return self.x_rng.choice(BIG_DURATIONS)
            return r.choice(DURATIONS)
        if t in self.enums:
            return f"{t}.{r.choice(self.enums[t])}"
        rec = self.records[t] if t in self.records else self.arecords[t]
        vals = [self.fit(self.literal(ft, r), ft, self.field_ranges.get((t, f))) for f, ft in rec.fields]
        return f"{t}(" + self.arglist([f for f, _ in rec.fields], vals, True) + ")"

    def const_value(self, t: str) -> str:
        """A constant's value: a literal, or an edge computed at compile time."""
        r = self.rng
        if t == "f64" and r.random() < 0.5:
            return r.choice(["0.0 / 0.0", "1.0 / 0.0", "-1.0 / 0.0", "-0.0", "1e308 * 10.0", "-(0.0 / 0.0)"])
        if t == "i32" and r.random() < 0.3:
            return r.choice(["2147483647 + 1", "-2147483648 / -1", "7 / 0", "-7 % 0", "-2147483648 % -1", "i32(1e12)",
                             "i32(0.0 / 0.0)", "-7 / 2", "-7 % 2"])
        if t == "u32" and r.random() < 0.3:
            return r.choice(["u32(0) - 1", "u32(-1.5)", "u32(1e20)", "4294967295 * 2"])
        if t == "i64" and r.random() < 0.3:
            return r.choice(["i64(-1e300)", "9223372036854775807 + 1", "i64(2147483647) * 3"])
        return self.literal(t)

    def doc(self, indent: str = "") -> list[str]:
        """Sometimes (the "more" stream) a `///` doc comment for the item that follows."""
        if not (self.more and self.x_rng.random() < 0.25):
            return []
        return [f"{indent}/// {self.x_rng.choice(DOC_TEXTS)}" for _ in range(self.x_rng.choice([1, 1, 2]))]

    def derived_const(self, t: str, earlier: list[Var]) -> str:
        """A constant's value; in the "more" stream, sometimes computed from
        earlier constants, functions of std.math or the math built-ins."""
        x = self.x_rng
        same = [k.name for k in earlier if k.type == t]
        if not (self.more and t in NUM_TYPES and x.random() < 0.4):
            return self.const_value(t)
        k = x.choice(same) if same else self.literal(t, x)
        if t == "f64":
            forms = [f"{k} * 2.0", f"-{k}", f"{k} + 0.5", f"sqrt({k})", f"floor({k})", f"min({k}, 1.0)"]
            if self.std_math:
                forms += [f"clamp({k}, -1.0, 1.0)", f"sign({k})"]
            return x.choice(forms)
        forms = [f"{k} + 1", f"-{k}", f"{k} * 3", f"{k} / 2", f"abs({k})", f"max({k}, {t}(5))"]
        return x.choice(forms)

    # ---- expressions ----------------------------------------------------------------

    def leaf(self, t: str, scope: list[Var], anch: bool = True) -> str:
        """A variable, a field, a constant or a literal of type t.

        `anch` says whether the context gives the expression its type (an
        assignment, an argument, the right operand of a comparison); where it
        does not, an integer literal of another type than i32 is wrapped in a
        conversion, as a person would have to write it.
        """
        r = self.rng
        if self.actx and self.arr_rng.random() < 0.3:
            read = self.aread(t, scope)
            if read:
                return read
        vars_ = [v.name for v in scope if v.type == t]
        for v in scope:  # fields of records, nested ones too
            if v.type in self.records:
                for f, ft in self.records[v.type].fields:
                    if ft == t:
                        vars_.append(f"{v.name}.{f}")
                    elif ft in self.records:
                        vars_ += [f"{v.name}.{f}.{g}" for g, gt in self.records[ft].fields if gt == t]
        consts = [c.name for c in self.consts if c.type == t]
        choice = r.random()
        if vars_ and choice < 0.7:
            return r.choice(vars_)
        if consts and choice < 0.85:
            return r.choice(consts)
        if t == "f64" and anch and self.more and self.x_rng.random() < 0.15:
            return self.x_rng.choice(F64_INT_LITERALS)
        lit = self.literal(t)
        if t in INT_TYPES and not anch and t != "i32":
            return f"{t}({lit})"
        return f"({lit})" if lit.startswith("-") else lit

    def expr(self, t: str, scope: list[Var], depth: int = 3, anch: bool = True) -> str:
        if t == "f64" and self.more and depth > 0 and self.x_rng.random() < 0.08:
            return self.with_math(t, self._expr(t, scope, depth - 1, anch), scope, 1)
        return self._expr(t, scope, depth, anch)

    def _expr(self, t: str, scope: list[Var], depth: int = 3, anch: bool = True) -> str:
        r = self.rng
        self.budget -= 1
        if depth <= 0 or self.budget <= 0 or r.random() < 0.25:
            return self.leaf(t, scope, anch)
        d = depth - 1
        if self.more and not self.in_fn and t in NUM_TYPES and self.x_rng.random() < 0.12:
            # Two extern calls as the operands of one operator: the order of
            # the calls is the language's (left to right), not the compiler's.
            exts = [(n, ps) for n, ps, rt in self.externs if rt == t]
            if exts:
                calls = []
                for _ in range(2):
                    name, params = self.x_rng.choice(exts)
                    vals = [self.expr(pt, scope, min(d, 1)) for _, pt in params]
                    calls.append(f"{name}(" + self.arglist([p for p, _ in params], vals, False) + ")")
                ops = ["+", "-", "*"] + (["/"] if t == "f64" else [])
                return f"({calls[0]} {self.x_rng.choice(ops)} {calls[1]})"
        if t in NUM_TYPES:
            k = r.random()
            if k < 0.35:
                ops = ["+", "-", "*", "/"] + (["%"] if t != "f64" else [])
                op = r.choice(ops)
                return f"({self.expr(t, scope, d, anch)} {op} {self.expr(t, scope, d, anch)})"
            if k < 0.45:
                operand = self.expr(t, scope, d, anch)
                if t == "u32" and INT_LITERAL.fullmatch(operand):
                    operand = f"u32({operand})"  # `-4294967295` is a u32 literal out of range
                return f"(-{operand})"
            if k < 0.6:
                src = r.choice([x for x in NUM_TYPES if x != t] + [t])
                inner = self.expr(src, scope, d, False)
                return f"{t}({inner})"
            if k < 0.7:
                f = r.choice(["abs", "min", "max"])
                if f == "abs":
                    return f"abs({self.expr(t, scope, d, anch)})"
                return f"{f}({self.expr(t, scope, d, anch)}, {self.expr(t, scope, d, anch)})"
            if k < 0.78:
                then = self.expr(t, scope, d, anch)
                return f"(if {self.cond(scope, d)} then {then} else {self.expr(t, scope, d, anch)})"
            if k < 0.86 and t == "f64":
                return f"seconds({self.expr('duration', scope, d)})"
            if k < 0.93:
                call = self.call(t, scope, d)
                if call:
                    return call
            return self.leaf(t, scope, anch)
        if t == "bool":
            return self.cond(scope, depth)
        if t == "duration":
            k = r.random()
            if k < 0.3:
                return f"({self.expr(t, scope, d)} {r.choice(['+', '-'])} {self.expr(t, scope, d)})"
            if k < 0.4:
                return f"(-{self.expr(t, scope, d)})"
            if k < 0.55:
                f = r.choice(["abs", "min", "max"])
                if f == "abs":
                    return f"abs({self.expr(t, scope, d)})"
                return f"{f}({self.expr(t, scope, d)}, {self.expr(t, scope, d)})"
            if k < 0.65:
                return f"(if {self.cond(scope, d)} then {self.expr(t, scope, d)} else {self.expr(t, scope, d)})"
            return self.leaf(t, scope)
        # enums and records
        k = r.random()
        if k < 0.2:
            return f"(if {self.cond(scope, d)} then {self.expr(t, scope, d)} else {self.expr(t, scope, d)})"
        if k < 0.35:
            call = self.call(t, scope, d)
            if call:
                return call
        if t in self.records and k < 0.6:
            rec = self.records[t]
            vals = [self.expr(ft, scope, d) for _, ft in rec.fields]
            return f"{t}(" + self.arglist([f for f, _ in rec.fields], vals, True) + ")"
        return self.leaf(t, scope)

    def call(self, t: str, scope: list[Var], depth: int) -> str | None:
        exts = [(n, ps) for n, ps, rt in self.externs if rt == t]
        if exts and not self.in_fn and self.ext_rng.random() < 0.5:
            # The simulator's extern returns the zero value of its type, as the
            # generated stubs of both targets do: the call, its arguments and
            # the conversion of the result are what is compared.
            name, params = self.ext_rng.choice(exts)
            vals = [self.expr(pt, scope, depth) for _, pt in params]
            return f"{name}(" + self.arglist([p for p, _ in params], vals, False) + ")"
        cands = [(n, ps) for n, ps, rt in self.fns if rt == t]
        if self.std_math:
            # std.math's parameters are given by position only (their names are not listed here).
            cands += [(n, [("", pt) for pt in ps]) for n, ps in STD_MATH.get(t, [])]
        if not cands:
            return None
        name, params = self.rng.choice(cands)
        vals = [self.expr(pt, scope, depth) for _, pt in params]
        if params and not params[0][0]:
            return f"{name}(" + ", ".join(vals) + ")"
        return f"{name}(" + self.arglist([p for p, _ in params], vals, False) + ")"

    def cond(self, scope: list[Var], depth: int = 2) -> str:
        r = self.rng
        self.budget -= 1
        d = depth - 1
        k = r.random()
        if depth <= 0 or self.budget <= 0 or k < 0.45:
            t = r.choice(list(NUM_TYPES) + ["duration", "bool"] + list(self.enums))
            op = r.choice(["==", "!="] if t in self.enums or t == "bool" else ["==", "!=", "<", "<=", ">", ">="])
            left = self.leaf(t, scope, anch=False)
            right = self.leaf(t, scope) if depth <= 0 or self.budget <= 0 else self.expr(t, scope, min(d, 1))
            return f"({left} {op} {right})"
        if k < 0.6:
            return f"({self.cond(scope, d)} {r.choice(['and', 'or'])} {self.cond(scope, d)})"
        if k < 0.7:
            return f"(not {self.cond(scope, d)})"
        if k < 0.8:
            call = self.call("bool", scope, d)
            if call:
                return call
        t = r.choice(NUM_TYPES)
        return f"({self.expr(t, scope, d, False)} {r.choice(['<', '>=', '==', '!='])} {self.expr(t, scope, d)})"

    def guard(self, scope: list[Var], ctrl: Ctrl, in_plan: bool) -> str:
        """A small rule condition: what the guard analysis can decide quickly.

        `in_plan` is false for the rules of `new`, which must not wait on a
        subordinate (its error is only tested by the `*` rules after them).
        """
        r = self.rng
        if not in_plan:  # `new` tests no subordinate
            scope = [v for v in scope if v.name not in self.sub_values]
        if self.more and self.x_rng.random() < 0.15:
            self.budget = 6
            return self.cond(scope, 2)
        if self.more and self.x_rng.random() < 0.1:
            call = self.extern_test(scope)
            if call:
                return call
        opts = []
        for s in ctrl.subs if in_plan else []:
            opts += [f"{s.name}.done", f"{s.name}.executing", f"(not {s.name}.executing)"]
            opts += [f"{s.name}.{rep}" for rep in s.reports]
            opts += [f"({s.name}.{v.name} {'==' if v.type in self.enums or v.type == 'bool' else '>='} {self.literal(v.type) if v.type != 'f64' else '0.5'})"
                     for v in s.status if v.type in SCALARS[:5] or v.type in self.enums]
            opts.append(f"({s.name}.age >= 20 ms)")
            opts.append(f"({s.name}.error_code != 0)")
        if in_plan:
            opts += [f"(in_state >= {r.choice([10, 20, 30, 50])} ms)", f"(in_state < {r.choice([20, 40])} ms)"]
        ints = [v for v in scope if v.type in ("i32", "bool", "duration", "f64") or v.type in self.enums]
        for v in ints:
            if v.type == "bool":
                opts.append(v.name)
            elif v.type in self.enums:
                opts.append(f"({v.name} == {self.literal(v.type)})")
            elif v.type == "duration":
                opts.append(f"({v.name} > {r.choice(DURATIONS)})")
            else:
                lit = self.literal(v.type)
                opts.append(f"({v.name} {r.choice(['<', '>=', '==', '!='])} {'(' + lit + ')' if lit.startswith('-') else lit})")
        if not opts:
            return "(in_state >= 20 ms)" if in_plan else "true"
        g = r.choice(opts)
        if r.random() < 0.3:
            g = f"({g} {r.choice(['and', 'or'])} {r.choice(opts)})"
        elif r.random() < 0.15:
            g = f"(not {g})"
        return g

    # ---- statements -----------------------------------------------------------------

    def extern_test(self, scope: list[Var]) -> str | None:
        """A call of an extern that returns a bool (the "more" stream), or None."""
        exts = [(n, ps) for n, ps, rt in self.externs if rt == "bool"]
        if not exts or self.in_fn:
            return None
        name, params = self.x_rng.choice(exts)
        self.budget = 4
        vals = [self.expr(pt, scope, 1) for _, pt in params]
        return f"{name}(" + self.arglist([p for p, _ in params], vals, False) + ")"

    def extern_stmt(self, scope: list[Var]) -> str:
        """A call of an extern whose value is not used, as a statement or a
        job (the extern statements stream): its journal still counts it."""
        e = self.es_rng
        with self.drawing_from(e):
            name, params, _ = e.choice(self.externs)
            self.budget = 6
            vals = [self.expr(pt, scope, 2) for _, pt in params]
            return f"{name}(" + self.arglist([p for p, _ in params], vals, e.random() < 0.3) + ")"

    def lvalues(self, targets: list[Var]) -> list[tuple[str, str]]:
        """Assignable places: variables and their record fields."""
        out = [(v.name, v.type) for v in targets]
        for v in targets:
            if v.type in self.records:
                for f, ft in self.records[v.type].fields:
                    out.append((f"{v.name}.{f}", ft))
                    if ft in self.records:
                        out += [(f"{v.name}.{f}.{g}", gt) for g, gt in self.records[ft].fields]
        return out

    def assign(self, targets: list[Var], scope: list[Var]) -> str:
        r = self.rng
        name, t = r.choice(self.lvalues(targets))
        self.budget = 14
        ops = ["="]
        if t in NUM_TYPES:
            ops += ["+=", "-=", "*="]
        elif t == "duration":
            ops += ["+=", "-="]
        return f"{name} {r.choice(ops)} {self.with_math(t, self.expr(t, scope, 4), scope)}"

    def math_leaf(self, scope: list[Var]) -> str:
        """An f64 operand for a math built-in, from the math stream: an f64
        variable, `cycle`, or an edge (signed zeros, halves, NaN, infinities, huge)."""
        mr = self.math_rng
        vars_ = [v.name for v in scope if v.type == "f64"]
        k = mr.random()
        if vars_ and k < 0.4:
            return mr.choice(vars_)
        if k < 0.5:
            return "f64(cycle)"
        return mr.choice(MATH_EDGES)

    def with_math(self, t: str, e: str, scope: list[Var], depth: int = 2) -> str:
        """`e` (of type t), sometimes inside math built-ins or added to `cycle`."""
        mr = self.math_rng
        if t == "i64" and mr.random() < 0.15:
            return f"({e} + cycle)"
        if t != "f64" or depth <= 0 or mr.random() < 0.6:
            return e
        f = mr.choice(MATH_FUNCS)
        inner = self.with_math(t, e, scope, depth - 1)
        if f in ("copysign", "min", "max"):
            other = self.math_leaf(scope)
            return f"{f}({inner}, {other})" if mr.random() < 0.5 else f"{f}({other}, {inner})"
        return f"{f}({inner})"

    def block(self, targets: list[Var], scope: list[Var], indent: str, n: int, depth: int = 2) -> list[str]:
        r = self.rng
        lines = []
        for _ in range(n):
            if self.use_ext_stmts and self.externs and self.es_rng.random() < 0.2:
                lines.append(f"{indent}{self.extern_stmt(scope)};")  # besides the statement drawn below
            if self.bcalls and self.blk_rng.random() < 0.35:
                lines.append(f"{indent}{self.bcall(scope)};")
                continue
            if self.atargets and self.arr_rng.random() < 0.35:
                lines.append(f"{indent}{self.astmt(scope)};")
                continue
            if depth > 0 and r.random() < 0.2:
                self.budget = 6
                lines.append(f"{indent}if {self.cond(scope, 2)} {{")
                lines += self.block(targets, scope, indent + "    ", r.randint(1, 2), depth - 1)
                for _ in range(r.randint(0, 1)):
                    self.budget = 6
                    lines.append(f"{indent}}} elif {self.cond(scope, 2)} {{")
                    lines += self.block(targets, scope, indent + "    ", 1, depth - 1)
                if r.random() < 0.5:
                    lines.append(f"{indent}}} else {{")
                    lines += self.block(targets, scope, indent + "    ", r.randint(1, 2), depth - 1)
                lines.append(f"{indent}}}")
            else:
                lines.append(f"{indent}{self.assign(targets, scope)};")
        return lines

    # ---- arrays ---------------------------------------------------------------------

    def array_type(self, nested: bool = True) -> str:
        """An array type `[T; N]` (N a literal or an integer constant), registered in `self.arrays`."""
        a = self.arr_rng
        pool = ["f64"] * 4 + ["i32", "i32", "i64", "u32", "bool", "duration"] + list(self.enums) + list(self.records)
        elem = a.choice(pool)
        if nested and self.arrays and a.random() < 0.1:
            elem = a.choice(sorted(self.arrays))  # an array of arrays
        n = a.randint(1, 5)
        if self.more and self.x_rng.random() < 0.1:
            n = self.x_rng.choice([17, 64, 300])  # longer arrays: loops over them, not unrolled code
        size = str(n)
        if self.len_consts and a.random() < 0.4:
            size, n = a.choice(self.len_consts)
        t = f"[{elem}; {size}]"
        self.arrays[t] = (elem, n)
        return t

    def array_literal(self, t: str, r: random.Random, scenario: bool = False) -> str:
        elem, n = self.arrays[t]
        size = t.rsplit(";", 1)[1].strip()[:-1]

        def one() -> str:
            if elem == "f64":
                return r.choice(FLOAT_EDGES if scenario else ARRAY_FLOAT_EDGES)
            if elem in self.arrays:
                return self.array_literal(elem, r, scenario)
            return self.literal(elem, r)

        if not scenario and r.random() < 0.3:
            return f"[{one()}; {size}]"
        return "[" + ", ".join(one() for _ in range(n)) + "]"

    def int_array_literal(self, t: str) -> str:
        """An array of type t written out with integer literals wherever they
        may stand (f64 elements too), at the edges of the element type."""
        tp = self.tp_rng
        elem, n = self.arrays[t]

        def one() -> str:
            if elem in self.arrays:
                return self.int_array_literal(elem)
            if elem == "f64":
                return tp.choice(["1", "3", "(-2)", "0", "2147483647", "4294967295", "(-9007199254740993)"])
            return self.literal(elem, tp)

        if tp.random() < 0.25:
            return f"[{one()}; {t.rsplit(';', 1)[1].strip()[:-1]}]"
        return "[" + ", ".join(one() for _ in range(n)) + "]"

    def index(self, n: int, scope: list[Var]) -> str:
        """An index into an array of n elements: in range, out of range, or a
        variable (an input the scenario sets to an edge) that may be either."""
        a = self.arr_rng
        ivars = [v.name for v in scope if v.type in INT_TYPES] + self.aidx
        k = a.random()
        if k < 0.3:
            return str(a.randrange(n))
        if k < 0.4:
            return a.choice([str(n), "(-1)", "2147483647", "(-2147483648)", "4294967296", str(n + 1)])
        if ivars and k < 0.85:
            v = a.choice(ivars)
            return v if a.random() < 0.7 else f"({v} {a.choice(['+', '-', '%'])} {a.randint(1, n + 1)})"
        return a.choice(["cycle", f"(cycle % {n + 1})", f"(cycle - {n})"])

    def aread(self, t: str, scope: list[Var]) -> str | None:
        """An expression of type t that reads an array of the current controller."""
        a = self.arr_rng
        opts = []
        for p, at in self.actx or []:
            elem, n = self.arrays[at]
            if elem == t:
                opts += [("at", p, at)] * 3
                if t in NUM_TYPES or t == "duration":
                    opts += [("fold", p, at)] * 2
            if elem in self.arrays and self.arrays[elem][0] == t:
                opts.append(("at2", p, at))
            if elem in self.records and any(ft == t for _, ft in self.records[elem].fields):
                opts.append(("field", p, at))
            if t == "i32":
                opts.append(("len", p, at))
            for name, ft, it, ret, _ in self.afns:
                if ft == at and ret == t:
                    opts.append(("fn", p, at))
        if not opts:
            return None
        kind, p, at = a.choice(opts)
        elem, n = self.arrays[at]
        if kind == "at":
            return f"{p}[{self.index(n, scope)}]"
        if kind == "fold":
            return f"{a.choice(['sum', 'min_of', 'max_of'])}({p})"
        if kind == "at2":
            return f"{p}[{self.index(n, scope)}][{self.index(self.arrays[elem][1], scope)}]"
        if kind == "field":
            f = a.choice([f for f, ft in self.records[elem].fields if ft == t])
            return f"{p}[{self.index(n, scope)}].{f}"
        if kind == "len":
            return f"len({p})"
        name, _, it, _, _ = a.choice([f for f in self.afns if f[1] == at and f[3] == t])
        i = self.index(n, scope)
        return f"{name}({p}, {it}({i}))"

    def aval(self, at: str, scope: list[Var]) -> str:
        """A whole array of type at: another array of that type, a literal, or a function's result."""
        a = self.arr_rng
        same = [p for p, t in self.actx or [] if t == at]
        fns = [(f, elem) for f, t, elem, _ in self.arfns if t == at]
        if fns and a.random() < 0.35:
            f, elem = a.choice(fns)
            arg = a.choice(same) if same and a.random() < 0.7 else self.array_literal(at, a)
            self.budget = 4
            return f"{f}({arg}, {self.expr(elem, scope, 1)})"
        if same and a.random() < 0.5:
            return a.choice(same)
        return self.array_literal(at, a)

    def astmt(self, scope: list[Var]) -> str:
        """An assignment to an array: one element (an index in or out of range), or the whole."""
        a = self.arr_rng
        p, at = a.choice(self.atargets)
        elem, n = self.arrays[at]
        k = a.random()
        if self.aidx and k < 0.1:
            w = a.choice(self.aidx)
            return f"{w} = ({w} + {a.choice(['1', '(-1)', '2147483647'])})"
        if k < 0.7:
            ops = ["="]
            if elem in NUM_TYPES:
                ops += ["+=", "-=", "*="]
            elif elem == "duration":
                ops += ["+=", "-="]
            i = self.index(n, scope)
            if elem in self.arrays:
                return f"{p}[{i}] = {self.aval(elem, scope)}"
            self.budget = 8
            return f"{p}[{i}] {a.choice(ops)} {self.expr(elem, scope, 2)}"
        return f"{p} = {self.aval(at, scope)}"

    def bcall(self, scope: list[Var]) -> str:
        """One step of a function block instance: inputs by name, in order, or none."""
        b = self.blk_rng
        inst, inputs = b.choice(self.bcalls)
        self.budget = 8
        args = [self.expr(t, scope, 2) for _, t in inputs]
        k = b.random()
        if k < 0.85:
            return f"{inst}(" + self.arglist([i for i, _ in inputs], args, k < 0.5) + ")"
        return f"{inst}()"

    def declare_arrays(self) -> None:
        a = self.arr_rng
        n = self.names
        if a.random() < 0.4:
            size = a.randint(1, 4)
            self.len_consts.append((n.fresh("LEN", upper=True), size))
        for _ in range(a.randint(0, 2)):
            t = self.array_type()
            self.aconsts.append(Var(n.fresh("KA", upper=True), t))
        for _ in range(a.randint(0, 2)):
            self.aenv.append(Var(n.fresh("ain"), self.array_type()))
        if a.random() < 0.4:
            rname = n.fresh("RecA")
            self.arecords[rname] = Record(rname, [(n.fresh("xs"), self.array_type(nested=False)), (n.fresh("k"), "i32")])
        for _ in range(a.randint(0, 2)):
            at = self.array_type(nested=False)
            elem, size = self.arrays[at]
            it = a.choice(INT_TYPES)
            if elem in NUM_TYPES or elem == "duration":
                body = a.choice(["xs[i]", f"(xs[i] + {a.choice(['sum', 'min_of', 'max_of'])}(xs))", "xs[len(xs) - 1]",
                                 "(max_of(xs) - xs[i])"])
            else:
                body = "xs[i]"
            self.afns.append((n.fresh("afun"), at, it, elem, body))
        for _ in range(a.choice([0, 1, 1, 2])):
            # A function whose result is an array: each element from the
            # parameter's elements and a scalar, in or out of order.
            at = self.array_type(nested=False)
            elem, size = self.arrays[at]
            if elem not in NUM_TYPES and elem != "duration":
                continue
            parts = []
            for i in range(size):
                j = a.randrange(size)
                if elem == "duration":
                    parts.append(a.choice([f"xs[{i}]", f"(xs[{j}] + k)", "k", f"(k - xs[{i}])"]))
                else:
                    parts.append(a.choice([f"xs[{i}]", f"(xs[{j}] + k)", "k", f"(xs[{i}] * k)", f"(k - xs[{j}])"]))
            body = "[" + ", ".join(parts) + "]"
            if a.random() < 0.3:
                body = f"(if sum(xs) > k then xs else {body})"
            self.arfns.append((n.fresh("arfun"), at, elem, body))

    def hierarchy_arrays(self) -> None:
        a = self.arr_rng
        n = self.names
        for c in self.ctrls:
            if c.instance_of:
                continue
            for _ in range(a.randint(0, 2)):
                c.alocals.append(Var(n.fresh("aloc"), self.array_type()))
            for _ in range(a.choice([0, 0, 1, 2])):
                c.astatus.append(Var(n.fresh("ast"), self.array_type()))
            if not c.type_name and a.random() < 0.4:
                v = Var(n.fresh("aout"), self.array_type())
                c.awrites.append(v)
                self.agm.append(v)
            if self.arecords and a.random() < 0.6:
                c.arecs.append(Var(n.fresh("w"), a.choice(sorted(self.arecords))))
        for c in self.ctrls:
            src = c.instance_of or c
            if c.instance_of:
                continue
            pool = self.aenv + [v for v in self.agm if v not in c.awrites]
            src.areads = a.sample(pool, min(len(pool), a.randint(0, 2)))
        for c in self.ctrls:
            # An array parameter of a verb: the supervisor (or the scenario,
            # for the root) passes a whole array with the command.
            if c.instance_of or not c.verbs or a.random() < 0.6:
                continue
            i = a.randrange(len(c.verbs))
            verb, params = c.verbs[i]
            c.verbs[i] = (verb, params + [(n.fresh("pa"), self.array_type())])

    def controller_type(self) -> None:
        """One leaf controller becomes a controller type with two or three instances,
        under the same supervisor, each with its own parameter values and outputs."""
        ct = self.ct_rng
        n = self.names
        cands = [c for c in self.ctrls[1:] if not c.subs]  # a leaf controller or a simulator
        if not cands or ct.random() < 0.25 or not self.features:
            return
        c = ct.choice(cands)
        parent = next((p for p in self.ctrls if c in p.subs), None)  # none for a simulator
        c.type_name = n.fresh("Ty")
        c.tparams = [(n.fresh("k"), ct.choice(["f64", "f64", "i32", "i64", "u32", "bool", "duration"]))
                     for _ in range(ct.randint(0, 3))]
        tp = self.tp_rng
        if self.arrays and tp.random() < 0.7:
            c.atparams = [(n.fresh("ka"), tp.choice(sorted(self.arrays))) for _ in range(tp.randint(1, 2))]
        for w in c.writes:  # the type writes through `gm` parameters named like its outputs
            self.gm_out.remove(w)
        names = [c.name] + [n.fresh("C", upper=True) for _ in range(ct.randint(1, 2))]
        for name in names:
            vals = [self.literal(t, ct) for _, t in c.tparams] + [self.int_array_literal(t) for _, t in c.atparams]
            c.inst_values.append(vals[:len(c.tparams)])
            outs = []
            for w in c.writes:
                g = Var(n.fresh("out"), w.type)
                self.gm_out.append(g)
                outs.append(self.bind_field(g))
            params = [p for p, _ in c.tparams + c.atparams] + [w.name for w in c.writes]
            values = vals + outs
            # The arguments are written out with the design (`instance_args`):
            # `gm` parameters read may still be added to them.
            c.instances.append((name, (list(zip(params, values)), ct.random() >= 0.5)))
            if name != c.name:
                clone = Ctrl(name, c.level, simulator=c.simulator, verbs=c.verbs, reports=c.reports, status=c.status,
                             locals=c.locals, writes=c.writes, instance_of=c)
                if parent is not None:
                    parent.subs.append(clone)
                self.ctrls.append(clone)
        c.own_outs = [g for g in self.gm_out[len(self.gm_out) - len(c.writes) * len(names):]]

    def bind_field(self, g: Var) -> str:
        """The Global Memory an instance binds a `gm` parameter it writes to:
        `g`, or (the bindings stream) a field of `g`, which then becomes a
        record of the field's type and another."""
        tb = self.tb_rng
        if not self.use_bindings or tb.random() >= 0.4:
            return g.name
        rname, fname = self.names.fresh("RecB"), self.names.fresh("fb")
        self.records[rname] = Record(rname, [(self.names.fresh("fa"), tb.choice(["i32", "bool", "f64"])), (fname, g.type)]
                                     if tb.random() < 0.5 else [(fname, g.type), (self.names.fresh("fa"), "u32")])
        g.type = rname
        return f"{g.name}.{fname}"

    def read_bindings(self) -> None:
        """`gm` parameters a controller type reads (the bindings stream), each
        instance binding its own Global Memory variable or field of one, of
        one type, not one its own instances write."""
        tb = self.tb_rng
        if not self.use_bindings:
            return
        for c in self.ctrls:
            if not c.type_name or tb.random() < 0.3:
                continue
            # Not what its instances write, nor what the type reads already (E0101).
            own = {g.name for g in getattr(c, "own_outs", [])} | {v.name for v in c.reads}
            sources: dict[str, list[str]] = {}
            for v in self.env + self.gm_out:
                if v.name in own:
                    continue
                sources.setdefault(v.type, []).append(v.name)
                for f, ft in self.records[v.type].fields if v.type in self.records else []:
                    sources.setdefault(ft, []).append(f"{v.name}.{f}")
            types = sorted(t for t in sources if t in SCALARS or t in self.enums or t in self.records)
            if not types:
                continue
            t = tb.choice(types)
            fields = sorted(t for t in types if any("." in x for x in sources[t]))
            if fields and tb.random() < 0.8:  # a type that some field has, so that an instance may bind a field
                t = tb.choice(fields)
            pname = self.names.fresh("src")
            c.gm_reads.append((pname, t))
            c.reads.append(Var(pname, t))
            for _, (pairs, _) in c.instances:
                fields = [x for x in sources[t] if "." in x]
                pairs.append((pname, tb.choice(fields if fields and tb.random() < 0.6 else sources[t])))

    def instance_args(self, pairs: list[tuple[str, str]], named: bool) -> str:
        return self.arglist([p for p, _ in pairs], [v for _, v in pairs], named)

    def hierarchy_blocks(self) -> None:
        b = self.blk_rng
        n = self.names
        if not self.use_blocks:
            return
        if self.use_arrays and b.random() < 0.6:
            self.user_blocks.append(n.fresh("ACC", upper=True))
        kinds = sorted(STD_BLOCKS) + self.user_blocks * 3
        for c in self.ctrls:
            if c.instance_of or b.random() < 0.4:
                continue
            for _ in range(b.randint(1, 2)):
                kind = b.choice(kinds)
                if kind in STD_BLOCKS:
                    params, inputs, outputs = STD_BLOCKS[kind]
                    vals = [(p, b.choice(vs)) for p, vs in params]
                else:
                    vals = [("g", b.choice(_F))]
                    if self.acc_wrap:
                        vals.append(("w", "[" + ", ".join(self.tp_rng.choice(INT_EDGES["u32"] + ["0", "1", "2", "3"]) for _ in range(2)) + "]"))
                    inputs = [("x", "f64"), ("i", "i32")]
                    outputs = [("y", "f64")]
                args = self.arglist([p for p, _ in vals], [v for _, v in vals], b.random() >= 0.5)
                c.blocks.append((n.fresh("fb"), kind, args, inputs, outputs))

    def user_block(self, name: str) -> list[str]:
        """A block of the design's own, with an array state indexed by an input."""
        if self.acc_wrap:
            # `w[1] - 3` wraps as a u32 when w[1] < 3, and `w[0] * 2` may.
            return [f"block {name}(g: f64, w: [u32; 2]) {{", "    input x: f64 = 0.0", "    input i: i32 = 0",
                    "    state buf: [f64; 3] = [0.0, (-0.0), 1.0]", "    output y: f64 = 0.0", "    step {",
                    "        buf[i] = x * g + f64(w[1] - 3) - f64(w[0] * 2);",
                    "        y = sum(buf) + min_of(buf) - max_of(buf) + buf[i + 1];", "    }", "}"]
        return [f"block {name}(g: f64) {{", "    input x: f64 = 0.0", "    input i: i32 = 0",
                "    state buf: [f64; 3] = [0.0, (-0.0), 1.0]", "    output y: f64 = 0.0", "    step {",
                "        buf[i] = x * g;", "        y = sum(buf) + min_of(buf) - max_of(buf) + buf[i + 1];", "    }", "}"]

    # ---- rates and CPUs -------------------------------------------------------------

    def placement(self) -> None:
        """One to three CPUs whose heartbeats divide one another (E0602), every
        controller on one of them, a third at a divided rate (a whole number of
        its CPU's heartbeats, E0607); the instances of a controller type run at
        their CPU's rate."""
        m = self.mc_rng
        ncpu = min(len(self.ctrls), m.choice([1, 2, 2, 3]))
        beat = m.choice([5, 10, 20])
        beats = []
        for _ in range(ncpu):
            beats.append(beat)
            beat *= m.choice([1, 2, 3, 5])
        m.shuffle(beats)
        names = [self.names.fresh("CPU", upper=True) for _ in range(ncpu)]
        ctrls = list(self.ctrls)
        m.shuffle(ctrls)
        where = {c.name: i for i, c in enumerate(ctrls[:ncpu])}
        for c in ctrls[ncpu:]:
            where[c.name] = m.randrange(ncpu)
        for i, (name, hb) in enumerate(zip(names, beats)):
            here = [c for c in self.ctrls if where[c.name] == i]
            if m.random() < 0.7:
                here.sort(key=lambda c: -c.level)
            else:
                m.shuffle(here)
            self.cpus.append((name, hb, here))
            for c in here:
                if not c.type_name and not c.instance_of and m.random() < 0.3:
                    self.periods[c.name] = hb * m.choice([2, 3, 4])

    def ages(self, c: Ctrl) -> list[Var]:
        """`age(...)` of what the controller reads: Global Memory and its subordinates."""
        m = self.mc_rng
        out = [Var(f"age({v.name})", "duration") for v in c.reads if m.random() < 0.5]
        for s in c.subs:
            if m.random() < 0.5:
                out.append(Var(m.choice([f"age({s.name})", f"{s.name}.age"]), "duration"))
        return out

    def faults(self, cycles: int) -> list[tuple[int, str]]:
        """`freeze` a controller or `stop` a CPU somewhere in the run."""
        m = self.mc_rng
        out = []
        if m.random() < 0.3:
            out.append((m.randint(1, cycles), f"freeze {m.choice(self.ctrls).name}"))
        if m.random() < 0.15:
            out.append((m.randint(1, cycles), f"stop {m.choice(self.cpus)[0]}"))
        return out

    # ---- declarations ---------------------------------------------------------------

    def declare(self) -> None:
        r = self.rng
        n = self.names
        for _ in range(r.randint(0, 2)):
            self.enums[n.fresh("En")] = [n.fresh("M", upper=True) for _ in range(r.randint(1, 4))]
        for _ in range(r.randint(0, 2)):
            fields = []
            for _ in range(r.randint(1, 3)):
                fields.append((n.fresh("f"), self.rtype(allow_record=True)))
            name = n.fresh("Rec")
            self.records[name] = Record(name, fields)  # earlier records only: no recursion
        for _ in range(r.randint(1, 5)):
            self.consts.append(Var(n.fresh("K", upper=True), self.rtype()))
        for _ in range(r.randint(0, 3)):
            params = [(n.fresh("a"), self.rtype()) for _ in range(r.randint(1, 3))]
            self.fns.append((n.fresh("fun"), params, self.rtype(scalar_weight=10)))
        e = self.ext_rng
        for i in range(e.choice([0, 0, 1, 2])):
            pool = list(SCALARS) * 4 + list(self.enums) + list(self.records)
            params = [(f"x{j}", e.choice(pool)) for j in range(e.randint(0, 3))]
            self.externs.append((f"ext{self.seed % 1000}_{i}", params, e.choice(pool)))
        for _ in range(r.randint(1, 5)):
            self.env.append(Var(n.fresh("in"), self.rtype(scalar_weight=8)))
        if not any(v.type in NUM_TYPES for v in self.env):
            self.env.append(Var(n.fresh("in"), r.choice(NUM_TYPES)))
        if self.use_arrays:
            self.declare_arrays()
        for rec in self.records.values():  # ranges on record fields: every value of the record keeps them
            for f, ft in rec.fields:
                _, bounds = self.ranged(ft, [], 0.3)
                if bounds:
                    self.field_ranges[(rec.name, f)] = bounds

    def hierarchy(self) -> None:
        r = self.rng
        n = self.names
        count = r.randint(1, 4)
        root = Ctrl(n.fresh("C", upper=True), level=count + 1)
        self.ctrls = [root]
        for _ in range(count - 1):
            parent = r.choice([c for c in self.ctrls if c.level > 1])
            child = Ctrl(n.fresh("C", upper=True), level=parent.level - 1)
            parent.subs.append(child)
            self.ctrls.append(child)
        if r.random() < 0.5:
            self.ctrls.append(Ctrl(n.fresh("SIM", upper=True), level=0, simulator=True))
        for c in self.ctrls:
            for _ in range(r.randint(0, 3)):
                c.status.append(Var(n.fresh("st"), self.rtype()))
            for _ in range(r.randint(0, 2)):
                c.locals.append(Var(n.fresh("loc"), self.rtype()))
            for _ in range(r.randint(0 if c.status else 1, 2)):
                v = Var(n.fresh("out"), self.rtype())
                c.writes.append(v)
                self.gm_out.append(v)
            if not c.simulator:
                for _ in range(r.randint(1, 2)):
                    params = [(n.fresh("p"), self.rtype()) for _ in range(r.randint(0, 2))]
                    c.verbs.append((n.fresh("V", upper=True), params))
                c.reports = [n.fresh("REP", upper=True) for _ in range(r.randint(0, 2))]
        self.controller_type()
        for c in self.ctrls:
            if c.instance_of:
                continue
            own = c.writes + getattr(c, "own_outs", [])
            pool = self.env + [v for v in self.gm_out if v not in own]
            c.reads = r.sample(pool, min(len(pool), r.randint(1, 4)))
        if self.use_arrays:
            self.hierarchy_arrays()
        self.hierarchy_blocks()
        self.read_bindings()
        self.sim_verbs()
        self.verb_sets()
        for c in self.ctrls:
            if c.instance_of:
                src = c.instance_of
                c.reads, c.astatus = src.reads, src.astatus

    def stream_type(self, rng: random.Random) -> str:
        return rng.choice(list(SCALARS) * 3 + list(self.enums) + list(self.records))

    def sim_verbs(self) -> None:
        """Simulators that accept commands (the simulator verbs stream): from a
        controller that takes one as a subordinate, or from the scenario when
        it stands outside the command tree."""
        s = self.sv_rng
        n = self.names
        sims = [c for c in self.ctrls if c.simulator and not c.instance_of]
        if not self.use_sim_verbs or not sims:
            return
        for c in sims:
            for _ in range(s.randint(1, 2)):
                c.verbs.append((n.fresh("V", upper=True), [(n.fresh("p"), self.stream_type(s)) for _ in range(s.randint(0, 2))]))
            if s.random() < 0.3:
                c.reports.append(n.fresh("REP", upper=True))
        # Not a controller type: each of its instances would command the same subordinate (E0300).
        supervisors = [c for c in self.ctrls if not c.simulator and not c.type_name and not c.instance_of]
        for c in self.ctrls:  # the instances of a simulator type too, each on its own
            if c.simulator and s.random() < 0.5:
                s.choice(supervisors).subs.append(c)

    def verb_sets(self) -> None:
        """A verb set of the design's own (the verb sets stream) that one to
        three controllers bring in with `verbs NAME`, and std.lifecycle's."""
        v = self.vs_rng
        n = self.names
        if not self.use_verbsets:
            return
        cands = [c for c in self.ctrls if not c.instance_of]
        name = n.fresh("Vs")
        verbs = [(n.fresh("V", upper=True), [(n.fresh("p"), self.stream_type(v)) for _ in range(v.randint(0, 2))])
                 for _ in range(v.randint(1, 2))]
        self.verbsets[name] = verbs
        for c in v.sample(cands, min(len(cands), v.randint(1, 3))):
            c.vsets.append(name)
            c.verbs.extend(verbs)
        if v.random() < 0.4:
            std = v.choice(sorted(STD_VERBSETS))
            for c in v.sample(cands, min(len(cands), v.randint(1, 2))):
                c.vsets.append(std)
                c.verbs.extend(STD_VERBSETS[std])

    def type_period(self) -> None:
        """A controller type's `period` (the bindings stream): a whole number
        of the heartbeats of every CPU its instances run on (E0607)."""
        import math

        tb = self.tb_rng
        for c in self.ctrls:
            if not c.type_name or tb.random() >= 0.5:
                continue
            if self.use_rates:
                beats = [hb for _, hb, here in self.cpus for x in here if x is c or x.instance_of is c]
                self.type_periods[c.type_name] = math.lcm(*beats) * tb.choice([1, 2, 3])
            elif not self.more:  # one CPU of HEARTBEAT_MS (the "more" stream may draw another heartbeat)
                self.type_periods[c.type_name] = HEARTBEAT_MS * tb.choice([2, 3, 5])

    def function(self, name: str, params: list[tuple[str, str]], ret: str, index: int) -> str:
        # A function calls only functions declared before it: no recursion.
        saved = self.fns
        self.fns = self.fns[:index]
        self.budget = 10
        self.in_fn = True
        body = self.expr(ret, [Var(p, t) for p, t in params], 3)
        self.in_fn = False
        self.fns = saved
        # Ranges on the parameters and the result document them (the checker
        # assumes them, no target checks them at run time).
        return (f"fn {name}(" + ", ".join(f"{p}: {self.ranged(t, [], 0.25)[0]}" for p, t in params)
                + f") -> {self.ranged(ret, [], 0.25)[0]} =\n    {body}")

    def bounded(self, t: str, bounds: tuple[str, str] | None) -> str:
        return f"{t} in {bounds[0]}..{bounds[1]}" if bounds else t

    def verb_line(self, verb: str, params: list[tuple[str, str]]) -> str:
        """`verb V(p: T, ...)`, a parameter sometimes with a range (kept for the scenario's commands)."""
        texts = []
        for p, t in params:
            text, bounds = self.ranged(t, [])
            if bounds:
                self.param_ranges[(verb, p)] = bounds
            texts.append(f"{p}: {text}")
        return f"verb {verb}" + (f"({', '.join(texts)})" if texts else "")

    # ---- plans ----------------------------------------------------------------------

    def jobs(self, c: Ctrl, targets: list[Var], scope: list[Var], states_left: bool) -> str:
        r = self.rng
        out = []
        for _ in range(r.randint(0, 2)):
            out.append(self.assign(targets, scope))
        if self.atargets and self.arr_rng.random() < 0.25:
            out.append(self.astmt(scope))
        if self.bcalls and self.blk_rng.random() < 0.2:
            out.append(self.bcall(scope))
        for s in c.subs:
            if r.random() < 0.5:
                verb, params = r.choice(s.verbs)
                self.budget = 8
                args = [self.aval(t, scope) if t in self.arrays else self.expr(t, scope, 2) for _, t in params]
                named = bool(params) and r.random() < 0.5
                out.append(f"{s.name}.{verb}({self.arglist([p for p, _ in params], args, named)})")
        if c.reports and r.random() < 0.4:
            out.append(f"report {r.choice(c.reports)}")
        r.shuffle(out)
        if self.use_ext_stmts and self.externs and self.es_rng.random() < 0.3:
            out.insert(self.es_rng.randint(0, len(out)), self.extern_stmt(scope))
        return ", ".join(out)

    def plan(self, c: Ctrl, verb: str, params: list[tuple[str, str]], scope: list[Var], targets: list[Var]) -> list[str]:
        r = self.rng
        n = self.names
        scope = scope + [Var(f"cmd.{p}", t) for p, t in params if t not in self.arrays]
        if self.more and self.x_rng.random() < 0.3:
            scope = scope + [Var("in_state", "duration")]
        saved_actx = self.actx
        self.actx = (self.actx or []) + [(f"cmd.{p}", t) for p, t in params if t in self.arrays]
        states = [n.fresh("S", upper=True) for _ in range(r.randint(0, 3))]
        continuous = bool(states) and r.random() < 0.2
        mods = (" continuous" if continuous else "") + (" ordered" if r.random() < 0.5 else "")
        labels = iter(f"R{i}" for i in range(100))
        rules = []

        def rule(cond: str, state: str, nxt: str) -> None:
            self.budget = 6
            jobs = self.jobs(c, targets, scope, bool(states))
            rules.extend(self.doc("        "))
            rules.append(f"        {next(labels)}: {cond} | {state} -> {nxt}" + (f" | {jobs};" if jobs else ";"))

        def end() -> str:
            x = self.x_rng
            if self.more and x.random() < 0.25:
                named = [k.name for k in self.consts if k.type == "i32"]
                return x.choice(["error(0)", "error(-5)", "error(2147483647)"] + [f"error({k})" for k in named] * 2)
            return r.choice(["done", f"error({r.randint(1, 99)})", "done"])

        first = states[0] if states else end()
        k = r.random()
        if k < 0.4:
            rule("true", "new", first)
        else:
            g = self.guard(scope, c, False)
            if g == "true":
                rule("true", "new", first)
            else:
                rule(g, "new", first)
                other = r.choice(states + ["done", "error(5)"])
                rule("otherwise" if k < 0.7 else f"not {g}", "new", other)
        if states:
            for s in c.subs:
                rule(f"{s.name}.error", "*", f"error({r.randint(1, 99)})")
            x = self.x_rng
            if self.more and x.random() < 0.4:
                # A `*` rule of another kind: any condition, any target.
                self.budget = 6
                rule(self.guard(scope, c, True), "*", x.choice(states + ["*", "done", end()]))
        for i, st in enumerate(states):
            targets_ = states + ["*", "done", f"error({r.randint(1, 99)})"]
            # Rules whose conditions start alike, with an extern call: each
            # condition evaluated calls it again (nothing shared between rules).
            shared = self.extern_test(scope) if self.more and self.x_rng.random() < 0.3 else None
            for _ in range(r.randint(0, 2)):
                g = self.guard(scope, c, True)
                rule(f"({shared} and {g})" if shared else g, st, r.choice(targets_))
            if i + 1 < len(states):
                rule(self.guard(scope, c, True), st, states[i + 1])
            if r.random() < 0.3:
                rule("otherwise", st, r.choice(targets_ + [end()]))
            else:
                rule(f"in_state >= {r.choice([20, 30, 50, 100])} ms", st, end())
        self.actx = saved_actx
        if self.use_stubs and self.stub_rng.random() < 0.25:
            # A stub plan (docs/language.md section 9.5) in place of the one
            # drawn, whose draws the rest of the seed keeps: it accepts the
            # verb and stays executing until the next command.
            return [f"    plan {verb} continuous {{", f"        R0: true | new -> {self.stub_rng.choice(['EXECUTING', 'S0'])};", "    }"]
        return [f"    plan {verb}{mods} {{", *rules, "    }"]

    # ---- the design -----------------------------------------------------------------

    def design(self, name: str) -> str:
        r = self.rng
        self.declare()
        self.hierarchy()
        if self.use_rates:
            self.placement()
        if self.use_bindings:
            self.type_period()
        out = [f"// generated by bench/difftest_gen.py, seed {self.seed}", f"design {name}", ""]
        if self.std_math:
            out += ["import std.math", ""]
        if any(k in STD_BLOCKS for c in self.ctrls for _, k, _, _, _ in c.blocks):
            out += ["import std.blocks", ""]
        if any(v in STD_VERBSETS for c in self.ctrls for v in c.vsets):
            out += ["import std.lifecycle", ""]
        for e, members in self.enums.items():
            out.append(f"enum {e} {{ {', '.join(members)} }}")
        a = self.arr_rng
        for rec in self.records.values():
            out.append(f"record {rec.name} {{ " + ", ".join(f"{f}: {self.bounded(t, self.field_ranges.get((rec.name, f)))}" for f, t in rec.fields) + " }")
        for lname, size in self.len_consts:
            out.append(f"const {lname}: i32 = {size}")
        for rec in self.arecords.values():
            out.append(f"record {rec.name} {{ " + ", ".join(f"{f}: {t}" for f, t in rec.fields) + " }")
        for i, cst in enumerate(self.consts):
            out += self.doc()
            value = self.derived_const(cst.type, self.consts[:i])
            out.append(f"const {cst.name}: {self.ranged(cst.type, [value])[0]} = {value}")
        for cst in self.aconsts:
            out.append(f"const {cst.name}: {cst.type} = {self.literal(cst.type, a)}")
        for i, (fname, params, ret) in enumerate(self.fns):
            out += self.doc()
            out.append(self.function(fname, params, ret, i))
        for fname, at, it, ret, body in self.afns:
            out.append(f"fn {fname}(xs: {at}, i: {it}) -> {ret} =\n    {body}")
        for fname, at, elem, body in self.arfns:
            out.append(f"fn {fname}(xs: {at}, k: {elem}) -> {at} =\n    {body}")
        for ename, params, ret in self.externs:
            out.append(f"extern fn {ename}(" + ", ".join(f"{p}: {self.ranged(t, [], 0.2)[0]}" for p, t in params)
                       + f") -> {self.ranged(ret, [], 0.2)[0]} budget 1 us")
        for vsname, verbs in self.verbsets.items():
            out.append(f"verbset {vsname} {{")
            out += ["    " + self.verb_line(verb, params) for verb, params in verbs]
            out.append("}")
        for bname in self.user_blocks:
            out += self.user_block(bname)
        for v in self.env:
            out += self.doc()
            init = self.literal(v.type)
            out.append(f"gm {v.name}: {self.ranged(v.type, [init])[0]} = {init} from env")
        for v in self.aenv:
            out.append(f"gm {v.name}: {v.type} = {self.literal(v.type, a)} from env")
        for v in self.gm_out:
            init = self.literal(v.type)
            out.append(f"gm {v.name}: {self.ranged(v.type, [init])[0]} = {init}")
        for v in self.agm:
            out.append(f"gm {v.name}: {v.type} = {self.literal(v.type, a)}")
        out.append("")
        for c in self.ctrls:
            if c.instance_of:
                continue
            kind = "simulator" if c.simulator else "controller"
            if c.type_name:
                tps = [f"{p}: {self.ranged(t, [vals[i] for vals in c.inst_values])[0]}" for i, (p, t) in enumerate(c.tparams)]
                tps += [f"{p}: {t}" for p, t in c.atparams] + [f"{w.name}: gm" for w in c.writes]
                tps += [f"{p}: gm" for p, _ in c.gm_reads]
                period = f" period {self.type_periods[c.type_name]} ms" if c.type_name in self.type_periods else ""
                out.append(f"{kind} type {c.type_name}({', '.join(tps)}) level {c.level} budget 100 us{period} {{")
            else:
                period = f" period {self.periods[c.name]} ms" if c.name in self.periods else ""
                out += self.doc()
                out.append(f"{kind} {c.name} level {c.level} budget 100 us{period} {{")
            if c.subs:
                out.append(f"    subordinates {', '.join(s.name for s in c.subs)}")
            if c.reads or c.areads:
                out.append(f"    reads {', '.join(v.name for v in c.reads + c.areads)}")
            if c.writes or c.awrites:
                out.append(f"    writes {', '.join(v.name for v in c.writes + c.awrites)}")
            from_sets = {verb for vs in c.vsets for verb, _ in self.verbsets.get(vs, STD_VERBSETS.get(vs, []))}
            out += [f"    verbs {vs}" for vs in c.vsets]
            for verb, params in c.verbs:
                if verb not in from_sets:
                    out.append("    " + self.verb_line(verb, params))
            if c.reports:
                out.append(f"    reports {', '.join(c.reports)}")
            for v in c.status:
                init = self.literal(v.type)
                out.append(f"    status {v.name}: {self.ranged(v.type, [init])[0]} = {init}")
            for v in c.locals:
                init = self.literal(v.type)
                out.append(f"    local {v.name}: {self.ranged(v.type, [init])[0]} = {init}")
            for v in c.astatus:
                out.append(f"    status {v.name}: {v.type} = {self.literal(v.type, a)}")
            for v in c.alocals + c.arecs:
                out.append(f"    local {v.name}: {v.type} = {self.literal(v.type, a)}")
            for inst, bkind, bargs, _, _ in c.blocks:
                out.append(f"    block {inst}: {bkind}({bargs})")
            targets = c.status + c.locals + c.writes
            scope = c.reads + targets
            for s in c.subs:  # the supervisor's view of a subordinate's status fields
                scope = scope + [Var(f"{s.name}.{v.name}", v.type) for v in s.status]
                if self.more and self.x_rng.random() < 0.5:
                    # Its status as values, outside rule conditions too (`fault = S.error_code`).
                    values = [Var(f"{s.name}.error_code", "i32"), Var(f"{s.name}.done", "bool"),
                              Var(f"{s.name}.error", "bool"), Var(f"{s.name}.executing", "bool")]
                    self.sub_values.update(v.name for v in values)
                    scope = scope + values
                # A block's outputs are status fields of its controller, `INSTANCE__OUTPUT`.
                for inst, _, _, _, outputs in (s.instance_of or s).blocks:
                    scope += [Var(f"{s.name}.{inst}__{o}", t) for o, t in outputs if self.blk_rng.random() < 0.6]
            scope += [Var(p, t) for p, t in c.tparams]  # a controller type's value parameters
            if self.use_rates:
                scope += self.ages(c)
            for inst, _, _, _, outputs in c.blocks:
                scope += [Var(f"{inst}.{o}", t) for o, t in outputs]
            own = [(v.name, v.type) for v in c.alocals + c.astatus + c.awrites]
            own += [(f"{w.name}.{self.arecords[w.type].fields[0][0]}", self.arecords[w.type].fields[0][1]) for w in c.arecs]
            self.atargets = own
            self.actx = own + [(v.name, v.type) for v in c.areads + self.aconsts] + list(c.atparams)
            self.actx += [(f"{s.name}.{v.name}", v.type) for s in c.subs for v in s.astatus]
            self.aidx = [f"{w.name}.{self.arecords[w.type].fields[1][0]}" for w in c.arecs]
            self.bcalls = [(inst, inputs) for inst, _, _, inputs, _ in c.blocks]
            for block in ("pre", "post"):
                if r.random() < 0.8:
                    out.append(f"    {block} {{")
                    out += self.block(targets, scope, "        ", r.randint(1, 4))
                    out.append("    }")
            for verb, params in c.verbs:
                out += self.plan(c, verb, params, scope, targets)
            out.append("}")
            self.actx, self.atargets, self.aidx, self.bcalls = None, [], [], []
            for iname, (pairs, named) in c.instances:
                out.append(f"{kind} {iname}: {c.type_name}({self.instance_args(pairs, named)})")
            out.append("")
        order = list(self.ctrls)
        if r.random() < 0.7:
            order.sort(key=lambda c: -c.level)  # simulators last, supervisors first
        else:
            r.shuffle(order)
        if not self.use_rates:
            self.cpus = [("MAIN", HEARTBEAT_MS, order)]
        one_beat = None
        if not self.use_rates and self.more and self.x_rng.random() < 0.3:
            # The heartbeat in other units and lengths: time-outs written in
            # ms then fall between steps (rounded up to the next one, W0601).
            one_beat = self.x_rng.choice(["10000 us", "1500 us", "2 ms", "250 us", "1 s"])
        for cpu, beat, here in self.cpus:
            out += self.doc() + [f"cpu {cpu} {{", f"    heartbeat {one_beat or f'{beat} ms'}", f"    schedule {', '.join(c.name for c in here)}", "}", ""]
        return "\n".join(out)

    def scenario(self) -> str:
        r = self.rng
        cycles = r.randint(10, 60)
        if self.use_rates:
            cycles += self.mc_rng.randint(0, 60)  # ticks of the shortest heartbeat: slow CPUs need more
        lines = [f'scenario "seed {self.seed}"', f"cycles {cycles}"]
        root = self.ctrls[0]
        events = []
        for _ in range(r.randint(1, 6)):
            verb, params = r.choice(root.verbs)
            args = [self.array_literal(t, self.arr_rng, scenario=True) if t in self.arrays else self.literal(t) for _, t in params]
            # A command's argument must lie in its parameter's range (E0206).
            args = [self.fit(a, t, self.param_ranges.get((verb, p))) for (p, t), a in zip(params, args)]
            named = bool(params) and r.random() < 0.5
            events.append((r.randint(1, cycles), f"{root.name}.{verb}({self.arglist([p for p, _ in params], args, named)})"))
        for _ in range(r.randint(0, 10)):
            v = r.choice(self.env)
            cand = [c.name for c in self.consts if c.type == v.type]
            value = r.choice(cand) if cand and r.random() < 0.3 else self.literal(v.type)
            events.append((r.randint(1, cycles), f"{v.name} = {value}"))
        for v in self.aenv:
            a = self.arr_rng
            for _ in range(a.randint(0, 3)):
                events.append((a.randint(1, cycles), f"{v.name} = {self.array_literal(v.type, a, scenario=True)}"))
        if self.use_rates:
            events += self.faults(cycles)
        events += self.sim_commands(cycles)
        events.sort(key=lambda e: e[0])
        lines += [f"at {t}: {text}" for t, text in events]
        if self.use_expects:
            lines += self.expects(cycles)
        return "\n".join(lines) + "\n"

    def sim_commands(self, cycles: int) -> list[tuple[int, str]]:
        """Commands to the simulators with verbs outside the command tree (the simulator verbs stream)."""
        s = self.sv_rng
        subs = {id(x) for c in self.ctrls for x in c.subs}
        out = []
        for c in self.ctrls:
            if not c.simulator or not c.verbs or id(c) in subs:
                continue
            for _ in range(s.randint(0, 3)):
                verb, params = s.choice(c.verbs)
                args = [self.fit(self.literal(t, s), t, self.param_ranges.get((verb, p))) for p, t in params]
                out.append((s.randint(1, cycles), f"{c.name}.{verb}({self.arglist([p for p, _ in params], args, s.random() < 0.5)})"))
        return out

    def expects(self, cycles: int) -> list[str]:
        """`expect` lines (the expectations stream): the statuses, states,
        verbs and rules of controllers, their status fields and Global Memory
        in conditions drawn like the design's.  Whether they hold does not
        matter: the harness compares what they find in the simulator with
        what they find in each program's trace."""
        x = self.ex_rng
        scope = [Var(v.name, v.type) for v in self.env + self.gm_out]
        for c in self.ctrls:
            scope += [Var(f"{c.name}.{v.name}", v.type) for v in c.status]
            scope += [Var(f"{c.name}.error_code", "i32"), Var(f"{c.name}.echo", "i32"), Var(f"{c.name}.done", "bool")]
        out = []
        for _ in range(x.randint(1, 5)):
            c = x.choice(self.ctrls)
            k = x.random()
            if k < 0.15:
                cond = f"{c.name}.status == {x.choice(['DONE', 'EXEC', 'ERROR', 'UNINITIALIZED'] + c.reports)}"
            elif k < 0.25 and c.verbs:
                cond = f"{c.name}.verb {x.choice(['==', '!='])} {x.choice(c.verbs)[0]}"
            elif k < 0.35:
                cond = f"{c.name}.state {x.choice(['==', '!='])} {x.choice(['new', 'done', 'error'])}"
            elif k < 0.45:
                cond = f"{x.choice(['', 'not '])}{c.name}.{x.choice(['done', 'error', 'executing'] + c.reports)}"
            else:
                with self.drawing_from(x):
                    self.in_fn = True  # no extern call in an expectation (E0211)
                    self.budget = 8
                    cond = self.cond(scope, 2)
                    self.in_fn = False
            lo = x.randint(1, cycles)
            when = x.choice(["at", "within", "always", "final"])
            if when == "at":
                out.append(f"expect at {lo}: {cond}")
            elif when == "within":
                out.append(f"expect within {lo}..{x.randint(lo, cycles)}: {cond}")
            else:
                out.append(f"expect {when}: {cond}")
        return out


def draw(seed: int, attempt: int, hostile: bool = False, features: bool = True) -> Case:
    """One draw, not checked.  `features=False`: no arrays, controller types or
    blocks -- the seed's design as the generator drew it before them."""
    gen = DesignGen(seed * 1000 + attempt, hostile, features)
    name = f"d{seed}"
    design = gen.design(name)
    return Case(seed, design, gen.scenario(), attempt, name)


def generate(seed: int, hostile: bool = False, max_attempts: int = 50, features: bool = True) -> Case:
    """The first draw of `seed` whose design checks without errors and whose scenario loads.

    Random conditions often hide a later rule behind an earlier one (E0506)
    or are never true (E0513); such rules, and then the rules of states that
    their deletion left unreachable (E0502), are deleted and the design
    checked again, a few times, before the next draw is taken.
    """
    for attempt in range(max_attempts):
        case = draw(seed, attempt, hostile, features)
        for _ in range(8):
            errors, dead = check_case(case)
            if not errors:
                return case
            # Only dead rules: delete them (a controller type's is reported once per instance, at one line).
            if not dead or any(not e.startswith(tuple(f"{c}:" for c in DEAD_CODES)) for e in errors):
                break
            lines = case.design.split("\n")
            case.design = "\n".join(x for i, x in enumerate(lines, 1) if i not in dead)
    raise RuntimeError(f"seed {seed}: no valid design in {max_attempts} draws")


# The findings of rules that never fire, which `generate` deletes (at the line of each finding).
DEAD_CODES = ("E0506", "E0513", "E0502")

_SOLVER_CACHE: list[str] = []


def solver_cache() -> str:
    """The run's one folder of solver results (`rcsc.checks.cache`), made on first use.

    The generator's check of a design, the runner's check and every
    `rcsc build` of it ask the solver the same questions; their entries are
    keyed by the plans' content, so the later checks read the first one's
    answers (RCSC_NO_CACHE=1 still turns this off)."""
    if not _SOLVER_CACHE:
        import atexit
        import shutil
        import tempfile

        folder = tempfile.mkdtemp(prefix="difftest-cache-")
        atexit.register(shutil.rmtree, folder, True)
        _SOLVER_CACHE.append(folder)
    return _SOLVER_CACHE[0]


def check_case(case: Case) -> tuple[list[str], set[int]]:
    """The errors of `rcsc check` on the design and of loading its scenario
    (none: clean), and the lines of the rules that can never fire (E0506)."""
    import tempfile
    from pathlib import Path

    from rcsc.diagnostics import Diagnostics
    from rcsc.driver import check_path
    from rcsc.front.scenario import text_to_scenario
    from rcsc.front.source import SourceFile

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"{case.name}.rcs"
        path.write_text(case.design, encoding="utf-8")
        result = check_path(str(path), cache_dir=solver_cache())
        errors = [f"{d.code}: {d.message}" for d in result.diags.errors]
        # Rules that never fire: hidden (E0506), never true (E0513), or in a
        # state that the deletion of such rules left unreachable (E0502).
        dead = {d.span.line for d in result.diags.errors if d.code in DEAD_CODES and d.span is not None}
        if errors or result.model is None:
            return errors or ["no model"], dead
        diags = Diagnostics()
        sc = text_to_scenario(SourceFile("s.scn", case.scenario), result.model, diags)
        errors = [f"{d.code}: {d.message}" for d in diags.errors]
        if sc is None and not errors:
            errors = ["scenario did not load"]
        return errors, set()
