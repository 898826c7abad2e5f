"""Results kept between runs: a small on-disk store under `.rcsc-cache/`.

`rcsc check` keeps the guard analysis of each plan shape (see
`rcsc.checks.guards`) and the value analysis of each plan (see
`rcsc.checks.values`) in the folder `.rcsc-cache/` next to the design's root
file, so that a second run only asks the solver about plans that changed,
and the findings of each design (`rcsc.checks.replay`), so that a run on
unchanged files checks nothing.  The language server keeps the same entries
in memory (`MemoryStore`).  `--no-cache` (or
`RCSC_NO_CACHE=1`) turns it off; deleting the folder is always safe.

Each entry is one JSON file named by the SHA-256 of its key.  The file
holds a format number, the key, the version of the code that wrote it (a
hash of rcsc's own sources and of the installed z3, so an upgrade never reads an
old entry) and a checksum of the payload.  Writes are atomic
(`rcsc.outputs.safeio.write_file`).  An entry that is missing, stale, truncated or
otherwise corrupt is ignored (the result is computed again and the entry
rewritten); a folder that cannot be written just means no caching.  Nothing
here raises.

Values are JSON with tags for what JSON lacks: tuples, floats (exact, NaN
and infinities included, as hex), dictionaries with non-string keys and
rcsc types (by name, resolved against the design that reads the entry).
No entry is ever executed or unpickled: a cache folder that came with a
downloaded design cannot run code.
"""

from __future__ import annotations

import hashlib
import json
import os
from functools import lru_cache
from pathlib import Path

from rcsc.outputs import safeio
from rcsc.semantics.types import BUILTIN_TYPES, Type

FORMAT = 1
FOLDER = ".rcsc-cache"
_MAX_ENTRY = 16 * 1024 * 1024  # bytes; a larger file is not an entry of ours


