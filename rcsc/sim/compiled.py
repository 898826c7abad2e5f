"""`rcsc test --target NAME`: scenarios run on the compiled Main Program (`run_compiled`).

The design is built once per content (a folder under the build directory
named by the hash of the generated files and the rcsc version, reused while
it exists), each scenario is compiled to its event file (rcsc/outputs/events.py)
and run with `--fast` (one CPU) or under the launcher with `--lockstep`
(several CPUs), and the expectations are evaluated on the program's JSON-lines
trace by the code the simulator's runs use (rcsc/sim/runner.py).
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import rcsc
from rcsc.diagnostics import Diagnostics
from rcsc.front.scenario import Scenario
from rcsc.outputs import backend
from rcsc.outputs.events import event_text
from rcsc.semantics import model as m
from rcsc.semantics.types import ArrayType, FloatType, RecordType, Type
from rcsc.sim.runner import Expectations, RunResult
from rcsc.sim.trace import CtrlSnapshot, Snapshot

RUN_TIMEOUT = 600.0


class CompiledError(Exception):
    """A build or a run that did not give a trace (the message says why)."""


@dataclass
class Build:
    folder: Path
    program: Path  # the Main Program (one CPU) or the launcher (several CPUs)
    multi: bool


def _key(target: str, files: list[backend.OutFile]) -> str:
    h = hashlib.sha256(f"rcsc {rcsc.__version__} {target}\n".encode())
    for f in sorted(files, key=lambda f: f.path):
        h.update(f"{f.path}\0{len(f.text)}\0".encode())
        h.update(f.text.encode("utf-8"))
    return h.hexdigest()[:16]


def _run_tool(cmd: list[str], cwd: Path, env: dict | None = None) -> None:
    try:
        r = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=RUN_TIMEOUT, stdin=subprocess.DEVNULL)
    except FileNotFoundError as exc:
        raise CompiledError(f"`{cmd[0]}` is not installed: {exc.strerror}") from exc
    except subprocess.TimeoutExpired as exc:
        raise CompiledError(f"`{' '.join(cmd)}` took more than {RUN_TIMEOUT:.0f} s") from exc
    if r.returncode != 0:
        raise CompiledError(f"`{' '.join(cmd)}` failed in {cwd}:\n{(r.stdout + r.stderr)[-3000:]}")


def build(design: m.Design, target_name: str, build_root: str) -> Build:
    """The design built for `target_name` under `build_root` (reused when its content is unchanged)."""
    tg = backend.get_target(target_name)(design, backend.BuildOptions())
    diags = Diagnostics()
    tg.check(diags)
    if diags.has_errors():
        raise CompiledError("the target refuses the design: " + "; ".join(d.message for d in diags.errors))
    files = tg.files()
    # The design's name is cut (a folder's name has at most 255 bytes); the
    # digest of the files tells builds apart.
    # The folder is absolute: the build commands run inside it, so a path
    # relative to where rcsc was started (the default `build/rcsc-test`) would
    # mean another place to them (cargo's CARGO_TARGET_DIR, for one).
    folder = Path(build_root).absolute() / f"{design.name[:100]}-{target_name}-{_key(target_name, files)}"
    multi = len(design.cpus) > 1
    program = Path(tg.program(str(folder)))
    done = folder / ".rcsc-built"
    if done.is_file() and program.is_file():
        return Build(folder, program, multi)
    try:
        backend.write_files(files, str(folder), tg.entry_files)
    except OSError as exc:
        raise CompiledError(f"cannot write the build to {folder}: {exc.strerror or exc}") from exc
    for cmd, env in tg.build_commands(str(folder)):
        _run_tool(cmd, folder, dict(os.environ, **env) if env else None)
    if not program.is_file():
        raise CompiledError(f"the build did not make {program}")
    done.write_text(f"{program.name}\n", encoding="utf-8")
    return Build(folder, program, multi)


def _trace_int(text: str):
    """A number without a point or an exponent in a trace line.

    The programs print an f64 that is a whole number without a point, so
    negative zero is `-0`, which JSON reads as the integer 0: its sign,
    which an expectation can observe (`1.0 / x`, `copysign`), would be
    lost.  No integer is ever printed as `-0`, so this is the f64."""
    return -0.0 if text == "-0" else int(text)


def read_trace(text: str) -> list[dict]:
    """The lines of a program's JSON-lines trace (ValueError if one is not JSON)."""
    return [trace_line(x) for x in text.split("\n") if x]


def trace_line(line: str) -> dict:
    """One line of a program's trace (ValueError if it is not JSON)."""
    return json.loads(line, parse_int=_trace_int)


def _value(v, t: Type):
    """A trace value as the simulator holds it."""
    if isinstance(t, RecordType):
        return {n: _value(v[n], ft) for n, ft in t.fields}
    if isinstance(t, ArrayType):
        return [_value(x, t.elem) for x in v]
    if isinstance(t, FloatType):
        return float(v)  # also "nan", "inf", "-inf"
    return v


