"""The language server (`rcsc lsp`, Language Server Protocol over stdio).

Built on pygls (the optional dependency `rcsc[lsp]`).  For each open `.rcs`
document it publishes the same findings as `rcsc check` (configuration
included), from the editor's unsaved text: on open and save at once, while
typing after a short pause (a newer edit cancels the pending check).  A
module is checked through the design that imports it (found as `rcsc check`
finds it), with the unsaved texts of every open document; an edit of an open
module checks again the open designs whose last check read it.  The
configuration's own findings (E0009, E0010) are published on the configuration
file.  Only documents the editor opened are checked or answered for.

Requests: hover (a name's declaration, a verb's signature, the explanation
of a diagnostic code under the cursor), go to definition (names, states,
verbs, controllers, enum members), document symbols (controllers with their
verbs and plans and rules, global declarations), completion of names, and
whole-document formatting through `rcsc fmt`.

Positions: LSP counts characters in UTF-16 code units, rcsc in code points;
`_position` and `_offset` convert.
"""

from __future__ import annotations

import asyncio
import os
import re
from collections.abc import Sequence
from urllib.parse import unquote, urlparse

from lsprotocol import types as lsp
from pygls.lsp.server import LanguageServer
from pygls.protocol import LanguageServerProtocol
from pygls.workspace import TextDocument, Workspace

import rcsc
from rcsc import codes
from rcsc.checks import cache, incremental
from rcsc.editor import fmt, symbols
from rcsc.front import workspace
from rcsc import config as cfg
from rcsc.diagnostics import Diagnostics, Severity
from rcsc.front.source import SourceFile, Span

DEBOUNCE_SECONDS = 0.15

_SEVERITY = {
    Severity.ERROR: lsp.DiagnosticSeverity.Error,
    Severity.WARNING: lsp.DiagnosticSeverity.Warning,
    Severity.NOTE: lsp.DiagnosticSeverity.Information,
}

_KIND = {
    "const": lsp.SymbolKind.Constant,
    "gm": lsp.SymbolKind.Variable,
    "fn": lsp.SymbolKind.Function,
    "extern": lsp.SymbolKind.Function,
    "enum": lsp.SymbolKind.Enum,
    "member": lsp.SymbolKind.EnumMember,
    "record": lsp.SymbolKind.Struct,
    "verb-set": lsp.SymbolKind.Interface,
    "controller": lsp.SymbolKind.Class,
    "verb": lsp.SymbolKind.Method,
    "plan": lsp.SymbolKind.Namespace,
    "rule": lsp.SymbolKind.Event,
    "local": lsp.SymbolKind.Field,
    "status": lsp.SymbolKind.Property,
    "cpu": lsp.SymbolKind.Module,
    "state": lsp.SymbolKind.EnumMember,
}


# LSP ends a line at `\n`, `\r\n` or `\r` only (as rcsc does), where Python's
# str.splitlines also ends one at a form feed, U+2028, U+0085 and others.
_LSP_LINE = re.compile(r"[^\r\n]*(?:\r\n|\r|\n)|[^\r\n]+\Z")


def lsp_lines(text: str) -> list[str]:
    """The lines of `text` by the protocol's rules, each with its line end."""
    return _LSP_LINE.findall(text)


class _Document(TextDocument):
    """pygls's document with the protocol's line ends: pygls applies a range
    edit to the lines str.splitlines makes, so after a form feed or a U+2028
    every edit landed a line early and the server's text was no longer the
    editor's (diagnostics, and formatting that wrote the wrong text back)."""

    @property
    def lines(self) -> Sequence[str]:
        return tuple(lsp_lines(self.source))


class _Workspace(Workspace):
    def _create_text_document(self, doc_uri: str, source: str | None = None, version: int | None = None,
                              language_id: str | None = None) -> TextDocument:
        return _Document(doc_uri, source=source, version=version, language_id=language_id,
                         sync_kind=self._sync_kind, position_codec=self._position_codec)


