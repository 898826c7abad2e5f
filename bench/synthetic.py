#!/usr/bin/env python3
"""Generate a synthetic, VALID rcsc design of N controllers x P plans x R rules.

    python bench/synthetic.py [N [P [R]]] > out.rcs      (defaults 200 20 10)

The design is meant to look like a real RCS hierarchy, so that the checker's
time on it says something about real designs:

- a command tree built breadth-first with at most `BRANCH` (7) subordinates
  per controller; levels descend from the root (level = height above the
  leaves' depth), so every subordinate's level is below its supervisor's;
- Global Memory: each controller reads a raw sensor `cN_raw` written by the
  environment (`from env`) and writes its feedback `cN_fb`, read by its
  supervisor; a controller with subordinates also writes a setpoint `cN_sp`
  that its subordinates read.  Every variable has exactly one writer and at
  least one reader (the root's feedback is read by its first subordinate);
- verbs: with P >= 3 the Lifecycle verb set of std.lifecycle (INIT, HALT,
  ABORT) plus P - 3 verbs `V3 .. V{P-1}` whose parameters vary (f64, f64+i32,
  an enum, none); every verb has a plan;
- plans of exactly R rules: an entry rule `new -> S1` that commands every
  subordinate (one command each), an `otherwise` entry rule, a chain of
  states S1..Sm each with a progress rule (`A.done and B.done ...` for
  supervisors, sensor comparisons and `in_state >= k*heartbeat` for leaves),
  extra timeout / retry / report rules, and a last `*` rule that tests every
  commanded subordinate's `.error` (so E0505 holds).  Every state is
  reachable from `new` and can reach `done` or `error`;
- CPUs: one group of CPUs per level, heartbeats 10 ms * 2^(level-1)
  (harmonic), each CPU holding as many controllers as its heartbeat allows
  (budget 100 us each + 1 ms overhead); every duration in a plan is a whole
  multiple of the heartbeat of the controller's CPU.

The output is deterministic for given N, P, R.  `generate(n, p, r)` returns
the text; `main(argv)` prints it.
"""

from __future__ import annotations

import sys

BRANCH = 7  # span of control (W0310 fires above 9)
BUDGET_US = 100
OVERHEAD_MS = 1
BASE_HB_MS = 10

PARAM_KINDS = ("target", "target_count", "mode", "none")


def _verb_params(k: int) -> str:
    kind = PARAM_KINDS[k % len(PARAM_KINDS)]
    return {
        "target": "(target: f64 in -1000.0..1000.0)",
        "target_count": "(target: f64, count: i32 in 0..100)",
        "mode": "(mode: Mode)",
        "none": "",
    }[kind]


def _verb_kind(verb: str) -> str:
    if verb in ("INIT", "HALT", "ABORT"):
        return "none"
    return PARAM_KINDS[int(verb[1:]) % len(PARAM_KINDS)]


def _command_args(verb: str, sub_index: int) -> str:
    """Arguments for passing command `verb` down to a subordinate of the same interface."""
    kind = _verb_kind(verb)
    if kind == "target":
        # positional and named forms alternate
        return "scale(cmd.target, GAIN)" if sub_index % 2 else "target = scale(cmd.target, GAIN)"
    if kind == "target_count":
        return "target = cmd.target, count = cmd.count"
    if kind == "mode":
        return "mode = cmd.mode"
    return ""


