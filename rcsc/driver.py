"""The front-end pipeline in one call: path -> files -> model -> checks (`check_path`).

Every command (check, sim, build, ...) starts here, so they all see the same
findings.  Only a root file that cannot be read raises (`InputError`, exit
code 2); everything else is a diagnostic.
"""

from __future__ import annotations

import gc
import sys
from dataclasses import dataclass

from rcsc.checks import cache, suppress
from rcsc.checks import check_model, guards
from rcsc.diagnostics import Diagnostics
from rcsc.checks.hints import add_hints
from rcsc.front.loader import InputError, LoadedFile, path_to_files
from rcsc.semantics.model import Design
from rcsc.semantics.sema import ast_to_model

__all__ = ["CheckResult", "InputError", "check_path"]


@dataclass
class CheckResult:
    diags: Diagnostics
    model: Design | None
    files: list[LoadedFile]
    # An incremental re-check (rcsc.checks.incremental): the plans of the
    # unchanged controllers are elided in the model and blank in the trees.
    partial: bool = False

    @property
    def ok(self) -> bool:
        return not self.diags.has_errors()


def check_path(
    path: str, as_module: bool = False, overlay: dict[str, str] | None = None, cache_dir: str | None = None, keep_plans: bool = True,
    guard_store: cache.MemoryStore | None = None, memory: dict | None = None,
) -> CheckResult:
    """Load, analyse and check the design whose root file is `path` (or, with
    `as_module`, the module `path` on its own); `overlay` gives texts that
    replace files on disk (see `loader.path_to_files`).  With `cache_dir`
    (see `rcsc.checks.cache`), results of the guard and value analyses are
    read from and written to that folder; `guard_store` (a
    `cache.MemoryStore` that a long-lived process keeps between checks) is
    used instead when given.  `memory` (`incremental.memory_stores`, kept by
    a long-lived process: the language server) holds the last check of each
    design and the solver's analyses: after an edit inside plans only the
    edited controllers are checked again (`rcsc.checks.incremental`).
    Without `keep_plans`, the syntax trees of the
    result lack the controllers' plans (freed early to save memory; for
    callers that need only the findings and the model, like `rcsc check`).
    """
    # A compiler run allocates many long-lived objects and frees few: the
    # cyclic garbage collector would spend about half of a large design's
    # check time scanning them for nothing, so it pauses for the run.  When
    # it resumes, what the run built is frozen (moved out of the collector's
    # reach; reference counting still frees it), or the first collections
    # after the run would walk the whole heap.  What an earlier run froze is
    # unfrozen first, so a long-lived process (an editor's language server,
    # a test suite) does not keep the garbage of every run.  The garbage that
    # only the collector frees (see `collect_if_grown`) is collected here when
    # it has doubled since the last collection: a program that checks in a
    # loop stays bounded without calling `collect_if_grown` itself (the
    # language server and the daemon also call it at quiet moments, so
    # their checks seldom pay for it).
    collect_if_grown()
    was_enabled = gc.isenabled()
    gc.disable()
    gc.unfreeze()
    try:
        if memory is None:
            return _check_path(path, as_module, overlay, cache_dir, keep_plans, guard_store)
        from rcsc.checks import incremental

        result = incremental.recheck(path, as_module, None, stores=memory, overlay=overlay)
        if result is None:
            result = _check_path(path, as_module, overlay, None, keep_plans, memory["guards"], memory["values"])
        incremental.remember(path, as_module, None, result, stores=memory)
        return result
    finally:
        gc.freeze()
        if was_enabled:
            gc.enable()


# The memory blocks in use after the last collection of `collect_if_grown`;
# at first, those in use when this module was imported (the modules' own
# objects: a process's first check does not collect them).
_kept_after_collection = [sys.getallocatedblocks()]

# Blocks allowed on top of `factor` times what the last collection kept (a
# few megabytes): a small process (a few checks of a small design) never
# collects.
_SLACK = 200_000

# `collect_if_grown` collects when the memory in use has grown this many times.
_FACTOR = 2.0


def collect_if_grown(factor: float | None = None) -> bool:
    """A full garbage collection when the memory in use has grown `factor`
    times (`_FACTOR` unless given) since the last one; whether one ran.  `check_path` calls it
    before each check, and a long-lived process (the language server, the
    check daemon) at a quiet moment after one.

    Some of a check's objects hold themselves (an expression keeps the
    closure compiled for it and the list of its sub-expressions, each
    naming it), so reference counting alone does not free a finished check,
    and `check_path` freezes what each run leaves: without a collection a
    process that checks again and again grows by what each check leaves
    (about 5 MB per re-check of a 200-controller design).  A collection
    costs time in proportion to what is kept (0.15 s for such a design), so
    it runs when that has doubled, not after every check.  The measure is
    Python's count of allocated memory blocks, which costs microseconds;
    counting the frozen objects walks them (2.6 ms for a small design's,
    as long as a small check)."""
    factor = _FACTOR if factor is None else factor
    blocks = sys.getallocatedblocks()
    if blocks <= factor * _kept_after_collection[0] + _SLACK:
        return False
    was_enabled = gc.isenabled()
    gc.disable()
    gc.unfreeze()
    try:
        gc.collect()
    finally:
        gc.freeze()
        _kept_after_collection[0] = sys.getallocatedblocks()
        if was_enabled:
            gc.enable()
    return True


# The findings of an import that failed (the file cannot be read, lies
# outside the design folder, or is no standard-library module).
_IMPORT_CODES = frozenset({"E0003", "E0004", "E0005"})


def _check_path(path: str, as_module: bool, overlay: dict[str, str] | None, cache_dir: str | None, keep_plans: bool = True,
                guard_store=None, value_store=None) -> CheckResult:
    diags = Diagnostics()
    files = path_to_files(path, diags, as_module, overlay)
    if any(f.tree is None for f in files):
        # A file that does not parse leaves holes that would only produce
        # follow-on findings; report the syntax errors alone.
        add_hints(diags, None)
        return CheckResult(diags, None, files)
    if any(d.code in _IMPORT_CODES for d in diags.items):
        # So does an import that failed: every name the missing module
        # declares (a verb set, a function, a type) would be reported as
        # unknown wherever it is used, burying the one finding that matters.
        add_hints(diags, None)
        return CheckResult(diags, None, files)
    design = ast_to_model(files, diags, release_plans=not keep_plans)
    store = guard_store
    if value_store is None:
        value_store = guard_store  # a MemoryStore holds both analyses
    if store is None and cache_dir is not None and not cache.disabled_by_environment():
        store = cache.Store(cache_dir, "guards")
        value_store = cache.Store(cache_dir, "values")
    check_model(design, diags, guards.Options(store=store), value_store)
    # Unused suppressions are reported only when the checks all ran (errors
    # stop the guard analysis, whose findings an `allow` may be waiting for).
    suppress.apply([f.source for f in files], diags, report_unused=not diags.has_errors())
    add_hints(diags, design)
    return CheckResult(diags, design, files)
