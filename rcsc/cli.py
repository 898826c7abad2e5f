"""The `rcsc` command line (also `python -m rcsc`).

Each subcommand is one entry of `COMMANDS`: a function that adds its arguments
to its own sub-parser and a function that runs it and returns the exit code.
A new command (sim, test, build, graph, ...) is two functions and one entry.

Contract with CI (docs/ci.md):

- exit codes: 0 clean, 1 findings at error level (or any warning with
  `--deny-warnings`), 2 usage, I/O or internal error, 130 interrupted;
- stdout carries the report and nothing else; messages go to stderr;
- no input, however broken, ends in a Python traceback (set RCSC_BACKTRACE=1
  to see one for an internal error while debugging rcsc itself).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import stat
import sys
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType

import rcsc
from rcsc import codes, render
from rcsc.outputs import safeio
from rcsc.diagnostics import Diagnostics

EXIT_OK = 0
EXIT_FINDINGS = 1
EXIT_USAGE = 2  # also I/O errors and internal errors: DESIGN allows 0, 1, 2 only
EXIT_INTERRUPTED = 130  # the shell convention for SIGINT (128 + 2)

FORMATS = ("human", "short", "json", "sarif", "github")


class UsageError(Exception):
    """A problem with how rcsc was called or with the files it must touch."""


# ---------------------------------------------------------------------------
# output
# ---------------------------------------------------------------------------

def _write(stream, text: str) -> None:
    """Write `text`, replacing what the stream's encoding cannot show rather
    than failing (a C locale in CI must not turn a report into a crash)."""
    try:
        stream.write(text)
    except UnicodeEncodeError:
        encoding = getattr(stream, "encoding", None) or "ascii"
        stream.write(text.encode(encoding, "replace").decode(encoding))


def _error(message: str) -> None:
    _write(sys.stderr, f"error: {message}\n")


def _emit_report(text: str, output: str | None) -> None:
    """Send a report to `output` (a file) or to stdout."""
    if output is None:
        _write(sys.stdout, text)
        return
    try:
        safeio.write_report(output, text.encode("utf-8"))
    except OSError as exc:
        raise UsageError(f"cannot write `{output}`: {exc.strerror or exc}") from exc


def _report_out(files: contextlib.ExitStack, output: str | None) -> Callable[[str], None]:
    """A function that writes text to `output` (a report file, replaced as a
    whole when `files` closes without error; `safeio.report_stream`) or to
    stdout."""
    if output is None:
        return _stdout_writer()
    raw = files.enter_context(_report_file(output))

    def write(text: str) -> None:
        try:
            raw.write(text.encode("utf-8"))
        except OSError as exc:
            raise UsageError(f"cannot write `{output}`: {exc.strerror or exc}") from exc

    return write


def _stdout_writer() -> Callable[[str], None]:
    """Write to stdout until its reader goes away (`rcsc sim ... | head`):
    then the rest is dropped and the run goes on, so that its verdict
    (the exit code, the failed expectations on stderr) is still given."""
    gone = False

    def write(text: str) -> None:
        nonlocal gone
        if gone:
            return
        try:
            _write(sys.stdout, text)
            sys.stdout.flush()
        except BrokenPipeError:
            gone = True
            # Python flushes stdout again at exit: let that go nowhere.
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
            os.close(devnull)

    return write


@contextlib.contextmanager
def _report_file(output: str):
    """`safeio.report_stream`, its failures (refused, disk full) a usage error naming the file."""
    try:
        with safeio.report_stream(output) as raw:
            yield raw
    except OSError as exc:
        raise UsageError(f"cannot write `{output}`: {exc.strerror or exc}") from exc


class _StepLog:
    """`rcsc sim --step-log`: the simulator's step lines, written as they come."""

    def __init__(self, out: Callable[[str], None]) -> None:
        self.out = out

    def append(self, line: str) -> None:
        self.out(line + "\n")


def _use_color(choice: str, output: str | None, stream=None) -> bool:
    """Whether a report gets ANSI colour.

    `--color always|never` decides first; a report written to a file (`-o`)
    has none.  Otherwise, as https://force-color.org specifies, a non-empty
    FORCE_COLOR turns colour on even for a pipe and wins over NO_COLOR; a
    non-empty NO_COLOR (https://no-color.org) or TERM=dumb turns it off; else
    only a terminal gets colour.
    """
    if choice == "always":
        return True
    if choice == "never" or output is not None:
        return False
    if os.environ.get("FORCE_COLOR"):
        return True
    if os.environ.get("NO_COLOR") or os.environ.get("TERM") == "dumb":
        return False
    isatty = getattr(stream or sys.stdout, "isatty", None)
    return bool(isatty and isatty())


def _render(diags: Diagnostics, fmt: str, color: bool, quiet: bool = False) -> str:
    from rcsc import render

    if fmt == "human":
        return render.render_human(diags, color=color, summary=not quiet)
    if fmt == "short":
        return render.render_short(diags)
    if fmt == "github":
        return render.render_github(diags)
    if fmt == "json":
        return render.render_json(diags, rcsc.__version__)
    return render.render_sarif(diags, rcsc.__version__)


def _exit_code(diags: Diagnostics, deny_warnings: bool) -> int:
    if diags.has_errors() or (deny_warnings and diags.warnings):
        return EXIT_FINDINGS
    return EXIT_OK


# ---------------------------------------------------------------------------
# rcsc check
# ---------------------------------------------------------------------------

def _load_driver() -> ModuleType:
    """The front-end pipeline, imported late so that `rcsc explain` and
    `--version` work even when the front end is broken (tests replace this)."""
    from rcsc import driver

    return driver


# In the check daemon (`rcsc.daemon`): what it keeps in memory between calls
# (`incremental.memory_stores`), put in front of each design's cache folder.
DAEMON_MEMORY: dict | None = None
# How the daemon answered each design of the running call: "replay", "partial" or "full".
DAEMON_ANSWERS: list[str] = []


