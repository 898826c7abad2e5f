"""`rcsc doc`: a design as one static HTML page (the paper's first objective,
human understanding of the design, section 2.1).

The page shows the command hierarchy and the Global Memory data flow
(pictures from `rcsc.outputs.graph`), the CPUs, and per controller its level,
budget, CPU, verbs with parameters, reads and writes, status values and
fields, and each plan as a state table laid out like the paper's Appendix C
(Event, Current State, Next State, Job list) beside its state graph.  The
checker's findings stand next to the rules they concern; findings that
concern no rule are listed with their plan, their controller or the design.

The page needs no server and fetches nothing: CSS and SVG are inline, and
the only script records JavaScript errors into the page (the tests read
them back from a headless browser).  Without Graphviz the page still has
every table, with a note in place of the pictures.

The logic is here, in Python: it builds plain view objects (`Page`,
`ControllerView`, `PlanView`, ...) that the Jinja2 template in
rcsc/templates/doc.html.j2 only lays out (autoescaped, strict undefined).
The output is deterministic: declaration order everywhere, no timestamps,
no absolute paths.
"""

from __future__ import annotations

import os
import textwrap
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import jinja2
from markupsafe import Markup

from rcsc.outputs import graph, safeio
from rcsc.semantics import model as m
from rcsc.checks.frames import fmt_ns
from rcsc.diagnostics import Diagnostic, Severity
from rcsc.semantics.types import ArrayType, DurationType, EnumType, RecordType, Type

TEMPLATES = Path(__file__).resolve().parent / "templates"
INDEX = "index.html"


# ---------------------------------------------------------------------------
# view objects: everything the template shows, already formatted
# ---------------------------------------------------------------------------

Text = list[tuple[str, bool]]  # (text, is code): a message with its `quoted` names


@dataclass
class FindingView:
    code: str
    severity: str  # error | warning | note
    message: Text
    where: str  # file:line:col, file name only
    notes: list[Text]


@dataclass
class Picture:
    """An inline SVG, or the reason there is none."""

    svg: Markup | None
    note: str = ""


@dataclass
class RuleRow:
    label: str
    event: str
    otherwise: bool
    state: str
    next: str
    next_kind: str  # named | same | done | error | new
    jobs: list[str]
    findings: list[FindingView]
    doc: str = ""  # the rule's `///` comment


@dataclass
class PlanView:
    anchor: str
    controller: str
    verb: str
    modifiers: list[str]  # continuous, ordered
    rows: list[RuleRow]
    picture: Picture
    findings: list[FindingView]  # about the plan, not one rule
    doc: str = ""

    @property
    def flagged(self) -> int:
        return sum(1 for r in self.rows if r.findings) + (1 if self.findings else 0)


@dataclass
class Fact:
    """One `name: value` line; `links` are (text, anchor) pairs shown after the value."""

    name: str
    value: str
    links: list[tuple[str, str]] = field(default_factory=list)


@dataclass
class VerbView:
    signature: str
    plan_anchor: str | None
    doc: str = ""


@dataclass
class ControllerView:
    anchor: str
    name: str
    simulator: bool
    facts: list[Fact]
    verbs: list[VerbView]
    statuses: list[str]
    status_fields: list[str]
    locals: list[str]
    pre: list[str]
    post: list[str]
    plans: list[PlanView]
    findings: list[FindingView]
    doc: str = ""
    status_field_docs: list[str] = field(default_factory=list)  # one per status field ("" for none)
    local_docs: list[str] = field(default_factory=list)


@dataclass
class GmRow:
    anchor: str
    name: str
    type: str
    init: str
    writers: list[tuple[str, str]]  # (name, anchor)
    readers: list[tuple[str, str]]
    doc: str = ""


@dataclass
class CpuRow:
    name: str
    heartbeat: str
    overhead: str
    schedule: list[tuple[str, str]]
    load: str  # budgets + overhead against the heartbeat


@dataclass
class Page:
    banner: str
    design: str
    summary: list[str]
    hierarchy: Picture
    dataflow: Picture
    gm: list[GmRow]
    cpus: list[CpuRow]
    controllers: list[ControllerView]
    findings: list[FindingView]  # about the design, not one controller
    counts: dict[str, int]
    graphviz_note: str


# ---------------------------------------------------------------------------
# formatting values and declarations
# ---------------------------------------------------------------------------

