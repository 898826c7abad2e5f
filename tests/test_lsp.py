"""The language server, driven over stdio like an editor drives it: real
JSON-RPC messages with Content-Length framing to `python -m rcsc lsp`
(initialize, didOpen, publishDiagnostics, didChange, hover, definition,
documentSymbol, completion, formatting, shutdown, exit)."""

from __future__ import annotations

import json
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from rcsc import cli

pytest.importorskip("pygls")  # the `lsp` extra; the test extra installs it

ROOT = Path(__file__).resolve().parent.parent
SUBMARINE = ROOT / "examples" / "submarine" / "submarine.rcs"


class Client:
    """A minimal LSP client over the server's stdin/stdout."""

    def __init__(self, cwd: Path) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "rcsc", "lsp"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, cwd=cwd)
        self.next_id = 0
        self.inbox: queue.Queue = queue.Queue()
        self.notifications: list[dict] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        out = self.proc.stdout
        assert out is not None
        while True:
            headers = {}
            while True:
                line = out.readline()
                if not line:
                    return
                if line in (b"\r\n", b"\n"):
                    break
                key, _, value = line.decode("ascii").partition(":")
                headers[key.strip().lower()] = value.strip()
            body = out.read(int(headers["content-length"]))
            self.inbox.put(json.loads(body))

    def send(self, message: dict) -> None:
        data = json.dumps({"jsonrpc": "2.0", **message}).encode("utf-8")
        assert self.proc.stdin is not None
        self.proc.stdin.write(b"Content-Length: %d\r\n\r\n" % len(data) + data)
        self.proc.stdin.flush()

    def notify(self, method: str, params: dict) -> None:
        self.send({"method": method, "params": params})

    def request(self, method: str, params: dict | None, timeout: float = 60) -> object:
        self.next_id += 1
        rid = self.next_id
        self.send({"id": rid, "method": method, "params": params})
        deadline = time.monotonic() + timeout
        while True:
            msg = self.inbox.get(timeout=max(0.01, deadline - time.monotonic()))
            if msg.get("id") == rid and "method" not in msg:
                assert "error" not in msg, msg
                return msg.get("result")
            self.notifications.append(msg)

    def diagnostics(self, uri: str, timeout: float = 60, after: int = 0) -> list[dict]:
        """The next publishDiagnostics for `uri` (past the first `after` ones)."""
        deadline = time.monotonic() + timeout
        seen = 0
        pool = list(self.notifications)
        self.notifications.clear()
        while True:
            while pool:
                msg = pool.pop(0)
                if msg.get("method") == "textDocument/publishDiagnostics" and msg["params"]["uri"] == uri:
                    if seen == after:
                        return msg["params"]["diagnostics"]
                    seen += 1
            pool.append(self.inbox.get(timeout=max(0.01, deadline - time.monotonic())))

    def close(self) -> int:
        self.request("shutdown", None)
        self.notify("exit", None)
        return self.proc.wait(timeout=30)


DESIGN = """design lsp_demo

gm speed: f64 = 0.0

enum Mode { SLOW, FAST }

controller TOP level 1 budget 1 ms {
    verb RUN(goal: f64)
    writes speed
    local mode: Mode = Mode.SLOW

    plan RUN {
        E0: cmd.goal > 1.0 | new -> S1 | speed = cmd.goal, mode = Mode.FAST;
        E1: speed > 2.0 | S1 -> done;
        E2: otherwise | S1 -> S1;
    }
}

cpu main {
    heartbeat 10 ms
    schedule TOP
}
"""


def _uri(path: Path) -> str:
    return path.resolve().as_uri()


def _pos(text: str, needle: str, nth: int = 0, delta: int = 0) -> dict:
    idx = -1
    for _ in range(nth + 1):
        idx = text.index(needle, idx + 1)
    idx += delta
    line = text.count("\n", 0, idx)
    return {"line": line, "character": idx - (text.rfind("\n", 0, idx) + 1)}


@pytest.fixture
def client(tmp_path: Path):
    c = Client(tmp_path)
    result = c.request("initialize", {"processId": None, "rootUri": _uri(tmp_path), "capabilities": {}})
    caps = result["capabilities"]
    assert caps["hoverProvider"] and caps["definitionProvider"] and caps["documentFormattingProvider"]
    assert caps["documentSymbolProvider"] and "completionProvider" in caps
    c.notify("initialized", {})
    yield c
    if c.proc.poll() is None:
        c.proc.kill()