def _check_in_daemon(path: str, as_module: bool):
    """`_check` with the daemon's memory: the findings of an unchanged design
    replayed, else the edited controllers re-checked with the syntax trees
    kept of the others, else a full check; every entry also read from and
    written to the design's cache folder, as `rcsc check` does."""
    from rcsc.checks import cache, incremental
    from rcsc.checks import replay as replays

    assert DAEMON_MEMORY is not None
    where = cache.folder_for(path)
    stores = {ns: cache.LayeredStore(DAEMON_MEMORY[ns], cache.Store(where, ns))
              for ns in (incremental.NAMESPACE, replays.NAMESPACE, "guards", "values")}
    stores[incremental.TREES] = DAEMON_MEMORY[incremental.TREES]
    hit = replays.lookup(path, as_module, where, store=stores[replays.NAMESPACE])
    if hit is not None:
        DAEMON_ANSWERS.append("replay")
        return hit
    driver = _load_driver()
    try:
        # The report needs the findings only: the plans' syntax trees go as soon as they are modelled.
        result = driver.check_path(path, as_module=as_module, memory=stores, keep_plans=False)
    except driver.InputError as exc:
        raise UsageError(str(exc)) from exc
    DAEMON_ANSWERS.append("partial" if result.partial else "full")
    return result


def _check(path: str, as_module: bool = False, cache: bool = True, replay: bool = False):
    """Run the front end on `path`; an unreadable root file is a usage error (exit 2).

    With `cache`, the guard and value analyses use the design's `.rcsc-cache/` folder
    (every command that checks a design does, so `rcsc build` after `rcsc check`
    asks the solver nothing new; RCSC_NO_CACHE=1 turns it off for all of them);
    with `replay` too, a design whose files are all unchanged since a check
    stored there answers with that check's findings (`rcsc.checks.replay`:
    findings only, no model, so only for `rcsc check`).
    """
    if cache and replay and DAEMON_MEMORY is not None:
        from rcsc.checks.cache import disabled_by_environment

        if not disabled_by_environment():
            return _check_in_daemon(path, as_module)
    if cache and replay:
        from rcsc.checks import replay as replays
        from rcsc.checks.cache import folder_for

        hit = replays.lookup(path, as_module, folder_for(path))
        if hit is not None:
            return hit
        # Only plans of some controllers changed: check those again (rcsc.checks.incremental).
        from rcsc.checks import incremental

        quick = incremental.recheck(path, as_module, folder_for(path))
        if quick is not None:
            incremental.remember(path, as_module, folder_for(path), quick)
            return quick
    driver = _load_driver()
    # `rcsc check` (replay) needs the findings only: the plans' syntax trees
    # are freed as soon as they are converted.
    keep_plans = not replay
    try:
        if cache:
            from rcsc.checks.cache import folder_for

            result = driver.check_path(path, as_module=as_module, cache_dir=folder_for(path), keep_plans=keep_plans)
        else:
            result = driver.check_path(path, as_module=as_module, keep_plans=keep_plans)
    except driver.InputError as exc:
        raise UsageError(str(exc)) from exc
    if cache and replay:
        incremental.remember(path, as_module, folder_for(path), result)
    return result


def _add_check_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "paths", metavar="PATH", nargs="+",
        help="design files, module files, folders (searched for *.rcs) or glob patterns",
    )
    p.add_argument(
        "--no-cache", action="store_true",
        help="do not read or write the cache of solver results and findings (.rcsc-cache/ next to the design; also RCSC_NO_CACHE=1)",
    )
    p.add_argument(
        "--daemon", action="store_true",
        help="have the check daemon answer (started on first use, it stays and keeps the last check in memory: "
             "a re-check after an edit in a large design takes a fraction of the time; `rcsc daemon --help`)",
    )
    _add_report_arguments(p)
    p.add_argument("-q", "--quiet", action="store_true", help="print the findings only: no summary line, no notes")
    g = p.add_argument_group("configuration (docs/configuration.md)")
    which = g.add_mutually_exclusive_group()
    which.add_argument("--config", metavar="FILE", help="use this rcsc.toml or pyproject.toml instead of searching for one")
    which.add_argument("--no-config", action="store_true", help="ignore every configuration file")
    g.add_argument("--select", metavar="CODES", help="report only these warnings (comma-separated codes or prefixes)")
    g.add_argument("--ignore", metavar="CODES", help="never report these warnings (comma-separated codes or prefixes)")
    g.add_argument(
        "--severity", metavar="CODE=LEVEL", action="append", default=[],
        help="report warning CODE as error, warning or note (repeatable)",
    )


def _add_report_arguments(p: argparse.ArgumentParser) -> None:
    """Options of every command that reports findings (check, and later build)."""
    p.add_argument("--format", choices=FORMATS, default="human", help="report format (default: human)")
    p.add_argument("--deny-warnings", action="store_true", help="exit with 1 on warnings too")
    p.add_argument(
        "--color", choices=("auto", "always", "never"), default="auto",
        help="colour the human report (default: auto, a terminal without NO_COLOR, or FORCE_COLOR)",
    )
    p.add_argument("-o", "--output", metavar="FILE", help="write the report to FILE instead of stdout")


def _cli_overrides(args: argparse.Namespace):
    """The configuration flags as a function that amends a loaded Config."""
    from rcsc import config as cfg

    def split(value: str | None) -> list[str] | None:
        if value is None:
            return None
        return [v.strip() for v in value.split(",") if v.strip()]

    select, ignore = split(args.select), split(args.ignore)
    # `--select` chooses the warnings to report (errors are always reported):
    # one that names no warning would silently hide them all.
    if select is not None and not select:
        raise UsageError("--select: no code given (to report no warnings, use --ignore W)")
    if select and cfg.selects_no_warning(select):
        raise UsageError(f"--select: `{args.select}` names no warning (errors are always reported; --select chooses warnings, e.g. W05)")
    severity: dict = {}
    for item in args.severity:
        code, _, level = item.partition("=")
        code = code.strip().upper()
        if code not in codes.CODES or level.strip() not in cfg.SEVERITIES:
            raise UsageError(f"--severity `{item}`: write CODE=error|warning|note with a known code")
        if not code.startswith("W"):
            raise UsageError(f"--severity `{item}`: the severity of an error cannot be changed")
        severity[code] = cfg.SEVERITIES[level.strip()]
    for flag, values in (("--select", select), ("--ignore", ignore)):
        for v in values or []:
            if not any(c.startswith(v) for c in codes.CODES):
                raise UsageError(f"{flag}: `{v}` is not a diagnostic code or a prefix of one")
            if flag == "--ignore" and v.startswith("E"):
                raise UsageError(f"{flag}: errors cannot be ignored (`{v}`)")

    def amend(conf):
        if select is not None:
            conf.select = select
        if ignore:
            conf.ignore = conf.ignore + ignore
        conf.severity.update(severity)
        return conf

    return amend


