"""Project configuration: `rcsc.toml` or the `[tool.rcsc]` table of pyproject.toml.

The configuration is found by walking up from the checked file's folder: the
first folder holding an `rcsc.toml`, or a `pyproject.toml` with a
`[tool.rcsc]` table, wins (an `rcsc.toml` beats a pyproject.toml in the same
folder).  Keys (docs/configuration.md):

    select = ["W"]                  # warnings reported (codes or prefixes; default all)
    ignore = ["W0311"]              # warnings never reported
    severity = { W0403 = "error" }  # a warning made an error or a note
    exclude = ["generated/**"]      # files a folder search skips
    [per-file-ignores]              # path glob (relative to the config's folder) -> warnings
    "legacy/*.rcs" = ["W0514"]

Only warnings (W-codes) can be left out or have their severity changed: an
error means the design is wrong, and every command that uses the design (sim,
build) refuses it whatever a report shows.  A mistake in the configuration
(unknown key, wrong type, unknown code, TOML syntax) is an E0009 finding with
a span inside the TOML file, reported with the design's own findings.
"""

from __future__ import annotations

import fnmatch
import os
import re
from dataclasses import dataclass, field

from rcsc.codes import CODES
from rcsc.diagnostics import Diagnostic, Diagnostics, Severity
from rcsc.front.source import SourceFile, Span
from rcsc.outputs import safeio

CONFIG_NAME = "rcsc.toml"
PYPROJECT = "pyproject.toml"
KEYS = ("select", "ignore", "severity", "exclude", "per-file-ignores")
SEVERITIES = {"error": Severity.ERROR, "warning": Severity.WARNING, "note": Severity.NOTE}
_CODE_PREFIX = re.compile(r"[EW]\d{0,4}")


@dataclass
class Config:
    """The settings in force for the files under `root` (a folder)."""

    root: str = "."
    path: str | None = None  # the TOML file, None for the defaults
    select: list[str] | None = None
    ignore: list[str] = field(default_factory=list)
    severity: dict[str, Severity] = field(default_factory=dict)
    exclude: list[str] = field(default_factory=list)
    per_file_ignores: dict[str, list[str]] = field(default_factory=dict)

    def relative(self, path: str) -> str:
        """`path` relative to the configuration's folder, with `/` separators."""
        rel = os.path.relpath(os.path.abspath(path), os.path.abspath(self.root))
        return rel.replace(os.sep, "/")

    def excluded(self, path: str) -> bool:
        rel = self.relative(path)
        return any(fnmatch.fnmatchcase(rel, pat) for pat in self.exclude)

    def apply(self, diags: Diagnostics) -> Diagnostics:
        """The findings that this configuration reports, with their severities."""
        out = Diagnostics()
        for d in diags.items:
            kept = self.filter_one(d)
            if kept is not None:
                out.items.append(kept)
        return out

    def filter_one(self, d: Diagnostic) -> Diagnostic | None:
        if not d.code.startswith("W"):
            return d
        if self.select is not None and not _matches(d.code, self.select):
            return None
        if _matches(d.code, self.ignore):
            return None
        if d.span is not None and self.per_file_ignores:
            rel = self.relative(d.span.file.path)
            for pattern, codes in self.per_file_ignores.items():
                if fnmatch.fnmatchcase(rel, pattern) and _matches(d.code, codes):
                    return None
        if d.code in self.severity:
            d.severity = self.severity[d.code]
        return d


def _matches(code: str, patterns: list[str]) -> bool:
    return any(code.startswith(p) for p in patterns)


def find(start: str) -> tuple[str, bool] | None:
    """The configuration file that governs `start` (a file or folder), with
    whether it is a pyproject.toml; None when there is none."""
    folder = os.path.abspath(start)
    if not os.path.isdir(folder):
        folder = os.path.dirname(folder)
    while True:
        candidate = os.path.join(folder, CONFIG_NAME)
        if os.path.isfile(candidate):
            return candidate, False
        candidate = os.path.join(folder, PYPROJECT)
        if os.path.isfile(candidate) and _has_tool_table(candidate):
            return candidate, True
        parent = os.path.dirname(folder)
        if parent == folder:
            return None
        folder = parent