@lru_cache(maxsize=1)
def code_version() -> str:
    """A hash of the sources of the installed rcsc package and of the installed z3."""
    digest = hashlib.sha256(_z3_identity())
    base = Path(__file__).resolve().parents[1]  # the rcsc package, not this folder
    for path in sorted(base.rglob("*.py")):
        digest.update(str(path.relative_to(base)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:32]


def _z3_identity() -> bytes:
    """What tells one installed z3 from another, without importing it (an
    unchanged design is answered from the cache in a fraction of the time
    z3's import takes): its generated API module and the size and time of
    each of its libraries.  A z3 installed otherwise is asked its version."""
    import importlib.util

    spec = importlib.util.find_spec("z3")
    folder = os.path.dirname(spec.origin) if spec is not None and spec.origin else ""
    try:
        out = [Path(folder, "z3core.py").read_bytes()]
        lib = os.path.join(folder, "lib")
        for name in sorted(os.listdir(lib)):
            st = os.stat(os.path.join(lib, name))
            out.append(f"{name}:{st.st_size}:{st.st_mtime_ns}".encode())
    except OSError:
        import z3

        return z3.get_version_string().encode()
    return b"\x00".join(out)


def folder_for(design_path: str) -> str:
    """The cache folder of the design whose root file is `design_path`."""
    return os.path.join(os.path.dirname(os.path.abspath(design_path)), FOLDER)


def disabled_by_environment() -> bool:
    return os.environ.get("RCSC_NO_CACHE", "") not in ("", "0")


class Store:
    """Entries of one namespace (e.g. "guards") in one cache folder."""

    def __init__(self, folder: str, namespace: str) -> None:
        self.folder = folder
        self.namespace = namespace
        self.writable = True
        self.hits = self.misses = self.writes = 0

    def _path(self, key: str) -> str:
        return os.path.join(self.folder, f"{self.namespace}-{key}.json")

    def get(self, key: str):
        """The value stored under `key` (a hex digest), or None."""
        try:
            raw = safeio.read_input(self._path(key), _MAX_ENTRY)
            doc = json.loads(raw)
            payload = doc["payload"]
            ok = (
                doc["format"] == FORMAT
                and doc["key"] == key
                and doc["code"] == code_version()
                and doc["checksum"] == hashlib.sha256(payload.encode()).hexdigest()
            )
            value = json.loads(payload) if ok else None
        except (OSError, ValueError, KeyError, TypeError):
            value = None
        if value is None:
            self.misses += 1
        else:
            self.hits += 1
        return value

    def put(self, key: str, value) -> None:
        """Store `value` (JSON-able after `encode`) under `key`; silently skipped when the folder is not writable."""
        if not self.writable:
            return
        payload = json.dumps(value, separators=(",", ":"), allow_nan=False)
        doc = {
            "format": FORMAT,
            "key": key,
            "code": code_version(),
            "checksum": hashlib.sha256(payload.encode()).hexdigest(),
            "payload": payload,
        }
        try:
            if not os.path.isdir(self.folder):
                os.makedirs(self.folder, exist_ok=True)
                # Tell version control and backup tools what this folder is.
                safeio.write_file(os.path.join(self.folder, ".gitignore"), b"# written by rcsc: a cache, safe to delete\n*\n")
                safeio.write_file(
                    os.path.join(self.folder, "CACHEDIR.TAG"),
                    b"Signature: 8a477f597d28d172789f06886806bc55\n# rcsc check's cache; see https://bford.info/cachedir/\n",
                )
            safeio.write_file(self._path(key), json.dumps(doc).encode())
            self.writes += 1
        except OSError:
            self.writable = False


class MemoryStore:
    """A `Store` in memory, for a long-lived process (the language server):
    the same entries (kept as the JSON data `encode` makes), at most `limit`
    of them (the oldest go first)."""

    def __init__(self, limit: int = 50_000) -> None:
        self.limit = limit
        self.entries: dict[str, object] = {}
        self.hits = self.misses = self.writes = 0

    def get(self, key: str):
        value = self.entries.get(key)
        if value is None:
            self.misses += 1
        else:
            self.hits += 1
        return value

    def put(self, key: str, value) -> None:
        try:  # what the disk store could not hold is not held here either
            json.dumps(value, allow_nan=False)
        except (ValueError, TypeError):
            return
        self.keep(key, value)

    def keep(self, key: str, value) -> None:
        """`put` a value known to be JSON data (the disk store just took it)."""
        self.entries.pop(key, None)
        self.entries[key] = value
        self.writes += 1
        while len(self.entries) > self.limit:
            del self.entries[next(iter(self.entries))]


class LayeredStore:
    """A `MemoryStore` in front of a folder's `Store` (the check daemon,
    `rcsc.daemon`): an entry is read from memory, else from the folder
    (and then kept in memory), and written to both, so that a check made by
    the daemon leaves the folder as `rcsc check` would and finds what
    `rcsc check` stored there."""

    def __init__(self, front: MemoryStore, back: Store) -> None:
        self.front, self.back = front, back

    def get(self, key: str):
        value = self.front.get(key)
        if value is None:
            value = self.back.get(key)
            if value is not None:
                self.front.put(key, value)
        return value

    def put(self, key: str, value) -> None:
        self.back.put(key, value)  # raises, as `Store.put` does, for what JSON cannot hold
        if self.back.writable:
            self.front.keep(key, value)  # the folder just took it: JSON data
        else:
            self.front.put(key, value)  # the folder took nothing: the memory checks for itself


def digest(key) -> str:
    """The hex SHA-256 of a key made of tuples, strings, numbers and None."""
    return hashlib.sha256(repr(key).encode()).hexdigest()


# ---- tagged JSON ---------------------------------------------------------------------------


class NotStorable(Exception):
    """A value the tagged JSON cannot hold (the entry is then not written)."""


def encode(value):
    """`value` as plain JSON data (see the module docstring)."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        return {"f": value.hex()}
    if isinstance(value, tuple):
        return {"t": [encode(v) for v in value]}
    if isinstance(value, list):
        return [encode(v) for v in value]
    if isinstance(value, dict):
        return {"d": [[encode(k), encode(v)] for k, v in value.items()]}
    if isinstance(value, Type):
        return {"ty": str(value)}
    raise NotStorable(type(value).__name__)


def decode(data, types: dict[str, Type]):
    """The value `encode` turned into `data`; `types` resolves type names (KeyError if unknown)."""
    if isinstance(data, list):
        return [decode(v, types) for v in data]
    if isinstance(data, dict):
        if "f" in data:
            return float.fromhex(data["f"])
        if "t" in data:
            return tuple(decode(v, types) for v in data["t"])
        if "d" in data:
            return {decode(k, types): decode(v, types) for k, v in data["d"]}
        if "ty" in data:
            name = data["ty"]
            return BUILTIN_TYPES[name] if name in BUILTIN_TYPES else types[name]
        raise ValueError("unknown tag")
    return data
