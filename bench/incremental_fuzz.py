#!/usr/bin/env python3
"""Random edits inside plans, of headers and of declarations: the incremental re-check must equal a full check.

    python bench/incremental_fuzz.py --seeds 0..49          # designs of the differential tester, edited
    python bench/incremental_fuzz.py --seeds 0..9 --keep /tmp/incr-fails
    python bench/incremental_fuzz.py --seeds 0..49 --memory  # as the language server re-checks
    python bench/incremental_fuzz.py --seeds 0..19 --daemon  # rcsc check --daemon against fresh processes
    python bench/incremental_fuzz.py --seeds 0..49 --headers 0.8  # mostly edits of controllers' headers
    python bench/incremental_fuzz.py --seeds 0..49 --declarations 0.8  # mostly edits of declarations outside them

For each seed it takes a design (the differential tester's draw for the seed,
unchecked, so it may hold findings; or an example or a synthetic design),
runs `rcsc check` on it (which stores its findings and outline in
`.rcsc-cache/`), copies the folder, makes the same random edits inside the
plans of one or two controllers in both copies, and then runs `rcsc check`
in the first copy (the incremental re-check when it applies) and, in the
second, `rcsc check` with `RCSC_INCREMENTAL=0` (a full check with the same
solver cache).  The two JSON reports must be equal byte for byte, and so
must the SARIF reports (which list suppressed findings), witnesses
included: only a solver question that ran out of wall-clock time may be
left out (`normalized`).

With `--memory` it re-checks successive edits in one process, as the
language server does (the unchanged controllers' syntax trees kept between
re-checks), and compares every finding (message, notes, witness, places of
it and its labels) with a full check's.  With `--daemon` it writes successive edits to disk and checks
each with `rcsc check --daemon`, comparing the JSON report with that of
`rcsc check --no-cache` in a fresh process.

It prints how many edits took the incremental path (the others are
checked in full: an edit that changes what other controllers see, a design
with controller types, ...) and every disagreement, with the edit.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT))

from rcsc.front import items as it  # noqa: E402

_NUMBER = re.compile(r"(?<![A-Za-z_0-9.])[0-9]+(?:\.[0-9]+)?(?![A-Za-z_0-9.])")
_CMP = {"<=": "<", "<": "<=", ">=": ">", ">": ">=", "==": "!=", "!=": "=="}
_CMP_RE = re.compile(r"<=|>=|==|!=|(?<![-<>=!])[<>](?![=])")
# How often `edit` edits a header instead of plans (`--headers` sets it).
HEADER_RATE = 0.2
# How often `edit` edits a declaration outside the controllers (`--declarations`).
DECLARATION_RATE = 0.15
_DECLARATION = re.compile(r"^(const|gm|enum|record|fn|extern)\b[^\n]*$", re.M)
_RULE = re.compile(r"^[ \t]*[A-Za-z_][A-Za-z0-9_]*:[^\n]*;[^\n]*$", re.M)


def design_for(seed: int) -> str:
    """A design for `seed`: mostly the differential tester's draws, sometimes an example or a synthetic design."""
    import difftest_gen
    import synthetic

    kind = seed % 10
    if kind == 7:
        examples = sorted(ROOT.glob("examples/*/*.rcs"))
        return examples[(seed // 10) % len(examples)].read_text(encoding="utf-8")
    if kind == 8:
        return synthetic.generate(4 + seed % 5, 3, 6)
    return difftest_gen.draw(seed, 0, features=kind != 9).design


def edit(text: str, rng: random.Random) -> tuple[str, list[str]] | None:
    """The text with 1 to 3 random edits inside the plan bodies of one or two
    controllers (a fifth of the time, one edit of a controller's header
    instead: `edit_header`), and what was done."""
    found = it.controller_items(text)
    if not found:
        return None
    if rng.random() < DECLARATION_RATE:
        return edit_declaration(text, found, rng)
    if rng.random() < HEADER_RATE:
        return edit_header(text, found, rng)
    with_bodies = [x for x in found if x.bodies]
    if not with_bodies:
        return None
    targets = rng.sample(with_bodies, min(len(with_bodies), rng.choice((1, 1, 2))))
    bodies = [(x.name, b) for x in targets for b in x.bodies]
    done: list[str] = []
    # Edit from the end of the text so earlier offsets stay valid.
    picks = sorted(rng.sample(bodies, min(len(bodies), rng.randint(1, 3))), key=lambda p: -p[1][1])
    for cname, (verb, s, e) in picks:
        body = text[s:e]
        new_body, what = _mutate(body, rng)
        if new_body is None:
            continue
        text = text[:s] + new_body + text[e:]
        done.append(f"{cname}.{verb}: {what}")
    return (text, done) if done else None


def edit_header(text: str, found: list, rng: random.Random) -> tuple[str, list[str]] | None:
    """The text with one edit of a random controller's header (outside its
    plan bodies): a number changed (a range, an initial value, a budget, a
    level), a local added or written twice, a line of `pre` or `post`
    commented out; and what was done."""
    x = rng.choice(found)
    kinds = ["number", "number", "local", "twice", "pre"]
    rng.shuffle(kinds)
    for kind in kinds:
        done = _edit_header(text, x, kind, rng)
        if done is not None:
            return done
    return None


def _edit_header(text: str, x, kind: str, rng: random.Random) -> tuple[str, list[str]] | None:
    first = x.bodies[0][1] if x.bodies else x.end
    head_end = text.rfind("plan", x.start, first) if x.bodies else x.end
    head_end = head_end if head_end > x.start else first
    head = text[x.start:head_end]
    if kind == "number":
        nums = [n for n in _NUMBER.finditer(head)]
        if not nums:
            return None
        n = rng.choice(nums)
        new = str(int(float(n.group())) + rng.choice((-1, 1, 7))) if "." not in n.group() else n.group() + "5"
        at = x.start + n.start()
        return text[:at] + new + text[at + len(n.group()):], [f"{x.name} header: {n.group()} -> {new}"]
    brace = text.index("{", x.start) + 1
    if kind == "local":
        return text[:brace] + "\n    local fz_extra: i32 in 0..9 = 3" + text[brace:], [f"{x.name} header: a local"]
    lines = [m for m in re.finditer(r"^[ \t]*(local|pre|post)\b[^\n]*$", head, re.M)]
    if not lines:
        return None
    line = rng.choice(lines)
    at = x.start + line.start()
    if kind == "twice" and line.group(1) == "local":
        return text[:at] + line.group() + "\n" + text[at:], [f"{x.name} header: a local written twice"]
    if line.group().rstrip().endswith("}") and "{" in line.group():
        return text[:at] + "    // " + text[at:], [f"{x.name} header: a line commented out"]
    return None


def edit_declaration(text: str, found: list, rng: random.Random) -> tuple[str, list[str]] | None:
    """The text with one edit of a declaration outside the controllers: a
    number changed (a constant, a range, an initial value, a number in a
    function), a comparison turned round in a function, a member added to
    an enum, a constant added that nothing uses; and what was done."""
    inside = [(x.start, x.end) for x in found]
    lines = [m for m in _DECLARATION.finditer(text) if not any(s <= m.start() < e for s, e in inside)]
    kinds = ["number", "number", "compare", "member", "new"]
    rng.shuffle(kinds)
    for kind in kinds:
        if kind == "new":
            at = found[0].start
            return text[:at] + "const FZ_NEW: i32 = 5\n\n" + text[at:], ["a constant nothing uses"]
        if not lines:
            continue
        line = rng.choice(lines)
        head = line.group()
        if kind == "number":
            nums = list(_NUMBER.finditer(head))
            if not nums:
                continue
            n = rng.choice(nums)
            new = str(int(float(n.group())) + rng.choice((-1, 1, 7))) + (".5" if "." in n.group() else "")
            at = line.start() + n.start()
            return text[:at] + new + text[at + len(n.group()):], [f"`{head[:40]}`: {n.group()} -> {new}"]
        if kind == "compare" and line.group(1) == "fn":
            ops = list(_CMP_RE.finditer(head))
            if not ops:
                continue
            m = rng.choice(ops)
            at = line.start() + m.start()
            return text[:at] + _CMP[m.group()] + text[at + len(m.group()):], [f"`{head[:40]}`: {m.group()} -> {_CMP[m.group()]}"]
        if kind == "member" and line.group(1) == "enum" and "}" in head:
            at = line.start() + head.rindex("}")
            return text[:at].rstrip() + ", FZ_EXTRA " + text[at:], [f"`{head[:40]}`: a member added"]
    return None


def _mutate(body: str, rng: random.Random) -> tuple[str | None, str]:
    kind = rng.choice(("number", "number", "compare", "delete", "duplicate", "comment", "lines", "error", "allow", "type"))
    rules = list(_RULE.finditer(body))
    if kind == "number":
        nums = list(_NUMBER.finditer(body))
        if not nums:
            return None, ""
        m = rng.choice(nums)
        old = m.group()
        new = str(int(float(old)) + rng.choice((-1, 1, 7))) + (".5" if "." in old else "")
        return body[:m.start()] + new + body[m.end():], f"{old} -> {new}"
    if kind == "compare":
        ops = list(_CMP_RE.finditer(body))
        if not ops:
            return None, ""
        m = rng.choice(ops)
        return body[:m.start()] + _CMP[m.group()] + body[m.end():], f"{m.group()} -> {_CMP[m.group()]}"
    if not rules:
        return None, ""
    r = rng.choice(rules)
    if kind == "delete":
        return body[:r.start()] + body[r.end():], f"delete `{r.group().strip()[:40]}`"
    if kind == "duplicate":
        line = r.group()
        label = re.match(r"[ \t]*([A-Za-z_][A-Za-z0-9_]*):", line).group(1)  # type: ignore[union-attr]
        copy = line.replace(label + ":", label + "_dup:", 1)
        return body[:r.end()] + "\n" + copy + body[r.end():], f"duplicate {label}"
    if kind == "comment":
        return body[:r.start()] + "    // a comment\n    /* and { another } */\n" + body[r.start():], "comments"
    if kind == "lines":
        return body[:r.end()] + "\n\n\n" + body[r.end():], "blank lines"
    if kind == "error":
        line = r.group()
        new = re.sub(r"->\s*[^|;]+?\s*(\||;)", r"-> error(7) \1", line, count=1)
        return body[:r.start()] + new + body[r.end():], "next state -> error(7)"
    if kind == "allow":
        return body[:r.start()] + "    // rcsc: allow(W0515) the order is meant\n" + body[r.start():], "allow W0515"
    # A type error in a condition.
    line = r.group()
    new = line.replace(":", ": 1 + true and", 1)
    return body[:r.start()] + new + body[r.end():], "type error"


def normalized(report: str):
    """A JSON report without the findings of a solver question that ran out
    of wall-clock time (the machine's load decides those).  Everything else,
    witnesses included, must agree: each plan is analysed in a z3 context of
    its own (rcsc.checks.smt, `own_context`), so what z3 answers does not
    depend on what the process asked before."""
    try:
        doc = json.loads(report)
    except ValueError:
        return report
    return [d for d in doc["diagnostics"] if not (d["code"] == "W0518" and any("canceled" in n or "timeout" in n for n in d["notes"]))]


def normalized_sarif(report: str):
    try:
        doc = json.loads(report)
    except ValueError:
        return report
    results = doc["runs"][0]["results"]
    return [r for r in results if not (r["ruleId"] == "W0518" and ("canceled" in json.dumps(r) or "timeout" in json.dumps(r)))]


def _check(folder: Path, name: str, *extra: str, env: dict | None = None) -> str:
    out = subprocess.run([sys.executable, "-m", "rcsc", "check", name, *extra], cwd=folder, capture_output=True, text=True,
                         env=env, timeout=600)
    if out.returncode not in (0, 1) or "Traceback" in out.stderr:
        return f"exit {out.returncode}\n{out.stderr}"
    return out.stdout


def run_seed(seed: int, work: Path) -> dict:
    rng = random.Random(seed)
    text = design_for(seed)
    edited = edit(text, rng)
    if edited is None:
        return {"seed": seed, "skipped": True}
    new_text, what = edited
    a, b = work / f"s{seed}a", work / f"s{seed}b"
    a.mkdir()
    (a / "d.rcs").write_text(text, encoding="utf-8")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("RCSC_NO_CACHE", None)
    _check(a, "d.rcs", "--format", "short", env=env)
    shutil.copytree(a, b)
    (a / "d.rcs").write_text(new_text, encoding="utf-8")
    (b / "d.rcs").write_text(new_text, encoding="utf-8")
    # The probe asks the re-check whether it applies.  It runs in both
    # copies, so that both solver caches then hold the same answers for the
    # edited plans (a partial run that finds it does not apply has asked the
    # solver already; its answers stay in the cache, as they would for a
    # user).
    probe_code = ("from rcsc.checks import incremental; r = incremental.recheck('d.rcs', False, '.rcsc-cache'); "
                  "print(r is not None, incremental.last_miss)")
    probe = subprocess.run([sys.executable, "-c", probe_code], cwd=a, capture_output=True, text=True, env=env, timeout=600)
    subprocess.run([sys.executable, "-c", probe_code], cwd=b, capture_output=True, text=True, env=env, timeout=600)
    used = probe.stdout.startswith("True")
    miss = probe.stdout.strip().split(" ", 1)[-1] if not used else ""
    inc = _check(a, "d.rcs", "--format", "json", env=env)
    full_env = dict(env, RCSC_INCREMENTAL="0")
    full = _check(b, "d.rcs", "--format", "json", env=full_env)
    exact = inc == full
    ok = exact or normalized(inc) == normalized(full)
    if ok:
        sa, sb = _check(a, "d.rcs", "--format", "sarif", env=env), _check(b, "d.rcs", "--format", "sarif", env=full_env)
        ok = sa == sb or normalized_sarif(sa) == normalized_sarif(sb)
    return {"seed": seed, "used": used, "miss": miss, "ok": ok, "exact": exact, "edits": what, "inc": inc, "full": full}


def places(result) -> list:
    """Each finding of a `rcsc.driver.CheckResult`, whole: code, severity,
    message, notes, data (the witness among them) and the places of it and
    of its labels."""
    def at(span):
        return None if span is None else (span.file.path, span.start, span.end, span.line, span.col)

    return sorted((d.code, str(d.severity), d.message, at(d.span), [(at(lab.span), lab.message) for lab in d.labels], list(d.notes),
                   json.dumps(d.data, sort_keys=True, default=repr)) for d in result.diags.items)


def edit_between(text: str, rng: random.Random) -> tuple[str, list[str]] | None:
    """The text with a doc comment, a plain comment or blank lines written
    before a random controller (outside every plan: the next check is a
    full one, and what it keeps must not outlive it)."""
    found = it.controller_items(text)
    if not found:
        return None
    x = rng.choice(found)
    kind = rng.choice(("doc", "blank", "comment"))
    written = {"doc": "/// documented\n", "blank": "\n\n", "comment": "// plain\n"}[kind]
    return text[:x.start] + written + text[x.start:], [f"{kind} before {x.name}"]


def successive_edits(text: str, rng: random.Random, edits: int):
    """Up to `edits` successive random edits of `text` (mostly inside plans,
    a quarter of the time before a controller): each edited text and what
    was done."""
    for _ in range(edits):
        edited = edit_between(text, rng) if rng.random() < 0.25 else edit(text, rng)
        if edited is None:
            return
        text = edited[0]
        yield text, "; ".join(edited[1])


def run_seed_in_memory(seed: int, work: Path, edits: int = 8) -> dict:
    """The language server's way (`--memory`): one process keeps the last
    check, the solver's answers and the unchanged controllers' syntax trees
    in memory (`incremental.memory_stores`); `edits` successive random edits
    of the seed's design (mostly inside plans, sometimes before a
    controller) are each re-checked that way and compared, place for place,
    with a full check of the same text, finding for finding."""
    import random

    from rcsc.checks import cache, incremental
    from rcsc.driver import check_path

    folder = work / f"m{seed}"
    folder.mkdir()
    path = folder / "d.rcs"
    text = design_for(seed)
    path.write_text(text, encoding="utf-8")
    real = os.path.realpath(path)
    memory = incremental.memory_stores(cache.MemoryStore())
    check_path(str(path), memory=memory)
    rng = random.Random(seed)
    used = kept = 0
    done: list[str] = []
    for text, what in successive_edits(text, rng, edits):
        done.append(what)
        result = check_path(str(path), overlay={real: text}, memory=memory)
        if not getattr(result, "partial", False):
            continue  # checked in full (the edit changed what others see): nothing here was kept
        used += 1
        kept += incremental.last_kept
        full = check_path(str(path), overlay={real: text}, guard_store=memory["guards"])
        if places(result) != places(full):
            path.write_text(text, encoding="utf-8")
            return {"seed": seed, "used": used, "kept": kept, "ok": False, "edits": done}
    return {"seed": seed, "used": used, "kept": kept, "ok": True, "edits": done}


def main_memory(lo: int, hi: int, keep: str | None, verbose: bool) -> int:
    used = kept = bad = checks = 0
    with tempfile.TemporaryDirectory(prefix="incr-fuzz-") as tmp:
        for seed in range(lo, hi + 1):
            r = run_seed_in_memory(seed, Path(tmp))
            used, kept, checks = used + r["used"], kept + r["kept"], checks + len(r["edits"])
            if verbose:
                print(f"seed {seed}: {r['used']} of {len(r['edits'])} re-checks in part, {r['kept']} kept trees used")
            if not r["ok"]:
                bad += 1
                print(f"seed {seed}: DISAGREE after {r['edits']}")
                if keep:
                    shutil.copytree(Path(tmp) / f"m{seed}", Path(keep) / f"m{seed}", dirs_exist_ok=True)
    print(f"{hi - lo + 1} designs, {checks} successive edits in memory, {used} re-checked in part, "
          f"{kept} kept controller trees used, {bad} disagreements")
    return 1 if bad else 0


def run_seed_daemon(seed: int, work: Path, edits: int = 6) -> dict:
    """The check daemon's way (`--daemon`): successive random edits of the
    seed's design written to disk, each checked by `rcsc check --daemon`
    (the daemon keeps the last check and the unchanged controllers' trees)
    and compared with `rcsc check --no-cache` in a fresh process: the same
    JSON report (as `normalized` says)."""
    from rcsc import daemon

    folder = work / f"d{seed}"
    folder.mkdir()
    path = folder / "d.rcs"
    text = design_for(seed)
    path.write_text(text, encoding="utf-8")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    here = os.getcwd()
    os.chdir(folder)
    try:
        daemon.request(["d.rcs", "--format", "json"])
        rng = random.Random(seed)
        used = 0
        done: list[str] = []
        for text, what in successive_edits(text, rng, edits):
            done.append(what)
            path.write_text(text, encoding="utf-8")
            got = daemon.request(["d.rcs", "--format", "json"])
            used += got["answers"] == ["partial"]
            fresh = _check(folder, "d.rcs", "--format", "json", "--no-cache", env=env)
            if got["stdout"] != fresh and normalized(got["stdout"]) != normalized(fresh):
                return {"seed": seed, "used": used, "ok": False, "edits": done}
    finally:
        os.chdir(here)
    return {"seed": seed, "used": used, "ok": True, "edits": done}


def main_daemon(lo: int, hi: int, keep: str | None, verbose: bool) -> int:
    from rcsc import daemon

    used = bad = checks = 0
    with tempfile.TemporaryDirectory(prefix="incr-fuzz-") as tmp:
        os.environ["RCSC_DAEMON_DIR"] = str(Path(tmp) / "sockets")
        os.environ.pop("RCSC_NO_CACHE", None)
        os.environ.pop("RCSC_INCREMENTAL", None)
        try:
            for seed in range(lo, hi + 1):
                r = run_seed_daemon(seed, Path(tmp))
                used, checks = used + r["used"], checks + len(r["edits"])
                if verbose:
                    print(f"seed {seed}: {r['used']} of {len(r['edits'])} answered in part")
                if not r["ok"]:
                    bad += 1
                    print(f"seed {seed}: DISAGREE after {r['edits']}")
                    if keep:
                        shutil.copytree(Path(tmp) / f"d{seed}", Path(keep) / f"d{seed}", dirs_exist_ok=True)
        finally:
            daemon.stop()
    print(f"{hi - lo + 1} designs, {checks} successive edits checked by the daemon, {used} re-checked in part, {bad} disagreements")
    return 1 if bad else 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0..19", help="A..B (inclusive)")
    ap.add_argument("--keep", help="copy the folders of disagreeing seeds here")
    ap.add_argument("-v", "--verbose", action="store_true", help="one line per seed: the path taken and the edits")
    ap.add_argument("--memory", action="store_true", help="the language server's way: successive edits re-checked in one process")
    ap.add_argument("--daemon", action="store_true", help="successive edits checked by `rcsc check --daemon`, against fresh processes")
    ap.add_argument("--headers", type=float, metavar="RATE", help="how often an edit is one of a header (default 0.2)")
    ap.add_argument("--declarations", type=float, metavar="RATE",
                    help="how often an edit is one of a declaration outside the controllers (default 0.15)")
    args = ap.parse_args(argv)
    global HEADER_RATE, DECLARATION_RATE
    if args.headers is not None:
        HEADER_RATE = args.headers
    if args.declarations is not None:
        DECLARATION_RATE = args.declarations
    lo, hi = (int(x) for x in args.seeds.split(".."))
    if args.memory:
        return main_memory(lo, hi, args.keep, args.verbose)
    if args.daemon:
        return main_daemon(lo, hi, args.keep, args.verbose)
    used = bad = skipped = exact = 0
    with tempfile.TemporaryDirectory(prefix="incr-fuzz-") as tmp:
        for seed in range(lo, hi + 1):
            r = run_seed(seed, Path(tmp))
            if r.get("skipped"):
                skipped += 1
                continue
            used += r["used"]
            exact += r["exact"]
            if args.verbose:
                print(f"seed {seed}: {'incremental' if r['used'] else 'full (' + r['miss'] + ')'}; {'; '.join(r['edits'])}")
            if not r["ok"]:
                bad += 1
                print(f"seed {seed}: DISAGREE after {r['edits']}")
                if args.keep:
                    for suffix in "ab":
                        shutil.copytree(Path(tmp) / f"s{seed}{suffix}", Path(args.keep) / f"s{seed}{suffix}", dirs_exist_ok=True)
                    Path(args.keep, f"s{seed}.json").write_text(json.dumps(r, indent=1), encoding="utf-8")
    n = hi - lo + 1 - skipped
    print(f"{n} edited designs, {used} re-checked incrementally, {bad} disagreements ({skipped} skipped; "
          f"{exact} reports equal byte for byte, the others after leaving out solver questions out of time)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