def _ctrl(design: m.Design, name: str, s: dict) -> CtrlSnapshot:
    c = design.controllers[name]
    fields = {n: _value(s["fields"][n], v.type) for n, v in c.status_fields.items()}
    return CtrlSnapshot(s["echo"], s["status"], s["verb"], s["state"], s["rule"], s["error_code"], fields)


def snapshots(design: m.Design, sc: Scenario, lines: list[dict], multi: bool) -> list[Snapshot]:
    """`views` as a list (the differential tester compares them with the simulator's)."""
    return list(views(design, sc, lines, multi))


def views(design: m.Design, sc: Scenario, lines: Iterable[dict], multi: bool) -> Iterator[Snapshot]:
    """What the expectations see at each tick 1..cycles, rebuilt from the
    program's trace as it is read (a long run's trace need not be whole in
    memory; its lines come in time order, as the simulator's do).

    One CPU: the line of the tick (after a `stop`, the last one).  Several
    CPUs: at tick N (instant (N-1) * base tick) each controller's status and
    each Global Memory variable as its CPU's latest cycle released by then
    left them (a variable: on its writer's CPU), inputs as the scenario last
    set them, the rest at its initial value."""
    pending = iter(lines)
    ahead: dict | None = next(pending, None)
    if not multi:
        last = None
        for tick in range(1, sc.cycles + 1):
            while ahead is not None and ahead["cycle"] <= tick:
                if ahead["cycle"] == tick:
                    last = ahead
                ahead = next(pending, None)
            if last is None:
                raise CompiledError(f"the trace has no line for cycle {tick}")
            gm = {n: _value(last["gm"][n], v.type) for n, v in design.gm.items()}
            yield Snapshot(tick, gm, {n: _ctrl(design, n, last["ctrl"][n]) for n in design.controllers})
        return
    writer: dict[str, str] = {}
    for c in design.controllers.values():
        for use in c.writes:
            if c.cpu:
                writer.setdefault(use.name, c.cpu)
    base = design.base_tick_ns
    latest: dict[str, dict] = {}
    env = {n: v.init for n, v in design.gm.items() if v.from_env}
    inputs = sorted(sc.inputs, key=lambda i: i.cycle)
    j = 0
    seen_t = 0
    for tick in range(1, sc.cycles + 1):
        instant = (tick - 1) * base
        while ahead is not None and ahead["t"] <= instant:
            if ahead["t"] < seen_t:
                raise CompiledError(f"the trace goes back in time (t = {ahead['t']} after {seen_t})")
            seen_t = ahead["t"]
            latest[ahead["cpu"]] = ahead
            ahead = next(pending, None)
        while j < len(inputs) and inputs[j].cycle <= tick:
            env[inputs[j].var] = inputs[j].value
            j += 1
        gm = {}
        for n, v in design.gm.items():
            w = writer.get(n)
            if n in env:
                gm[n] = env[n]
            elif w in latest:
                gm[n] = _value(latest[w]["gm"][n], v.type)
            else:
                gm[n] = v.init
        ctrls = {}
        for n, c in design.controllers.items():
            cpu = c.cpu or next(iter(design.cpus))
            if cpu not in latest:
                raise CompiledError(f"the trace has no cycle of CPU {cpu} by tick {tick}")
            ctrls[n] = _ctrl(design, n, latest[cpu]["ctrl"][n])
        yield Snapshot(tick, gm, ctrls)


def run_compiled(design: m.Design, sc: Scenario, b: Build, work: Path) -> RunResult:
    """Runs `sc` on the built program and evaluates its expectations on the trace."""
    ctrls = backend.built_controllers(design, backend.BuildOptions())
    work.mkdir(parents=True, exist_ok=True)
    events = work / f"{Path(sc.path).stem}.events"
    trace = work / f"{Path(sc.path).stem}.jsonl"
    events.write_text(event_text(design, sc, ctrls), encoding="utf-8")
    mode = ["--lockstep"] if b.multi else ["--fast", "--no-console"]
    cmd = [str(b.program), *mode, "--no-timing", "--scenario", str(events), "--trace", str(trace)]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=RUN_TIMEOUT, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired as exc:
        raise CompiledError(f"the program ran for more than {RUN_TIMEOUT:.0f} s") from exc
    if r.returncode != 0:
        raise CompiledError(f"the program exited with status {r.returncode}:\n{r.stderr[-3000:]}")
    expectations = Expectations(design, sc.expects)
    try:
        with trace.open(encoding="utf-8") as f:
            for view in views(design, sc, (trace_line(x) for x in f), b.multi):
                expectations.see(view)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise CompiledError(f"the program's trace is unreadable: {exc}") from exc
    return RunResult(sc, [], expectations.results(), multi_cpu=b.multi)