class _Protocol(LanguageServerProtocol):
    """pygls' protocol, whose workspace makes `_Document`s.

    The protocol makes its `Workspace` itself when the editor initializes
    the session, and stores it in `_workspace`; this property turns the one
    it stores into a `_Workspace` with the same root, folders, sync kind and
    position encoding.  Only this server's protocol is concerned: other
    pygls servers in the process keep pygls' own documents."""

    @property  # type: ignore[override]
    def _workspace(self) -> Workspace | None:
        return self.__dict__.get("_rcs_workspace")

    @_workspace.setter
    def _workspace(self, ws: Workspace | None) -> None:
        if ws is not None and not isinstance(ws, _Workspace):
            ws = _Workspace(ws.root_uri, ws._sync_kind, list(ws.folders.values()), ws.position_encoding)
        self.__dict__["_rcs_workspace"] = ws


def uri_to_path(uri: str) -> str:
    parsed = urlparse(uri)
    return unquote(parsed.path) if parsed.scheme == "file" else uri


def path_to_uri(path: str) -> str:
    from pathlib import Path

    return Path(os.path.abspath(path)).as_uri()


def _utf16_len(text: str) -> int:
    """UTF-16 code units: two for a character beyond U+FFFF, one for any
    other (a lone surrogate too, which the codec would refuse)."""
    return len(text) + sum(1 for ch in text if ord(ch) > 0xFFFF)


def _position(source: SourceFile, offset: int) -> lsp.Position:
    line, col = source.line_col(offset)
    return lsp.Position(line=line - 1, character=_utf16_len(source.line_text(line)[: col - 1]))


def _offset(source: SourceFile, pos: lsp.Position) -> int:
    """The code-point offset of an LSP position (UTF-16 column)."""
    line = pos.line + 1
    if line > source.line_count:
        return len(source.text)
    text = source.line_text(line)
    units = 0
    for i, ch in enumerate(text):
        if units >= pos.character:
            return source._line_starts[line - 1] + i
        units += 2 if ord(ch) > 0xFFFF else 1
    return source._line_starts[line - 1] + len(text)


def _range(span: Span) -> lsp.Range:
    return lsp.Range(start=_position(span.file, span.start), end=_position(span.file, max(span.start, span.end)))