def _has_tool_table(path: str) -> bool:
    """Whether a pyproject.toml configures rcsc: a `tool.rcsc` key however
    TOML spells it (`[tool.rcsc]`, `[[tool.rcsc]]`, `rcsc.ignore = ...` under
    `[tool]`), which `load` then reads or reports (E0009).  A file that is not
    valid TOML counts when a line names the table, so that its mistake is
    reported rather than the file passed over."""
    import tomllib

    try:
        # A file of another encoding counts when it names the table: `load`
        # then reports where it is not UTF-8.
        text = safeio.decode_lossy(safeio.read_input(path))[0]
    except OSError:
        return False
    try:
        tool = tomllib.loads(text).get("tool")
    except tomllib.TOMLDecodeError:
        return re.search(r"^\s*\[+\s*tool\s*\.\s*rcsc\s*[\].]", text, re.M) is not None
    return isinstance(tool, dict) and "rcsc" in tool


def load_for(start: str, diags: Diagnostics, explicit: str | None = None) -> Config:
    """The configuration for `start` (found by walking up, or the file
    `explicit`); its mistakes are added to `diags`."""
    if explicit is not None:
        found: tuple[str, bool] | None = (explicit, os.path.basename(explicit) == PYPROJECT)
    else:
        found = find(start)
    if found is None:
        return Config()
    return load(found[0], found[1], diags)


def load(path: str, in_pyproject: bool, diags: Diagnostics) -> Config:
    import tomllib

    config = Config(root=os.path.dirname(os.path.abspath(path)) or ".", path=path)
    from rcsc.front.loader import InputError, read_source

    try:
        source, utf8 = read_source(path, diags)
    except (OSError, InputError) as exc:
        diags.add("E0009", None, f"cannot read the configuration `{path}`: {getattr(exc, 'strerror', None) or exc}")
        return config
    if not utf8:
        return config  # E0010 points at the byte
    try:
        doc = tomllib.loads(source.text)
    except tomllib.TOMLDecodeError as exc:
        diags.add("E0009", _error_span(source, str(exc)), f"the configuration is not valid TOML: {_strip_position(str(exc))}", "here")
        return config
    table: object = doc
    section = ""
    if in_pyproject:
        table = doc.get("tool", {}).get("rcsc", {})
        section = "tool.rcsc"
    if not isinstance(table, dict):
        diags.add("E0009", _key_span(source, section, ""), "`[tool.rcsc]` must be a table", "not a table")
        return config
    _read_table(table, config, source, section, diags)
    return config


def selects_no_warning(codes: list[str]) -> bool:
    """Whether a non-empty `select` names only error codes, and so would hide
    every warning without saying so (an empty one says "no warnings")."""
    return bool(codes) and all(c.upper().startswith("E") for c in codes)


