"""The minimiser of the differential tester: a failing case shrunk to a short repro.

`minimise(case, fails)` takes a generated `Case` and a predicate that says
whether a candidate still shows the failure, and shrinks greedily, keeping
every candidate whose design still checks without errors and whose scenario
still loads (`difftest_gen.check_case`): scenario lines are dropped and the
cycle count lowered, then whole controllers (with their places in
`subordinates` and `schedule` and the lines that use them), the design's brace blocks (controller items such as
`pre`/`post`, plans, `if` statements), single lines (rules, statements,
declarations), names of `reads`/`writes`/`reports` lists, jobs of rules, and finally expressions are replaced by one of
their parenthesised sub-expressions.  It repeats until a whole pass changes
nothing or the time budget is spent.

`finding_predicate(finding)` builds the usual predicate: the same kind of
finding in the same build configuration, by running only that configuration.
"""

from __future__ import annotations

import re
import time
from dataclasses import replace
from typing import Callable

from difftest_gen import Case, check_case

Predicate = Callable[[Case], bool]


def _valid(case: Case) -> bool:
    errors, _ = check_case(case)
    return not errors


class Shrinker:
    def __init__(self, fails: Predicate, budget_s: float) -> None:
        self.fails = fails
        self.deadline = time.monotonic() + budget_s
        self.tries = 0

    def accept(self, cand: Case) -> bool:
        if time.monotonic() > self.deadline:
            return False
        self.tries += 1
        return _valid(cand) and self.fails(cand)

    def out_of_time(self) -> bool:
        return time.monotonic() > self.deadline


def _blocks(lines: list[str]) -> list[tuple[int, int]]:
    """(first, last) line index of every brace block that opens and closes on its own lines."""
    out, stack = [], []
    for i, line in enumerate(lines):
        opens, closes = line.count("{"), line.count("}")
        if line.strip().startswith("}") and stack and opens == closes:
            continue  # `} else {`: the block goes on
        for _ in range(closes - opens if closes > opens else 0):
            if stack:
                out.append((stack.pop(), i))
        if opens > closes:
            stack.append(i)
    return sorted(out, key=lambda b: b[0] - b[1])  # largest first


def _paren_groups(text: str) -> list[str]:
    """Every balanced `( ... )` of the text, outermost first."""
    out, stack = [], []
    for i, ch in enumerate(text):
        if ch == "(":
            stack.append(i)
        elif ch == ")" and stack:
            j = stack.pop()
            out.append(text[j:i + 1])
    return sorted(set(out), key=len, reverse=True)


def _split_top(text: str, sep: str = ",") -> list[str]:
    parts, depth, cur = [], 0, ""
    for ch in text:
        depth += ch == "("
        depth -= ch == ")"
        if ch == sep and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    parts.append(cur)
    return parts


