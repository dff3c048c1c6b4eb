"""Runs on a shared machine: parallel runs and stop signals, as JSON (issue 19's figures).

``python benchmarks/shared_machine.py parallel [--runs 8]`` runs the quickstart once alone
and then ``--runs`` times at once, none with ``--bus`` (each run takes a portable-bus
channel of its own), all with the same seed, and reports per run its exit code, whether it
passed, the channel it printed, and whether its ``telemetry.csv`` equals the run alone's
byte for byte.

``python benchmarks/shared_machine.py second [--repeats 5]`` starts a realtime run on a
named hilbus channel and, once it runs, a second run on the same channel; it reports how
long until the second was refused and until the first's console named a second sender
(seconds from the second's start), and what each summary says.

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
import threading
import time
from pathlib import Path
from typing import Any

from bench.results.record import read_lines, run_file

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


def _telemetry(run_dir: Path) -> str | None:
    """The text of a run's telemetry, plain or compressed (None if it has none)."""
    path = run_file(run_dir, "telemetry.csv")
    return "".join(read_lines(path)) if path.exists() else None


def _start(out: Path, xdg: Path, extra: list[str], group: bool = False) -> subprocess.Popen[str]:
    env = dict(os.environ, XDG_RUNTIME_DIR=str(xdg))
    return subprocess.Popen(
        [sys.executable, "-m", "bench.operator.entry", "run", str(QUICKSTART), "--seed", "5",
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
    reference = _telemetry(scratch / "alone")
    t0 = time.monotonic()
    procs = [_start(scratch / f"p{i}", xdg, []) for i in range(runs)]
    rows = []
    for i, p in enumerate(procs):
        _, err = p.communicate(timeout=RUN_TIMEOUT_S)
        out = scratch / f"p{i}"
        s = _summary(out) or {}
        rows.append({"exit_code": p.returncode, "passed": s.get("passed"),
                     "channel": _channel(err),
                     "telemetry_equals_alone": _telemetry(out) == reference,
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


def _timestamped(stream: Any, into: list[tuple[float, str]]) -> None:
    """Append each line of ``stream`` to ``into`` with the time it was read."""
    for line in stream:
        into.append((time.monotonic(), line))


def second_bench(repeats: int) -> dict[str, Any]:
    """A second run started on the named bus of a running one, ``repeats`` times: how long
    until the second is refused and until the first's console names a second sender [s],
    and whether both summaries say so."""
    rows = []
    for k in range(repeats):
        scratch = Path(tempfile.mkdtemp(prefix="thil-2nd-"))
        xdg = scratch / "xdg"
        xdg.mkdir()
        bus = f"hilbus:second{os.getpid()}x{k}"
        first = _start(scratch / "first", xdg, ["--mode", "realtime", "--duration", "6",
                                                "--bus", bus])
        assert first.stderr is not None
        lines: list[tuple[float, str]] = []
        reader = threading.Thread(target=_timestamped, args=(first.stderr, lines), daemon=True)
        reader.start()
        while not any(ln.startswith(PROGRESS_MARK) for _, ln in lines):
            if first.poll() is not None:
                break
            time.sleep(0.05)  # polling the reader thread's list
        t0 = time.monotonic()
        second = _start(scratch / "second", xdg, ["--bus", bus])
        second.communicate(timeout=RUN_TIMEOUT_S)
        refused_s = time.monotonic() - t0
        first.wait(timeout=RUN_TIMEOUT_S)
        reader.join(timeout=RUN_TIMEOUT_S)
        told = [t for t, ln in lines if t >= t0 and "second sender" in ln]
        s1, s2 = _summary(scratch / "first") or {}, _summary(scratch / "second") or {}
        rows.append({
            "second_exit_code": second.returncode, "second_refused_after_s": round(refused_s, 3),
            "first_console_after_s": round(told[0] - t0, 3) if told else None,
            "first_summary_compromised": (s1.get("compromised") or {}).get("messages"),
            "second_summary_ended": s2.get("ended"), "second_heard": s2.get("second_sender_heard"),
        })
    return {"repeats": repeats, "per_run": rows,
            "max_refused_after_s": max(r["second_refused_after_s"] for r in rows),
            "max_first_console_after_s": max((r["first_console_after_s"] or float("inf"))
                                             for r in rows)}


def main(argv: list[str] | None = None) -> None:
    """Command line: print the JSON figures."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    pp = sub.add_parser("parallel", help="runs at once without --bus vs a run alone")
    pp.add_argument("--runs", type=int, default=8, help="runs at once (default 8)")
    sp = sub.add_parser("signals", help="SIGTERM at a random moment")
    sp.add_argument("--runs", type=int, default=20, help="runs per mode (default 20)")
    sp.add_argument("--seed", type=int, default=SEED, help=f"moments' seed (default {SEED})")
    sb = sub.add_parser("second", help="a second run on the named bus of a running one")
    sb.add_argument("--repeats", type=int, default=5, help="times (default 5)")
    args = ap.parse_args(argv)
    result = (parallel(args.runs) if args.what == "parallel"
              else signals(args.runs, args.seed) if args.what == "signals"
              else second_bench(args.repeats))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
