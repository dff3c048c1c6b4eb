"""Memory and run-folder growth of long lockstep runs, as JSON (issue 19's resource figures).

``python benchmarks/run_resources.py [--durations 600 7200] [--scenario FILE]`` runs
``thruster-hil run SCENARIO --duration D`` once per duration, each on a private hilbus
channel and in a scratch run folder, and samples every ``--every`` wall seconds, from
``/proc``, the resident memory (VmRSS) of each process of the run: the supervisor (the
command), the bench (its child) and the flight software (the bench's child), together
with the simulated time reached (the last row of ``telemetry.csv``, or of the default
compressed ``telemetry.csv.gz``, followed as it grows). It prints one JSON
object per run:

- ``rss_mb``: per process, the RSS at the first sample at or after ``--from-s`` simulated
  seconds (default 60), at the last sample taken while the simulation still advanced and
  before :data:`IN_RUN_FRACTION` of the duration (``at_end_of_sim``: the run loop, not the
  end-of-run work of summary and plots, which flushes the last telemetry rows), the growth
  between these two, and the highest RSS (VmHWM, the kernel's own high-water mark, so a
  short peak between two samples is counted too, the end-of-run work's included);
- ``peak_rss_mb_any_process``: the largest RSS any process of the run reached, from the
  kernel's accounting of the waited-for descendants (``getrusage(RUSAGE_CHILDREN)``);
- ``folder``: the run folder's size and its bytes per simulated second, per file too;
- ``exit_code``, ``wall_s``, ``realtime_factor``.

Figures are from one machine at one time: quote medians and compare within one
invocation (these machines are shared and noisy).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import uuid
import zlib
from pathlib import Path
from typing import Any

from bench.results.record import GZIP_WBITS

REPO = Path(__file__).resolve().parents[1]
QUICKSTART = REPO / "scenarios" / "quickstart.toml"
KB_PER_MB = 1024.0
BYTES_PER_KB = 1024.0
ROLES = ("supervisor", "bench", "flight_sw")
IN_RUN_FRACTION = 0.99  # samples past this share of the duration may be the end-of-run work


def _status_kb(pid: int, field: str) -> float | None:
    """A ``/proc/PID/status`` field in kB (VmRSS, VmHWM); None once the process is gone."""
    try:
        text = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return None
    for line in text.splitlines():
        if line.startswith(field + ":"):
            return float(line.split()[1])
    return None


def _children(pid: int) -> list[int]:
    """The direct children of ``pid`` (Linux: /proc/PID/task/*/children)."""
    out: list[int] = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            out += [int(c) for c in (task / "children").read_text().split()]
        except OSError:
            continue
    return out


def _tree(root: int) -> dict[str, int]:
    """The run's processes by role: the command, its child the bench, the bench's child."""
    roles = {"supervisor": root}
    bench = _children(root)
    if bench:
        roles["bench"] = bench[0]
        fsw = _children(bench[0])
        if fsw:
            roles["flight_sw"] = fsw[0]
    return roles


class TelemetryTail:
    """The simulated time of the last complete row of a run's telemetry, followed as the
    file grows: plain ``telemetry.csv`` or the default compressed ``telemetry.csv.gz``
    (decompressed incrementally, only what was added since the last look)."""

    def __init__(self, run_dir: Path) -> None:
        self.run_dir = run_dir
        self.path: Path | None = None
        self.offset = 0
        self.unpack: Any = None
        self.rest = b""  # text after the last newline seen (an incomplete row)
        self.t_s = 0.0

    def sim_time_s(self) -> float:
        """The time of the newest complete row (0 before one)."""
        if self.path is None:
            for name in ("telemetry.csv", "telemetry.csv.gz"):
                if (self.run_dir / name).exists():
                    self.path = self.run_dir / name
                    self.unpack = zlib.decompressobj(GZIP_WBITS) if name.endswith(".gz") else None
            if self.path is None:
                return 0.0
        try:
            with open(self.path, "rb") as f:
                f.seek(self.offset)
                data = f.read()
        except OSError:
            return self.t_s
        self.offset += len(data)
        text = self.rest + (self.unpack.decompress(data) if self.unpack is not None else data)
        lines = text.split(b"\n")
        self.rest = lines[-1]
        for line in reversed(lines[:-1]):
            try:
                self.t_s = float(line.split(b",", 1)[0])
                break
            except ValueError:
                continue
        return self.t_s


def _folder(out: Path, duration_s: float) -> dict[str, Any]:
    files = {p.name: p.stat().st_size for p in sorted(out.iterdir()) if p.is_file()}
    total = sum(files.values())
    return {
        "total_mb": round(total / BYTES_PER_KB / KB_PER_MB, 3),
        "kb_per_sim_s": round(total / BYTES_PER_KB / duration_s, 3),
        "kb_per_sim_s_by_file": {k: round(v / BYTES_PER_KB / duration_s, 3)
                                 for k, v in files.items()},
    }


def measure(scenario: Path, duration_s: float, from_s: float, every_s: float,
            extra: list[str]) -> dict[str, Any]:
    """One run of ``duration_s`` simulated seconds, sampled as the module docstring says."""
    scratch = Path(tempfile.mkdtemp(prefix="thil-res-"))
    out = scratch / "run"
    env = dict(os.environ, XDG_RUNTIME_DIR=str(scratch))
    cmd = [sys.executable, "-m", "bench.operator.entry", "run", str(scenario), "--duration",
           str(duration_s), "--bus", f"hilbus:res{uuid.uuid4().hex[:8]}", "--out", str(out),
           *extra]
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, cwd=REPO, env=env, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    first: dict[str, float] = {}
    last: dict[str, float] = {}
    hwm: dict[str, float] = {}
    t_before = -1.0
    tail = TelemetryTail(out)
    while p.poll() is None:
        t_sim = tail.sim_time_s()
        advancing = t_sim > t_before
        t_before = t_sim
        for role, pid in _tree(p.pid).items():
            rss, peak = _status_kb(pid, "VmRSS"), _status_kb(pid, "VmHWM")
            if rss is None or peak is None:
                continue
            if from_s <= t_sim < IN_RUN_FRACTION * duration_s and advancing:
                first.setdefault(role, rss)
                last[role] = rss
            hwm[role] = max(hwm.get(role, 0.0), peak)
        time.sleep(every_s)  # the sampling period, not a wait for a condition
    wall_s = time.monotonic() - t0
    children_peak_kb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss

    def mb(kb: float | None) -> float | None:
        return None if kb is None else round(kb / KB_PER_MB, 1)

    rss_mb = {role: {"at_from_s": mb(first.get(role)), "at_end_of_sim": mb(last.get(role)),
                  "growth": mb(last[role] - first[role]) if role in first else None,
                  "highest": mb(hwm.get(role))} for role in ROLES}
    result = {
        "duration_s": duration_s,
        "from_s": from_s,
        "exit_code": p.returncode,
        "wall_s": round(wall_s, 1),
        "realtime_factor": round(duration_s / wall_s, 1),
        "rss_mb": rss_mb,
        "peak_rss_mb_any_process": mb(children_peak_kb),
        "folder": _folder(out, duration_s) if out.is_dir() else None,
    }
    return result


def main(argv: list[str] | None = None) -> None:
    """Command line: print the JSON figures of each duration."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--durations", type=float, nargs="+", default=[600.0, 7200.0],
                    help="simulated seconds of each run (default 600 7200)")
    ap.add_argument("--scenario", type=Path, default=QUICKSTART,
                    help="scenario file (default the quickstart)")
    ap.add_argument("--from-s", type=float, default=60.0,
                    help="simulated time from which growth is counted (default 60)")
    ap.add_argument("--every", type=float, default=0.25,
                    help="sampling period [wall s] (default 0.25)")
    ap.add_argument("extra", nargs="*", help="further options of thruster-hil run, after --")
    args = ap.parse_args(argv)
    runs = [measure(args.scenario, d, args.from_s, args.every, args.extra)
            for d in args.durations]
    print(json.dumps({"scenario": str(args.scenario), "runs": runs}, indent=2))


if __name__ == "__main__":
    main()