def _read_table(table: dict, config: Config, source: SourceFile, section: str, diags: Diagnostics) -> None:
    def bad(key: str, message: str, label: str, sub: str = "") -> None:
        sec = f"{section}.{key}".strip(".") if sub else section
        diags.add("E0009", _key_span(source, sec, sub or key), message, label)

    for key, value in table.items():
        if key not in KEYS:
            d = diags.add("E0009", _key_span(source, section, key), f"unknown configuration key `{key}`", "unknown key")
            d.with_note("the keys are: " + ", ".join(KEYS))
            continue
        if key in ("select", "ignore", "exclude"):
            if not (isinstance(value, list) and all(isinstance(v, str) for v in value)):
                bad(key, f"`{key}` must be a list of strings", "not a list of strings")
                continue
            if key == "exclude":
                config.exclude = list(value)
                continue
            codes = _codes(value, key, source, section, diags)
            if key == "select" and selects_no_warning(codes):
                bad(key, "`select` names no warning: errors are always reported, and `select` chooses the warnings",
                    "only error codes")
                continue
            if key == "select":
                config.select = codes
            else:
                config.ignore = codes
        elif key == "severity":
            if not isinstance(value, dict):
                bad(key, "`severity` must be a table of CODE = \"error\" | \"warning\" | \"note\"", "not a table")
                continue
            for code, level in value.items():
                if code not in CODES:
                    bad(key, f"unknown diagnostic code `{code}`", "unknown code", code)
                elif not code.startswith("W"):
                    bad(key, f"the severity of error `{code}` cannot be changed", "an error stays an error", code)
                elif not isinstance(level, str):
                    bad(key, f"the severity of `{code}` must be a string: \"error\", \"warning\" or \"note\"", "not a string", code)
                elif level not in SEVERITIES:
                    bad(key, f"unknown severity `{level}` (use \"error\", \"warning\" or \"note\")", "unknown severity", code)
                else:
                    config.severity[code] = SEVERITIES[level]
        else:  # per-file-ignores
            if not isinstance(value, dict):
                bad(key, "`per-file-ignores` must be a table of \"GLOB\" = [CODES]", "not a table")
                continue
            for pattern, codes in value.items():
                if not (isinstance(codes, list) and all(isinstance(v, str) for v in codes)):
                    bad(key, f"`per-file-ignores.\"{pattern}\"` must be a list of codes", "not a list of strings", pattern)
                    continue
                config.per_file_ignores[pattern] = _codes(codes, f"{key}", source, section, diags)


def _codes(values: list[str], key: str, source: SourceFile, section: str, diags: Diagnostics) -> list[str]:
    """The valid code prefixes of a list; the others are findings."""
    out = []
    for v in values:
        span = _value_span(source, v)
        if not _CODE_PREFIX.fullmatch(v) or not any(c.startswith(v) for c in CODES):
            diags.add("E0009", span, f"`{v}` in `{key}` is not a diagnostic code or a prefix of one", "unknown code").with_help(
                "`rcsc explain --list` lists the codes"
            )
        elif key != "select" and v.startswith("E"):
            diags.add("E0009", span, f"errors cannot be ignored (`{v}` in `{key}`)", "an error code").with_note(
                "an error means the design is wrong; only warnings (W-codes) can be left out of a report"
            )
        else:
            out.append(v)
    return out


_POSITION = re.compile(r"\(at line (\d+), column (\d+)\)|\(at end of document\)")


def _error_span(source: SourceFile, message: str) -> Span:
    mt = _POSITION.search(message)
    if not mt or mt.group(1) is None:
        end = len(source.text) if "end of document" in message else 0
        return Span(source, end, end)
    start = source.offset(int(mt.group(1)), int(mt.group(2)))
    return Span(source, start, min(start + 1, len(source.text)))


def _strip_position(message: str) -> str:
    return _POSITION.sub("", message).strip()


def _key_span(source: SourceFile, section: str, key: str) -> Span:
    """The span of `key` in table `[section]` (the first one that looks like
    it; tomllib keeps no positions), else of the section header, else 0:0."""
    text = source.text
    start, end = 0, len(text)
    if section:
        header = re.search(r"^\s*\[\s*" + r"\s*\.\s*".join(re.escape(p) for p in section.split(".")) + r"\s*\]", text, re.M)
        if header:
            start = header.end()
            nxt = re.search(r"^\s*\[", text[start:], re.M)
            end = start + nxt.start() if nxt else len(text)
            if not key:
                return Span(source, header.start() + len(header.group(0)) - len(header.group(0).lstrip()), header.end())
    if key:
        mt = re.compile(r"^[ \t]*(\"?" + re.escape(key) + r"\"?)[ \t]*=", re.M).search(text, start, end)
        if mt is None:  # an inline table: `severity = { W0403 = ... }`
            mt = re.compile(r"[{,][ \t]*(\"?" + re.escape(key) + r"\"?)[ \t]*=").search(text, start, end)
        if mt:
            return Span(source, mt.start(1), mt.end(1))
    return Span(source, start, start)


def _value_span(source: SourceFile, value: str) -> Span:
    i = source.text.find(f'"{value}"')
    if i < 0:
        i = source.text.find(f"'{value}'")
    return Span(source, i, i + len(value) + 2) if i >= 0 else Span(source, 0, 0)
