"""Full flight-software cycle time of every reproduction configuration, as JSON.

Runs each reproduction scenario once per allocator of interest with ``thruster-hil run``
in lockstep over a private portable bus (real processes) and reads the flight software's
own measurement from ``fsw_stats.json``: per 50 Hz cycle, the time from SYNC receipt to
the last command frame sent (estimation, control, allocation, modulation, encoding and
sending). Prints p50, p99 and max [µs], and p99 as a fraction of the control period; the
budget (issue 3) is 10 % of the period. Figures from one invocation: the machine is shared.

    python benchmarks/fsw_cycle.py
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from reproductions import SCENARIOS, run_scenario

CONTROL_PERIOD_US = 20_000.0  # THR_CMD cycle time in the DBC (50 Hz)
BUDGET_FRACTION = 0.10
CASES = (
    ("three_axis_tracking_cascade", ()),
    ("formation_keeping_nftsm", ()),
    ("formation_keeping_nftsm", ("flight_sw.allocator={kind='pseudo_inverse'}",)),
    ("mrp_trajectory_tracking", ("flight_sw.allocator={kind='robust_polyhedral'}",)),
    ("mrp_trajectory_tracking", ("flight_sw.allocator={kind='robust_polytopic'}",)),
    ("mrp_trajectory_tracking", ("flight_sw.allocator={kind='robust_lft'}",)),
    ("mrp_trajectory_tracking", ("flight_sw.allocator={kind='qp_osqp'}",)),
    ("capture_inertia_identification", ()),
)


def main() -> None:
    """Run every case, print JSON."""
    out: dict[str, Any] = {
        "benchmark": "fsw_cycle",
        "cpus": os.cpu_count(),
        "load_avg_1min": os.getloadavg()[0],
        "control_period_us": CONTROL_PERIOD_US,
        "budget_fraction": BUDGET_FRACTION,
        "cases": {},
    }
    with tempfile.TemporaryDirectory(prefix="thil-cycle-") as tmp:
        for i, (name, sets) in enumerate(CASES):
            run_dir = Path(tmp) / f"{i}-{name}"
            run_scenario(SCENARIOS / f"{name}.toml", sets, run_dir)
            stats_path = run_dir / "fsw_stats.json"
            label = name + "".join(f" [{s}]" for s in sets)
            if not stats_path.exists():
                out["cases"][label] = {"error": "no fsw_stats.json"}
                continue
            cyc = json.loads(stats_path.read_text(encoding="utf-8"))["cycle_time_us"]
            cyc["p99_fraction_of_period"] = round(cyc["p99"] / CONTROL_PERIOD_US, 4)
            cyc["within_budget"] = cyc["p99"] <= BUDGET_FRACTION * CONTROL_PERIOD_US
            out["cases"][label] = cyc
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