class _CheckRun:
    """One `rcsc check PATH...`: every design checked once, modules through
    the designs that import them, every finding in one bag."""

    def __init__(self, args: argparse.Namespace) -> None:
        from rcsc import config as cfg

        self.args = args
        self.cfg = cfg
        self.amend = _cli_overrides(args)
        self.total = Diagnostics()
        self.covered: set[str] = set()  # real paths of every file some check loaded
        self.checked: set[str] = set()  # real paths of the roots checked
        self.configs: dict[str | None, object] = {}
        self.usage_problem = False
        self.loaded = 0  # roots that could be read

    def config_for(self, path: str):
        args = self.args
        if args.no_config:
            found = None
        elif args.config:
            found = (args.config, os.path.basename(args.config) == self.cfg.PYPROJECT)
        else:
            found = self.cfg.find(path)
        key = found[0] if found else None
        if key not in self.configs:
            if found is None:
                conf = self.cfg.Config()
            else:
                conf = self.cfg.load(_display(found[0]), found[1], self.total)
            self.configs[key] = self.amend(conf)
        return self.configs[key]

    def run(self, path: str, as_module: bool = False) -> None:
        conf = self.config_for(path)
        self.checked.add(os.path.realpath(path))
        try:
            result = _check(path, as_module, cache=not self.args.no_cache, replay=True)
        except UsageError as exc:
            _error(str(exc))
            self.usage_problem = True
            return
        self.loaded += 1
        self.total.extend(conf.apply(result.diags))
        for f in getattr(result, "files", None) or []:
            if not f.source.path.startswith("<stdlib>"):
                self.covered.add(os.path.realpath(f.source.path))

    def imports_module(self, design: str, module_real: str) -> bool:
        from rcsc.front.loader import InputError, path_to_files

        try:
            files = path_to_files(design, Diagnostics())
        except InputError:
            return False
        return any(os.path.realpath(f.source.path) == module_real for f in files if not f.is_root)


def _run_check(args: argparse.Namespace) -> int:
    from rcsc.front import workspace

    if args.daemon and DAEMON_MEMORY is None:
        from rcsc import daemon  # (`rcsc.launch` hands such a call on before this module loads)

        if not daemon.attempted:  # (when it did and no daemon answered, check here)
            code = daemon.client_main(_ARGV)
            if code is not None:
                return code

    run = _CheckRun(args)
    expanded = workspace.expand(args.paths)
    for problem in expanded.problems:
        _error(problem)
    explicit = {os.path.realpath(p) for p in args.paths if os.path.isfile(p)}
    files = [
        f for f in expanded.files
        if os.path.realpath(f) in explicit or not run.config_for(f).excluded(f)
    ]
    modules = []
    for f in files:
        if workspace.header_kind(f) == "module":
            modules.append(f)
        else:
            run.run(f)
    for m in modules:
        real = os.path.realpath(m)
        if real in run.covered:
            continue
        for design in workspace.candidate_designs(m):
            if os.path.realpath(design) not in run.checked and run.imports_module(design, real):
                run.run(_display(design))
        if real not in run.covered:
            run.run(m, as_module=True)
    if run.loaded == 0 and not run.total.items:
        # Nothing could be read: the messages on stderr are the whole answer.
        return EXIT_USAGE
    color = args.format == "human" and _use_color(args.color, args.output)
    _emit_report(_render(run.total, args.format, color, quiet=args.quiet), args.output)
    if run.usage_problem or (expanded.problems and not run.total.items):
        return EXIT_USAGE
    return _exit_code(run.total, args.deny_warnings)


def _display(path: str) -> str:
    """`path` relative to the current folder when it is inside it."""
    rel = os.path.relpath(path)
    return path if rel.startswith("..") else rel


# ---------------------------------------------------------------------------
# rcsc explain
# ---------------------------------------------------------------------------

def _add_explain_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("code", metavar="CODE", nargs="?", help="a diagnostic code such as E0100")
    p.add_argument("--list", action="store_true", help="list every code with its severity and title")


def _run_explain(args: argparse.Namespace) -> int:
    if args.list == (args.code is not None):
        raise UsageError("give either a CODE or --list (`rcsc explain E0100`, `rcsc explain --list`)")
    if args.list:
        lines = [f"{c.code}  {c.severity.value:<7}  {c.title}" for c in sorted(codes.CODES.values(), key=lambda c: c.code)]
        _write(sys.stdout, "\n".join(lines) + "\n")
        return EXIT_OK
    text = codes.explain(args.code)
    if text is None:
        raise UsageError(f"unknown diagnostic code `{args.code}`; `rcsc explain --list` shows them all")
    _write(sys.stdout, text)
    return EXIT_OK


# ---------------------------------------------------------------------------
# rcsc sim
# ---------------------------------------------------------------------------

TRACE_FORMATS = ("jsonl", "csv", "vcd")


def _report_to_stderr(diags: Diagnostics) -> None:
    from rcsc import render

    _write(sys.stderr, render.render_human(diags, color=_use_color("auto", None, sys.stderr)))


def _add_sim_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", metavar="DESIGN", help="the design's root file")
    p.add_argument("--scenario", metavar="FILE", required=True, help="the scenario to run (see docs/scenarios.md)")
    p.add_argument("--trace-format", choices=TRACE_FORMATS, default=None, help="trace format (default: from the -o suffix, else jsonl)")
    p.add_argument("-o", "--output", metavar="FILE", help="write the trace to FILE instead of stdout")
    p.add_argument("--step-log", metavar="FILE", help="also write one line per step (controller, verb, state, rule) to FILE, "
                   "as the compiled Main Program's --step-log")
    p.add_argument("--externs", metavar="FILE.py", help="Python functions standing in for the design's extern functions "
                   "(without: they return zero values; see docs/scenarios.md)")


def _checked_scenario(design_path: str, scenario_path: str):
    """The checked design and its parsed scenario (`rcsc sim`, `rcsc events`);
    None after reporting the findings that stop either."""
    from rcsc.front.scenario import text_to_scenario

    result = _check(design_path)
    if not result.ok or result.model is None:
        _report_to_stderr(result.diags)
        return None
    from rcsc.front.loader import InputError, read_source

    diags = Diagnostics()
    try:
        source, utf8 = read_source(scenario_path, diags)
    except (OSError, InputError) as exc:
        raise UsageError(f"{scenario_path}: cannot read: {getattr(exc, 'strerror', None) or exc}") from exc
    sc = text_to_scenario(source, result.model, diags) if utf8 else None
    if sc is None or diags.items:  # the scenario's warnings (W0706, W0707) too
        _report_to_stderr(diags)
    if sc is None:
        return None
    return result.model, sc


