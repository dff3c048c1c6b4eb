"""Real-time factor of the lockstep quickstart, and latency of a realtime run, as JSON.

Runs ``thruster-hil run scenarios/quickstart.toml`` N times in lockstep over the portable
bus (each in a private runtime directory) and, optionally, once in realtime mode; prints
one JSON object: per-run and median real-time factor and wall time, the flight software's
cycle time percentiles (SYNC receipt to last frame sent), and for the realtime run the
measured sensor-to-command latency, the one-way latency of single messages each way and
deadline misses. Medians over one invocation: this
machine is shared and noisy.

    python benchmarks/quickstart_runs.py --runs 5 --realtime-s 60
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import uuid
from pathlib import Path
from typing import Any

from bench.operator.analysis.timing import RunTiming

REPO = Path(__file__).resolve().parents[1]
QUICKSTART = REPO / "scenarios" / "quickstart.toml"


ONE_WAY = ("IMU_RATE", "STR_QUAT", "THR_CMD_0")  # bench -> flight software, and back


def _run(extra: list[str], scratch: Path, bus: str | None = None) -> dict[str, Any]:
    out = scratch / uuid.uuid4().hex[:8]
    xdg = Path(tempfile.mkdtemp(prefix="xdg-", dir=scratch))
    env = dict(os.environ, XDG_RUNTIME_DIR=str(xdg))
    bus = bus or f"hilbus:bm{uuid.uuid4().hex[:8]}"
    subprocess.run(
        [sys.executable, "-m", "bench.operator.entry", "run", str(QUICKSTART), "--bus", bus,
         "--out", str(out), *extra],
        cwd=REPO, env=env, capture_output=True, check=False,
    )
    summary: dict[str, Any] = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    summary["run_dir"] = str(out)
    return summary


def main() -> None:
    """Parse arguments, run, print JSON."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--runs", type=int, default=3, help="lockstep runs (default 3)")
    p.add_argument("--realtime-s", type=float, default=0.0,
                   help="also one realtime run of this many seconds (0: none)")
    p.add_argument("--realtime-bus", default=None,
                   help="bus of the realtime run (default: a private portable bus; "
                   "e.g. socketcan:vcan0 inside the CI guest)")
    args = p.parse_args()
    with tempfile.TemporaryDirectory(prefix="thil-bench-") as tmp:
        scratch = Path(tmp)
        lock = [_run([], scratch) for _ in range(args.runs)]
        result: dict[str, Any] = {
            "benchmark": "quickstart_runs",
            "cpus": os.cpu_count(),
            "load_avg_1min": os.getloadavg()[0],
            "lockstep": {
                "sim_time_s": lock[0]["sim_time_s"],
                "realtime_factor": [s["realtime_factor"] for s in lock],
                "realtime_factor_median": statistics.median(s["realtime_factor"] for s in lock),
                "wall_time_s_median": statistics.median(s["wall_time_s"] for s in lock),
                "fsw_cycle_time_us": [s["fsw"].get("cycle_time_us") for s in lock],
                "converged": [s["converged"] for s in lock],
                "settling_time_s": lock[0]["settling_time_s"],
                "steady_state_attitude_error_deg": lock[0]["steady_state_attitude_error_deg"],
            },
        }
        if args.realtime_s > 0:
            rt = _run(["--mode", "realtime", "--duration", str(args.realtime_s)], scratch,
                      args.realtime_bus)
            timing = RunTiming.load(rt["run_dir"])
            result["realtime"] = {
                "bus": rt["bus"],
                "sim_time_s": rt["sim_time_s"],
                "converged": rt["converged"],
                "settling_time_s": rt["settling_time_s"],
                "steady_state_attitude_error_deg": rt["steady_state_attitude_error_deg"],
                "latency_us_sensor_to_command": rt["latency_us"]["sensor_to_command"],
                # sending to the receiver's arrival stamp, per message (bench frames: from
                # the flight software's receive log, fsw_rx.csv)
                "one_way_latency_us": {
                    name: timing.message(name).latency.to_dict() for name in ONE_WAY
                },
                "deadline_misses": rt["deadline_misses"],
                "fsw_cycle_time_us": rt["fsw"].get("cycle_time_us"),
            }
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
