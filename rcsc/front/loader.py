"""Loading a design: the root file and everything it imports (`path_to_files`).

Local imports are confined to the design's folder (the folder of the root
file): absolute paths and paths that climb out of it are refused (E0004).
Standard-library modules come from the installed `rcsc.stdlib` package.  Each
file is loaded once, however often it is imported, so import cycles are
harmless.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from importlib import resources

from rcsc.outputs import safeio
from rcsc.front import ast
from rcsc.diagnostics import Diagnostics
from rcsc.front.parse import text_to_ast
from rcsc.front.source import SourceFile, Span, skip_trivia


class InputError(Exception):
    """The root file cannot be read: a usage/I-O error (exit code 2), not a finding."""


@dataclass
class LoadedFile:
    source: SourceFile
    tree: ast.File | None
    module: str  # module name ("" for the root design or header-less files)
    is_root: bool = False
    # Where the text came from: the real path of a local file, `<stdlib>/MODULE`
    # for a standard-library module (see `rcsc.checks.replay`).
    real: str = ""


def read_source(path: str, diags: Diagnostics, display: str | None = None) -> tuple[SourceFile, bool]:
    """The file at `path` as a SourceFile shown as `display`, and whether it
    is UTF-8 text.  A file that is not is still a source, with U+FFFD for
    its bad bytes, and an E0010 finding points at the first one: a file of
    another encoding is a mistake in the input, reported where it is, not a
    file that cannot be read.  OSError (InputError for a special or huge
    file) when it cannot be read at all."""
    try:
        data = safeio.read_input(path)
    except safeio.InputError as exc:
        raise InputError(str(exc)) from exc
    text, bad, at = safeio.decode_lossy(data)
    source = SourceFile(display or path, text)
    if bad is not None:
        diags.add("E0010", Span(source, bad, bad + 1), "this file is not UTF-8 text", f"byte 0x{data[at]:02x} is not UTF-8").with_note(
            f"at byte {at} of the file; rcsc reads every file as UTF-8"
        ).with_help("save the file as UTF-8 (from Latin-1, for example: `iconv -f latin1 -t utf-8`)")
    return source, bad is None


def stdlib_path(module: str):
    """The resource of a stdlib module `std.math` -> stdlib/std/math.rcs, or None."""
    parts = module.split(".")
    if not all(p.isidentifier() for p in parts):
        return None
    node = resources.files("rcsc.stdlib")
    for p in parts[:-1]:
        node = node.joinpath(p)
    node = node.joinpath(parts[-1] + ".rcs")
    return node if node.is_file() else None


def path_to_files(
    path: str, diags: Diagnostics, as_module: bool = False, overlay: dict[str, str] | None = None,
    root_holes: list[tuple[int, int]] | None = None,
) -> list[LoadedFile]:
    """Read and parse the root design file and, transitively, its imports.

    With `as_module`, the root may also be a `module` (checked on its own,
    as `rcsc check` does for a module that no design imports).  `overlay`
    maps real paths to texts that replace the files' contents (the unsaved
    documents of an editor, for the language server).  `root_holes`: ranges
    of the root text that the parser reads as blanks (see
    `rcsc.front.parse.text_to_ast`)."""
    overlay = overlay or {}
    utf8 = True
    try:
        text = overlay.get(os.path.realpath(path))
        if text is None:
            root, utf8 = read_source(path, diags)
        else:
            root = SourceFile(path, text)
    except FileNotFoundError as exc:
        raise InputError(f"{path}: no such file") from exc
    except IsADirectoryError as exc:
        raise InputError(f"{path}: is a folder, not a design file") from exc
    except OSError as exc:
        raise InputError(f"{path}: {exc.strerror or exc}") from exc

    root_dir = os.path.realpath(os.path.dirname(os.path.abspath(path)))
    files: list[LoadedFile] = []
    seen: set[str] = set()

    def visit(source: SourceFile, real: str, is_root: bool, display_dir: str | None, utf8: bool = True) -> None:
        seen.add(real)
        if not utf8:  # E0010 is reported; the rest would be read wrong
            files.append(LoadedFile(source, None, "", is_root, real))
            return
        tree = text_to_ast(source, diags, root_holes if is_root else None)
        module = ""
        if tree is not None:
            module = tree.name.name if tree.name is not None and tree.kind == "module" else ""
            if not (is_root and as_module and tree.kind == "module"):
                _check_header(tree, source, is_root, diags)
        files.append(LoadedFile(source, tree, module, is_root, real))
        if tree is None:
            return
        for item in tree.items:
            if isinstance(item, ast.Import):
                if item.is_file:
                    if display_dir is None:
                        diags.add("E0004", _target_span(item), "a standard-library module cannot import a local file", "local import in the standard library")
                        continue
                    _import_file(item, real, display_dir)
                else:
                    _import_std(item)

    def _import_file(item: ast.Import, importer_real: str, display_dir: str) -> None:
        target = item.target
        if os.path.isabs(target) or target.startswith("~"):
            diags.add("E0004", _target_span(item), "import of an absolute path", "absolute path").with_help(
                "import files by a path relative to the importing file, inside the design folder"
            )
            return
        if "\0" in target:
            # No file name holds a NUL; the system's path functions refuse one.
            diags.add("E0003", _target_span(item), "cannot read the imported file: its path holds a NUL character", "NUL character in the path")
            return
        real = os.path.realpath(os.path.join(os.path.dirname(importer_real), target))
        if os.path.commonpath([real, root_dir]) != root_dir:
            diags.add("E0004", _target_span(item), f"import of `{target}` leaves the design folder", "outside the design folder").with_note(
                f"the design folder is `{os.path.dirname(path) or '.'}`"
            )
            return
        if real in seen:
            return
        display = os.path.normpath(os.path.join(display_dir, target))
        try:
            source, utf8 = (SourceFile(display, overlay[real]), True) if real in overlay else read_source(real, diags, display)
        except InputError as exc:
            diags.add("E0003", _target_span(item), f"cannot read `{target}`: {exc}", "imported here")
            return
        except OSError as exc:
            reason = (exc.strerror or "no such file").lower()
            diags.add("E0003", _target_span(item), f"cannot read `{target}`: {reason}", "imported here")
            return
        visit(source, real, False, os.path.dirname(display), utf8)

    def _import_std(item: ast.Import) -> None:
        res = stdlib_path(item.target)
        if res is None:
            diag = diags.add("E0005", _target_span(item), f"no standard-library module `{item.target}`", "unknown module").with_note(
                "the standard library has: " + ", ".join(stdlib_modules())
            )
            diag.guess(item.target, stdlib_modules())
            if not item.target.startswith("std."):
                # A bare name is read as a standard-library module; a file
                # of the design is imported by its quoted path.
                diag.with_help(f'to import a file of the design, quote its path: `import "{item.target.replace(".", "/")}.rcs"`')
            return
        key = "<stdlib>/" + item.target
        if key in seen:
            return
        text = res.read_text(encoding="utf-8")
        visit(SourceFile("<stdlib>/" + item.target.replace(".", "/") + ".rcs", text), key, False, None)

    try:
        visit(root, os.path.realpath(path), True, os.path.dirname(path), utf8)
    finally:
        # `visit` and the import readers call each other through this
        # frame's cells: a cycle that would keep `files` (every syntax tree)
        # alive until a garbage collection, which a long-lived process (the
        # language server, the check daemon) runs rarely or never.
        del visit, _import_file, _import_std
    return files


def stdlib_modules() -> list[str]:
    """Names of the standard-library modules, sorted."""
    out = []
    base = resources.files("rcsc.stdlib")
    for pkg in sorted(base.iterdir(), key=lambda p: p.name):
        if pkg.is_dir() and not pkg.name.startswith(("_", ".")):
            for f in sorted(pkg.iterdir(), key=lambda p: p.name):
                if f.name.endswith(".rcs"):
                    out.append(f"{pkg.name}.{f.name[:-4]}")
    return out


def _check_header(tree: ast.File, source: SourceFile, is_root: bool, diags: Diagnostics) -> None:
    if is_root and tree.kind != "design":
        span = tree.name.span if tree.name is not None else _first_token_span(source)
        diags.add("E0006", span, "a design file must begin with `design NAME`", "expected `design NAME` here").with_help(
            "start the file with a line such as `design submarine`"
        )
    elif not is_root and tree.kind == "design":
        assert tree.name is not None
        diags.add("E0006", tree.name.span, "an imported file must be a `module`, not a `design`", "second design").with_help(
            "a design has exactly one `design` file; begin imported files with `module NAME`"
        )


def _target_span(item: ast.Import) -> Span:
    """The span of just the imported path or module name (not the `import` keyword)."""
    text, start = item.span.text, item.span.start
    if item.is_file:
        # STRING is the last token and cannot contain a quote.
        i = text.rfind('"', 0, max(0, len(text) - 1))
        return Span(item.span.file, start + i, item.span.end) if i >= 0 else item.span
    i = skip_trivia(text, len("import")) if text.startswith("import") else 0
    return Span(item.span.file, start + i, item.span.end)


def _first_token_span(source: SourceFile) -> Span:
    text = source.text
    i = skip_trivia(text, 0)
    j = i
    while j < len(text) and not text[j].isspace():
        j += 1
    return Span(source, i, j)