def _run_sim(args: argparse.Namespace) -> int:
    from rcsc.sim import externs as sim_externs
    from rcsc.sim import trace
    from rcsc.sim.runner import RunResult, ScenarioRun

    loaded = _checked_scenario(args.path, args.scenario)
    if loaded is None:
        return EXIT_FINDINGS
    design, sc = loaded
    externs = None
    if args.externs:
        diags = Diagnostics()
        externs = sim_externs.load(args.externs, design, diags)
        if diags.items:
            _report_to_stderr(diags)
        if externs is None:
            return EXIT_FINDINGS
    fmt = args.trace_format
    if fmt is None:
        suffix = (args.output or "").rsplit(".", 1)[-1].lower()
        fmt = suffix if suffix in TRACE_FORMATS else "jsonl"
    # The trace and the step log are written as the run makes them, so a
    # scenario of any length runs in constant memory.  Several CPUs: the
    # JSON-lines trace has one line per CPU cycle; CSV and VCD show the
    # observer's view (what expectations see) per base tick.
    # A step log to a device or pipe while the trace goes to stdout (say
    # `--step-log /dev/stdout`): two writers to one stream would mix, so both
    # are held and written one after the other, the step log first.
    hold = bool(args.step_log) and args.output is None and os.path.lexists(args.step_log) \
        and not stat.S_ISREG(os.lstat(args.step_log).st_mode)
    held_trace: list[str] = []
    held_steps: list[str] = []
    try:
        with contextlib.ExitStack() as files:
            if hold:
                out, steps = held_trace.append, held_steps
            else:
                out = _report_out(files, args.output)
                steps = _StepLog(_report_out(files, args.step_log)) if args.step_log else None
            run = ScenarioRun(design, sc, externs=externs, step_log=steps)
            if fmt == "jsonl":
                chunks = trace.jsonl_chunks(design, (rec for t in run.ticks() for rec in t.ran))
            elif fmt == "csv":
                chunks = trace.csv_chunks(design, ((t.view, t.last) for t in run.ticks()))
            else:
                chunks = trace.vcd_chunks(design, ((t.view, t.last) for t in run.ticks()), design.base_tick_ns)
            for chunk in chunks:
                out(chunk)
    except sim_externs.ExternCallError as exc:
        diags = Diagnostics()
        exc.report(diags)
        _report_to_stderr(diags)
        return EXIT_FINDINGS
    if hold:
        _emit_report("".join(x + "\n" for x in held_steps), args.step_log)
        _write(sys.stdout, "".join(held_trace))
    assert run.results is not None
    run = RunResult(sc, [], run.results, multi_cpu=run.multi)
    if not run.passed:
        from rcsc.sim.testrun import failure_text

        _write(sys.stderr, render.escape_controls(failure_text(run)) + "\n")
        return EXIT_FINDINGS
    return EXIT_OK


# ---------------------------------------------------------------------------
# rcsc events
# ---------------------------------------------------------------------------

def _add_events_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", metavar="DESIGN", help="the design's root file")
    p.add_argument("scenario", metavar="SCENARIO", help="the scenario to compile (see docs/scenarios.md)")
    p.add_argument("-o", "--output", metavar="FILE", help="write the event file to FILE instead of stdout (see docs/events.md)")
    p.add_argument(
        "--exclude-simulators", action="store_true", help="for a deployment build (`rcsc build --exclude-simulators`)"
    )


def _run_events(args: argparse.Namespace) -> int:
    from rcsc.outputs import backend
    from rcsc.outputs.events import event_text

    loaded = _checked_scenario(args.path, args.scenario)
    if loaded is None:
        return EXIT_FINDINGS
    design, sc = loaded
    ctrls = backend.built_controllers(design, backend.BuildOptions(exclude_simulators=args.exclude_simulators))
    _emit_report(event_text(design, sc, ctrls), args.output)
    return EXIT_OK


# ---------------------------------------------------------------------------
# rcsc console
# ---------------------------------------------------------------------------

def _add_console_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", metavar="DESIGN", help="the design's root file (the one the running Main Program was built from)")
    p.add_argument("--run", dest="run_id", metavar="ID", help="the run id the Main Program was started with (`--run ID`); default: the only one running")
    p.add_argument("--color", choices=("auto", "always", "never"), default="auto", help="colour diagnostics (default: auto)")
    p.add_argument("--screen", action="store_true", help="full-screen view on a terminal: the live status table above the command line")


def _run_console(args: argparse.Namespace) -> int:
    from rcsc.sim import console

    result = _check(args.path)
    if not result.ok or result.model is None:
        _report_to_stderr(result.diags)
        return EXIT_FINDINGS
    design = result.model
    run = args.run_id
    try:
        if run is None:
            runs = console.find_runs(design.name)
            if len(runs) != 1:
                raise console.ConsoleError(
                    "E0810",
                    f"no running Main Program of `{design.name}` publishes an operator segment; start it with `--run ID`"
                    if not runs else f"several runs of `{design.name}` are running ({', '.join(runs)}): give `--run ID`",
                )
            run = runs[0]
        tty = sys.stdin.isatty() and sys.stdout.isatty()
        if args.screen:
            if not tty:
                raise UsageError("--screen needs a terminal; without it the console reads commands line by line")
            return console.run_screen(design, run)
        if tty:
            try:
                import readline  # noqa: F401  (line editing and history for input())
            except ImportError:
                pass

            def typed():
                while True:
                    try:
                        yield input("> ")
                    except EOFError:
                        return

            lines = typed()
        else:
            lines = sys.stdin
        return console.run_console(design, run, lines, sys.stdout, color=_use_color(args.color, None, sys.stdout))
    except console.ConsoleError as exc:
        diags = Diagnostics()
        diags.add(exc.code, None, exc.message)
        _report_to_stderr(diags)
        return EXIT_FINDINGS
    except KeyboardInterrupt:
        return EXIT_OK


# ---------------------------------------------------------------------------
# rcsc test
# ---------------------------------------------------------------------------