class _Tree:
    def __init__(self, n: int) -> None:
        self.n = n
        self.parent = [-1] + [(i - 1) // BRANCH for i in range(1, n)]
        self.children: list[list[int]] = [[] for _ in range(n)]
        for i in range(1, n):
            self.children[self.parent[i]].append(i)
        self.depth = [0] * n
        for i in range(1, n):
            self.depth[i] = self.depth[self.parent[i]] + 1
        max_depth = max(self.depth)
        self.level = [max_depth - d + 1 for d in self.depth]


def _cpus(tree: _Tree) -> tuple[list[str], dict[int, int]]:
    """CPU declarations and each controller's heartbeat in ms."""
    out: list[str] = []
    hb_of: dict[int, int] = {}
    levels = sorted(set(tree.level), reverse=True)
    for lv in levels:
        hb = BASE_HB_MS * 2 ** (lv - 1)
        cap = (hb * 1000 - OVERHEAD_MS * 1000) // BUDGET_US
        members = [i for i in range(tree.n) if tree.level[i] == lv]
        for chunk_no, start in enumerate(range(0, len(members), cap)):
            chunk = members[start:start + cap]
            for i in chunk:
                hb_of[i] = hb
            names = ", ".join(f"C{i}" for i in chunk)
            out.append(
                f"cpu level{lv}_{chunk_no} {{\n    heartbeat {hb} ms\n    overhead {OVERHEAD_MS} ms\n    schedule {names}\n}}\n"
            )
    return out, hb_of


def _plan(i: int, verb: str, subs: list[int], r: int, hb: int, continuous: bool, reports: bool, halt: bool = False) -> str:
    """One plan of exactly `r` rules (`reports`: this controller declares AT_GOAL)."""
    me = f"c{i}"
    kind = _verb_kind(verb)
    if kind != "none" or verb.startswith("V"):
        # a task verb involves one to three subordinates; INIT/HALT/ABORT all of them
        k = int(verb[1:]) if verb.startswith("V") else 0
        subs = [subs[(k + j) % len(subs)] for j in range(min(len(subs), 1 + k % 3))] if subs else []
    sub_names = [f"C{s}" for s in subs]
    rules: list[tuple[str, str, str, str]] = []  # guard, state, next, jobs

    def dur(k: int) -> str:
        return f"{k * hb} ms"

    # ---- entry condition and jobs ------------------------------------------
    if kind == "target":
        cond0 = f"abs(cmd.target - {me}_raw) > 0.01 and not ({me}_raw < -1000.0)"
        setup = ["target = cmd.target", f"{me}_fb = {me}_raw"]
    elif kind == "target_count":
        cond0 = f"cmd.count > 0 and cmd.target >= {me}_raw - 500.0"
        setup = ["target = cmd.target", "count = 0"]
    elif kind == "mode":
        cond0 = "cmd.mode != Mode.IDLE or phase == Phase.READY"
        setup = ["phase = Phase.BUSY"]
    else:
        cond0 = f"phase != Phase.FAULT and {me}_raw <= 1000.0"
        setup = ["phase = Phase.BUSY", "count = 0"]
    if subs:
        setup.append(f"{me}_sp = target")
    cmds = [f"{n}.{verb}({_command_args(verb, k)})" for k, n in enumerate(sub_names)]
    if r <= 2:
        # Too few rules to wait for the subordinates: a plan that commanded
        # them and finished at once would report done while they still work
        # (W0521), so these plans do their own part only.
        cmds = []

    if r == 1:
        return f"    plan {verb} {{\n        E0: true | new -> done | {', '.join(setup + cmds)};\n    }}\n"
    if r == 2:
        rules.append((cond0, "new", "done", ", ".join(setup + cmds)))
        rules.append(("otherwise", "new", "error(10)", "phase = Phase.FAULT"))
    else:
        # The entry rules cover every input of `new` (a condition and its
        # negation, NaN included), so the `*` rule below never sees a
        # subordinate's error left over from an earlier command there.
        rules.append((cond0 if r >= 4 else "true", "new", "S1", ", ".join(setup + cmds)))
        if r >= 4:
            rules.append((f"not ({cond0})", "new", "error(10)", "phase = Phase.FAULT"))
        body = r - len(rules) - 1  # rules for the chain states (one rule is the `*` one)
        m = max(1, (body + 1) // 2)
        extras = body - m
        per_state = [[] for _ in range(m)]
        for k in range(extras):
            per_state[k % m].append(k)
        # The `*` rule that fails the plan when a subordinate fails (E0505) or
        # a leaf times out comes first after the entry rules: a fault wins over
        # progress (the guard analysis, W0515, accepts an earlier error rule).
        if subs:
            guard = " or ".join(f"{n}.error" for n in sub_names)
            rules.append((guard, "*", "error(1)", "phase = Phase.FAULT"))
        else:
            rules.append((f"in_state >= {dur(30 + 5 * m + extras)} or {me}_raw > 2000.0", "*", "error(2)", "phase = Phase.FAULT"))
        for s in range(1, m + 1):
            state = f"S{s}"
            nxt = "done" if s == m else f"S{s + 1}"
            if subs:
                waits = " and ".join(f"{n}.done" for n in sub_names[:2])
                if len(sub_names) > 2:
                    waits += " and not (" + " or ".join(f"{n}.executing" for n in sub_names[2:]) + ")"
                guard = waits if s % 2 else f"{waits} and C{subs[0]}.progress >= 0.0"
                jobs = [f"{me}_fb = lowpass({me}_fb, C{subs[0]}.progress, 0.5)", "count += 1"]
                if s < m:  # next phase: command the first subordinate again
                    jobs.append(f"{sub_names[0]}.{verb}({_command_args(verb, 0)})")
            else:
                guard = f"in_state >= {dur(s)} and approx_eq({me}_raw, target, 0.5)"
                jobs = [f"{me}_fb = {me}_raw", "progress = percent_of(f64(count), 10.0)"]
            if s == m:
                jobs.append("phase = Phase.READY")
            progress = (guard, state, nxt, ", ".join(jobs))
            # Extras: fault rules (-> error) before the progress rule; at most
            # one rule that stays (-> *) after it, exclusive with the progress
            # rule (it waits for the first subordinate, or the leaf is off
            # target), so that no two rules of a state compete (W0515).
            faults, stays = [], []
            for e_no, extra in enumerate(per_state[s - 1]):
                variant = (extra + i) % 3
                can_report = reports and (not subs or subs[0] % 2 == 0)  # even-numbered controllers report AT_GOAL
                if variant != 0 and not stays and (variant == 1 or can_report):
                    if variant == 1:
                        wait = f"not C{subs[0]}.done and " if subs else ""
                        stays.append((f"{wait}{me}_raw < target - 1.0 and count < 100", state, "*", "target = ramp_toward(target, cmd_target_or_zero, 0.5), count += 1"))
                    else:
                        guard = f"C{subs[0]}.AT_GOAL" if subs else f"approx_eq({me}_raw, target, 0.1) and in_state < {dur(s)}"
                        stays.append((guard, state, "*", "report AT_GOAL"))
                elif variant == 2:
                    stop = "phase = Phase.FAULT" + ("".join(f", {n}.HALT()" for n in sub_names) if halt else "")
                    wait = f" and not C{subs[0]}.done" if subs and not halt else ""
                    faults.append((f"(count >= 100 or {me}_raw > 1000.0){wait}", state, "error(3)", stop))
                else:
                    # A time-out must not leave the subordinates running
                    # (W0527): it halts them, or (without a HALT verb) gives
                    # up only while the first one still works.
                    if subs and halt:
                        stop = "phase = Phase.FAULT, " + ", ".join(f"{n}.HALT()" for n in sub_names)
                        faults.append((f"in_state >= {dur(20 + 5 * s + e_no)}", state, "error(2)", stop))
                    elif subs:
                        faults.append((f"in_state >= {dur(20 + 5 * s + e_no)} and not C{subs[0]}.done", state, "error(2)", "phase = Phase.FAULT"))
                    else:
                        faults.append((f"in_state >= {dur(20 + 5 * s + e_no)}", state, "error(2)", "phase = Phase.FAULT"))
            rules.extend(faults + [progress] + stays)

    assert len(rules) == r, (len(rules), r)
    lines = [f"    plan {verb}{' continuous' if continuous else ''} {{"]
    for k, (guard, state, nxt, jobs) in enumerate(rules):
        repl = "cmd.target" if kind in ("target", "target_count") else "0.0"
        jobs = jobs.replace("cmd_target_or_zero", repl)
        tail = f" | {jobs}" if jobs else ""
        lines.append(f"        E{k}: {guard} | {state} -> {nxt}{tail};")
    lines.append("    }")
    return "\n".join(lines) + "\n"


def generate(n: int = 200, p: int = 20, r: int = 10) -> str:
    if n < 1 or p < 1 or r < 1:
        raise ValueError("N, P and R must be at least 1")
    tree = _Tree(n)
    cpus, hb_of = _cpus(tree)
    verbs = (["INIT", "HALT", "ABORT"] + [f"V{k}" for k in range(3, p)]) if p >= 3 else [f"V{k}" for k in range(3, 3 + p)]
    out: list[str] = []
    out.append(f"// synthetic design: {n} controllers x {p} plans x {r} rules (bench/synthetic.py)\n")
    out.append(f"design synthetic_{n}_{p}_{r}\n\n")
    out.append("import std.math\n")
    if p >= 3:
        out.append("import std.lifecycle\n")
    out.append("\nenum Mode { IDLE, RUN, SERVICE }\n")
    out.append("enum Phase { READY, BUSY, FAULT }\n")
    out.append("record Limits { lo: f64, hi: f64 }\n")
    out.append("const GAIN: f64 = 0.5\n")
    out.append("const MAX_COUNT: i32 = 100\n")
    out.append("fn scale(x: f64, k: f64) -> f64 = clamp(x * k, -1000.0, 1000.0)\n")
    out.append("fn within(x: f64, l: Limits) -> bool = x >= l.lo and x <= l.hi\n\n")

    for i in range(n):
        out.append(f"gm c{i}_raw: f64 = 0.0 from env\n")
        out.append(f"gm c{i}_fb: f64 = 0.0\n")
        if tree.children[i]:
            out.append(f"gm c{i}_sp: f64 in -1000.0..1000.0 = 0.0\n")
    out.append("\n")

    for i in range(n):
        subs = tree.children[i]
        hb = hb_of[i]
        reports = i % 2 == 0
        out.append(f"controller C{i} level {tree.level[i]} budget {BUDGET_US} us {{\n")
        if subs:
            out.append(f"    subordinates {', '.join(f'C{s}' for s in subs)}\n")
        reads = [f"c{i}_raw"] + [f"c{s}_fb" for s in subs]
        if i > 0:
            reads.append(f"c{tree.parent[i]}_sp")
        if i == 1 or n == 1:
            reads.append("c0_fb")  # the root's feedback has a reader too (itself when alone)
        writes = [f"c{i}_fb"] + ([f"c{i}_sp"] if subs else [])
        out.append(f"    reads {', '.join(reads)}\n")
        out.append(f"    writes {', '.join(writes)}\n")
        if p >= 3:
            out.append("    verbs Lifecycle\n")
        for v in verbs:
            if v not in ("INIT", "HALT", "ABORT"):
                out.append(f"    verb {v}{_verb_params(int(v[1:]))}\n")
        if reports:
            out.append("    reports AT_GOAL\n")
        out.append("    status progress: f64 = 0.0\n")
        out.append("    local target: f64 = 0.0\n")
        out.append("    local count: i32 in 0..1000 = 0\n")
        out.append("    local phase: Phase = Phase.READY\n")
        out.append("    local limits: Limits = Limits(lo = -1000.0, hi = 1000.0)\n")
        pre = [f"if not within(c{i}_raw, limits) {{ phase = Phase.FAULT; }}"]
        if i > 0:
            pre.append(f"target = lowpass(target, c{tree.parent[i]}_sp, GAIN);")
        out.append(f"    pre {{ {' '.join(pre)} }}\n")
        post = ["if count > MAX_COUNT { count = MAX_COUNT; }"]
        if subs:
            avg = " + ".join(f"c{s}_fb" for s in subs)
            post.append(f"progress = ({avg}) / {len(subs)}.0;")
        out.append(f"    post {{ {' '.join(post)} }}\n")
        for k, v in enumerate(verbs):
            continuous = k == len(verbs) - 1 and p >= 5
            out.append(_plan(i, v, subs, r, hb, continuous, reports, halt=p >= 3))
        out.append("}\n\n")
    out.extend(cpus)
    return "".join(out)


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) > 3 or any(not a.isdigit() for a in args):
        print("usage: python bench/synthetic.py [N [P [R]]]   (defaults 200 20 10)", file=sys.stderr)
        return 2
    nums = [int(a) for a in args] + [200, 20, 10][len(args):]
    sys.stdout.write(generate(*nums))
    return 0


if __name__ == "__main__":
    sys.exit(main())