class RcsServer(LanguageServer):
    """The server and its state: the last check of each open document."""

    def __init__(self) -> None:
        super().__init__("rcsc", rcsc.__version__, protocol_cls=_Protocol)
        self.pending: dict[str, asyncio.Task] = {}
        self.indexes: dict[str, symbols.Index] = {}  # uri -> index of its design
        self.sources: dict[str, SourceFile] = {}  # uri -> the text the index was built from
        self.roots: dict[str, tuple[str, bool]] = {}  # uri -> (root file, as a module) of its last check
        self.read: dict[str, set[str]] = {}  # uri -> the real paths of the files its last check read
        self.checked: dict[str, str] = {}  # uri -> the editor's text its last check saw
        # The guard analysis of every plan shape met so far: a re-check asks
        # the solver only about plans whose shape the edit changed.
        self.guard_store = cache.MemoryStore()
        # The last check of each design, for the incremental re-check after
        # an edit inside plans (rcsc.checks.incremental).
        self.stores = incremental.memory_stores(self.guard_store)

    # -- checking ------------------------------------------------------------

    def overlay(self) -> dict[str, str]:
        out = {}
        for uri, doc in self.workspace.text_documents.items():
            path = uri_to_path(uri)
            if "\0" not in path:  # no file has such a path (`check` says so)
                out[os.path.realpath(path)] = doc.source
        return out

    def check(self, uri: str) -> list[lsp.Diagnostic]:
        """Check the document `uri` now; publish and return its findings."""
        from rcsc import driver

        path = uri_to_path(uri)
        doc = self.opened(uri)
        if doc is None:  # not open (a save or a request for a document the editor did not open): nothing to check
            return []
        if "\0" in path:
            # The system's path functions refuse a NUL, and no file has one.
            diag = lsp.Diagnostic(range=lsp.Range(start=lsp.Position(line=0, character=0), end=lsp.Position(line=0, character=0)),
                                  message="the document's path holds a NUL character: no file can have it, so it is not checked",
                                  severity=lsp.DiagnosticSeverity.Error, source="rcsc")
            self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri=uri, diagnostics=[diag], version=doc.version))
            return [diag]
        overlay = self.overlay()
        real = os.path.realpath(path)
        root, as_module = path, False
        if workspace.header_kind_text(doc.source) == "module":
            as_module = True
            for design in workspace.candidate_designs(path):
                try:
                    files = driver.path_to_files(design, Diagnostics(), overlay=overlay)
                except driver.InputError:
                    continue
                if any(os.path.realpath(f.source.path) == real for f in files if not f.is_root):
                    root, as_module = design, False
                    break
        self.roots[uri] = (root, as_module)
        self.checked[uri] = doc.source
        try:
            result = driver.check_path(root, as_module=as_module, overlay=overlay, memory=self.stores)
        except driver.InputError as exc:
            self.sources.pop(uri, None)  # no index for a design that cannot be read
            self.indexes.pop(uri, None)
            diag = lsp.Diagnostic(range=lsp.Range(start=lsp.Position(line=0, character=0), end=lsp.Position(line=0, character=0)),
                                  message=str(exc), severity=lsp.DiagnosticSeverity.Error, source="rcsc")
            self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri=uri, diagnostics=[diag], version=doc.version))
            return [diag]
        self.read[uri] = {os.path.realpath(f.source.path) for f in result.files}
        config_diags = Diagnostics()
        found = cfg.find(path)
        conf = cfg.load(found[0], found[1], config_diags) if found else cfg.Config()
        if found:
            self.publish_config(found[0], config_diags)
        reported = conf.apply(result.diags)
        if getattr(result, "partial", False):
            # The unchanged controllers' plans were not parsed: the index is
            # made again when a lookup needs it (`index`).
            self.indexes.pop(uri, None)
        else:
            self.indexes[uri] = symbols.build([f.tree for f in result.files if f.tree is not None])
        own = next((f.source for f in result.files if os.path.realpath(f.source.path) == real), None)
        self.sources[uri] = own or SourceFile(path, doc.source)
        out = []
        for d in reported.sorted():
            if d.span is None or os.path.realpath(d.span.file.path) != real:
                continue
            message = d.message
            for note in d.notes:
                message += f"\nnote: {note}"
            for help_ in d.helps:
                message += f"\nhelp: {help_}"
            related = [
                lsp.DiagnosticRelatedInformation(
                    location=lsp.Location(uri=path_to_uri(label.span.file.path), range=_range(label.span)), message=label.message
                )
                for label in d.labels
                if not label.span.file.path.startswith("<")
            ]
            out.append(lsp.Diagnostic(
                range=_range(d.span), message=message, severity=_SEVERITY[d.severity], code=d.code, source="rcsc",
                code_description=lsp.CodeDescription(href=codes.help_uri(d.code)) if d.code in codes.CODES else None,
                related_information=related or None,
            ))
        self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri=uri, diagnostics=out, version=doc.version))
        driver.collect_if_grown()  # the findings are out: what the last checks left can go
        return out

    def opened(self, uri: str) -> TextDocument | None:
        """The open document `uri`, or None: pygls would read a document the
        editor has not opened from disk (and fail when there is no such file).
        pygls keys its documents by the unquoted URI."""
        return self.workspace.text_documents.get(unquote(uri))

    def publish_config(self, path: str, diags: Diagnostics) -> None:
        """The configuration's own findings (E0009, E0010), on the configuration file,
        as `rcsc check` reports them there."""
        out = [lsp.Diagnostic(range=_range(d.span) if d.span is not None else lsp.Range(start=lsp.Position(line=0, character=0),
                                                                                      end=lsp.Position(line=0, character=0)),
                              message=d.message, severity=_SEVERITY[d.severity], code=d.code, source="rcsc")
               for d in diags.sorted()]
        self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri=path_to_uri(path), diagnostics=out))

    def dependents(self, uri: str) -> list[str]:
        """The other open documents whose last check read the file of `uri`
        (a design importing the module being edited)."""
        path = uri_to_path(uri)
        if "\0" in path:
            return []
        real = os.path.realpath(path)
        return [u for u, files in self.read.items() if u != uri and real in files and self.opened(u) is not None]

    def schedule(self, uri: str, delay: float) -> None:
        """Check `uri` after `delay` seconds unless another edit comes first."""
        task = self.pending.pop(uri, None)
        if task is not None:
            task.cancel()

        async def later() -> None:
            await asyncio.sleep(delay)
            self.pending.pop(uri, None)
            self.check(uri)

        self.pending[uri] = asyncio.ensure_future(later())

    # -- lookups ---------------------------------------------------------------

    def checked_source(self, uri: str) -> SourceFile | None:
        """The text of `uri` as its current check saw it (checking it first if
        needed), or None for a document that has no check (not open, a path
        no file can have, an unreadable design)."""
        doc = self.opened(uri)
        if doc is None:
            return None
        if uri not in self.sources or self.checked.get(uri) != doc.source:
            self.check(uri)  # none yet, or older than the text: renew it
        return self.sources.get(uri) if uri in self.roots else None

    def symbol_at(self, uri: str, pos: lsp.Position) -> tuple[symbols.Symbol | None, SourceFile | None, int]:
        if self.checked_source(uri) is None:
            return None, None, 0
        idx = self.index(uri)
        source = self.sources[uri]  # the text the index was made from
        offset = _offset(source, pos)
        return symbols.lookup(idx, source, offset), source, offset

    def index(self, uri: str) -> symbols.Index:
        """The symbol index of the design of `uri`; after an incremental
        re-check (which leaves unchanged plans unparsed), made from a parse
        of the texts the check saw."""
        found = self.indexes.get(uri)
        if found is None:
            from rcsc import driver

            root, as_module = self.roots[uri]
            try:
                files = driver.path_to_files(root, Diagnostics(), as_module, self.overlay())
            except driver.InputError:
                files = []
            found = self.indexes[uri] = symbols.build([f.tree for f in files if f.tree is not None])
            own = next((f.source for f in files if os.path.realpath(f.source.path) == os.path.realpath(uri_to_path(uri))), None)
            if own is not None:
                self.sources[uri] = own
        return found