def _add_test_arguments(p: argparse.ArgumentParser) -> None:
    from rcsc.outputs import backend

    p.add_argument("paths", metavar="PATH", nargs="*", default=["."], help="design files, scenario files or folders (default: .)")
    p.add_argument("--junit", metavar="FILE", help="also write a JUnit XML report to FILE")
    p.add_argument(
        "--target", choices=("sim", *backend.target_names()), default="sim",
        help="run the scenarios in the simulator (default) or on the compiled Main Program (built once, see docs/events.md)",
    )
    p.add_argument("--build-dir", metavar="DIR", default="build/rcsc-test", help="where --target c|rust|ada builds the design (default: build/rcsc-test)")
    p.add_argument("--externs", metavar="FILE.py", help="in the simulator: Python functions standing in for the extern functions "
                   "(see docs/scenarios.md)")


def _run_test(args: argparse.Namespace) -> int:
    from rcsc.sim import testrun

    if args.externs and args.target != "sim":
        raise UsageError("--externs is for the simulator: a compiled Main Program uses the externs you wrote for its target")
    plan, problems = testrun.discover(args.paths)
    for problem in problems:
        _error(problem)
    report = testrun.Report()
    cache: dict = {}
    for design, scenarios in plan:
        if not scenarios:
            continue
        for scn in scenarios:
            outcome = testrun.run_one(design, scn, cache, args.target, args.build_dir, externs=args.externs)
            report.outcomes.append(outcome)
            word = "PASS" if outcome.passed else "FAIL"
            unit = "ticks" if outcome.result is not None and outcome.result.multi_cpu else "cycles"
            extra = f" ({outcome.cycles} {unit}, {outcome.seconds:.2f} s)" if outcome.cycles else ""
            _write(sys.stdout, render.escape_controls(f"{word} {scn}{extra}") + "\n")
            if outcome.notes is not None:
                _write(sys.stdout, render.escape_controls(render.render_short(outcome.notes)))
            if not outcome.passed:
                if outcome.message:
                    _write(sys.stdout, render.escape_controls("".join(f"    {line}\n" for line in outcome.message.splitlines())))
                if outcome.diags is not None:
                    _write(sys.stdout, render.escape_controls(render.render_short(outcome.diags)))
    _write(sys.stdout, f"{report.passed} passed, {report.failed} failed\n")
    if args.junit:
        _emit_report(testrun.to_junit(report), args.junit)
    if problems or report.failed:
        return EXIT_FINDINGS if report.outcomes or not problems else EXIT_USAGE
    if not report.outcomes:
        _error("no scenarios found (scenarios are *.scn files beside a design or in its scenarios/ folder)")
        return EXIT_USAGE
    return EXIT_OK


# ---------------------------------------------------------------------------
# rcsc budget
# ---------------------------------------------------------------------------

def _add_budget_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", metavar="DESIGN", help="the design's root file")
    p.add_argument("--measured", metavar="RUN.json", action="append", default=[],
                   help="a run file of the compiled Main Program (`--timing-out RUN.json`): the measured worst case per "
                   "controller and per (verb, state, rule) beside the budgets (repeat for each CPU)")
    p.add_argument("--callgrind", metavar="SCENARIO",
                   help="measure instruction counts instead: build the C Main Program and run SCENARIO under "
                   "valgrind's callgrind (the same counts on every run)")
    p.add_argument("--ns-per-insn", metavar="NS", type=float, default=1.0,
                   help="nanoseconds per instruction when instruction counts are compared with budgets (default: 1)")
    p.add_argument("--timing-out", metavar="FILE", help="with --callgrind: also write the run file to FILE")
    p.add_argument("--build-dir", metavar="DIR", default="build/rcsc-test", help="where --callgrind builds the design (default: build/rcsc-test)")


def _run_budget(args: argparse.Namespace) -> int:
    from rcsc.checks import measured
    from rcsc.checks.frames import format_budget_table

    if args.ns_per_insn <= 0:
        raise UsageError("--ns-per-insn needs a positive number")
    if args.timing_out and not args.callgrind:
        raise UsageError("--timing-out writes the run file of --callgrind")
    if not (args.measured or args.callgrind):
        result = _check(args.path)
        if result.model is None:
            _report_to_stderr(result.diags)
            return EXIT_FINDINGS
        _write(sys.stdout, format_budget_table(result.model))
        if result.diags.items:
            _report_to_stderr(result.diags)
        return _exit_code(result.diags, False)
    runs: list[measured.Run] = []
    diags = Diagnostics()
    if args.callgrind:
        from rcsc.sim import callgrind, compiled

        loaded = _checked_scenario(args.path, args.callgrind)
        if loaded is None:
            return EXIT_FINDINGS
        design, sc = loaded
        try:
            text = callgrind.measure(design, sc, args.build_dir)
        except compiled.CompiledError as exc:
            raise UsageError(f"--callgrind: {exc}") from exc
        if args.timing_out:
            _emit_report(text, args.timing_out)
        run = measured.parse_run(args.timing_out or f"callgrind of {args.callgrind}", text, diags)
        if run is not None:
            runs.append(run)
        result_diags = Diagnostics()
    else:
        result = _check(args.path)
        if result.model is None or not result.ok:
            _report_to_stderr(result.diags)
            return EXIT_FINDINGS
        design, result_diags = result.model, result.diags
    for path in args.measured:
        try:
            text = safeio.read_text(path)
        except OSError as exc:
            raise UsageError(f"{path}: cannot read: {getattr(exc, 'strerror', None) or exc}") from exc
        run = measured.parse_run(path, text, diags)
        if run is not None:
            runs.append(run)
    measured.check(design, runs, diags, args.ns_per_insn)
    _write(sys.stdout, format_budget_table(design))
    _write(sys.stdout, measured.format_table(design, runs, args.ns_per_insn))
    result_diags.extend(diags)
    if result_diags.items:
        _report_to_stderr(result_diags)
    return _exit_code(result_diags, False)


# ---------------------------------------------------------------------------
# rcsc graph
# ---------------------------------------------------------------------------

def _add_graph_arguments(p: argparse.ArgumentParser) -> None:
    from rcsc.outputs.graph import FORMATS, VIEWS

    p.add_argument("path", metavar="DESIGN", help="the design's root file")
    p.add_argument("--view", choices=VIEWS, default=None, help="what to draw (default: plan with --plan, else hierarchy)")
    p.add_argument("--controller", metavar="C", help="the controller of the plan view")
    p.add_argument("--plan", metavar="VERB", help="the plan (verb) of the plan view")
    p.add_argument("--compact", action="store_true", help="plan view: label edges with the rule label only (Figure 13 style)")
    p.add_argument("--format", choices=FORMATS, default=None, help="output format (default: from the -o suffix, else dot); svg and png need Graphviz")
    p.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of stdout")


