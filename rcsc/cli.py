"""The `rcsc` command line (also `python -m rcsc`).

Each subcommand is one entry of `COMMANDS`: a function that adds its arguments
to its own sub-parser and a function that runs it and returns the exit code.
A new command (sim, test, build, graph, ...) is two functions and one entry.

Contract with CI (DESIGN.md section 6):

- exit codes: 0 clean, 1 findings at error level (or any warning with
  `--deny-warnings`), 2 usage, I/O or internal error, 130 interrupted;
- stdout carries the report and nothing else; messages go to stderr;
- no input, however broken, ends in a Python traceback (set RCSC_BACKTRACE=1
  to see one for an internal error while debugging rcsc itself).
"""

from __future__ import annotations

import argparse
import os
import sys
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType

import rcsc
from rcsc import codes
from rcsc.diagnostics import Diagnostics

EXIT_OK = 0
EXIT_FINDINGS = 1
EXIT_USAGE = 2  # also I/O errors and internal errors: DESIGN allows 0, 1, 2 only
EXIT_INTERRUPTED = 130  # the shell convention for SIGINT (128 + 2)

FORMATS = ("human", "short", "json", "sarif")


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
        with open(output, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(text)
    except OSError as exc:
        raise UsageError(f"cannot write `{output}`: {exc.strerror or exc}") from exc


def _use_color(choice: str, output: str | None) -> bool:
    if choice == "always":
        return True
    if choice == "never" or output is not None:
        return False
    # auto: only a terminal gets colour, and https://no-color.org is honoured.
    if os.environ.get("NO_COLOR") or os.environ.get("TERM") == "dumb":
        return False
    isatty = getattr(sys.stdout, "isatty", None)
    return bool(isatty and isatty())


def _render(diags: Diagnostics, fmt: str, color: bool) -> str:
    from rcsc import render

    if fmt == "human":
        return render.render_human(diags, color=color)
    if fmt == "short":
        return render.render_short(diags)
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


def _check(path: str):
    """Run the front end on `path`; an unreadable root file is a usage error (exit 2)."""
    driver = _load_driver()
    try:
        return driver.check_path(path)
    except driver.InputError as exc:
        raise UsageError(str(exc)) from exc


def _add_check_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", metavar="PATH", help="the design's root file (it begins with `design NAME`)")
    _add_report_arguments(p)


def _add_report_arguments(p: argparse.ArgumentParser) -> None:
    """Options of every command that reports findings (check, and later build)."""
    p.add_argument("--format", choices=FORMATS, default="human", help="report format (default: human)")
    p.add_argument("--deny-warnings", action="store_true", help="exit with 1 on warnings too")
    p.add_argument(
        "--color", choices=("auto", "always", "never"), default="auto",
        help="colour the human report (default: auto, a terminal without NO_COLOR)",
    )
    p.add_argument("-o", "--output", metavar="FILE", help="write the report to FILE instead of stdout")


def _run_check(args: argparse.Namespace) -> int:
    result = _check(args.path)
    color = args.format == "human" and _use_color(args.color, args.output)
    _emit_report(_render(result.diags, args.format, color), args.output)
    return _exit_code(result.diags, args.deny_warnings)


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

    isatty = getattr(sys.stderr, "isatty", None)
    color = bool(isatty and isatty()) and not os.environ.get("NO_COLOR")
    _write(sys.stderr, render.render_human(diags, color=color))


def _add_sim_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", metavar="DESIGN", help="the design's root file")
    p.add_argument("--scenario", metavar="FILE", required=True, help="the scenario to run (see docs/scenarios.md)")
    p.add_argument("--trace-format", choices=TRACE_FORMATS, default=None, help="trace format (default: from the -o suffix, else jsonl)")
    p.add_argument("-o", "--output", metavar="FILE", help="write the trace to FILE instead of stdout")


def _run_sim(args: argparse.Namespace) -> int:
    from rcsc import trace
    from rcsc.runner import run_scenario
    from rcsc.scenario import text_to_scenario
    from rcsc.source import SourceFile

    result = _check(args.path)
    if not result.ok or result.model is None:
        _report_to_stderr(result.diags)
        return EXIT_FINDINGS
    design = result.model
    try:
        with open(args.scenario, encoding="utf-8") as fh:
            text = fh.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"{args.scenario}: cannot read: {getattr(exc, 'strerror', None) or exc}") from exc
    diags = Diagnostics()
    sc = text_to_scenario(SourceFile(args.scenario, text), design, diags)
    if sc is None:
        _report_to_stderr(diags)
        return EXIT_FINDINGS
    run = run_scenario(design, sc)
    fmt = args.trace_format
    if fmt is None:
        suffix = (args.output or "").rsplit(".", 1)[-1].lower()
        fmt = suffix if suffix in TRACE_FORMATS else "jsonl"
    # Several CPUs: the JSON-lines trace has one line per CPU cycle; CSV and
    # VCD show the observer's view (what expectations see) per base tick.
    if fmt == "jsonl":
        text = trace.cycles_to_jsonl(design, run.cpu_cycles) if len(design.cpus) > 1 else trace.to_jsonl(design, run.trace_snapshots)
    elif fmt == "csv":
        text = trace.to_csv(design, run.snapshots)
    else:
        text = trace.to_vcd(design, run.snapshots, design.base_tick_ns)
    _emit_report(text, args.output)
    if not run.passed:
        from rcsc.testrun import failure_text

        _write(sys.stderr, failure_text(run) + "\n")
        return EXIT_FINDINGS
    return EXIT_OK


