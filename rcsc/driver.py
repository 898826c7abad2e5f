"""The front-end pipeline in one call: path -> files -> model -> checks (`check_path`).

Every command (check, sim, build, ...) starts here, so they all see the same
findings.  Only a root file that cannot be read raises (`InputError`, exit
code 2); everything else is a diagnostic.
"""

from __future__ import annotations

import gc
from dataclasses import dataclass

from rcsc import suppress
from rcsc.checks import check_model
from rcsc.diagnostics import Diagnostics
from rcsc.hints import add_hints
from rcsc.loader import InputError, LoadedFile, path_to_files
from rcsc.model import Design
from rcsc.sema import ast_to_model

__all__ = ["CheckResult", "InputError", "check_path"]


@dataclass
class CheckResult:
    diags: Diagnostics
    model: Design | None
    files: list[LoadedFile]

    @property
    def ok(self) -> bool:
        return not self.diags.has_errors()


def check_path(path: str) -> CheckResult:
    """Load, analyse and check the design whose root file is `path`."""
    # A compiler run allocates many long-lived objects and frees few: the
    # cyclic garbage collector would spend about half of a large design's
    # check time scanning them for nothing, so it pauses for the run.
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        return _check_path(path)
    finally:
        if was_enabled:
            gc.enable()


def _check_path(path: str) -> CheckResult:
    diags = Diagnostics()
    files = path_to_files(path, diags)
    if any(f.tree is None for f in files):
        # A file that does not parse leaves holes that would only produce
        # follow-on findings; report the syntax errors alone.
        add_hints(diags, None)
        return CheckResult(diags, None, files)
    design = ast_to_model(files, diags)
    check_model(design, diags)
    # Unused suppressions are reported only when the checks all ran (errors
    # stop the guard analysis, whose findings an `allow` may be waiting for).
    suppress.apply([f.source for f in files], diags, report_unused=not diags.has_errors())
    add_hints(diags, design)
    return CheckResult(diags, design, files)
