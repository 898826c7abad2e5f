"""The table of diagnostic codes: stable code, default severity, title, explanation.

Codes never change meaning once released.  `rcsc explain CODE` prints the
explanation; the SARIF rendering publishes the table as rule metadata.  The
tests require every code here to have an explanation and a test input that
asserts its code, line and column.

Numbering: E00xx syntax and files, E01xx names, E02xx types and values,
E03xx hierarchy, E04xx Global Memory ownership, E05xx plans, E06xx timing.
W-codes are warnings (lints); they fail a run only with --deny-warnings.
"""

from __future__ import annotations

from dataclasses import dataclass

from rcsc.diagnostics import Severity


@dataclass(frozen=True)
class Code:
    code: str
    severity: Severity
    title: str
    explanation: str


_E = Severity.ERROR
_W = Severity.WARNING

_TABLE: list[tuple[str, Severity, str, str]] = [
    # ---- syntax and files ---------------------------------------------------
    ("E0001", _E, "syntax error", """
The parser met a token that cannot continue the design at this point. The
note lists what would have been accepted. A common cause is a state-table rule
missing its closing `;`. Every rule has the form

    LABEL: condition | current-state -> next-state | job, job ;
"""),
    ("E0002", _E, "unexpected character", """
The text contains a character that is not part of the language, or a string
(an import path) that is never closed. Comments are `// ...` and `/* ... */`.
"""),
    ("E0003", _E, "cannot read imported file", """
An `import "path.rcs"` names a file that does not exist or cannot be read. Paths
are relative to the folder of the file that imports them. No file name holds a
NUL character: a path with one is refused here too.
"""),
    ("E0004", _E, "import outside the design folder", """
A local import must stay inside the design's own folder (the folder of the file
given to rcsc). Absolute paths and paths that climb out with `..` are refused so
that a design can be moved and checked anywhere. Shared code belongs in a
standard-library module or a copy inside the design folder.
"""),
    ("E0005", _E, "unknown standard-library module", """
`import std.NAME` names a module that the installed rcsc standard library does
not have. `rcsc explain E0005` lists nothing more; see docs/stdlib.md for the
modules that exist.
"""),
    ("E0006", _E, "wrong file header", """
The file given to rcsc must begin with `design NAME`; a file brought in with
`import` must begin with `module NAME` (or have no header). One design is one
file set with exactly one `design` header.
"""),
    ("E0007", _E, "nested too deeply", """
An expression or a block of `if` statements is nested more than 128 levels
deep (for example a sum of hundreds of terms written on one line). rcsc refuses
it rather than risk running out of stack in later passes. Compute parts of the
expression in locals or move them into functions.
"""),
    ("E0008", _E, "bidirectional control character", """
The text contains a Unicode bidirectional control character (U+202A to U+202E,
U+2066 to U+2069, U+200E, U+200F or U+061C), in a comment, a string or anywhere
else. These characters change the order in which an editor or a code review
displays the text around them, so a design can show one thing and mean another
(the "trojan source" attack, CVE-2021-42574): a condition that looks commented
out, a comment that seems to end early. rcsc refuses them wherever they stand;
delete them. Other non-ASCII text is allowed in comments.
"""),
    ("E0009", _E, "invalid configuration", """
The configuration file (`rcsc.toml`, or the `[tool.rcsc]` table of a
`pyproject.toml`, the first one found walking up from the checked file) has a
mistake: it is not valid TOML, it has a key rcsc does not know, a value of the
wrong type, or a diagnostic code that does not exist. The keys are `select`,
`ignore`, `severity`, `exclude` and `per-file-ignores` (docs/configuration.md).
Only warnings can be ignored or have their severity changed: an error means
the design is wrong whatever a report shows.
"""),
    ("E0010", _E, "file is not UTF-8 text", """
rcsc reads designs, modules, scenarios and the configuration as UTF-8. The
file has a byte that is not UTF-8 (often a file saved as Latin-1 or
Windows-1252: an accented letter in a comment is enough); the finding points
at the first one, shown as `\ufffd`. Nothing else of the file is checked, as
the rest could be read wrong. Save the file as UTF-8 (for example with
`iconv -f latin1 -t utf-8 old.rcs > new.rcs`).
"""),
    ("W0008", _W, "malformed or unused suppression", """
A comment `// rcsc: allow(CODE) reason` suppresses the CODE findings that start
on its line (or, when it stands alone on its line, on the next line). It must
name known warning codes (an error cannot be allowed), give a reason, and
cover a finding; otherwise it is reported, so that stale or careless
suppressions do not pile up. Suppressed findings stay in the SARIF report,
marked as suppressed in the source with their reason.

Wrong:

    F3: level >= 2.0 | S1 -> done;   // rcsc: allow(W0515)

Fixed:

    F3: level >= 2.0 | S1 -> done;   // rcsc: allow(W0515) the arrival wins over the time-out on purpose
"""),
    # ---- names --------------------------------------------------------------
    ("E0100", _E, "unknown name", """
A name is used that is not declared where it is used. Inside a controller the
visible names are: constants, functions, enum types, the Global Memory variables
the controller lists in `reads` or `writes`, its locals and status fields, its
subordinates (as `SUB.done`, ...), and in a plan `cmd.PARAM` and `in_state`.
A GM variable that exists but is not listed in `reads` is reported with a help.
"""),
    ("E0101", _E, "duplicate definition", """
Two declarations in the same scope have the same name. Every type, constant,
Global Memory variable, function, controller, CPU, verb, local, status field
and rule label must be unique in its scope.

A local or a status field may not take the name of a Global Memory variable
its controller reads or writes: inside the controller the bare name would be
the local, and the variable would silently never be read or written.
"""),
    ("W0101", _W, "a status field or value named like a built-in status", """
A status field, and an extra status value of `reports`, are there to be read:
by the supervisor (`SUB.name`), by scenarios (`NAME.name`) and by the
console. A few names already mean something there.

A supervisor reads `SUB.done`, `SUB.error`, `SUB.executing`, `SUB.error_code`
and `SUB.age` as its built-in view of the subordinate, and a scenario reads
`NAME.done`, `NAME.error`, `NAME.executing`, `NAME.error_code` and
`NAME.echo` from the controller's status block. A status field or value with
one of these names still holds its value (a status value is still reported),
and the generated code keeps it, but those readers never see it: they read
the built-in, so a supervisor that waits on `SUB.done` after `report done`
waits for the plan to finish instead.

A scenario also compares `NAME.status`, `NAME.state`, `NAME.rule` and
`NAME.verb` with names (`NAME.state == S1`). A field with one of these names
is read as the field elsewhere (`NAME.state > 2`), and as the built-in in
such a comparison: one name with two meanings, reported too.

(A status field named like one of the controller's own status values is
E0101: `SUB.homed` could name either.)

Wrong:

    status done: bool = false          // SUB.done is the built-in
    reports done                       // so is this one

Fixed:

    status homed: bool = false         // SUB.homed is this field
    reports AT_GOAL                    // SUB.AT_GOAL is this value
"""),
    ("E0102", _E, "unknown type", """
A type name is neither a built-in type (bool, i32, i64, u32, f64, duration) nor
an enum or record declared in the design or its imports.
"""),
    ("E0103", _E, "no such field or attribute", """
`x.name` names a field that the record, enum, command or subordinate does not
have. On a subordinate `S` the attributes are `S.done`, `S.error`,
`S.executing`, `S.error_code`, `S.age`, its declared extra status values
(`S.AT_GOAL`) and its declared status fields.
"""),
    ("E0104", _E, "unknown controller", """
A `subordinates` list or a CPU `schedule` names a controller that the design
does not declare.
"""),
    ("E0105", _E, "verb not accepted by the subordinate", """
A job list issues `SUB.VERB(...)` but SUB declares no such verb. A command may
only use a verb that the subordinate accepts (paper section 5.3.2).
"""),
    ("E0106", _E, "unknown verb set, or a verb set declared as a verb", """
`verbs NAME` in a controller names no `verbset` of the design or its imports.
Declare the verb set, import the module that has it (`import std.lifecycle`
for `Lifecycle`), or list the verbs one by one with `verb`.

`verb NAME` (one verb, without parameters or a plan of that name) where NAME
is a verb set was meant as `verbs NAME`: write `verbs` to take the set's verbs.
"""),
    ("E0107", _E, "unknown status value", """
`report NAME` names a status value the controller did not declare with
`reports NAME`. The built-in values DONE, EXEC and ERROR are set by `-> done`,
by a new command and by `-> error(code)`; extra values are declared.
"""),
    ("E0108", _E, "command parameter outside a plan", """
`cmd.PARAM` reads a parameter of the command being executed. It is only
available inside the plan of a verb that declares that parameter, because in
`pre` and `post` the active command may be any verb (or none).
"""),
    # ---- types and values ---------------------------------------------------
    ("E0200", _E, "mismatched types", """
An expression has a different type from the one its place requires: a condition
that is not bool, an assignment of f64 to an i32 variable, an argument of the
wrong type. rcsc never converts silently between numeric types (except that an
integer literal may stand for an f64); use `f64(x)`, `i32(x)`, `i64(x)`,
`u32(x)` to convert.
"""),
    ("E0201", _E, "wrong number of arguments", """
A call of a function, a record constructor or a command to a subordinate gives
more or fewer arguments than the declaration has parameters.
"""),
    ("E0202", _E, "bad named argument", """
A named argument `name = value` names no parameter, names one twice, or gives a
parameter already given by position.
"""),
    ("E0203", _E, "assignment to a read-only value", """
Only locals, status fields, Global Memory variables listed in the controller's
`writes`, and fields of those may be assigned. Constants, command parameters,
GM variables the controller only reads, subordinates' status and `in_state`
are read-only.
"""),
    ("E0204", _E, "not a constant expression", """
Constant values, initial values, enum-free ranges and `error(code)` codes must
be computable when the design is compiled: literals, constants, enum members
and arithmetic on them.
"""),
    ("E0205", _E, "recursive function", """
Functions must run in bounded time (paper section 1.3: atomic algorithms), so a
function may not call itself, directly or through other functions.
"""),
    ("E0206", _E, "value outside its declared range", """
A constant or initial value lies outside the range declared with
`TYPE in LO..HI`, or the range is empty (LO > HI).
"""),
    ("E0207", _E, "integer literal out of range", """
An integer literal does not fit in the fixed-width type its place requires
(i32: -2^31..2^31-1, i64: -2^63..2^63-1, u32: 0..2^32-1).
"""),
    ("E0208", _E, "operator not defined for this type", """
The operator cannot be applied to values of this type: arithmetic on bool or
enums, `%` on f64, ordering comparisons on enums or bools, `and`/`or`/`not` on
numbers.
"""),
    ("E0209", _E, "missing or repeated controller attribute", """
Every controller declares `level N` and `budget DURATION` once in its header,
and every CPU declares `heartbeat DURATION` and `schedule ...` once.
"""),
    ("E0210", _E, "duration finer than a nanosecond", """
Durations are exact whole numbers of nanoseconds. `1.5 us` is fine; `0.0001 ns`
cannot be represented.
"""),
    ("E0212", _E, "float literal out of range", """
A decimal float literal is larger in magnitude than the largest f64 (about
1.8e308). It would silently become infinity, so it is refused; write the
largest value you mean, or compute infinity explicitly (e.g. `1.0 / 0.0`).
"""),
    ("E0211", _E, "not callable here", """
The name called is not a function, extern, record type or conversion, or an
`extern` function is called inside a pure `fn` (pure functions must be the same
on every target and cannot call hand-written code).
"""),
    ("W0213", _W, "the value of a call is not used", """
A function call written as a statement, in `pre`, `post`, an `if` or a rule's
job list, whose value nothing takes. A `fn`, a built-in function and a
conversion do nothing but compute their value, so the call has no effect:
most often an assignment was meant. (A block instance is called as a
statement on purpose, and so may an `extern` function, for what its
hand-written code does.)

Wrong:

    post { abs(speed); }

Right:

    post { speed = abs(speed); }
"""),
    # ---- controller types and function blocks -------------------------------
    ("E0260", _E, "unknown controller type or block", """
`controller NAME: TYPE(...)` names a controller type that is not declared, or
`block NAME: TYPE(...)` in a controller names a block that is not declared.
The standard blocks need `import std.blocks`.

Wrong:

    controller XAX: Axs(lo = 0.0, hi = 600.0)

Fixed:

    controller XAX: Axis(lo = 0.0, hi = 600.0)
"""),
    ("E0261", _E, "missing argument of a controller type or block", """
Every parameter of a controller type or a block needs a value where it is
instantiated: parameters have no defaults.

Wrong:

    controller type Axis(max_speed: f64, pos_cmd: gm) level 1 budget 1 ms { ... }
    controller XAX: Axis(max_speed = 2.0)

Fixed:

    controller XAX: Axis(max_speed = 2.0, pos_cmd = x_cmd)
"""),
    ("E0262", _E, "extra or unknown argument", """
An instance gives an argument the type (or block) has no parameter for, gives
one twice, or gives more positional arguments than there are parameters; or a
call of a block instance passes a value to something that is not one of the
block's inputs.

Wrong:

    block f: LOWPASS(tau = 0.5, dt = 0.01, gain = 2.0)

Fixed:

    block f: LOWPASS(tau = 0.5, dt = 0.01)
"""),
    ("E0263", _E, "`gm` parameter not bound to Global Memory", """
A `gm` parameter of a controller type stands for a Global Memory variable (or a
field of one) that each instance chooses; its argument must be such a name, not
an expression.

Wrong:

    controller XAX: Axis(pos_cmd = x_cmd + 1.0)

Fixed:

    controller XAX: Axis(pos_cmd = x_cmd)
    controller YAX: Axis(pos_cmd = table.y)    // a field is fine
"""),
    ("E0264", _E, "parameter used as a variable", """
The value parameters of a controller type or a block are compile-time constants
inside it: they cannot be assigned, and a member cannot have a parameter's name.

Wrong:

    controller type Axis(max_speed: f64) level 1 budget 1 ms {
        post { max_speed = 1.0; }
    }

Fixed:

    controller type Axis(max_speed: f64) level 1 budget 1 ms {
        local speed: f64 = 0.0
        post { speed = max_speed; }
    }
"""),
    ("E0265", _E, "misuse of a block's step", """
A block has exactly one `step`: a list of assignments to its own `state` and
`output` members, run in order each time the block is called. It has no `if`
statements, calls or commands (a choice is an `if ... then ... else`
expression), and it does not assign its inputs or parameters.

Wrong:

    step { if e > 0.0 { y = 1.0; } }

Fixed:

    step { y = if e > 0.0 then 1.0 else y; }
"""),
    ("E0266", _E, "misuse of a block instance", """
From the controller, a block instance is run by calling it with its inputs,
`pid(err = e);`, and read through its outputs, `pid.y`. Its state and inputs
are private, its outputs are written only by its step, and the instance itself
is not a value.

Wrong:

    post { u = pid.integ; pid.y = 0.0; }

Fixed:

    post { pid(err = e); u = pid.y; }
"""),
    ("E0267", _E, "block instance defined twice", """
Two `block` lines of one controller use the same name, or a block instance has
the name of a status field or local of the controller. Each instance has its
own state, so each needs its own name.

Wrong:

    block f: LOWPASS(tau = 0.5, dt = 0.01)
    block f: LOWPASS(tau = 0.1, dt = 0.01)

Fixed:

    block f: LOWPASS(tau = 0.5, dt = 0.01)
    block g: LOWPASS(tau = 0.1, dt = 0.01)
"""),
    ("W0260", _W, "controller type or block never instantiated", """
A controller type or block declared in the design has no instance. Its body is
checked in each instance (with that instance's arguments), so with none it is
not checked at all: instantiate it, or remove it.

Wrong:

    controller type Axis(lo: f64, hi: f64) level 1 budget 1 ms { ... }

Fixed:

    controller type Axis(lo: f64, hi: f64) level 1 budget 1 ms { ... }
    controller XAX: Axis(lo = 0.0, hi = 600.0)
"""),
    ("W0261", _W, "block instance never called", """
A controller declares a block instance but never runs a step of it: its
outputs keep their initial values forever, and its step is not checked
(a step is checked where it is called).

Wrong:

    block filt: LOWPASS(tau = 0.5, dt = 0.01)
    post { out = filt.y; }

Fixed:

    block filt: LOWPASS(tau = 0.5, dt = 0.01)
    post { filt(x = raw); out = filt.y; }
"""),
    # ---- arrays and path plans ----------------------------------------------
    ("E0250", _E, "empty array", """
An array holds at least one element: its length (`[T; N]`, `[value; N]`) is 1
or more, and an array literal `[a, b, ...]` lists at least one element. A path
plan steps through the knots of a path, so an empty path has nothing to step
through: give it at least one knot and keep the number in use in a separate
count (`count: i32 in 1..8`).

Wrong:

    verb FOLLOW(xs: [f64; 0])

Fixed:

    verb FOLLOW(xs: [f64; MAX_KNOTS], count: i32 in 1..8)
"""),
    ("E0251", _E, "array length is not an integer constant", """
An array's length, and the count of `[value; count]`, is fixed when the design
is compiled: an integer literal or the name of an integer constant, at most
65536. The value repeated by `[value; count]` is a constant too (fill an array
of run-time values element by element, or write the elements out).

Wrong:

    local xs: [f64; n] = [0.0; n]        // n is a local

Fixed:

    const N: i32 = 16
    local xs: [f64; N] = [0.0; N]
"""),
    ("E0252", _E, "array literal of the wrong length", """
An array literal must have as many elements as the array type it initialises or
is assigned to: arrays of different lengths are different types. Write every
element, or use the repeat form `[value; N]`.

Wrong:

    gm trail: [f64; 4] = [0.0, 0.0]

Fixed:

    gm trail: [f64; 4] = [0.0; 4]
"""),
    ("E0253", _E, "not an array, or an index that is not an integer", """
Only arrays can be indexed (`a[i]`), and an index is an integer (`i32`, `i64` or
`u32`); `len`, `sum`, `min_of` and `max_of` take an array. Convert a float
index explicitly, which says how it is rounded.

Wrong:

    setpoint = cmd.xs[t / DT]            // t / DT is f64

Fixed:

    setpoint = cmd.xs[i32(t / DT)]
"""),
    ("E0254", _E, "operation not defined for arrays", """
Arrays are assigned and passed whole, and read and written element by element.
They cannot be compared with `==`/`!=` (compare the elements you mean), updated
whole with `+=`, `-=` or `*=`, or carry a declared range on their elements.

Wrong:

    F1: path == HOME_PATH | new -> done;

Fixed:

    F1: path[0] == HOME_PATH[0] and path[1] == HOME_PATH[1] | new -> done;
"""),
    ("W0250", _W, "array index always out of range", """
The index is a constant outside 0..N-1 of an array of N elements. The access is
defined (a read gives the element type's zero value: 0, 0.0, false, the first
enum member, a record or array of zeros; a write is ignored) and is the same in
the simulator, C and Rust, but it is almost certainly an off-by-one.

Wrong:

    setpoint = Knot(x = cmd.xs[8], y = cmd.ys[8])     // xs: [f64; 8]

Fixed:

    setpoint = Knot(x = cmd.xs[7], y = cmd.ys[7])
"""),
    ("W0251", _W, "array index may be out of range", """
In the rule named, with the inputs of the witness (its own condition true, the
earlier rules of its state false, declared ranges assumed), an index is outside
0..N-1 of the array it reads or writes. Out of range a read gives the element
type's zero value and a write is ignored, in every execution, so the step goes
on with a wrong value. A path plan steps its knot index through the path: test
the end of the path in an earlier rule of the state, and keep the index from
going below zero (a declared range).

Wrong:

    status k: i32 = 0
    F1: k >= cmd.count          | STEP -> SETTLE;
    F2: otherwise               | STEP -> STEP | setpoint = cmd.xs[k], k += 1;

Fixed:

    status k: i32 in 0..8 = 0
    F1: k >= cmd.count or k >= len(cmd.xs) | STEP -> SETTLE;
    F2: otherwise               | STEP -> STEP | setpoint = cmd.xs[k], k += 1;
"""),
    # ---- hierarchy ----------------------------------------------------------
    ("E0300", _E, "controller has more than one supervisor", """
RCS hierarchies are trees (paper sections 3.2 and 3.5): every controller takes
commands from exactly one supervisor. Two controllers list this one in their
`subordinates`.
"""),
    ("E0301", _E, "cycle in the command hierarchy", """
Following `subordinates` from this controller leads back to it. The chain of
command must be a tree.
"""),
    ("E0302", _E, "subordinate level not below its supervisor", """
A subordinate's `level` must be lower than its supervisor's (paper section 3.5:
levels are ordered by time horizon and span of control).
"""),
    ("E0303", _E, "more than one top-level controller", """
Operator commands enter at the top of the hierarchy only (paper section 3.7), so
all non-simulator controllers form one tree with a single root. Simulators
(plant models) may stand outside the tree.
"""),
    ("W0310", _W, "too many subordinates", """
The paper (section 3.4) recommends a span of control of about seven, and no
more than about nine, subordinates per supervisor. A wider fan-out usually means
a missing intermediate level.
"""),
    ("W0311", _W, "plan has many rules", """
State tables of more than about ten rules are hard to review (paper section
3.4). Consider splitting the task into sub-tasks for a subordinate.
"""),
    # ---- ownership ----------------------------------------------------------
    ("E0400", _E, "Global Memory variable has more than one writer", """
Every Global Memory variable has exactly one writer (paper section 3.8.5): one
controller that lists it in `writes`, or the environment (`from env`) for raw
sensor values. Two writers make the value depend on schedule order and break
the triple-buffering contract.
"""),
    ("E0401", _E, "Global Memory variable is read but never written", """
A controller reads a variable that no controller writes and that is not marked
`from env`; its value would stay at its initial value forever.
"""),
    ("E0402", _E, "Global Memory variable has no initial value", """
Every Global Memory variable needs an initial value (`gm x: f64 = 0.0`), the
value readers see before the first write.
"""),
    ("W0403", _W, "Global Memory variable is never read", """
A variable that nobody reads is dead data in every cycle's buffer exchange.
Remove it, or add it to the `reads` of the controller that is meant to use it.
An actuator output that goes to the plant through the I/O hooks is read by the
environment: declare it `to env` (the mirror of `from env`).

Wrong:

    gm valve_cmd: f64 = 0.0        // written by FILL, sent to the valve

Fixed:

    gm valve_cmd: f64 = 0.0 to env
"""),
    # ---- plans --------------------------------------------------------------
    ("E0500", _E, "verb has no plan", """
Every verb a controller accepts needs a plan (a state table) with the same name
(paper section 5.3.2.1). Without one the command would be accepted and ignored.
"""),
    ("E0501", _E, "plan for an undeclared verb", """
A plan's name must be a verb the controller declares with `verb NAME` or brings
in with `verbs SET`.
"""),
    ("E0502", _E, "state unreachable from `new`", """
No sequence of rules leads from the entry state `new` to this state, so its
rules can never fire.
"""),
    ("E0503", _E, "state cannot reach `done` or `error`", """
From this state no sequence of rules ends the plan, so once there the command
never completes. Plans that are meant to run until superseded (regulators that
report AT_GOAL) are declared `plan NAME continuous`.
"""),
    ("E0504", _E, "two commands to one subordinate in one job list", """
A job list may issue at most one command per subordinate per cycle: commands are
not queued, and the second would silently supersede the first.
"""),
    ("E0505", _E, "state waits on a subordinate but ignores its error", """
A state has a rule that waits for `SUB.done` (or another status of SUB), but no
rule that applies in this state tests `SUB.error`, and SUB can fail for a verb
this controller sends it. If it fails, the plan waits forever. Reported once
per plan and subordinate, at the first wait.

SUB counts as able to fail for a verb when its plan for that verb has an
`error(...)` rule (or reports ERROR), when SUB is a `simulator` (a plant model
that a deployment replaces by the real plant), or when the design has no plan
for the verb. A subordinate whose plans always end in `done` (the INIT and HALT
plans that NIST's RCS-Design tool generates) needs no error rule.

Wrong:

    plan RUN {
        E0: true     | new -> S1 | LOW.GO();
        E1: LOW.done | S1  -> done;      // LOW.GO can end in error(4)
    }

Fixed (the `*` error rule right after the `new` rules):

    plan RUN {
        E0: true      | new -> S1 | LOW.GO();
        E9: LOW.error | *   -> error(4);
        E1: LOW.done  | S1  -> done;
    }
"""),
    ("E0506", _E, "rule can never fire", """
Earlier rules of the same state always match first (first match wins), so this
rule is dead logic: either an earlier rule is unconditional (`true`), or the
guard analysis proved that whenever this rule's condition holds, one of the
earlier rules it names holds too. An `otherwise` is dead when the other rules of
its state together match every input. A `*` rule is dead only if it is hidden in
every state; the witness shows an input where its condition holds and which rule
fires instead.
"""),
    ("E0507", _E, "command to a controller that is not a subordinate", """
A controller may only command its own subordinates (chain of command, paper
section 3.7). List the controller in `subordinates`.
"""),
    ("E0508", _E, "duplicate rule label", """
Rule labels (E0, E1, ...) identify rules in traces, generated code and findings,
so they must be unique within a plan.
"""),
    ("E0509", _E, "more than one `otherwise` for a state", """
A state has at most one `otherwise` rule, the rule taken when no other rule of
that state fires.
"""),
    ("E0510", _E, "invalid state in a rule", """
`new` is the entry state and cannot be a next state (only a new command enters
it); `done` and `error` are terminal and cannot be current states; `otherwise`
needs a concrete current state, not `*`.
"""),
    ("E0511", _E, "plan has no rule for `new`", """
When a command arrives its plan starts in state `new`. With no rule for `new`
(or `*`), the plan never leaves it and the command is never answered.
"""),
    ("E0512", _E, "duplicate plan", """
A controller has two plans with the same name. Each verb has exactly one plan
(its state table), so a second plan for the same verb is either a leftover copy
or a misspelt verb name.
"""),
    ("W0519", _W, "command storm: a rule re-commands a subordinate every cycle", """
A rule that stays in its state (`-> *` or `S1 -> S1`) and commands a
subordinate, without testing that subordinate's status in its condition, fires
again in the next cycle and sends the command again. Commands are not queued:
each one supersedes the last, so the subordinate restarts its plan every cycle
and never finishes.

Wrong:

    E1: level < 1.0 | FILLING -> * | VALVE.OPEN();

Fixed (command once on the way in, then wait):

    E0: true             | new     -> FILLING | VALVE.OPEN();
    E1: VALVE.error      | *       -> error(2);
    E2: level >= 1.0     | FILLING -> done;
"""),
    ("W0520", _W, "`*` rule that tests a subordinate comes before the `new` rules", """
When a new command arrives, a subordinate's status still answers the previous
command (DONE and ERROR stay until it is commanded again). A `*` rule that
tests a subordinate, written before the rules for `new`, can fire in `new` on
that stale status instead of the entry rule. Put `*` fault rules right after
the `new` rules.

Wrong:

    E9: LOW.error | *   -> error(1);
    E0: true      | new -> S1 | LOW.GO();

Fixed:

    E0: true      | new -> S1 | LOW.GO();
    E9: LOW.error | *   -> error(1);
"""),
    ("W0521", _W, "plan reports done while a subordinate may still be executing", """
A rule ends the plan with `done` in a state that was entered by commanding a
subordinate (or commands it itself), and its condition does not test that
subordinate. The supervisor then hears DONE while the delegated work is still
under way.

Wrong:

    E0: true          | new -> MOVING | AXIS.MOVE(x = 10.0);
    E1: in_state >= 2 s | MOVING -> done;

Fixed:

    E0: true          | new -> MOVING | AXIS.MOVE(x = 10.0);
    E9: AXIS.error    | *   -> error(3);
    E1: AXIS.done     | MOVING -> done;
"""),
    ("W0522", _W, "plan waits on a subordinate it never commands", """
A condition tests `SUB.done` (or `SUB.executing`, or an extra status of SUB),
but no rule of the plan commands SUB. SUB's status answers an earlier command,
from another plan or another run of this one, or none at all: the wait ends at
once on a stale DONE, or never.

Wrong:

    plan UNLOAD {
        U0: true     | new -> S1;
        U1: ARM.done | S1  -> done;
    }

Fixed:

    plan UNLOAD {
        U0: true      | new -> S1 | ARM.PLACE();
        U9: ARM.error | *   -> error(2);
        U1: ARM.done  | S1  -> done;
    }
"""),
    ("W0523", _W, "exact `==` on f64 in a condition", """
A measured or computed `f64` is almost never exactly equal to a value: a level
that passes 2.0 between two cycles is never `== 2.0`, and the rule never fires.
Compare with a tolerance or an inequality. When exact equality is meant (a
value copied unchanged, a flag stored as 0.0 or 1.0), say so on the line with
`// rcsc: allow(W0523) reason`.

Wrong:

    E1: level == 2.0 | FILLING -> done;

Fixed:

    E1: level >= 2.0 | FILLING -> done;
    E1: abs(level - 2.0) <= 0.01 | FILLING -> done;
"""),
    ("W0524", _W, "value can be outside its declared range", """
A job list puts a value into a ranged slot - an argument for a parameter
declared `x: i32 in 0..10`, an assignment to a ranged local, status field or
Global Memory variable, a field of a record whose declaration gives it a range
(`record Spec { n: i32 in 0..10 }`, filled by `Spec(n = ...)` or `spec.n = ...`)
- and for the inputs shown as witness (with the rule's
condition true and the earlier rules of its state false) the value is outside
the range. The checks of the receiving plan assume the range (a command with
x = 20 can leave every rule of `new` false, and the plan sits there for ever),
so the range must be kept where values enter it. An f64 that can be NaN (a
failed sensor) is outside every range, and `clamp`, `min` and `max` pass a NaN
on: when the witness is NaN, test the value in the condition instead
(`in_range(x, lo, hi)` is false for NaN).

Wrong:

    verb GO(x: i32 in 0..10)               // of LOW
    E0: true | new -> S1 | LOW.GO(x = n + 1);

Fixed:

    E0: n < 10 | new -> S1 | LOW.GO(x = n + 1);
    E1: otherwise | new -> error(2);
"""),
    ("W0525", _W, "integer overflow or division by zero", """
For the inputs shown as witness, integer arithmetic in a condition or a job
list wraps around its type (`+`, `-`, `*` on i32, i64, u32 or durations), or
`/` or `%` divides by zero, which gives 0 by the language's rules. Either is
rarely what the designer meant. Bound the operands with a range or a test in
the condition, or use a wider type. Arithmetic of constants that certainly
wraps or divides by zero (`2147483647 + 1`, `MAX_COUNT * 1000000`, `1 / 0`,
`abs(i32 MIN)`, a `sum` of constants)
is reported where it is written, in constants and initial values too, with
the value it was meant to have and the one it gets.

Wrong:

    E1: true | S1 -> done | rate = total / count;

Fixed:

    E1: count > 0 | S1 -> done | rate = total / count;
    E2: otherwise | S1 -> error(4);
"""),
    ("W0527", _W, "error exit leaves a commanded subordinate running", """
A rule ends the plan with `error(...)` in a state that was entered by
commanding a subordinate, its condition tests no subordinate (a time-out, a
sensor fault), and it does not command the subordinate again (to stop it). The
supervisor hears ERROR while the subordinate goes on with work nobody
supervises any more: a time-out that leaves an axis moving. (A rule that
reacts to one subordinate's failure while another finishes its part is not
reported.)

Wrong:

    E0: true            | new    -> MOVING | AXIS.MOVE(x = 10.0);
    E8: in_state >= 5 s | MOVING -> error(2);

Fixed:

    E8: in_state >= 5 s | MOVING -> error(2) | AXIS.HALT();
"""),
    ("W0526", _W, "loop of states can only be left through an error", """
The plan can end in `done`, but from a loop of states every way out leads to
`error(...)`: once in the loop, the command can only fail. Usually the rule
that leaves the loop on success is missing or its next state is misspelt (a
misspelt name makes a new state), or the loop's only exits are `*` fault
rules. A plan that always fails (an ABORT) and a `continuous` plan are not
reported.

Wrong:

    E0: true          | new  -> MOVE | AX.GO();
    E9: AX.error      | *    -> error(1);
    E1: AX.done       | MOVE -> WAIT | AX.GO();
    E2: AX.done       | WAIT -> MOVE | AX.GO();

Fixed:

    E2: AX.done and n >= 3 | WAIT -> done;
    E3: AX.done and n < 3  | WAIT -> MOVE | AX.GO(), n += 1;
"""),
    ("W0540", _W, "state can wait forever on a subordinate's held status", """
A subordinate's status answers the last command it was sent and holds until it
is commanded again: EXEC while it works, then DONE or ERROR (ERROR only when it
can fail for that verb); a `continuous` plan may instead hold the extra status
it last reported. Along the path shown (the rules from `new`), the
subordinates this state reads hold a status for which no rule of the state can
fire, whatever the inputs that still change: the plan waits forever. Typical
causes: a state that waits for a new status of a subordinate nobody commanded
again (the `*` error rule seems to cover it, but a subordinate that holds DONE
never reports ERROR), or a state that waits for a subordinate never commanded
on the way in. The witness gives the statuses held and the fixed inputs;
W0517 is the same finding when no subordinate's status is needed for it.

Wrong:

    L0: true       | new  -> MOVE | ARM.GO();
    L9: ARM.error  | *    -> error(2);
    L1: ARM.done   | MOVE -> LIFT;              // ARM holds DONE from here on
    L2: ARM.AT_TOP | LIFT -> done;              // never: ARM is not commanded again

Fixed:

    L1: ARM.done   | MOVE -> LIFT | ARM.LIFT();
    L2: ARM.AT_TOP or ARM.done | LIFT -> done;
"""),
    ("W0541", _W, "`done` unreachable with the subordinates' held status", """
The state graph has a way from this state to `done`, but along the path shown
(the rules from `new`) the rules on that way need a status that the
subordinates cannot report: they hold DONE or ERROR until commanded again, and
nothing commands them. What remains are the `error(...)` exits (usually `*`
fault rules): once there, the command can only fail. W0526 is the same finding
when no way to `done` exists at all.

Wrong:

    P0: true                            | new  -> FILL | V.OPEN();
    P9: V.error or H.error              | *    -> error(1);
    P1: V.done                          | FILL -> HEAT | H.ON();
    P2: H.done and V.AT_LEVEL           | HEAT -> done;        // V holds DONE here
    P3: H.done and not V.AT_LEVEL       | HEAT -> FILL | V.OPEN();

Fixed (the level is read from its sensor, not from a status the valve no
longer reports):

    P2: H.done and level >= 90.0        | HEAT -> done;
    P3: H.done and level < 90.0         | HEAT -> FILL | V.OPEN();
"""),
    ("W0542", _W, "wait on a subordinate not commanded on every way into the state", """
A rule of the state tests `SUB.done` (or `SUB.executing`, or an extra status),
and on the path shown (the rules from `new`) this plan has not commanded SUB:
its status still answers an earlier command, from another plan or an earlier
run of this one, or none at all. The wait ends at once on a stale DONE, or
never. The plan commands SUB elsewhere (W0522 is the plan that never does);
usually one way into the state forgot the command.

Wrong:

    E0: cmd.fast     | new -> S1 | ARM.GO();
    E1: not cmd.fast | new -> S1;               // no command on this way in
    E9: ARM.error    | *   -> error(2);
    E2: ARM.done     | S1  -> done;

Fixed:

    E1: not cmd.fast | new -> S1 | ARM.GO_SLOW();
"""),
    # ---- guards (z3): determinism and coverage of state tables ------------------
    ("E0513", _E, "condition is never true", """
The guard analysis proved that no input makes this rule's condition true, given
the types of the values it reads and their declared ranges (`i32 in 0..3`), and
that a subordinate is never done and failed at once. The rule can never fire,
wherever it stands in the table: correct the condition or remove the rule.
"""),
    ("W0514", _W, "condition is always true", """
A condition that is not the literal `true` holds for every input (for example
`n >= 0` on a `u32`, or a test the declared ranges always satisfy), and rules
after it in its state are therefore never reached. If the rule is meant to
catch everything, write `true`; otherwise the condition is not what was meant.
"""),
    ("W0515", _W, "rules of a state can both be true with different outcomes", """
Two rules of one state can both be true for the same input (and no earlier rule
is), and they lead to different next states or jobs: the order of the table
silently decides which one fires. The witness is such an input, and the notes
say how the two rules differ.

Most overlaps are bugs - an off-by-one (`>= 50` and `<= 60`), a missing
`and not ...`, a command storm - and the fix is to make the conditions
exclusive. When the earlier rule must win on purpose, say so for that pair with
`// rcsc: allow(W0515) reason` on the later rule's line. `plan X ordered`
declares the whole table prioritized and hides every overlap, real bugs
included: keep it for tables written as a priority list. Not reported when the
earlier rule leads to `error(...)` (a fault or time-out rule written first is
the paper's prioritized style), nor between a `new` rule and a later `*` rule
in `new` (a gap there is E0516, reported once).

Wrong:

    E1: level >= 50 | S1 -> done;
    E2: level <= 60 | S1 -> S2;        // 50..60: E1 wins by position

Fixed:

    E1: level > 60  | S1 -> done;
    E2: level <= 60 | S1 -> S2;
"""),
    ("E0516", _E, "a new command can leave every rule of `new` false", """
For the input shown as witness no rule of state `new` (nor any `*` rule) fires,
and `new` has no `otherwise`: the new command is accepted (status EXEC) and
nothing happens. Cover the missing case (e.g. `x > 0` and `x < 0` miss `x == 0`),
or add an `otherwise` rule for `new`.
"""),
    ("W0517", _W, "state can wait forever", """
Waiting in a state until a rule fires is normal. This state, however, can wait
for ever: for the values shown as witness of the inputs that cannot change
while the plan waits (the command's parameters, and locals, status fields and
Global Memory that only this controller writes outside `pre` and `post`), no
rule of the state can fire whatever the other inputs (subordinates' status,
sensors, time in state) do. Add a rule for the case, an `otherwise`, or a
time-out rule.
"""),
    ("W0518", _W, "guard analysis incomplete", """
The SMT solver could not decide a question about this plan's conditions within
its budget (a deterministic resource limit per question, so that every
machine gives the same answer; a time-out far above it is only a safety net),
or a condition could not be encoded. The analysis never counts that as a pass: the
rest of the plan is not analysed and this finding says what was being asked.
Simplify the condition, for example by computing a non-linear term in `pre`.
"""),
    # ---- timing -------------------------------------------------------------
    ("E0600", _E, "CPU budget exceeds its heartbeat", """
The sum of the budgets (worst-case step times) of the controllers due in a
cycle of a CPU, plus its declared overhead, must fit in one heartbeat period
(paper sections 3.8.6 and 3.9): the frame rule. Otherwise cycles overrun.
Every controller steps in the CPU's first cycle whatever its `period`, so
that frame holds all of them; `rcsc budget` lists every frame.
"""),
    ("W0601", _W, "duration is not a whole number of cycles", """
A time in a plan (`in_state >= 45 ms`) is measured in whole steps of the
controller: its CPU's heartbeat, or its `period` if it runs at a divided rate.
A duration that is not a multiple of it is rounded up to the next whole step;
write the rounded value to say what happens. A duration compared with an
`age` is measured in base ticks (the shortest heartbeat of the design).
"""),
    ("E0602", _E, "CPUs with non-harmonic heartbeats", """
All CPUs run on one time base whose tick is the shortest heartbeat, and
buffers cross between CPUs at the deadlines of their writers' cycles. So of
any two heartbeats one must be a whole multiple of the other: then every
release and deadline falls on a tick and data arrive at a fixed phase. This
holds for CPUs that exchange no data too, because scenarios address all CPUs
in ticks.
"""),
    ("E0603", _E, "controller is not scheduled", """
Every controller must appear in exactly one CPU `schedule`; a controller that is
never scheduled never runs.
"""),
    ("E0604", _E, "controller scheduled more than once", """
A controller appears twice in schedules (on one CPU or on two). Each controller
runs exactly once per cycle of exactly one CPU.
"""),
    ("E0607", _E, "controller period is not a whole number of heartbeats", """
A controller's `period D` says it steps on every n-th cycle of its CPU, so D
must be a whole multiple n of the CPU's heartbeat (n >= 1). A controller with
`period 50 ms` on a 20 ms CPU would have no fixed place in the cycle; choose a
multiple (40 ms, 60 ms) or move it to a CPU whose heartbeat divides 50 ms.
"""),
    ("W0610", _W, "a period constant differs from the heartbeat", """
A constant named as a time step (DT, TS, PERIOD, CYCLE, SAMPLE_TIME, TICK, or
ending in _DT or _PERIOD), in seconds (f64) or as a duration, is used by a
controller whose CPU beats at another period. A plant model or filter that
integrates with it is off by the ratio in every cycle.

Wrong:

    const DT: f64 = 0.03              // written for a 30 ms heartbeat
    cpu MAIN { heartbeat 10 ms  schedule TANK }

Fixed:

    const DT: f64 = 0.01
    cpu MAIN { heartbeat 10 ms  schedule TANK }
"""),
    ("E0611", _E, "an extern's budget does not fit in the caller's budget", """
An `extern fn` declares its worst-case time with `budget`. A controller that
calls an extern taking longer than its own whole step, or whose `pre` and
`post` call externs that together take longer, cannot keep its declared
budget, so the CPU budget check (E0600) would rest on a false number.

Wrong:

    extern fn solve_ik(x: f64) -> f64 budget 2 ms
    controller ARM level 1 budget 500 us { ... solve_ik(goal) ... }

Fixed:

    controller ARM level 1 budget 3 ms { ... solve_ik(goal) ... }
"""),
    # ---- code generation ----------------------------------------------------
    ("E0800", _E, "the target cannot build this design", """
`rcsc build` generates one Main Program per CPU. The C and Rust targets run
each CPU as its own process and exchange the buffers that cross between CPUs
through shared memory, where each published sample records the CPUs that read
it as one bit of a 64-bit word: a design with more than 64 CPUs is refused
rather than built with readers that would never be waited for (merge CPUs
that share a heartbeat). A target without that transport, divided rates
(`period`) or stamps of Global Memory (`age(V)`) refuses designs that need
them rather than emit a program that silently loses buffers, steps a
controller every cycle or reads a made-up age.
"""),
    ("E0820", _E, "the target has no such transport between CPUs", """
`rcsc build --transport` chooses how the buffers that cross between CPUs
travel from one CPU's process to another's: `shm` (POSIX shared memory, every
CPU on one host, the default) or `dds` (Eclipse Cyclone DDS, the CPUs on any
hosts of a network). A target builds only the transports it has (the C and
Rust targets have both; a new target may start with shared memory alone);
the others are refused rather than silently replaced by shared memory, which
would not reach another host.

Wrong (a target without the DDS transport):

    rcsc build ship.rcs --target mytarget --transport dds -o build/ship

Fixed:

    rcsc build ship.rcs --target c --transport dds -o build/ship-c
"""),
    ("E0821", _E, "a transport between CPUs for a design with one CPU", """
`--transport dds` carries the buffers that cross between the CPUs of a design
to the other CPUs' processes. A design with one CPU has nothing to carry, and
its Main Program would link a middleware it never uses: the option is refused.

Wrong:

    cpu MAIN heartbeat 10 ms { ... }
    rcsc build cell.rcs --target c --transport dds -o build/cell

Fixed:

    cpu MAIN heartbeat 10 ms { ... }
    rcsc build cell.rcs --target c -o build/cell
"""),
    # ---- measured timing (`rcsc budget --measured`) ------------------------
    ("E0840", _E, "a measured worst case exceeds the budget", """
`rcsc budget --measured RUN.json DESIGN` compares the step times the compiled
Main Program measured (its `--timing-out RUN.json` file, or instruction
counts from `rcsc budget --callgrind`) with the budgets the design declares.
Each step is counted under the rule that fired in it (or under "no rule" for
a step in which none fired): a rule whose worst step took longer than the
controller's `budget` breaks the CPU budget check (E0600), which adds the
declared budgets up on the promise that no step exceeds them.

Wrong (rule R1 calls an extern that takes about 300 us):

    controller TOP level 2 budget 2 us { ... R1: true | BUSY -> BUSY | x = spin(n); }

Fixed (a budget that holds the measured worst case, with margin):

    controller TOP level 2 budget 500 us { ... R1: true | BUSY -> BUSY | x = spin(n); }
"""),
    ("E0841", _E, "the run file does not fit the design", """
A run file given to `rcsc budget --measured` must be one the compiled Main
Program of this design wrote with `--timing-out` (or `rcsc budget --callgrind`
made): JSON with `"format": "rcs-timing-1"`, the design's name, and only
controllers the design has. A run of another design, of an older version of
it with other controllers, or a file of another kind would put figures beside
the wrong budgets.

Wrong:

    rcsc budget --measured build/other/run.json cell.rcs

Fixed (measure this design's program):

    ./cell_MAIN --scenario full_job.events --timing-out run.json --fast
    rcsc budget --measured run.json cell.rcs
"""),
    ("W0841", _W, "a scheduled controller was never measured", """
The run files given to `rcsc budget --measured` hold no step of a controller
scheduled on a CPU they measured: its worst case is unknown, so the table can
say nothing about its budget. The scenario was too short (a controller with
`period 100 ms` on a 10 ms heartbeat steps every tenth cycle) or the
controller was frozen by the scenario.

Wrong (a 0-cycle run, or a scenario that ends before the controller is due):

    cycles 0

Fixed:

    cycles 500
"""),
    # ---- scenarios ----------------------------------------------------------
    ("E0700", _E, "operator command to a controller below the top", """
Operator commands enter at the top of the hierarchy only (chain of command,
paper section 3.7). A scenario may command a controller that has no
supervisor; the rest receive commands from their supervisors' plans.
"""),
    ("E0701", _E, "scenario input to a variable the environment does not write", """
A scenario sets only Global Memory variables declared `from env` (raw sensors,
operator inputs). Every other variable has a controller as its one writer.
"""),
    ("E0702", _E, "cycle outside the scenario", """
Cycles are numbered from 1 to the scenario's `cycles`. A command, input or
expectation outside that range, or a window `within A..B` with A after B, would
never happen.
"""),
    ("E0703", _E, "unknown state, status, rule or verb in an expectation", """
`CTRL.state == NAME` compares with a state of one of CTRL's plans (or `new`,
`done`, `error`); `CTRL.status == NAME` with DONE, EXEC, ERROR, UNINITIALIZED
or an extra status value; `CTRL.rule` with a rule label; `CTRL.verb` with a verb.
A name that CTRL does not have is almost always a typo.
"""),
    ("E0704", _E, "missing or repeated scenario setting", """
A scenario says exactly once how many cycles it runs: `cycles 200`. Without it
the run has no end; with two `cycles` lines it is ambiguous which one counts.
Likewise a scenario has at most one `scenario "NAME"` line: the name shown in
reports and JUnit files.
"""),
    ("E0705", _E, "fault injection names no CPU or controller", """
`at N: stop CPU` stops a CPU (it runs no more cycles) and `at N: freeze CTRL`
freezes one controller (it is not stepped any more). The name after `stop` must
be one of the design's CPUs and the name after `freeze` one of its controllers.
"""),
    ("W0706", _W, "two commands to one controller, or two values for one input, in one cycle", """
A controller's command buffer holds one command, and a Global Memory variable
one value: of two commands to the same controller at the same cycle, or two
values for the same input, the controller sees only the last (the second
command supersedes the first, whose serial number is skipped), and the first
has no effect. That is most often a line copied without changing its cycle:
give each its own cycle, or remove the one not meant.

Wrong:

    at 10: SM.TRANSIT(speed = 12.0, leg_time = 600 s)
    at 10: SM.ALL_STOP()

Right:

    at 10: SM.TRANSIT(speed = 12.0, leg_time = 600 s)
    at 200: SM.ALL_STOP()
"""),
    ("W0707", _W, "scenario input outside the variable's declared range", """
A `from env` variable declared with a range (`gm level: f64 in 0.0..5.0 from
env`) tells the checker what the environment can give it: every state table
is checked for values inside that range only. A scenario input outside it
drives the design where nothing was checked: a plan proved always to answer
may wait for ever, an index proved in bounds may not be. To drill an
out-of-range sensor, widen the declared range so that the checks cover the
values the drill uses, and keep the input; otherwise correct the input.

Wrong:

    gm level: f64 in 0.0..5.0 = 0.0 from env
    ...
    at 10: level = 7.5
"""),
    ("E0830", _E, "the simulator's externs file does not load", """
`rcsc sim --externs FILE.py` (and `rcsc test --externs`) runs the design
with Python functions standing in for its extern functions. The file could
not be read, is not valid Python, raised an exception while it was loaded,
or its `externs()` function raised or returned something else than a dict of
functions by name. Nothing is simulated: a run without the externs the file
meant to give would not be the design's.

Wrong (externs.py):

    def path_length(dx, dy)
        return math.hypot(dx, dy)

Fixed:

    import math

    def path_length(dx, dy):
        return math.hypot(dx, dy)
"""),
    ("W0830", _W, "an extern has no implementation in the simulator's externs file", """
The externs file given with `--externs` defines no function named like this
extern (or its `externs()` dict has no such key), so in the simulator the
extern returns the zero value of its type, as without the file. Or the
`externs()` dict names a function the design does not declare. Usually a
typo: the finding names the closest function the file defines.

Wrong (externs.py, for `extern fn path_length(dx: f64, dy: f64) -> f64`):

    def pathlength(dx, dy):
        return math.hypot(dx, dy)

Fixed:

    def path_length(dx, dy):
        return math.hypot(dx, dy)
"""),
    ("E0831", _E, "an extern failed in the simulator", """
A Python function standing in for an extern (`--externs FILE.py`) raised an
exception, or returned a value that is not of the extern's type: an `int` in
range for the integer types and `duration` (nanoseconds), an `int` or
`float` for `f64`, a `bool`, an enum member's name, a `dict` with exactly
the record's fields, a `list` of the array's length. The run stops there:
the trace after it would not be the design's. The note says where the
function raised.

Wrong (for `extern fn gear_of(rpm: f64) -> i32`):

    def gear_of(rpm):
        return rpm / 1000.0

Fixed:

    def gear_of(rpm):
        return int(rpm // 1000)
"""),
    ("E0810", _E, "no running Main Program to attach the console to", """
`rcsc console DESIGN` attaches to a Main Program of that design that was
started with `--run ID`: the program then publishes its status and takes
requests in the shared memory `/rcs-<design>-<ID>.console`. Without `--run`
nothing is published; with several runs the console needs to know which.

Wrong:

    ./submarine_MAIN &
    rcsc console submarine.rcs

Fixed:

    ./submarine_MAIN --run bridge &
    rcsc console submarine.rcs --run bridge
"""),
    ("E0811", _E, "the running Main Program was built from another design", """
The console compiles operator commands against the design it is given, into
ids and bit patterns that are valid only for a Main Program built from the
same interface (the interface hash of docs/events.md). A program built
before a verb, parameter or controller changed would apply them wrongly, so
the console refuses to attach: rebuild and restart the program.

Wrong:

    rcsc build cell.rcs --target c -o build/cell    # then a verb is added to cell.rcs
    rcsc console cell.rcs --run r1

Fixed:

    rcsc build cell.rcs --target c -o build/cell && make -C build/cell
    ./build/cell/cell_MAIN --run r1 &
    rcsc console cell.rcs --run r1
"""),
    ("E0812", _E, "not a console command", """
A console line is either an operator command or input in the scenario syntax
(`SM.TRANSIT(speed = 12.0)`, `trip = true`) or a console word: `status`,
`pause`, `resume`, `step [N]`, `pause NODE`, `step NODE [N]`, `run NODE`,
`quit`, `help`, `exit`. A step count is a whole number from 1.

Wrong:

    step fast
    pause SM now

Fixed:

    step 10
    pause SM
"""),
    ("E0813", _E, "no such controller in the running Main Program", """
`pause NODE`, `step NODE` and `run NODE` name one controller of the running
Main Program. A deployment build (`--exclude-simulators`) has no simulators.

Wrong:

    pause TURBINE

Fixed:

    pause TB
"""),
    ("E0814", _E, "not an operator action", """
The console sends one operator command or one input at the next cycle. Cycle
numbers (`at N:`), expectations, `cycles` and the faults `stop` and `freeze`
belong in scenario files; to hold one controller use `pause NODE`.

Wrong:

    at 10: SM.INIT()
    freeze TB

Fixed:

    SM.INIT()
    pause TB
"""),
    ("E0815", _E, "the Main Program refused or did not answer a request", """
The console hands each request to the running Main Program through the ring
of its operator segment and waits for the answer. The program refuses a
request it cannot apply (its event reader's message is shown) and does not
answer once it has ended or is stopped in a debugger.

Wrong:

    kill -STOP $(pidof submarine_MAIN)    # then, in the console:
    SM.INIT()

Fixed:

    kill -CONT $(pidof submarine_MAIN)
    SM.INIT()
"""),
    ("E0816", _E, "another console is attached to this run", """
One console at a time operates a run (it holds a lock on the operator
segment), so that two operators never interleave commands unknowingly. Leave
the other console (`exit` or end of input) first.

Wrong:

    rcsc console submarine.rcs --run bridge    # in two terminals

Fixed:

    rcsc console submarine.rcs --run bridge    # in one terminal
"""),
    ("W0810", _W, "the Main Program has ended", """
The run the console is attached to has finished (its cycles are done, it was
quit, or it was stopped): nothing more is sent. The last status table stays
readable with `status`.

Wrong:

    ./submarine_MAIN --run r1 --cycles 10 &
    sleep 1; rcsc console submarine.rcs --run r1    # SM.INIT() comes too late

Fixed:

    ./submarine_MAIN --run r1 --paused &
    rcsc console submarine.rcs --run r1    # SM.INIT(), then resume
"""),
    ("W0240", _W, "doc comment documents nothing", """
A doc comment (`///` lines) documents the item written right after it: a
controller, plan, rule, verb, verb set, Global Memory variable, status field,
local, record field, function, extern, constant, enum, record or CPU. `rcsc doc`
shows it and the generated C and Rust code repeat it in comments. A `///` run
followed by something else (a `pre` block, a statement, the end of the file) or
separated from the item by another comment documents nothing; write `//` for a
plain comment.

Wrong:

    /// Reads the sensors.
    pre { level = raw * 0.1; }

Fixed:

    // Reads the sensors.
    pre { level = raw * 0.1; }

    /// Fills the tank to the requested level.
    verb FILL(level: f64)
"""),
    ("E0605", _E, "design has no CPU", """
A design needs at least one `cpu` with a heartbeat and a schedule to say where
and how often its controllers run. This holds for a design without
controllers too: a design is what runs (the simulator steps its CPUs, and
`rcsc build` makes one Main Program per CPU), so one with nothing to run is
refused rather than simulated as nothing. Declarations shared by several
designs belong in a `module` file that the designs import.
"""),
]