def _run_graph(args: argparse.Namespace) -> int:
    from rcsc.outputs import graph

    result = _check(args.path)
    if result.model is None:
        _report_to_stderr(result.diags)
        return EXIT_FINDINGS
    try:
        fmt = graph.format_for(args.format, args.output)
    except graph.GraphError as exc:
        raise UsageError(str(exc)) from exc
    if fmt == "png" and args.output is None and getattr(sys.stdout, "isatty", lambda: False)():
        raise UsageError("PNG is binary: give `-o FILE.png` (or pipe stdout to a file)")
    view = args.view or ("plan" if args.plan or args.controller else "hierarchy")
    if view != "plan":
        # Options of the plan view given with another view would be ignored
        # without a word, and the user would get a graph they did not ask for.
        given = [flag for flag, value in (("--controller", args.controller), ("--plan", args.plan), ("--compact", args.compact)) if value]
        if given:
            verb = "applies" if len(given) == 1 else "apply"
            raise UsageError(f"{', '.join(f'`{g}`' for g in given)} only {verb} to `--view plan`, not `--view {view}`")
    try:
        g = graph.select_graph(result.model, view, args.controller, args.plan, result.diags.sorted(), args.compact)
        data = graph.output_bytes(g, fmt)
    except graph.GraphError as exc:
        raise UsageError(str(exc)) from exc
    if args.output is None:
        sys.stdout.flush()
        sys.stdout.buffer.write(data)
    else:
        try:
            safeio.write_report(args.output, data)
        except OSError as exc:
            raise UsageError(f"cannot write `{args.output}`: {exc.strerror or exc}") from exc
    if result.diags.items:
        _report_to_stderr(result.diags)
    return _exit_code(result.diags, False)


# ---------------------------------------------------------------------------
# rcsc doc
# ---------------------------------------------------------------------------

def _add_doc_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", metavar="DESIGN", help="the design's root file")
    p.add_argument("-o", "--output", metavar="DIR", required=True, help="the folder to write index.html to (created if missing)")


def _run_doc(args: argparse.Namespace) -> int:
    from rcsc.outputs import doc, graph

    if os.path.exists(args.output) and not os.path.isdir(args.output):
        raise UsageError(f"`{args.output}` exists and is not a folder (rcsc doc writes index.html into a folder)")
    result = _check(args.path)
    if result.model is None:
        _report_to_stderr(result.diags)
        return EXIT_FINDINGS
    try:
        doc.write_site(result.model, result.diags.items, args.output)
    except doc.NotOurs as exc:
        raise UsageError(str(exc)) from exc
    except OSError as exc:
        raise UsageError(f"cannot write to `{args.output}`: {exc.strerror or exc}") from exc
    if not graph.dot_available():
        _write(sys.stderr, "note: Graphviz `dot` is not installed: the page has its tables but no pictures\n")
    if result.diags.items:
        _report_to_stderr(result.diags)
    return _exit_code(result.diags, False)


# ---------------------------------------------------------------------------
# rcsc build, rcsc targets
# ---------------------------------------------------------------------------

def _add_build_arguments(p: argparse.ArgumentParser) -> None:
    from rcsc.outputs import backend

    p.add_argument("path", metavar="DESIGN", help="the design's root file")
    p.add_argument("--target", required=True, choices=sorted(t.name for t in backend.targets()), help="the output language (`rcsc targets`)")
    p.add_argument("-o", "--output", metavar="DIR", required=True, help="the folder to write to (created if missing)")
    p.add_argument(
        "--exclude-simulators", action="store_true",
        help="deployment build: leave the simulators out and call I/O hooks (a file of yours) instead",
    )
    p.add_argument("--deny-warnings", action="store_true", help="refuse to build on warnings too")
    p.add_argument(
        "--transport", choices=["shm", "dds"], default="shm",
        help="how the buffers cross between the CPUs' processes: shared memory (one host, the default) or Cyclone DDS (any hosts)",
    )


def _run_build(args: argparse.Namespace) -> int:
    from rcsc.outputs import backend

    result = _check(args.path)
    if result.model is None or not result.ok:
        _report_to_stderr(result.diags)
        _write(sys.stderr, "error: no code is generated from a design with errors\n")
        return EXIT_FINDINGS
    if args.deny_warnings and result.diags.warnings:
        _report_to_stderr(result.diags)
        _write(sys.stderr, "error: no code is generated: warnings are denied\n")
        return EXIT_FINDINGS
    target = backend.get_target(args.target)(result.model, backend.BuildOptions(exclude_simulators=args.exclude_simulators, transport=args.transport))
    target.check(result.diags)
    if result.diags.has_errors():
        _report_to_stderr(result.diags)
        return EXIT_FINDINGS
    files = target.files()
    if os.path.exists(args.output) and not os.path.isdir(args.output):
        raise UsageError(f"`{args.output}` exists and is not a folder")
    try:
        res = backend.write_files(files, args.output, target.entry_files)
    except OSError as exc:
        raise UsageError(f"cannot write to `{args.output}`: {exc.strerror or exc}") from exc
    if res.recovered:
        _write(sys.stderr, f"note: {args.output}: {res.recovered}\n")
    if res.refused:
        names = "; ".join(res.refused)
        raise UsageError(
            f"not writing to `{args.output}`: {names} (a file rcsc did not generate has no `generated by rcsc` line, "
            "and rcsc follows no link it did not make); move it away or choose another folder. Nothing was written"
        )
    if result.diags.items:
        _report_to_stderr(result.diags)
    kept = f", kept {len(res.kept)} of yours ({', '.join(res.kept)})" if res.kept else ""
    _write(
        sys.stderr,
        f"wrote {len(res.written)} files, {len(res.unchanged)} unchanged{kept} in {args.output} ({args.target})\n",
    )
    return EXIT_OK


def _add_targets_arguments(p: argparse.ArgumentParser) -> None:
    del p  # no options


def _run_targets(args: argparse.Namespace) -> int:
    from rcsc.outputs import backend

    rows = [f"{t.name:<6} {t.summary}" for t in backend.targets()]
    _write(sys.stdout, "\n".join(rows) + "\n")
    return EXIT_OK


# ---------------------------------------------------------------------------
# rcsc fmt
# ---------------------------------------------------------------------------