def _open(client: Client, path: Path, text: str) -> str:
    uri = _uri(path)
    client.notify("textDocument/didOpen", {"textDocument": {"uri": uri, "languageId": "rcs", "version": 1, "text": text}})
    return uri


def _cli_findings(path: Path, capsys) -> set[tuple[str, int, int]]:
    cli.main(["check", str(path), "--format", "json"])
    doc = json.loads(capsys.readouterr().out)
    return {(d["code"], d["line"], d["column"]) for d in doc["diagnostics"]}


def test_diagnostics_match_rcsc_check_and_follow_edits(client: Client, tmp_path: Path, capsys) -> None:
    path = tmp_path / "d.rcs"
    broken = DESIGN.replace("speed > 2.0", "sped > 2.0")
    path.write_text(broken)
    uri = _open(client, path, broken)
    diags = client.diagnostics(uri)
    got = {(d["code"], d["range"]["start"]["line"] + 1, d["range"]["start"]["character"] + 1) for d in diags}
    assert got == _cli_findings(path, capsys)
    assert ("E0100", 14, 13) in got
    e0100 = next(d for d in diags if d["code"] == "E0100")
    assert e0100["codeDescription"]["href"].endswith("/codes.html#e0100") and e0100["severity"] == 1
    # Fix it in the editor only (unsaved): the server checks the new text.
    client.notify("textDocument/didChange", {
        "textDocument": {"uri": uri, "version": 2},
        "contentChanges": [{"text": DESIGN}],
    })
    fixed = client.diagnostics(uri)
    path.write_text(DESIGN)  # what the editor shows, for the command line
    got = {(d["code"], d["range"]["start"]["line"] + 1, d["range"]["start"]["character"] + 1) for d in fixed}
    assert got == _cli_findings(path, capsys)
    assert not any(code == "E0100" for code, _, _ in got)


def test_hover_definition_symbols_completion(client: Client, tmp_path: Path) -> None:
    path = tmp_path / "d.rcs"
    path.write_text(DESIGN)
    uri = _open(client, path, DESIGN)
    client.diagnostics(uri)
    doc = {"uri": uri}

    hover = client.request("textDocument/hover", {"textDocument": doc, "position": _pos(DESIGN, "speed > 2.0")})
    assert "gm speed: f64 = 0.0" in hover["contents"]["value"]

    loc = client.request("textDocument/definition", {"textDocument": doc, "position": _pos(DESIGN, "speed > 2.0")})
    assert loc["uri"] == uri and loc["range"]["start"] == _pos(DESIGN, "speed: f64")

    # A state: its definition is the rule that enters it.
    loc = client.request("textDocument/definition", {"textDocument": doc, "position": _pos(DESIGN, "S1 -> done")})
    assert loc["range"]["start"] == _pos(DESIGN, "S1 | speed")

    # An enum member through its enum.
    loc = client.request("textDocument/definition", {"textDocument": doc, "position": _pos(DESIGN, "FAST;")})
    assert loc["range"]["start"] == _pos(DESIGN, "FAST }")

    hover = client.request("textDocument/hover", {"textDocument": doc, "position": _pos(DESIGN, "cmd.goal", delta=5)})
    assert hover is None or "goal" in json.dumps(hover)

    outline = client.request("textDocument/documentSymbol", {"textDocument": doc})
    names = [s["name"] for s in outline]
    assert names == ["speed", "Mode", "TOP", "main"]
    top = outline[2]
    assert [c["name"] for c in top["children"]] == ["RUN", "mode", "RUN"]
    assert [r["name"] for r in top["children"][2]["children"]] == ["E0", "E1", "E2"]

    items = client.request("textDocument/completion", {"textDocument": doc, "position": _pos(DESIGN, "speed > 2.0")})
    labels = {i["label"] for i in items["items"]}
    assert {"speed", "Mode", "TOP", "mode", "RUN"} <= labels
    assert client.close() == 0


def test_hover_on_a_code_explains_it_and_verbs_show_their_signature(client: Client, tmp_path: Path) -> None:
    text = DESIGN.replace("design lsp_demo\n", "design lsp_demo\n// see E0505 for why\n")
    path = tmp_path / "d.rcs"
    path.write_text(text)
    uri = _open(client, path, text)
    client.diagnostics(uri)
    hover = client.request("textDocument/hover", {"textDocument": {"uri": uri}, "position": _pos(text, "E0505", delta=2)})
    assert hover["contents"]["value"].startswith("E0505 (error): state waits on a subordinate but ignores its error")
    hover = client.request("textDocument/hover", {"textDocument": {"uri": uri}, "position": _pos(text, "plan RUN", delta=6)})
    assert "plan RUN of TOP" in hover["contents"]["value"]