CODES: dict[str, Code] = {
    code: Code(code, sev, title, text.strip() + "\n") for code, sev, title, text in _TABLE
}


# Where the documentation is published.  Each code's explanation has a stable
# address, `help_uri(code)`: DOCS_URL + "/codes.html#" + the code in lower case
# (docs/codes.md, generated from this table, has an anchor per code), which
# SARIF reports give as each rule's helpUri.
DOCS_URL = "https://rcsc.readthedocs.io/en/latest"


def help_uri(code: str) -> str:
    return f"{DOCS_URL}/codes.html#{code.lower()}"


def markdown() -> str:
    """docs/codes.md: every code with its anchor, severity, title and explanation."""
    out = [
        "# Diagnostic codes",
        "",
        "<!-- generated by rcsc from rcsc/codes.py - do not edit; "
        "regenerate with `python -m pytest tests/test_codes.py --update-golden` -->",
        "",
        "Every finding rcsc reports has one of these codes; `rcsc explain CODE` prints",
        "the same text in a terminal. E-codes are errors, W-codes warnings (lints).",
        "",
    ]
    for c in sorted(CODES.values(), key=lambda c: c.code):
        out += [f'<a id="{c.code.lower()}"></a>', "", f"## {c.code}: {c.title}", "", f"*{c.severity.value}*", "", c.explanation.strip(), ""]
    return "\n".join(out)


def explain(code: str) -> str | None:
    c = CODES.get(code.upper())
    if c is None:
        return None
    return f"{c.code} ({c.severity.value}): {c.title}\n\n{c.explanation}"
