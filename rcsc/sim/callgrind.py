"""`rcsc budget --callgrind`: the worst case per (verb, state, rule) as
instruction counts, the same on every run (for CI).

The design is built for the C target (rcsc/sim/compiled.py, cached), the
scenario compiled to its event file, and the Main Program run once under
`valgrind --tool=callgrind` with, per scheduled controller,
`--zero-before=<the Main Program's step wrapper>` and
`--dump-after=<the controller's step function>`: every step leaves one
profile dump that holds exactly the instructions of that step.  The program's
`--step-log` says, line by line in the same order, which controller stepped
and its (verb, state, rule); the dumps and the lines together make a run file
in the format of `--timing-out` with `"unit": "insn"`.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

from rcsc.front.scenario import Scenario
from rcsc.outputs import backend
from rcsc.outputs.events import event_text
from rcsc.semantics import model as m
from rcsc.sim import compiled

_SUMMARY = re.compile(r"^summary:\s*(\d+)", re.M)


def _json_str(s: str) -> str:
    import json

    return json.dumps(s, ensure_ascii=False)


def measure(design: m.Design, sc: Scenario, build_root: str) -> str:
    """The run file's text; raises compiled.CompiledError when it cannot be made."""
    if shutil.which("valgrind") is None:
        raise compiled.CompiledError("`valgrind` is not installed (it is needed for --callgrind)")
    if len(design.cpus) != 1:
        raise compiled.CompiledError("--callgrind measures a design with one CPU (run each CPU's Main Program with --timing-out instead)")
    b = compiled.build(design, "c", build_root)
    tg = backend.get_target("c")(design, backend.BuildOptions())
    n = tg.n
    cpu = next(iter(design.cpus.values()))
    ctrls = backend.built_controllers(design, backend.BuildOptions())
    work = b.folder / "callgrind" / Path(sc.path).stem
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)
    events = work / "run.events"
    events.write_text(event_text(design, sc, ctrls), encoding="utf-8")
    names = [use.name for use in cpu.schedule]
    cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={work / 'cg.out'}"]
    for c in names:
        cmd.append(f"--zero-before={n.local('step', c)}")
    for c in names:
        cmd.append(f"--dump-after={n.ctrl_part(c, 'step')}")
    cmd += [str(b.program), "--fast", "--no-console", "--no-timing", "--scenario", str(events), "--step-log", str(work / "steps.tsv")]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=compiled.RUN_TIMEOUT, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired as exc:
        raise compiled.CompiledError(f"the program ran under callgrind for more than {compiled.RUN_TIMEOUT:.0f} s") from exc
    if r.returncode != 0:
        raise compiled.CompiledError(f"the program exited with status {r.returncode} under callgrind:\n{r.stderr[-3000:]}")
    steps = [line.split("\t") for line in (work / "steps.tsv").read_text(encoding="utf-8").splitlines()]
    counts = []
    for k in range(1, len(steps) + 1):
        dump = work / f"cg.out.{k}"
        found = _SUMMARY.search(dump.read_text(encoding="utf-8", errors="replace")) if dump.is_file() else None
        if found is None:
            raise compiled.CompiledError(f"callgrind left no profile for step {k} ({dump})")
        counts.append(int(found.group(1)))
    # (controller) -> (verb, state, rule) -> [steps, max, sum], in first-seen order, sorted below
    per: dict[str, dict[tuple[str, str, str], list[int]]] = {c: {} for c in names}
    for (ctrl, verb, state, rule), ir in zip(steps, counts):
        x = per.setdefault(ctrl, {}).setdefault((verb, state, rule), [0, 0, 0])
        x[0] += 1
        x[1] = max(x[1], ir)
        x[2] += ir
    return _run_text(design, cpu, sc.cycles, per)


def _run_text(design: m.Design, cpu: m.Cpu, cycles: int, per: dict[str, dict[tuple[str, str, str], list[int]]]) -> str:
    """The run file, laid out as the Main Program writes `--timing-out` (keys
    in a fixed order; rules by verb, state and rule number)."""
    parts = []
    for name, rules in per.items():
        c = design.controllers[name]
        verbs = {v: i for i, v in enumerate(c.verbs, 1)}
        states = {"": 0, "new": 1, "done": 2, "error": 3}
        labels: dict[tuple[str, str], int] = {}
        for p in c.plans.values():
            for st in p.states:
                states.setdefault(st, len(states))
            for r in p.rules:
                labels.setdefault((p.verb, r.label), len(labels) + 1)
        order = sorted(rules, key=lambda k: (verbs.get(k[0], 0), states.get(k[1], 0), labels.get((k[0], k[2]), 0) if k[2] else 0, k))
        rows = [
            f'\n {{"verb":{_json_str(v)},"state":{_json_str(s)},"rule":{_json_str(r)},"steps":{x[0]},"max_insn":{x[1]},"mean_insn":{x[2] // x[0]}}}'
            for (v, s, r) in order
            for x in [rules[(v, s, r)]]
        ]
        total = sum(x[0] for x in rules.values())
        worst = max((x[1] for x in rules.values()), default=0)
        parts.append(f'\n{{"name":{_json_str(name)},"budget_ns":{c.budget_ns},"steps":{total},"max_insn":{worst},"rules":[' + ",".join(rows) + "]}")
    return (f'{{"format":"rcs-timing-1","design":{_json_str(design.name)},"cpu":{_json_str(cpu.name)},"unit":"insn","cycles":{cycles},"controllers":['
            + ",".join(parts) + "\n]}\n")