def shrink_scenario(s: Shrinker, case: Case) -> Case:
    lines = case.scenario.splitlines()
    i = 0
    while i < len(lines) and not s.out_of_time():
        if lines[i].startswith("at "):
            cand = replace(case, scenario="\n".join(lines[:i] + lines[i + 1:]) + "\n")
            if s.accept(cand):
                case, lines = cand, lines[:i] + lines[i + 1:]
                continue
        i += 1
    m = re.search(r"^cycles (\d+)$", case.scenario, re.M)
    if m:
        n = int(m.group(1))
        for lower in sorted({1, 2, 5, n // 4, n // 2, n - 1}):
            if 0 < lower < n:
                cand = replace(case, scenario=case.scenario.replace(m.group(0), f"cycles {lower}"))
                if s.accept(cand):
                    return cand
    return case


def shrink_design(s: Shrinker, case: Case) -> Case:
    lines = case.design.split("\n")
    for first, last in _blocks(lines):  # indices shift after a cut: recompute lazily
        if s.out_of_time():
            return case
        cur = case.design.split("\n")
        if last >= len(cur) or cur[first] != lines[first] or cur[last] != lines[last]:
            continue
        cand = replace(case, design="\n".join(cur[:first] + cur[last + 1:]))
        if s.accept(cand):
            case = cand
    i = 0
    while not s.out_of_time():
        cur = case.design.split("\n")
        if i >= len(cur):
            break
        if cur[i].strip() and not cur[i].lstrip().startswith("design "):
            # One line, or two (a function and its body).
            cands = [cur[:i] + cur[i + 1:]] + ([cur[:i] + cur[i + 2:]] if cur[i].startswith("fn ") else [])
            if any(s.accept(c := replace(case, design="\n".join(lines_))) for lines_ in cands):
                case = c
                continue
        i += 1
    return case


def shrink_verbs(s: Shrinker, case: Case) -> Case:
    """Drop a verb together with its plan (and the commands that send it)."""
    for verb in re.findall(r"^    verb (\w+)", case.design, re.M):
        if s.out_of_time():
            break
        lines, out, skip = case.design.split("\n"), [], False
        for line in lines:
            if re.match(rf"^    verb {verb}\b", line) or re.search(rf"\.{verb}\(", line):
                continue
            if re.match(rf"^    plan {verb}\b", line):
                skip = True
            if skip:
                skip = line != "    }"
                continue
            out.append(line)
        cand = replace(case, design="\n".join(out))
        if s.accept(cand):
            case = cand
    return case


def _without_controller(design: str, name: str) -> str:
    """The design without controller `name`: its block, its place in lists, the lines that use it."""
    lines = design.split("\n")
    out, skip = [], False
    for line in lines:
        if re.match(rf"^(controller|simulator) {re.escape(name)} ", line):
            skip = True
        if skip:
            skip = line != "}"
            continue
        if re.search(rf"\b{re.escape(name)}\.", line):
            continue
        m = re.match(r"^(\s*(subordinates|schedule) )(.*)$", line)
        if m:
            items = [x.strip() for x in m.group(3).split(",") if x.strip() != name]
            if not items:
                continue
            line = m.group(1) + ", ".join(items)
        out.append(line)
    return "\n".join(out)


def shrink_controllers(s: Shrinker, case: Case) -> Case:
    for name in re.findall(r"^(?:controller|simulator) (\w+) ", case.design, re.M)[1:]:
        if s.out_of_time():
            break
        cand = replace(case, design=_without_controller(case.design, name))
        if s.accept(cand):
            case = cand
    return case


def shrink_lists(s: Shrinker, case: Case) -> Case:
    """Drop single names from `reads`, `writes`, `subordinates` and `reports` lists."""
    i = 0
    while not s.out_of_time():
        lines = case.design.split("\n")
        if i >= len(lines):
            break
        m = re.match(r"^(\s*(reads|writes|reports) )(.*)$", lines[i])
        changed = False
        if m:
            items = [x.strip() for x in m.group(3).split(",")]
            for k in range(len(items)):
                rest = items[:k] + items[k + 1:]
                new = [m.group(1) + ", ".join(rest)] if rest else []
                cand = replace(case, design="\n".join(lines[:i] + new + lines[i + 1:]))
                if s.accept(cand):
                    case, changed = cand, True
                    break
        if not changed:
            i += 1
    return case


def shrink_jobs(s: Shrinker, case: Case) -> Case:
    lines = case.design.split("\n")
    for i, line in enumerate(lines):
        m = re.match(r"^(\s*\w+: .*?\| \S+ -> [^|]+?) \| (.*);$", line)
        if not m or s.out_of_time():
            continue
        jobs = [j.strip() for j in _split_top(m.group(2))]
        k = 0
        while k < len(jobs) and not s.out_of_time():
            rest = jobs[:k] + jobs[k + 1:]
            new = f"{m.group(1)} | {', '.join(rest)};" if rest else f"{m.group(1)};"
            cand = replace(case, design="\n".join(lines[:i] + [new] + lines[i + 1:]))
            if s.accept(cand):
                case, lines, jobs = cand, cand.design.split("\n"), rest
                continue
            k += 1
    return case


def shrink_exprs(s: Shrinker, case: Case) -> Case:
    """Replace a parenthesised expression by one of its own parenthesised parts."""
    lines = case.design.split("\n")
    for i in range(len(lines)):
        changed = True
        while changed and not s.out_of_time():
            changed = False
            line = case.design.split("\n")[i]
            for group in _paren_groups(line)[:12]:
                for part in _paren_groups(group[1:-1])[:6]:
                    cand_line = line.replace(group, part, 1)
                    cand = replace(case, design="\n".join(case.design.split("\n")[:i] + [cand_line] + case.design.split("\n")[i + 1:]))
                    if s.accept(cand):
                        case, changed = cand, True
                        break
                if changed:
                    break
    return case


def minimise(case: Case, fails: Predicate, budget_s: float = 300.0) -> tuple[Case, int]:
    """The smallest case found within the budget that still fails; and the number of candidates tried."""
    s = Shrinker(fails, budget_s)
    while not s.out_of_time():
        before = (case.design, case.scenario)
        case = shrink_scenario(s, case)
        case = shrink_controllers(s, case)
        case = shrink_verbs(s, case)
        case = shrink_design(s, case)
        case = shrink_lists(s, case)
        case = shrink_jobs(s, case)
        case = shrink_exprs(s, case)
        if (case.design, case.scenario) == before:
            break
    return replace(case, design=re.sub(r"\n{3,}", "\n\n", case.design)), s.tries


def finding_predicate(kind: str, where: str, pattern: str = "") -> Predicate:
    """Fails when a run of the one configuration `where` gives a finding of `kind`
    (whose text matches `pattern`, if given)."""
    from difftest_run import C_CONFIGS, run_batch

    def fails(case: Case) -> bool:
        if where in C_CONFIGS:
            found = run_batch([case], ["c"], c_configs=[where])
        else:
            found = run_batch([case], ["rust"], rust_steps=(where,))
        return any(f.kind == kind and f.where == where and re.search(pattern, f.detail) for f in found)

    return fails
