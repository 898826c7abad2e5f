#!/usr/bin/env python3
"""MISRA C:2012 findings in the generated C (cppcheck's misra addon).

    python bench/misra.py                 # both examples, a table of counts per rule
    python bench/misra.py --list 15.5     # also every finding of rule 15.5
    python bench/misra.py --keep /tmp/misra

For each example (examples/submarine, examples/machining_cell) it generates
the C with `rcsc build --target c` into a temporary directory, runs

    cppcheck --addon=misra --enable=style --std=c99 --platform=unix64 -q *.c

over every generated .c file, and sorts each finding by the file it is in:

  controllers  the design's own files: <design>.c/.h, <design>_<NAME>.c/.h
               (controllers, simulators, extern stubs)
  runtime      rcs_runtime.c/.h, rcs_num.h and the Main Program main_<CPU>.c
               (left out when the build has no runtime files)

It prints the number of findings per MISRA rule for each example and group,
sorted by rule, with totals, then the other cppcheck findings (style checks
such as redundantAssignment) the same way.  The rule notes are short
paraphrases; cppcheck prints no rule texts without a licensed rule file
(--rule-texts).  A measurement, not a test: exit 0 whenever cppcheck ran.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
EXAMPLES = [
    ("submarine", ROOT / "examples" / "submarine" / "submarine.rcs"),
    ("machining_cell", ROOT / "examples" / "machining_cell" / "machining_cell.rcs"),
]
GROUPS = ("controllers", "runtime")
TEMPLATE = "{file}|{line}|{column}|{severity}|{id}|{message}"

# Short paraphrases of the MISRA C:2012 rules cppcheck reports most often.
NOTES = {
    "2.3": "unused type declaration",
    "2.4": "unused tag declaration",
    "2.5": "unused macro",
    "2.7": "unused parameter",
    "5.7": "tag name not unique",
    "5.9": "internal-linkage identifier not unique",
    "7.2": "unsigned constant without u suffix",
    "8.4": "external definition without visible declaration",
    "8.7": "external linkage used in one unit only",
    "8.9": "object could be defined at block scope",
    "9.2": "initializer not enclosed in braces",
    "9.3": "array partially initialized",
    "10.1": "operand of inappropriate essential type",
    "10.3": "assignment to narrower or different essential type",
    "10.4": "operands of different essential type categories",
    "10.6": "composite expression assigned to wider type",
    "10.8": "composite expression cast to different/wider type",
    "11.5": "conversion from pointer to void",
    "12.1": "implicit operator precedence (add parentheses)",
    "12.3": "comma operator",
    "13.3": "++/-- with other side effects",
    "14.4": "controlling expression not essentially Boolean",
    "15.4": "more than one break/goto in a loop",
    "15.5": "more than one exit point (return) in a function",
    "15.6": "body of if/loop not a compound statement",
    "15.7": "if ... else if without final else",
    "16.4": "switch without default",
    "16.6": "switch with fewer than two clauses",
    "17.1": "stdarg.h used",
    "17.2": "recursion",
    "17.7": "return value ignored",
    "17.8": "function parameter modified",
    "18.4": "pointer arithmetic with + or -",
    "19.2": "union used",
    "20.1": "#include after code",
    "20.5": "#undef used",
    "21.1": "#define of a reserved identifier",
    "21.3": "malloc/free used",
    "21.5": "signal.h used",
    "21.6": "stdio.h used",
    "21.8": "abort/exit/getenv/system used",
    "21.10": "time.h used",
    "22.8": "errno not set to zero before call",
}


def rule_key(rule: str) -> tuple:
    return tuple(int(p) if p.isdigit() else p for p in re.split(r"[.]", rule))


def group_of(filename: str, design: str) -> str:
    name = Path(filename).name
    if name.startswith("rcs_") or name.startswith("main_"):
        return "runtime"
    if name == f"{design}.c" or name == f"{design}.h" or name.startswith(f"{design}_"):
        return "controllers"
    return "other"


def generate(design_path: Path, out: Path) -> None:
    cmd = [sys.executable, "-m", "rcsc", "build", str(design_path), "--target", "c", "-o", str(out)]
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"rcsc build {design_path.name} failed ({r.returncode}):\n{r.stdout}{r.stderr}")


def run_cppcheck(gen: Path) -> tuple[list[tuple[str, int, str, str]], str, list[str]]:
    """Findings (file, line, id, message), deduplicated; cppcheck's other output; the files checked."""
    sources = sorted(p.name for p in gen.glob("*.c"))
    cmd = [
        "cppcheck", "--addon=misra", "--enable=style", "--std=c99", "--platform=unix64", "-q",
        "-I.", f"--template={TEMPLATE}", *sources,
    ]
    r = subprocess.run(cmd, cwd=gen, capture_output=True, text=True)
    findings = set()
    other = []
    for line in (r.stderr + "\n" + r.stdout).splitlines():
        parts = line.split("|", 5)
        if len(parts) == 6 and parts[1].isdigit():
            findings.add((parts[0], int(parts[1]), parts[4], parts[5]))
        elif line.strip() and not line.startswith((" ", "^")) and "|" not in line:
            other.append(line)
    if r.returncode != 0:
        other.append(f"cppcheck exit status {r.returncode}")
    return sorted(findings), "\n".join(other), sources


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--list", metavar="RULE", action="append", default=[], help="also print every finding of RULE (e.g. 15.5)")
    ap.add_argument("--keep", metavar="DIR", help="generate into DIR and keep it (default: a temporary directory)")
    args = ap.parse_args(argv)

    exe = shutil.which("cppcheck")
    if exe is None:
        print("cppcheck not found", file=sys.stderr)
        return 2
    version = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout.strip()

    tmp = None
    if args.keep:
        work = Path(args.keep)
        work.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="bench_misra_")
        work = Path(tmp.name)
    try:
        dirs = {}
        for name, path in EXAMPLES:
            dirs[name] = work / name
            generate(path, dirs[name])
        with ThreadPoolExecutor(max_workers=len(EXAMPLES)) as pool:
            results = dict(zip(dirs, pool.map(run_cppcheck, dirs.values())))
    finally:
        if tmp is not None:
            tmp.cleanup()

    # counts[(example, group)][id]
    columns = []
    counts: dict[tuple[str, str], Counter] = {}
    num_h = {}
    for name, _ in EXAMPLES:
        findings, other, sources = results[name]
        if other.strip():
            print(f"note: cppcheck said, for {name}:\n{other}\n", file=sys.stderr)
        has_runtime = any(group_of(f, name) == "runtime" for f in sources)
        for g in (*GROUPS, "other"):
            mine = Counter(i for f, _, i, _ in findings if group_of(f, name) == g)
            if (g == "runtime" and not has_runtime) or (g == "other" and not mine):
                continue
            columns.append((name, g))
            counts[(name, g)] = mine
        num_h[name] = sum(1 for f, _, i, _ in findings if Path(f).name == "rcs_num.h" and i.startswith("misra"))

    misra_ids = sorted({i for c in counts.values() for i in c if i.startswith("misra-c2012-")},
                       key=lambda i: rule_key(i.removeprefix("misra-c2012-")))
    other_ids = sorted({i for c in counts.values() for i in c if not i.startswith("misra-c2012-")})
    if not misra_ids:
        print("warning: no MISRA findings at all - did the misra addon run? (needs python3)", file=sys.stderr)

    heads = [f"{n[:9]}/{'ctrl' if g == 'controllers' else 'rt' if g == 'runtime' else g}" for n, g in columns]
    width = max(12, *(len(h) for h in heads))

    def table(title: str, ids: list[str], label) -> None:
        lw = max(12, *(len(label(i)) + 2 for i in ids))
        print(title)
        head = f"{'rule':<{lw}}" + "".join(f"{h:>{width + 1}}" for h in heads) + f"{'total':>8}  note"
        print(head)
        print("-" * len(head))
        for i in ids:
            row = [counts[c].get(i, 0) for c in columns]
            print(f"{label(i):<{lw}}" + "".join(f"{v:>{width + 1}}" for v in row) + f"{sum(row):>8}  "
                  + NOTES.get(label(i), ""))
        tot = [sum(counts[c].get(i, 0) for i in ids) for c in columns]
        print(f"{'total':<{lw}}" + "".join(f"{v:>{width + 1}}" for v in tot) + f"{sum(tot):>8}")
        print(f"{'rules':<{lw}}" + "".join(f"{sum(1 for i in ids if counts[c].get(i)):>{width + 1}}" for c in columns)
              + f"{len(ids):>8}")

    print(f"{version}, misra addon; cppcheck --addon=misra --enable=style --std=c99 on every generated .c")
    print("ctrl: the design's own files (<design>*.c/.h); rt: rcs_runtime.*, rcs_num.h, main_*.c\n")
    table("MISRA C:2012 findings per rule", misra_ids, lambda i: i.removeprefix("misra-c2012-"))
    print("(rt includes rcs_num.h, which the controllers also include: "
          + ", ".join(f"{n} {k}" for k, n in num_h.items()) + " of the rt findings)")
    if other_ids:
        print()
        table("other cppcheck findings (--enable=style)", other_ids, lambda i: i)

    for rule in args.list:
        want = rule if rule.startswith("misra") or not re.match(r"^\d", rule) else f"misra-c2012-{rule}"
        print(f"\nfindings of {want}:")
        for name, _ in EXAMPLES:
            for f, line, i, msg in results[name][0]:
                if i == want:
                    print(f"  {name}/{f}:{line}: {msg}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