# ---------------------------------------------------------------------------
# rcsc test
# ---------------------------------------------------------------------------

def _add_test_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("paths", metavar="PATH", nargs="*", default=["."], help="design files, scenario files or folders (default: .)")
    p.add_argument("--junit", metavar="FILE", help="also write a JUnit XML report to FILE")


def _run_test(args: argparse.Namespace) -> int:
    from rcsc import testrun

    plan, problems = testrun.discover(args.paths)
    for problem in problems:
        _error(problem)
    report = testrun.Report()
    cache: dict = {}
    for design, scenarios in plan:
        if not scenarios:
            continue
        for scn in scenarios:
            outcome = testrun.run_one(design, scn, cache)
            report.outcomes.append(outcome)
            word = "PASS" if outcome.passed else "FAIL"
            unit = "ticks" if outcome.result is not None and outcome.result.multi_cpu else "cycles"
            extra = f" ({outcome.cycles} {unit}, {outcome.seconds:.2f} s)" if outcome.cycles else ""
            _write(sys.stdout, f"{word} {scn}{extra}\n")
            if not outcome.passed:
                if outcome.message:
                    _write(sys.stdout, "".join(f"    {line}\n" for line in outcome.message.splitlines()))
                if outcome.diags is not None:
                    from rcsc import render

                    _write(sys.stdout, render.render_short(outcome.diags))
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


def _run_budget(args: argparse.Namespace) -> int:
    from rcsc.checks.frames import format_budget_table

    result = _check(args.path)
    if result.model is None:
        _report_to_stderr(result.diags)
        return EXIT_FINDINGS
    _write(sys.stdout, format_budget_table(result.model))
    if result.diags.items:
        _report_to_stderr(result.diags)
    return _exit_code(result.diags, False)


# ---------------------------------------------------------------------------
# rcsc graph
# ---------------------------------------------------------------------------

def _add_graph_arguments(p: argparse.ArgumentParser) -> None:
    from rcsc.graph import FORMATS, VIEWS

    p.add_argument("path", metavar="DESIGN", help="the design's root file")
    p.add_argument("--view", choices=VIEWS, default=None, help="what to draw (default: plan with --plan, else hierarchy)")
    p.add_argument("--controller", metavar="C", help="the controller of the plan view")
    p.add_argument("--plan", metavar="VERB", help="the plan (verb) of the plan view")
    p.add_argument("--compact", action="store_true", help="plan view: label edges with the rule label only (Figure 13 style)")
    p.add_argument("--format", choices=FORMATS, default=None, help="output format (default: from the -o suffix, else dot); svg and png need Graphviz")
    p.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of stdout")


