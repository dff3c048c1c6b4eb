"""Runs on a shared machine: parallel runs and stop signals, as JSON (issue 19's figures).

``python benchmarks/shared_machine.py parallel [--runs 8]`` runs the quickstart once alone
and then ``--runs`` times at once, none with ``--bus`` (each run takes a portable-bus
channel of its own), all with the same seed, and reports per run its exit code, whether it
passed, the channel it printed, and whether its ``telemetry.csv`` equals the run alone's
byte for byte.

``python benchmarks/shared_machine.py signals [--runs 20]`` starts ``--runs`` lockstep and
``--runs`` realtime quickstart runs one after the other, each in its own process group, and
sends SIGTERM to the group at a random moment (seeded: ``--seed``) after the run reports
progress; it reports per run the exit code (143 expected), whether ``summary.json`` is
valid JSON ending ``SIGTERM``, and what was left behind: pid files or the disk reserve in
the run folder, sockets in the private runtime directory, processes of the run still
alive.

Each run has a private ``XDG_RUNTIME_DIR`` (the portable bus's home) and a scratch
folder. Wall times depend on the machine's load; the verdicts do not.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
QUICKSTART = REPO / "scenarios" / "quickstart.toml"
CHANNEL_MARK = "thruster-hil: bus "  # the console line naming a run's own channel
PROGRESS_MARK = "progress"
SIGTERM_EXIT = 128 + signal.SIGTERM
RUN_TIMEOUT_S = 900.0  # a hang guard
SEED = 19
DURATIONS_S = {"lockstep": 60.0, "realtime": 8.0}
# the moment of the signal after the first progress line [s of wall time]
SIGNAL_WINDOW_S = {"lockstep": 2.5, "realtime": 6.0}


def _start(out: Path, xdg: Path, extra: list[str], group: bool = False) -> subprocess.Popen[str]:
    env = dict(os.environ, XDG_RUNTIME_DIR=str(xdg))
    return subprocess.Popen(
        [sys.executable, "-m", "bench.operator.cli", "run", str(QUICKSTART), "--seed", "5",
         "--out", str(out), *extra], cwd=REPO, env=env, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True, start_new_session=group)


def _channel(err: str) -> str | None:
    for line in err.splitlines():
        if line.startswith(CHANNEL_MARK):
            return line[len(CHANNEL_MARK):].split()[0]
    return None


def _summary(out: Path) -> dict[str, Any] | None:
    try:
        s = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return s if isinstance(s, dict) else None


def parallel(runs: int) -> dict[str, Any]:
    """The quickstart alone, then ``runs`` at once: telemetry equal, all passed."""
    scratch = Path(tempfile.mkdtemp(prefix="thil-par-"))
    xdg = scratch / "xdg"
    xdg.mkdir()
    t0 = time.monotonic()
    alone = _start(scratch / "alone", xdg, [])
    alone.communicate(timeout=RUN_TIMEOUT_S)
    alone_s = time.monotonic() - t0
    reference = (scratch / "alone" / "telemetry.csv").read_bytes()
    t0 = time.monotonic()
    procs = [_start(scratch / f"p{i}", xdg, []) for i in range(runs)]
    rows = []
    for i, p in enumerate(procs):
        _, err = p.communicate(timeout=RUN_TIMEOUT_S)
        out = scratch / f"p{i}"
        s = _summary(out) or {}
        tel = out / "telemetry.csv"
        rows.append({"exit_code": p.returncode, "passed": s.get("passed"),
                     "channel": _channel(err),
                     "telemetry_equals_alone": tel.exists() and tel.read_bytes() == reference,
                     "realtime_factor": s.get("realtime_factor")})
    return {
        "runs": runs, "alone": {"exit_code": alone.returncode, "wall_s": round(alone_s, 1)},
        "parallel_wall_s": round(time.monotonic() - t0, 1),
        "all_passed": all(r["exit_code"] == 0 and r["passed"] for r in rows),
        "all_equal_alone": all(r["telemetry_equals_alone"] for r in rows),
        "distinct_channels": len({r["channel"] for r in rows}),
        "per_run": rows,
    }


def _alive(pgid: int) -> list[int]:
    """Processes still in process group ``pgid``."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid:
            out.append(int(stat.parent.name))
    return out


def _one_stop(scratch: Path, k: int, mode: str, rng: random.Random) -> dict[str, Any]:
    out, xdg = scratch / f"{mode}-{k}", scratch / f"xdg-{mode}-{k}"
    xdg.mkdir()
    p = _start(out, xdg, ["--mode", mode, "--duration", str(DURATIONS_S[mode]), "--bus",
                          f"hilbus:sig{os.getpid()}{mode[0]}{k}"], group=True)
    assert p.stderr is not None
    for line in p.stderr:
        if line.startswith(PROGRESS_MARK):
            break
    delay_s = rng.uniform(0.0, SIGNAL_WINDOW_S[mode])
    time.sleep(delay_s)  # the random moment of the stop, not a wait for a condition
    os.killpg(p.pid, signal.SIGTERM)
    _, err = p.communicate(timeout=RUN_TIMEOUT_S)
    s = _summary(out)
    left = [f.name for f in out.glob("*.pid")] + [f.name for f in out.glob(".space-*")]
    sockets = [str(f.relative_to(xdg)) for f in xdg.rglob("*") if f.is_socket()]
    return {
        "mode": mode, "delay_s": round(delay_s, 3), "exit_code": p.returncode,
        "valid_summary": s is not None and s.get("ended") in ("SIGTERM", "completed"),
        "ended": None if s is None else s.get("ended"),
        "sim_time_s": None if s is None else s.get("sim_time_s"),
        "leftover_files": left, "leftover_sockets": sockets, "alive": _alive(p.pid),
        "traceback": "Traceback" in err,
    }


def signals(runs: int, seed: int) -> dict[str, Any]:
    """``runs`` lockstep and ``runs`` realtime runs, each stopped by SIGTERM at random."""
    rng = random.Random(seed)
    scratch = Path(tempfile.mkdtemp(prefix="thil-sig-"))
    rows = [_one_stop(scratch, k, mode, rng) for mode in ("lockstep", "realtime")
            for k in range(runs)]
    clean = [r for r in rows if r["valid_summary"] and not r["leftover_files"]
             and not r["leftover_sockets"] and not r["alive"] and not r["traceback"]
             and r["exit_code"] in (SIGTERM_EXIT, 0, 1)]
    return {"runs": len(rows), "valid_and_clean": len(clean),
            "stopped_by_sigterm": sum(r["ended"] == "SIGTERM" for r in rows),
            "per_run": rows}


def main(argv: list[str] | None = None) -> None:
    """Command line: print the JSON figures."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    pp = sub.add_parser("parallel", help="runs at once without --bus vs a run alone")
    pp.add_argument("--runs", type=int, default=8, help="runs at once (default 8)")
    sp = sub.add_parser("signals", help="SIGTERM at a random moment")
    sp.add_argument("--runs", type=int, default=20, help="runs per mode (default 20)")
    sp.add_argument("--seed", type=int, default=SEED, help=f"moments' seed (default {SEED})")
    args = ap.parse_args(argv)
    result = parallel(args.runs) if args.what == "parallel" else signals(args.runs, args.seed)
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