def _add_fmt_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("paths", metavar="PATH", nargs="+", help="files, folders (searched for *.rcs) or glob patterns; `-` formats stdin to stdout")
    p.add_argument("--check", action="store_true", help="change nothing; exit with 1 if a file is not formatted")
    p.add_argument("--diff", action="store_true", help="change nothing; print a unified diff of what would change")
    p.add_argument("-q", "--quiet", action="store_true", help="no summary line")


def _run_fmt(args: argparse.Namespace) -> int:
    import stat

    from rcsc import config as cfg
    from rcsc.editor import fmt
    from rcsc.front import workspace

    if args.paths == ["-"]:
        return _fmt_stdin(args)
    expanded = workspace.expand(args.paths)
    for problem in expanded.problems:
        _error(problem)
    explicit = {os.path.realpath(p) for p in args.paths if os.path.isfile(p)}
    code = EXIT_USAGE if expanded.problems else EXIT_OK
    changed = unchanged = 0
    for path in expanded.files:
        if os.path.realpath(path) not in explicit:
            found = cfg.find(path)
            if found and cfg.load(found[0], found[1], Diagnostics()).excluded(path):
                continue
        try:
            text = safeio.read_text(path)
        except OSError as exc:
            _error(f"{path}: cannot read: {getattr(exc, 'strerror', None) or exc}")
            code = EXIT_USAGE
            continue
        formatted, diags = fmt.format_source(path, text)
        if formatted is None:
            _report_to_stderr(diags)
            code = max(code, EXIT_FINDINGS) if code != EXIT_USAGE else code
            continue
        if formatted == text:
            unchanged += 1
            continue
        if args.diff:
            _write(sys.stdout, _fmt_diff(path, text, formatted))
        if args.check or args.diff:
            changed += 1
            if args.check:
                _write(sys.stderr, f"would reformat {render.escape_controls(path)}\n")
                code = max(code, EXIT_FINDINGS) if code != EXIT_USAGE else code
            continue
        try:
            st = os.stat(path)
            _fmt_may_write(path, st)
            safeio.write_file(path, formatted.encode("utf-8"), may_replace=lambda _p: True, mode=stat.S_IMODE(st.st_mode))
        except OSError as exc:
            _error(f"cannot write `{render.escape_controls(path)}`: {exc.strerror or exc}")
            code = EXIT_USAGE
            continue
        changed += 1
    if not args.quiet:
        verb = "would be reformatted" if (args.check or args.diff) else "reformatted"
        _write(sys.stderr, f"{changed} file{'s' if changed != 1 else ''} {verb}, {unchanged} unchanged\n")
    return code


def _fmt_stdin(args: argparse.Namespace) -> int:
    """`rcsc fmt -`: standard input formatted to standard output; with
    `--check` nothing is printed and the exit code says whether the text
    would change, with `--diff` the diff is printed instead."""
    from rcsc.editor import fmt

    raw = sys.stdin.buffer.read() if hasattr(sys.stdin, "buffer") else sys.stdin.read().encode("utf-8", "surrogateescape")
    try:
        text = safeio.decode_text(raw)
    except safeio.InputError as exc:
        _error(f"<stdin>: cannot read: {exc}")
        return EXIT_USAGE
    formatted, diags = fmt.format_source("<stdin>", text)
    if formatted is None:
        _report_to_stderr(diags)
        return EXIT_FINDINGS
    if not (args.check or args.diff):
        _write(sys.stdout, formatted)
        return EXIT_OK
    if formatted == text:
        return EXIT_OK
    if args.diff:
        _write(sys.stdout, _fmt_diff("<stdin>", text, formatted))
    if args.check:
        _write(sys.stderr, "would reformat <stdin>\n")
        return EXIT_FINDINGS
    return EXIT_OK


def _fmt_diff(path: str, text: str, formatted: str) -> str:
    import difflib

    names = (path, path) if os.path.isabs(path) or path == "<stdin>" else (f"a/{path}", f"b/{path}")
    diff = difflib.unified_diff(text.splitlines(keepends=True), formatted.splitlines(keepends=True), *names)
    return render.escape_controls("".join(diff))


def _fmt_may_write(path: str, st: os.stat_result) -> None:
    """Refuse to format a file its owner made read-only, or one with other
    hard links: the new text is written beside it and renamed over it (so
    that it is never half written), which would ignore the one (root may
    rename over anything) and separate it from the others."""
    import stat

    if not os.access(path, os.W_OK) or (st.st_uid == os.geteuid() and not st.st_mode & stat.S_IWUSR):
        raise PermissionError(f"it is read-only (mode {stat.S_IMODE(st.st_mode):o}); not reformatted")
    if st.st_nlink > 1:
        raise FileExistsError(f"it has {st.st_nlink} hard links, which replacing it would separate; not reformatted")


# ---------------------------------------------------------------------------
# rcsc lsp
# ---------------------------------------------------------------------------

def _add_lsp_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--stdio", action="store_true", help="talk over stdin/stdout (the default and only transport)")


def _run_lsp(args: argparse.Namespace) -> int:
    try:
        from rcsc.editor import lsp
    except ImportError as exc:
        raise UsageError(f"the language server needs pygls: pip install 'rcsc[lsp]' ({exc})") from exc
    return lsp.main()


# ---------------------------------------------------------------------------
# rcsc daemon
# ---------------------------------------------------------------------------

def _add_daemon_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("action", choices=("status", "stop", "serve"),
                   help="status: is one running; stop: make it exit; serve: be the daemon (what `rcsc check --daemon` starts)")
    p.add_argument("--socket", metavar="PATH", help=argparse.SUPPRESS)


def _run_daemon(args: argparse.Namespace) -> int:
    from rcsc import daemon

    try:
        if args.action == "serve":
            return daemon.serve(args.socket or daemon.socket_path())
        if args.action == "stop":
            _write(sys.stdout, "stopped the check daemon\n" if daemon.stop() else "no check daemon was running\n")
            return EXIT_OK
        found = daemon.status()
    except (daemon.DaemonError, OSError) as exc:
        raise UsageError(str(exc)) from exc
    if found is None:
        _write(sys.stdout, f"no check daemon is running (it would listen on {daemon.socket_path()})\n")
        return EXIT_OK
    _write(sys.stdout, f"the check daemon runs as process {found.get('pid')} on {found.get('socket')}: {found.get('calls')} checks "
                       f"answered, exits after {found.get('idle_s'):g} s without one\n")
    return EXIT_OK


# ---------------------------------------------------------------------------
# rcsc completion
# ---------------------------------------------------------------------------