def _run_graph(args: argparse.Namespace) -> int:
    from rcsc import graph

    result = _check(args.path)
    if result.model is None:
        _report_to_stderr(result.diags)
        return EXIT_FINDINGS
    fmt = graph.format_for(args.format, args.output)
    if fmt == "png" and args.output is None and getattr(sys.stdout, "isatty", lambda: False)():
        raise UsageError("PNG is binary: give `-o FILE.png` (or pipe stdout to a file)")
    view = args.view or ("plan" if args.plan or args.controller else "hierarchy")
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
            with open(args.output, "wb") as fh:
                fh.write(data)
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
    from rcsc import doc, graph

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
    from rcsc import backend

    p.add_argument("path", metavar="DESIGN", help="the design's root file")
    p.add_argument("--target", required=True, choices=sorted(t.name for t in backend.targets()), help="the output language (`rcsc targets`)")
    p.add_argument("-o", "--output", metavar="DIR", required=True, help="the folder to write to (created if missing)")
    p.add_argument(
        "--exclude-simulators", action="store_true",
        help="deployment build: leave the simulators out and call I/O hooks (a file of yours) instead",
    )
    p.add_argument("--deny-warnings", action="store_true", help="refuse to build on warnings too")


def _run_build(args: argparse.Namespace) -> int:
    from rcsc import backend

    result = _check(args.path)
    if result.model is None or not result.ok:
        _report_to_stderr(result.diags)
        _write(sys.stderr, "error: no code is generated from a design with errors\n")
        return EXIT_FINDINGS
    if args.deny_warnings and result.diags.warnings:
        _report_to_stderr(result.diags)
        _write(sys.stderr, "error: no code is generated: warnings are denied\n")
        return EXIT_FINDINGS
    target = backend.get_target(args.target)(result.model, backend.BuildOptions(exclude_simulators=args.exclude_simulators))
    target.check(result.diags)
    if result.diags.has_errors():
        _report_to_stderr(result.diags)
        return EXIT_FINDINGS
    files = target.files()
    if os.path.exists(args.output) and not os.path.isdir(args.output):
        raise UsageError(f"`{args.output}` exists and is not a folder")
    try:
        res = backend.write_files(files, args.output)
    except OSError as exc:
        raise UsageError(f"cannot write to `{args.output}`: {exc.strerror or exc}") from exc
    if res.refused:
        names = ", ".join(res.refused)
        raise UsageError(
            f"not writing to `{args.output}`: {names} would replace a file that rcsc did not generate "
            "(it has no `generated by rcsc` line); move it away or choose another folder"
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
    from rcsc import backend

    rows = [f"{t.name:<6} {t.summary}" for t in backend.targets()]
    _write(sys.stdout, "\n".join(rows) + "\n")
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
    "check": Command("check a design and report findings", _add_check_arguments, _run_check),
    "explain": Command("explain a diagnostic code", _add_explain_arguments, _run_explain),
    "sim": Command("run a scenario in the reference simulator and write its trace", _add_sim_arguments, _run_sim),
    "test": Command("run scenarios with expectations, like a test runner", _add_test_arguments, _run_test),
    "budget": Command("print each CPU's timing table (budgets against the heartbeat)", _add_budget_arguments, _run_budget),
    "graph": Command("draw the hierarchy, the data flow or a plan (DOT, SVG, PNG, Mermaid)", _add_graph_arguments, _run_graph),
    "doc": Command("write a one-page HTML description of a design", _add_doc_arguments, _run_doc),
    "build": Command("generate code for a target (`rcsc targets`) after every check passes", _add_build_arguments, _run_build),
    "targets": Command("list the code-generation targets", _add_targets_arguments, _run_targets),
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rcsc",
        description="A compiler and checker for NIST RCS real-time control designs.",
        epilog="exit codes: 0 clean, 1 errors found, 2 usage or I/O error",
        allow_abbrev=False,
    )
    parser.add_argument("--version", action="version", version=f"rcsc {rcsc.__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, command in COMMANDS.items():
        p = sub.add_parser(name, help=command.help, description=command.help, allow_abbrev=False)
        command.add_arguments(p)
        p.set_defaults(run=command.run)
    return parser


def _silence_stdout() -> None:
    """After a broken pipe, point stdout at /dev/null so that the interpreter's
    final flush does not raise again on the way out."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        return  # stdout is not a real file (tests capture it): nothing to flush


def _main(argv: list[str] | None) -> int:
    args = build_parser().parse_args(argv)
    code = args.run(args)
    sys.stdout.flush()  # a broken pipe surfaces here, inside the handlers
    return code


def main(argv: list[str] | None = None) -> int:
    """Run rcsc with `argv` (default: sys.argv[1:]) and return the exit code."""
    try:
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
            traceback.print_exc(file=sys.stderr)
        return EXIT_USAGE