def test_formatting_goes_through_rcsc_fmt(client: Client, tmp_path: Path) -> None:
    from rcsc.editor.fmt import format_text

    messy = DESIGN.replace("    verb RUN", "\tverb RUN   ")
    path = tmp_path / "d.rcs"
    path.write_text(messy)
    uri = _open(client, path, messy)
    client.diagnostics(uri)
    edits = client.request("textDocument/formatting", {"textDocument": {"uri": uri}, "options": {"tabSize": 4, "insertSpaces": True}})
    assert len(edits) == 1 and edits[0]["newText"] == format_text(messy)
    assert edits[0]["range"]["start"] == {"line": 0, "character": 0}


def test_module_is_checked_through_the_design_that_imports_it(client: Client, tmp_path: Path) -> None:
    (tmp_path / "lib").mkdir()
    design = DESIGN.replace("design lsp_demo\n", 'design lsp_demo\nimport "lib/m.rcs"\n')
    (tmp_path / "d.rcs").write_text(design)
    module = "module m\nconst K: i32 = true\n"
    (tmp_path / "lib" / "m.rcs").write_text(module)
    uri = _open(client, tmp_path / "lib" / "m.rcs", module)
    diags = client.diagnostics(uri)
    assert [(d["code"], d["range"]["start"]) for d in diags] == [("E0200", {"line": 1, "character": 15})]


def test_utf16_columns(client: Client, tmp_path: Path) -> None:
    """A character outside the BMP counts two UTF-16 units in LSP positions."""
    text = DESIGN.replace("gm speed", "/* \U0001F6A2 */ const Y: i32 = nope\ngm speed")
    path = tmp_path / "d.rcs"
    path.write_text(text)
    uri = _open(client, path, text)
    diags = client.diagnostics(uri)
    nope = [d for d in diags if d["code"] == "E0100"]
    # 8 code points before `const`, 9 UTF-16 units; `nope` 15 further.
    assert [d["range"]["start"]["character"] for d in nope] == [24]


def test_an_edit_inside_a_plan_is_rechecked_in_part(client: Client, tmp_path: Path, capsys) -> None:
    """After an edit inside one controller's plan the server re-checks that
    controller only (rcsc.checks.incremental); the findings are still what
    `rcsc check` reports, and lookups inside the other controllers' plans
    (which that re-check did not parse) still work."""
    sys.path.insert(0, str(ROOT / "bench"))
    import synthetic

    text = synthetic.generate(5, 3, 6)
    path = tmp_path / "d.rcs"
    path.write_text(text)
    uri = _open(client, path, text)
    client.diagnostics(uri)
    at = text.index("<= 1000.0", text.index("controller C1 "))
    edited = text[:at] + "<= 999.0" + text[at + len("<= 1000.0"):]
    client.notify("textDocument/didChange", {"textDocument": {"uri": uri, "version": 2}, "contentChanges": [{"text": edited}]})
    diags = client.diagnostics(uri)
    path.write_text(edited)
    got = {(d["code"], d["range"]["start"]["line"] + 1, d["range"]["start"]["character"] + 1) for d in diags}
    assert got == _cli_findings(path, capsys) and any(code == "E0516" for code, _, _ in got)
    # A local used in a rule of C3, whose plans the re-check left unparsed.
    rule = edited.index("count += 1", edited.index("controller C3 "))
    line = edited.count("\n", 0, rule)
    position = {"line": line, "character": rule - (edited.rfind("\n", 0, rule) + 1) + 2}
    hover = client.request("textDocument/hover", {"textDocument": {"uri": uri}, "position": position})
    assert hover is not None and "count" in hover["contents"]["value"]
    assert client.close() == 0