def make_server() -> RcsServer:
    server = RcsServer()
    @server.feature(lsp.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: RcsServer, params: lsp.DidOpenTextDocumentParams) -> None:
        ls.check(params.text_document.uri)
        # A module opened with unsaved text (restored by the editor) changes
        # what the open designs importing it read.
        for uri in ls.dependents(params.text_document.uri):
            ls.schedule(uri, 0)

    @server.feature(lsp.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: RcsServer, params: lsp.DidChangeTextDocumentParams) -> None:
        for uri in [params.text_document.uri, *ls.dependents(params.text_document.uri)]:
            ls.schedule(uri, DEBOUNCE_SECONDS)

    @server.feature(lsp.TEXT_DOCUMENT_DID_SAVE)
    def did_save(ls: RcsServer, params: lsp.DidSaveTextDocumentParams) -> None:
        for uri in [params.text_document.uri, *ls.dependents(params.text_document.uri)]:
            ls.schedule(uri, 0)

    @server.feature(lsp.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: RcsServer, params: lsp.DidCloseTextDocumentParams) -> None:
        uri = params.text_document.uri
        task = ls.pending.pop(uri, None)
        if task is not None:
            task.cancel()
        ls.indexes.pop(uri, None)
        ls.sources.pop(uri, None)
        ls.checked.pop(uri, None)
        ls.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri=uri, diagnostics=[]))
        # The designs that read this document's unsaved text now read the file.
        for other in ls.dependents(uri):
            ls.schedule(other, 0)
        ls.read.pop(uri, None)

    @server.feature(lsp.TEXT_DOCUMENT_HOVER)
    def hover(ls: RcsServer, params: lsp.HoverParams) -> lsp.Hover | None:
        sym, source, offset = ls.symbol_at(params.text_document.uri, params.position)
        if source is None:
            return None
        word = symbols.word_at(source, offset)
        if word is not None and symbols.CODE_RE.fullmatch(word[0]) and word[0] in codes.CODES:
            text = codes.explain(word[0]) or ""
            return lsp.Hover(contents=lsp.MarkupContent(kind=lsp.MarkupKind.Markdown, value=text),
                             range=_range(Span(source, word[1], word[2])))
        if sym is None or word is None:
            return None
        return lsp.Hover(contents=lsp.MarkupContent(kind=lsp.MarkupKind.Markdown, value=symbols.hover_text(sym)),
                         range=_range(Span(source, word[1], word[2])))

    @server.feature(lsp.TEXT_DOCUMENT_DEFINITION)
    def definition(ls: RcsServer, params: lsp.DefinitionParams) -> lsp.Location | None:
        sym, _, _ = ls.symbol_at(params.text_document.uri, params.position)
        if sym is None or sym.span.file.path.startswith("<"):
            return None
        return lsp.Location(uri=path_to_uri(sym.span.file.path), range=_range(sym.span))

    @server.feature(lsp.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    def document_symbol(ls: RcsServer, params: lsp.DocumentSymbolParams) -> list[lsp.DocumentSymbol]:
        uri = params.text_document.uri
        if ls.checked_source(uri) is None:
            return []
        idx = ls.index(uri)
        path = ls.sources[uri].path
        return [_doc_symbol(s) for s in idx.top.get(path, [])]

    @server.feature(lsp.TEXT_DOCUMENT_COMPLETION)
    def completion(ls: RcsServer, params: lsp.CompletionParams) -> lsp.CompletionList:
        uri = params.text_document.uri
        if ls.checked_source(uri) is None:
            return lsp.CompletionList(is_incomplete=False, items=[])
        idx = ls.index(uri)
        items = {}
        for name, sym in idx.globals.items():
            items[name] = lsp.CompletionItem(label=name, kind=lsp.CompletionItemKind.Variable, detail=sym.detail)
        source = ls.sources[uri]
        controller, _ = symbols._enclosing(idx, source.path, _offset(source, params.position))
        for name, sym in idx.members.get(controller or "", {}).items():
            if not name.startswith("plan "):
                items[name] = lsp.CompletionItem(label=name, kind=lsp.CompletionItemKind.Field, detail=sym.detail)
        return lsp.CompletionList(is_incomplete=False, items=[items[k] for k in sorted(items)])

    @server.feature(lsp.TEXT_DOCUMENT_FORMATTING)
    def formatting(ls: RcsServer, params: lsp.DocumentFormattingParams) -> list[lsp.TextEdit] | None:
        doc = ls.opened(params.text_document.uri)
        if doc is None:
            return None
        formatted, _ = fmt.format_source(uri_to_path(doc.uri), doc.source)
        if formatted is None or formatted == doc.source:
            return [] if formatted is not None else None
        # The end of the text by the protocol's line ends (`\r` alone too).
        lines = lsp_lines(doc.source)
        ended = not lines or lines[-1].endswith(("\n", "\r"))
        end = lsp.Position(line=len(lines), character=0) if ended else lsp.Position(line=len(lines) - 1, character=_utf16_len(lines[-1]))
        return [lsp.TextEdit(range=lsp.Range(start=lsp.Position(line=0, character=0), end=end), new_text=formatted)]

    return server


def _doc_symbol(sym: symbols.Symbol) -> lsp.DocumentSymbol:
    return lsp.DocumentSymbol(
        name=sym.name, kind=_KIND.get(sym.kind, lsp.SymbolKind.Variable), detail=sym.detail,
        range=_range(sym.decl), selection_range=_range(sym.span),
        children=[_doc_symbol(c) for c in sym.children] or None,
    )


def main() -> int:
    make_server().start_io()
    return 0
