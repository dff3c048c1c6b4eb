"""Hostile frames against a live lockstep run: the figures behind issue 18's acceptance line.

``python benchmarks/hostile_frames.py [--frames 100000] [--duration 600]`` runs the
quickstart in lockstep three times on private buses, with the same seed: alone; with a
second process sending ``--frames`` noise frames (no valid E2E protection: unknown and
extended IDs, error and remote frames, wrong DLC, bad CRC); and with ``--frames`` frames
that include forgeries (valid CRC: forged valve commands for the current cycle, replayed
SYNC and BENCH_STATUS, out-of-range values, the invalid alive counter). It prints one JSON
object: per run, the frames sent per category, the frames each receiver rejected (every
cause summed), whether the telemetry equals the clean run's byte for byte, the flight
software's restarts (taken and refused), stalls, whether the run was reported compromised
and for which messages, and the wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path
from typing import Any

from bench.results.record import read_lines, run_file

REPO = Path(__file__).resolve().parents[1]
QUICKSTART = REPO / "scenarios" / "quickstart.toml"
RATE_HZ = 20_000.0
PROGRESS_MARK = "progress"


def _rejects(s: dict[str, Any], node: str) -> int:
    total = sum((s["rejected_other"].get(node) or {}).values())
    for row in s["frames"].values():
        if row["sender"] == node:
            total += sum((row.get("at_sender") or {}).values())
        elif node == "BENCH" or row["sender"] == "BENCH":
            total += sum((row.get("rejected") or {}).values())
    return total


def _run(work: Path, name: str, duration_s: float, frames: int,
         attack: str | None) -> dict[str, Any]:
    env = dict(os.environ, XDG_RUNTIME_DIR=str(work))
    bus, out = f"hilbus:hostile{uuid.uuid4().hex[:8]}", work / name
    t0 = time.monotonic()
    run = subprocess.Popen(
        [sys.executable, "-m", "bench.operator.entry", "run", str(QUICKSTART), "--bus", bus,
         "--duration", str(duration_s), "--seed", "7", "--out", str(out)],
        env=env, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    sent = None
    if attack is not None:
        assert run.stderr is not None
        for line in run.stderr:  # the run is under way once it reports progress
            if line.startswith(PROGRESS_MARK):
                break
        args = [sys.executable, "-m", "bench.operator.hostile", "--bus", bus, "--frames",
                str(frames), "--rate-hz", str(RATE_HZ), *(["--forgeries"] if attack else [])]
        done = subprocess.run(args, env=env, cwd=REPO, capture_output=True, text=True,
                              check=True)
        sent = json.loads(done.stdout)["sent"]
    run.communicate()
    s = json.loads((out / "summary.json").read_text())
    return {"summary": s, "sent": sent, "wall_s": round(time.monotonic() - t0, 2),
            "telemetry": "".join(read_lines(run_file(out, "telemetry.csv")))}


def main() -> None:
    """Three runs, one JSON object (module docstring)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--frames", type=int, default=100_000, help="attack frames per run")
    p.add_argument("--duration", type=float, default=600.0,
                   help="simulated seconds per run (long enough to outlast the attack)")
    args = p.parse_args()
    with tempfile.TemporaryDirectory(prefix="thil-hostile-") as tmp:
        work = Path(tmp)
        work.chmod(0o700)
        clean = _run(work, "clean", args.duration, args.frames, None)
        report: dict[str, Any] = {"frames": args.frames, "duration_s": args.duration}
        for name, attack in (("clean", None), ("noise", "noise"), ("forgeries", "forged")):
            r = clean if attack is None else _run(work, name, args.duration, args.frames,
                                                  attack == "forged")
            s = r["summary"]
            report[name] = {
                "sent": r["sent"],
                "rejected_by": {n: _rejects(s, n) - _rejects(clean["summary"], n)
                                for n in ("BENCH", "FSW")},
                "telemetry_identical_to_clean": r["telemetry"] == clean["telemetry"],
                "fsw_restarts": s["fsw"].get("restarts"),
                "fsw_restarts_refused": s["fsw"].get("restarts_refused"),
                "stalls": (s.get("deadline_misses") or {}).get("stalls"),
                "compromised": (s.get("compromised") or {}).get("messages"),
                "error": s.get("error"),
                "wall_s": r["wall_s"],
            }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