def format_value(value: m.Value | None, t: Type | None) -> str:
    """A value as it would be written in the language."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int) and isinstance(t, DurationType):
        return fmt_ns(value)
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return f"{t.name}.{value}" if isinstance(t, EnumType) else value
    if isinstance(value, dict):
        types = dict(t.fields) if isinstance(t, RecordType) else {}
        inner = ", ".join(f"{k} = {format_value(v, types.get(k))}" for k, v in value.items())
        return f"{t.name if t else ''}({inner})"
    if isinstance(value, list):
        elem = t.elem if isinstance(t, ArrayType) else None
        return "[" + ", ".join(format_value(v, elem) for v in value) + "]"
    return str(value)


def format_var(v: m.Var) -> str:
    text = f"{v.name}: {v.type}"
    if v.range is not None:
        text += f" in {format_value(v.range.lo, v.type)}..{format_value(v.range.hi, v.type)}"
    if v.init is not None:
        text += f" = {format_value(v.init, v.type)}"
    return text


def verb_signature(verb: m.Verb) -> str:
    if not verb.params:
        return verb.name
    return f"{verb.name}(" + ", ".join(format_var(p) for p in verb.params) + ")"


def statement_text(stmt: m.Stmt) -> str:
    """A statement of a `pre` or `post` block as written, lines and comments
    kept, indentation relative to its first line."""
    span = stmt.span
    if span is None or span.end <= span.start:
        return "?"
    before = span.file.line_text(span.line)[: span.col - 1]
    indent = "".join(ch if ch == "\t" else " " for ch in before)
    return textwrap.dedent((indent + span.text).expandtabs(4)).strip("\n")


def controller_anchor(name: str) -> str:
    return f"ctl-{name}"


def plan_anchor(controller: str, verb: str) -> str:
    return f"plan-{controller}-{verb}"


def gm_anchor(name: str) -> str:
    return f"gm-{name}"


# ---------------------------------------------------------------------------
# findings: each one goes to the innermost rule, plan or controller holding it
# ---------------------------------------------------------------------------

def code_parts(text: str) -> Text:
    """Split a message at its backticks: the `quoted` parts are code."""
    parts = text.split("`")
    if len(parts) % 2 == 0:  # an unpaired backtick: all plain text
        return [(text, False)]
    return [(part, i % 2 == 1) for i, part in enumerate(parts) if part]


def finding_view(d: Diagnostic) -> FindingView:
    where = ""
    if d.span is not None:
        where = f"{os.path.basename(d.span.file.path)}:{d.span.line}:{d.span.col}"
    notes = [code_parts(f"note: {n}") for n in d.notes] + [code_parts(f"help: {h}") for h in d.helps]
    return FindingView(d.code, d.severity.value, code_parts(d.message), where, notes)


def place_findings(design: m.Design, diags: list[Diagnostic]) -> dict[tuple, list[FindingView]]:
    """Findings keyed by ("rule", C, VERB, index), ("plan", C, VERB), ("ctl", C) or ("design",)."""
    placed: dict[tuple, list[FindingView]] = {}
    for d in diags:
        placed.setdefault(_home(design, d), []).append(finding_view(d))
    return placed


def _home(design: m.Design, d: Diagnostic) -> tuple:
    for c in design.controllers.values():
        if not graph.span_inside(d.span, c.span):
            continue
        for plan in c.plans.values():
            if graph.span_inside(d.span, plan.span):
                for rule in plan.rules:
                    if graph.span_inside(d.span, rule.span):
                        return ("rule", c.name, plan.verb, rule.index)
                return ("plan", c.name, plan.verb)
        return ("ctl", c.name)
    return ("design",)


# ---------------------------------------------------------------------------
# pictures
# ---------------------------------------------------------------------------

class Pictures:
    """Collects the page's graphs, then renders them all with Graphviz,
    several at a time; each `Picture` handed out is filled in place."""

    def __init__(self) -> None:
        self.available = graph.dot_available()
        self.jobs: list[tuple[Picture, str, str]] = []  # (picture, id prefix, dot text)

    def add(self, prefix: str, g: graph.Graph) -> Picture:
        picture = Picture(None, "not rendered")
        self.jobs.append((picture, prefix, graph.to_dot(g)))
        return picture

    def render_all(self) -> None:
        if not self.available:
            for picture, _, _ in self.jobs:
                picture.note = "no picture: Graphviz `dot` is not installed"
            return
        with ThreadPoolExecutor(max_workers=min(8, os.cpu_count() or 1)) as pool:
            list(pool.map(self._render_one, self.jobs))

    @staticmethod
    def _render_one(job: tuple[Picture, str, str]) -> None:
        picture, prefix, dot_text = job
        try:
            picture.svg = Markup(graph.inline_svg(graph.render(dot_text, "svg"), prefix))
            picture.note = ""
        except graph.GraphError as exc:
            picture.note = f"no picture: {exc}"


# ---------------------------------------------------------------------------
# building the page
# ---------------------------------------------------------------------------

def _rule_row(rule: m.Rule, findings: list[FindingView]) -> RuleRow:
    return RuleRow(
        label=rule.label,
        event=graph.rule_event(rule),
        otherwise=rule.otherwise,
        state=str(rule.state),
        next=graph.source_text(rule.next.span, str(rule.next)),
        next_kind=rule.next.kind,
        jobs=graph.rule_jobs(rule),
        findings=findings,
        doc=rule.doc,
    )


def _plan_view(c: m.Controller, plan: m.Plan, placed: dict, pictures: Pictures, diags: list[Diagnostic]) -> PlanView:
    rows = [_rule_row(r, placed.get(("rule", c.name, plan.verb, r.index), [])) for r in plan.rules]
    anchor = plan_anchor(c.name, plan.verb)
    # Compact edge labels (the rule label only): the table beside the picture
    # gives each rule's condition, as in the paper's Appendix C.
    picture = pictures.add(anchor, graph.plan_graph(c, plan, diags, compact=True))
    findings = placed.get(("plan", c.name, plan.verb), [])
    modifiers = [word for word, on in (("continuous", plan.continuous), ("ordered", getattr(plan, "ordered", False))) if on]
    return PlanView(anchor, c.name, plan.verb, modifiers, rows, picture, findings, plan.doc)


def _links(names: list[str], anchor: Callable[[str], str]) -> list[tuple[str, str]]:
    return [(n, anchor(n)) for n in dict.fromkeys(names)]


def _controller_facts(design: m.Design, c: m.Controller, cpu: str | None) -> list[Fact]:
    facts = [
        Fact("kind", "simulator (plant model)" if c.simulator else "controller"),
        Fact("level", str(c.level)),
        Fact("budget", fmt_ns(c.budget_ns)),
        Fact("cpu", cpu or "(not scheduled)"),
    ]
    if c.divider > 1:
        facts.append(Fact("period", f"{fmt_ns(c.period_ns)} (every {c.divider} cycles of its CPU)"))
    if c.supervisor:
        facts.append(Fact("supervisor", "", _links([c.supervisor], controller_anchor)))
    elif not c.simulator:
        facts.append(Fact("supervisor", "none: takes the operator's commands"))
    subs = [u.name for u in c.subordinates if u.name in design.controllers]
    if subs:
        facts.append(Fact("subordinates", "", _links(subs, controller_anchor)))
    reads = [u.name for u in c.reads]
    writes = [u.name for u in c.writes]
    if reads:
        facts.append(Fact("reads", "", _links(reads, gm_anchor)))
    if writes:
        facts.append(Fact("writes", "", _links(writes, gm_anchor)))
    return facts


def _controller_view(design: m.Design, c: m.Controller, cpu: str | None, placed: dict, pictures: Pictures, diags: list[Diagnostic]) -> ControllerView:
    return ControllerView(
        anchor=controller_anchor(c.name),
        name=c.name,
        simulator=c.simulator,
        facts=_controller_facts(design, c, cpu),
        verbs=[VerbView(verb_signature(v), plan_anchor(c.name, v.name) if v.name in c.plans else None, v.doc) for v in c.verbs.values()],
        statuses=[f"{name} = {number}" for name, number in c.statuses.items()],
        status_fields=[format_var(v) for v in c.status_fields.values()],
        locals=[format_var(v) for v in c.locals.values()],
        pre=[statement_text(s) for s in c.pre],
        post=[statement_text(s) for s in c.post],
        plans=[_plan_view(c, plan, placed, pictures, diags) for plan in c.plans.values()],
        findings=placed.get(("ctl", c.name), []),
        doc=c.doc,
        status_field_docs=[v.doc for v in c.status_fields.values()],
        local_docs=[v.doc for v in c.locals.values()],
    )


def _gm_rows(design: m.Design) -> list[GmRow]:
    rows = []
    for var in design.gm.values():
        writers = [c.name for c in design.controllers.values() if any(u.name == var.name for u in c.writes)]
        readers = [c.name for c in design.controllers.values() if any(u.name == var.name for u in c.reads)]
        links = _links(writers, controller_anchor)
        if var.from_env:
            links = [("environment", "")] + links
        reader_links = _links(readers, controller_anchor)
        if var.to_env:
            reader_links = reader_links + [("environment", "")]
        rows.append(GmRow(gm_anchor(var.name), var.name, str(var.type), format_value(var.init, var.type), links, reader_links, var.doc))
    return rows


def _cpu_rows(design: m.Design) -> list[CpuRow]:
    rows = []
    for cpu in design.cpus.values():
        names = [u.name for u in cpu.schedule if u.name in design.controllers]
        # Every controller steps in cycle 1 whatever its period: the heaviest frame.
        total = sum(design.controllers[n].budget_ns for n in dict.fromkeys(names)) + cpu.overhead_ns
        share = f" ({100.0 * total / cpu.heartbeat_ns:.1f} % of the heartbeat)" if cpu.heartbeat_ns > 0 else ""
        rows.append(CpuRow(cpu.name, fmt_ns(cpu.heartbeat_ns), fmt_ns(cpu.overhead_ns), _links(names, controller_anchor), fmt_ns(total) + share))
    return rows


def _summary(design: m.Design) -> list[str]:
    ctrls = list(design.controllers.values())
    sims = sum(1 for c in ctrls if c.simulator)
    plans = sum(len(c.plans) for c in ctrls)
    rules = sum(len(p.rules) for c in ctrls for p in c.plans.values())
    return [
        f"{len(ctrls) - sims} controllers, {sims} simulators",
        f"{plans} plans, {rules} rules",
        f"{len(design.gm)} Global Memory variables",
        f"{len(design.cpus)} CPU" + ("s" if len(design.cpus) != 1 else ""),
    ]


def build_page(design: m.Design, diags: list[Diagnostic]) -> Page:
    """The whole page's view objects, pictures rendered."""
    diags = sorted(diags, key=Diagnostic.sort_key)
    placed = place_findings(design, diags)
    pictures = Pictures()
    hierarchy = pictures.add("hierarchy", graph.hierarchy_graph(design))
    dataflow = pictures.add("dataflow", graph.dataflow_graph(design))
    cpus = graph.cpu_of(design)
    controllers = [_controller_view(design, c, cpus.get(c.name), placed, pictures, diags) for c in design.controllers.values()]
    pictures.render_all()
    counts = {sev.value: sum(1 for d in diags if d.severity is sev) for sev in Severity}
    note = "" if pictures.available else (
        "Graphviz `dot` is not installed, so this page has no pictures; install it "
        "(Debian/Ubuntu: apt-get install graphviz) and run rcsc doc again."
    )
    return Page(
        banner=graph.BANNER,
        design=design.name,
        summary=_summary(design),
        hierarchy=hierarchy,
        dataflow=dataflow,
        gm=_gm_rows(design),
        cpus=_cpu_rows(design),
        controllers=controllers,
        findings=placed.get(("design",), []),
        counts=counts,
        graphviz_note=note,
    )


def _environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES)),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )


def render_html(design: m.Design, diags: list[Diagnostic]) -> str:
    """The page as HTML text."""
    return _environment().get_template("doc.html.j2").render(page=build_page(design, diags))


class NotOurs(OSError):
    """The target exists and was not written by rcsc: it is never overwritten."""


def _ours(path: str) -> bool:
    with open(path, "rb") as fh:
        return graph.BANNER.encode() in fh.read(1024)


def write_site(design: m.Design, diags: list[Diagnostic], out_dir: str) -> Path:
    """Write DIR/index.html (creating DIR) and return its path; OSError on failure.

    An existing index.html is replaced only if it is a regular file carrying
    rcsc's "generated" banner: a page a person wrote, or a symbolic link, is
    never overwritten or followed (NotOurs).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / INDEX
    try:
        safeio.write_file(str(path), render_html(design, diags).encode("utf-8"), may_replace=_ours)
    except FileExistsError as exc:
        raise NotOurs(str(exc)) from exc
    return path