def _add_completion_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("shell", choices=("bash", "zsh", "fish"), help="the shell to write the script for")


def _run_completion(args: argparse.Namespace) -> int:
    from rcsc.editor import completion

    _write(sys.stdout, completion.script(args.shell, build_parser()))
    return EXIT_OK


# ---------------------------------------------------------------------------
# the command table and the parser
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Command:
    help: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]


COMMANDS: dict[str, Command] = {
    "check": Command("check designs (files, folders, globs) and report findings", _add_check_arguments, _run_check),
    "explain": Command("explain a diagnostic code", _add_explain_arguments, _run_explain),
    "sim": Command("run a scenario in the reference simulator and write its trace", _add_sim_arguments, _run_sim),
    "events": Command("compile a scenario into the event file a compiled Main Program reads", _add_events_arguments, _run_events),
    "console": Command("operate a running Main Program: commands, live status, pause and step (docs/console.md)", _add_console_arguments, _run_console),
    "test": Command("run scenarios with expectations, like a test runner", _add_test_arguments, _run_test),
    "budget": Command("print each CPU's timing table (budgets against the heartbeat)", _add_budget_arguments, _run_budget),
    "graph": Command("draw the hierarchy, the data flow or a plan (DOT, SVG, PNG, Mermaid)", _add_graph_arguments, _run_graph),
    "doc": Command("write a one-page HTML description of a design", _add_doc_arguments, _run_doc),
    "build": Command("generate code for a target (`rcsc targets`) after every check passes", _add_build_arguments, _run_build),
    "targets": Command("list the code-generation targets", _add_targets_arguments, _run_targets),
    "fmt": Command("format design files: state tables in aligned columns, comments kept", _add_fmt_arguments, _run_fmt),
    "daemon": Command("the check daemon that answers `rcsc check --daemon` (status, stop)", _add_daemon_arguments, _run_daemon),
    "lsp": Command("run the language server on stdin/stdout (needs `pip install 'rcsc[lsp]'`)", _add_lsp_arguments, _run_lsp),
    "completion": Command("print a shell completion script (bash, zsh or fish)", _add_completion_arguments, _run_completion),
}


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The argument parser; with `only`, just that command's options are added.

    Adding a command's options may import what the command uses (graph views,
    build targets), so a run builds the options of its own command alone:
    `rcsc --version` and `rcsc explain` then load neither the checks nor z3,
    networkx or jinja2.  `rcsc completion` builds the whole tree.
    """
    parser = argparse.ArgumentParser(
        prog="rcsc",
        description="A compiler and checker for NIST RCS real-time control designs.",
        epilog="exit codes: 0 clean, 1 errors found, 2 usage or I/O error",
        allow_abbrev=False,
    )
    parser.add_argument("-V", "--version", action="version", version=f"rcsc {rcsc.__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, command in COMMANDS.items():
        p = sub.add_parser(name, help=command.help, description=command.help, allow_abbrev=False)
        if only is None or name == only:
            command.add_arguments(p)
        p.set_defaults(run=command.run)
    return parser


def _command_in(argv: list[str]) -> str | None:
    """The command word of `argv` (its first word that is not an option)."""
    for word in argv:
        if word == "--":
            return None
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def _silence_stdout() -> None:
    """After a broken pipe, point stdout at /dev/null so that the interpreter's
    final flush does not raise again on the way out."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        return  # stdout is not a real file (tests capture it): nothing to flush


# The arguments of the running command (`rcsc check --daemon` hands them on).
_ARGV: list[str] = []


# The arguments of every command that name files it reads (a list for
# `paths` and the repeatable `--measured`): no report of the command may
# replace one of them (`safeio.command_files`).
_INPUT_ARGUMENTS = ("path", "paths", "scenario", "externs", "config", "measured", "callgrind")


def _main(argv: list[str] | None) -> int:
    global _ARGV
    if argv is None:
        argv = sys.argv[1:]
    _ARGV = list(argv)
    command = _command_in(argv)
    # Without a known command word argparse only prints usage or the version.
    args = build_parser(command or "").parse_args(argv)
    # The files named as inputs are inputs even where the command stops
    # before reading them (`rcsc test s.scn --junit s.scn` with no design
    # beside the scenario): no report may replace them.  Folders and
    # patterns are claimed file by file as they are read.
    named: list = []
    for key in _INPUT_ARGUMENTS:
        value = getattr(args, key, None)
        named += value if isinstance(value, list) else [value]
    safeio.claim_inputs(p for p in named if isinstance(p, str) and p != "-")
    code = args.run(args)
    if not sys.stdout.closed:  # the language server closes it on `exit`
        sys.stdout.flush()  # a broken pipe surfaces here, inside the handlers
    return code


def entry() -> None:
    """The `rcsc` command and `python -m rcsc`: `main`, then exit.

    After Ctrl-C the process ends at once, without running finalizers: a
    library interrupted in the middle of building an object (z3 creating a
    context, say) may otherwise print its own traceback while Python shuts
    down, after rcsc has reported the interruption."""
    code = main()
    if code == EXIT_INTERRUPTED:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                continue
        os._exit(code)
    sys.exit(code)


def main(argv: list[str] | None = None) -> int:
    """Run rcsc with `argv` (default: sys.argv[1:]) and return the exit code."""
    try:
        with safeio.command_files():
            return _main(argv)
    except SystemExit as exc:
        # argparse exits for --help/--version (0) and usage errors (2), having
        # printed its message; return the code so that main() always returns.
        if exc.code is None:
            return EXIT_OK
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    except UsageError as exc:
        _error(str(exc))
        return EXIT_USAGE
    except KeyboardInterrupt:
        # An interrupt can land inside a library's constructor (z3's Context);
        # the half-built object's finalizer then fails at exit, printing
        # "Exception ignored ... Traceback".  After Ctrl-C that is noise.
        sys.unraisablehook = lambda _unraisable: None
        _write(sys.stderr, "\nerror: interrupted\n")
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        # The reader went away (`rcsc check ... | head`); the report is lost.
        _silence_stdout()
        return EXIT_USAGE
    except Exception as exc:  # noqa: BLE001 - the promise is "never a traceback"
        _error(f"internal compiler error: {type(exc).__name__}: {exc}")
        _write(sys.stderr, "note: this is a bug in rcsc; please report it with the input that caused it\n")
        if os.environ.get("RCSC_BACKTRACE"):
            import traceback

            traceback.print_exc(file=sys.stderr)
        return EXIT_USAGE