def test_a_document_whose_path_holds_a_nul_does_not_stop_the_others(client: Client, tmp_path: Path) -> None:
    """No file has a NUL in its path, but a client can send one (`%00`): the
    system's path functions refuse it.  That document gets a finding saying
    so, and the other documents are still checked (their check reads every
    open document)."""
    bad = _uri(tmp_path / "a.rcs").replace("a.rcs", "a%00b.rcs")
    client.notify("textDocument/didOpen", {"textDocument": {"uri": bad, "languageId": "rcs", "version": 1, "text": DESIGN}})
    found = client.diagnostics(bad)
    assert [d["message"] for d in found] == ["the document's path holds a NUL character: no file can have it, so it is not checked"]
    pos = {"line": 0, "character": 0}  # requests on it answer nothing (they raised KeyError)
    assert client.request("textDocument/hover", {"textDocument": {"uri": bad}, "position": pos}) is None
    assert client.request("textDocument/definition", {"textDocument": {"uri": bad}, "position": pos}) is None
    assert client.request("textDocument/documentSymbol", {"textDocument": {"uri": bad}}) == []
    assert client.request("textDocument/completion", {"textDocument": {"uri": bad}, "position": pos})["items"] == []
    path = tmp_path / "d.rcs"
    uri = _open(client, path, DESIGN.replace("speed > 2.0", "sped > 2.0"))
    assert any(d.get("code") == "E0100" for d in client.diagnostics(uri))
    assert client.close() == 0


@pytest.mark.parametrize("odd", ["\x0c", "\u2028", "\x85", "\x0b", "\x1c"])
def test_a_range_edit_after_a_character_python_counts_as_a_line_end(client: Client, tmp_path: Path, odd: str) -> None:
    """LSP ends lines at \\n, \\r\\n and \\r only; Python's splitlines also at
    a form feed, U+2028 and others.  A range edit after such a character
    must land where the editor made it: the server's text stays the
    editor's, its finding is where `rcsc check` puts it, and formatting
    writes the edited text back, not a mangled one."""
    text = DESIGN.replace("gm speed", f"// a{odd}b\ngm speed")
    uri = _open(client, tmp_path / "d.rcs", text)
    client.diagnostics(uri)
    i = text.index("speed > 2.0")
    start, end = _pos(text, "speed > 2.0"), _pos(text, "speed > 2.0", delta=5)
    client.notify("textDocument/didChange", {"textDocument": {"uri": uri, "version": 2},
                                             "contentChanges": [{"range": {"start": start, "end": end}, "text": "sped"}]})
    found = [d for d in client.diagnostics(uri) if d.get("code") == "E0100"]
    assert [d["range"]["start"] for d in found] == [start]
    edits = client.request("textDocument/formatting", {"textDocument": {"uri": uri}, "options": {"tabSize": 4, "insertSpaces": True}})
    new_text = edits[0]["newText"]
    assert "E1: sped > 2.0" in new_text.replace("  ", " ") and "spedoal" not in new_text
    assert client.close() == 0


@pytest.mark.parametrize("end", ["\r", "\r\n"])
def test_formatting_replaces_the_whole_document_whatever_its_line_ends(client: Client, tmp_path: Path, end: str) -> None:
    """The edit's range must end at the end of the text by the protocol's
    line rules: with lone CRs, an end at line 0 made the editor insert the
    formatted design before the old one."""
    messy = DESIGN.replace("E2: otherwise | S1 -> S1;", "E2:   otherwise|S1->S1;")
    text = messy.replace("\n", end)
    uri = _open(client, tmp_path / "d.rcs", text)
    client.diagnostics(uri)
    edits = client.request("textDocument/formatting", {"textDocument": {"uri": uri}, "options": {"tabSize": 4, "insertSpaces": True}})
    assert len(edits) == 1
    assert edits[0]["range"] == {"start": {"line": 0, "character": 0}, "end": {"line": messy.count("\n"), "character": 0}}
    assert client.close() == 0


