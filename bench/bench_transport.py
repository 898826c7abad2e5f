"""The DDS exchange between CPUs against shared memory: added latency and per-cycle cost.

Builds tests/sim/multicpu.rcs (a planner CPU and a servo CPU; commands,
status and Global Memory cross both ways) with both CPUs on a heartbeat of
1 ms and of 10 ms, as C with `--transport shm` and `--transport dds`, and
runs each build's launcher on this host (DDS on the loopback interface, a
random domain id):

- lockstep, N base ticks as fast as the CPUs go: every cycle a CPU waits
  for the other's sample of the cycle before, so the wall time per tick is
  the cost of one exchange round trip; DDS minus shared memory is the
  latency DDS adds to an exchange;
- real time, 2 s on the heartbeat: the longest cycle of each CPU (its work
  including the fetch of the other's sample and the publication of its own),
  the cycle overruns and the missing samples from the CPUs' timing tables.

    python bench/bench_transport.py                   # 1 ms and 10 ms, 5000 lockstep ticks
    python bench/bench_transport.py --ticks 20000 --keep /tmp/bt
"""

from __future__ import annotations

import argparse
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DESIGN = ROOT / "tests" / "sim" / "multicpu.rcs"
LOOPBACK = """<CycloneDDS><Domain><General><Interfaces><NetworkInterface name="lo"/></Interfaces>
<AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex>
<Peers><Peer address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>"""


def design_text(heartbeat_ms: int) -> str:
    """Both CPUs on `heartbeat_ms`, TOP every other cycle, budgets that fit."""
    text = DESIGN.read_text(encoding="utf-8")
    text = text.replace("heartbeat 20 ms", f"heartbeat {heartbeat_ms} ms").replace("heartbeat 10 ms", f"heartbeat {heartbeat_ms} ms")
    text = text.replace("period 40 ms", f"period {2 * heartbeat_ms} ms")
    return re.sub(r"budget \d+ ms", "budget 100 us", text)


def build(src: Path, transport: str, out: Path) -> Path:
    r = subprocess.run([sys.executable, "-c", "from rcsc.cli import entry; entry()", "build", str(src), "--target", "c", "--transport", transport, "-o", str(out)],
                       capture_output=True, text=True, cwd=ROOT)
    if r.returncode != 0:
        sys.exit(f"rcsc build failed:\n{r.stderr}")
    r = subprocess.run(["make", "-s", "CFLAGS=-O2"], cwd=out, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"make failed:\n{r.stderr}")
    return out / "run_twocpu"


def run(launcher: Path, env: dict, *args: str) -> tuple[float, str]:
    t0 = time.monotonic()
    r = subprocess.run([str(launcher), *args], capture_output=True, text=True, env=env, timeout=600, stdin=subprocess.DEVNULL)
    took = time.monotonic() - t0
    if r.returncode != 0:
        sys.exit(f"{launcher} {' '.join(args)} failed:\n{r.stderr}")
    return took, r.stderr


def timing(stderr: str) -> tuple[float, int, int]:
    """(the longest cycle of any CPU in us, cycle overruns, missing samples)
    from the CPUs' timing tables (their lines may interleave)."""
    work = [float(x) for x in re.findall(r"^cycles: \d+, max work ([\d.]+) us", stderr, re.M)]
    overruns = [int(x) for x in re.findall(r"^cycles: .*, (\d+) cycle overruns?$", stderr, re.M)]
    missing = [int(x) for x in re.findall(r"^missing samples: (\d+)", stderr, re.M)]
    if len(work) != 2 or len(overruns) != 2 or len(missing) != 2:
        sys.exit(f"cannot read the two timing tables:\n{stderr}")
    return max(work), sum(overruns), sum(missing)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ticks", type=int, default=5000, help="base ticks of each lockstep run")
    ap.add_argument("--keep", metavar="DIR", help="build here and keep it")
    args = ap.parse_args()
    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench-transport-"))
    work.mkdir(parents=True, exist_ok=True)
    config = work / "loopback.xml"
    config.write_text(LOOPBACK, encoding="utf-8")
    domain = str(random.SystemRandom().randint(1, 232))
    env = dict(os.environ, CYCLONEDDS_URI=config.as_uri())
    rows = []
    for hb in (1, 10):
        src = work / f"twocpu_{hb}ms.rcs"
        src.write_text(design_text(hb), encoding="utf-8")
        launchers = {t: build(src, t, work / f"{t}-{hb}ms") for t in ("shm", "dds")}
        extra = {"shm": [], "dds": ["--domain", domain]}
        for t, launcher in launchers.items():
            # Start-up and discovery are the same for any length: timed on a short run and taken away.
            short, _ = run(launcher, env, "--lockstep", "--no-timing", "--cycles", "10", *extra[t])
            took, _ = run(launcher, env, "--lockstep", "--no-timing", "--cycles", str(args.ticks + 10), *extra[t])
            per_tick = max(took - short, 0.0) / args.ticks * 1e6
            _, err = run(launcher, env, "--cycles", str(2000 // hb), *extra[t])
            rows.append((hb, t, per_tick, timing(err)))
    print(f"{'heartbeat':>9} {'transport':>9} {'lockstep us/tick':>17} {'real time: max work us':>23} {'overruns':>9} {'missing':>8}")
    for hb, t, per_tick, (work_us, overruns, missing) in rows:
        print(f"{hb:>6} ms {t:>9} {per_tick:>17.1f} {work_us:>23.1f} {overruns:>9} {missing:>8}")
    by = {(hb, t): (per, tab[0]) for hb, t, per, tab in rows}
    for hb in (1, 10):
        (ps, ws), (pd, wd) = by[(hb, "shm")], by[(hb, "dds")]
        print(f"{hb} ms heartbeat: DDS adds {pd - ps:.1f} us per lockstep exchange round (shm {ps:.1f}, dds {pd:.1f}) "
              f"and {wd - ws:.1f} us to the longest real-time cycle (shm {ws:.1f}, dds {wd:.1f})")
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