def test_editing_an_open_module_rechecks_the_open_design_that_imports_it(client: Client, tmp_path: Path) -> None:
    """The design's findings follow the module's unsaved text, and closing
    the module unsaved brings the file's text back."""
    (tmp_path / "lib").mkdir()
    module = "module m\nconst K: f64 = 1.0\n"
    (tmp_path / "lib" / "m.rcs").write_text(module)
    design = DESIGN.replace("design lsp_demo\n", 'design lsp_demo\nimport "lib/m.rcs"\n').replace("speed > 2.0", "speed > K")
    duri = _open(client, tmp_path / "d.rcs", design)
    assert "E0100" not in [d.get("code") for d in client.diagnostics(duri)]
    muri = _open(client, tmp_path / "lib" / "m.rcs", module)
    client.diagnostics(muri)
    # Opening the module checks the design again (its text is the file's here).
    assert "E0100" not in [d.get("code") for d in client.diagnostics(duri)]
    client.notify("textDocument/didChange", {"textDocument": {"uri": muri, "version": 2},
                                             "contentChanges": [{"text": "module m\nconst K2: f64 = 1.0\n"}]})
    assert "E0100" in [d.get("code") for d in client.diagnostics(duri)]
    client.notify("textDocument/didClose", {"textDocument": {"uri": muri}})
    assert "E0100" not in [d.get("code") for d in client.diagnostics(duri)]
    # Opened again with unsaved text the editor restored: the design reads that text.
    client.notify("textDocument/didOpen", {"textDocument": {"uri": muri, "languageId": "rcs", "version": 3,
                                                            "text": "module m\nconst K3: f64 = 1.0\n"}})
    assert "E0100" in [d.get("code") for d in client.diagnostics(duri)]
    assert client.close() == 0


def test_requests_for_documents_the_editor_did_not_open_answer_nothing(client: Client, tmp_path: Path) -> None:
    """No file read from disk behind the editor's back, no traceback: an
    empty answer (the server checks what the editor opened)."""
    (tmp_path / "there.rcs").write_text(DESIGN)
    for uri in (_uri(tmp_path / "there.rcs"), _uri(tmp_path / "missing.rcs"), "untitled:X"):
        pos = {"line": 0, "character": 0}
        assert client.request("textDocument/hover", {"textDocument": {"uri": uri}, "position": pos}) is None
        assert client.request("textDocument/definition", {"textDocument": {"uri": uri}, "position": pos}) is None
        assert client.request("textDocument/documentSymbol", {"textDocument": {"uri": uri}}) == []
        assert client.request("textDocument/completion", {"textDocument": {"uri": uri}, "position": pos})["items"] == []
        assert client.request("textDocument/formatting", {"textDocument": {"uri": uri}, "options": {"tabSize": 4, "insertSpaces": True}}) is None
        client.notify("textDocument/didSave", {"textDocument": {"uri": uri}})
    assert client.close() == 0
    assert b"Traceback" not in client.proc.stderr.read()


def test_the_configurations_own_findings_are_published_on_it(client: Client, tmp_path: Path) -> None:
    (tmp_path / "rcsc.toml").write_text('ignore = ["W9999"]\n')
    uri = _open(client, tmp_path / "d.rcs", DESIGN)
    found = client.diagnostics(_uri(tmp_path / "rcsc.toml"))
    assert [(d["code"], d["range"]["start"]) for d in found] == [("E0009", {"line": 0, "character": 10})]
    client.diagnostics(uri)
    assert client.close() == 0


def test_a_lone_surrogate_in_the_document_still_gets_its_findings(client: Client, tmp_path: Path) -> None:
    """An editor can hold a lone UTF-16 surrogate; the finding that quotes
    it must still reach the editor (it could not be encoded, and nothing was
    published for the document)."""
    text = DESIGN.replace("gm speed: f64 = 0.0", "gm speed: f64 = 0.0\ngm \ud83dspeed: f64 = 0.0")
    uri = _open(client, tmp_path / "d.rcs", text)
    found = client.diagnostics(uri, timeout=30)
    assert any(d.get("code") == "E0002" for d in found), found
    assert client.close() == 0


def test_the_server_keeps_its_documents_to_itself() -> None:
    """rcsc's protocol makes documents with the protocol's line ends
    (`_Document`) without changing pygls for other servers in the process:
    pygls' protocol module still makes pygls' own workspace."""
    import pygls.protocol.language_server as protocol_module
    from pygls.workspace import Workspace

    from rcsc.editor import lsp as rcs_lsp

    server = rcs_lsp.make_server()
    assert protocol_module.Workspace is Workspace
    protocol = server.protocol
    protocol._workspace = Workspace("file:///tmp", position_encoding="utf-16")
    ws = protocol.workspace
    assert isinstance(ws, rcs_lsp._Workspace) and ws.root_uri == "file:///tmp"
    ws.put_text_document(_text_document("file:///tmp/a.rcs", "a\x0cb\nc"))
    assert list(ws.get_text_document("file:///tmp/a.rcs").lines) == ["a\x0cb\n", "c"]


def _text_document(uri: str, text: str):
    from lsprotocol import types as lsp_types

    return lsp_types.TextDocumentItem(uri=uri, language_id="rcs", version=1, text=text)
