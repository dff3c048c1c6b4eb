"""Worst-case response times of the project's DBC messages; prints one JSON object.

For each bitrate (125 kbit/s, 500 kbit/s, 1 Mbit/s) and each periodic message of
``dbc/thruster_hil.dbc`` (``GenMsgCycleTime`` > 0, zero queuing jitter, deadline = period):
worst-case frame length (bits), transmission time C and worst-case response time R (µs)
from :func:`bench.operator.analysis.rta.response_times` (Davis, Burns, Bril, Lukkien 2007, revised
analysis), the message's utilisation C/T, its level-m busy period, instances checked,
and whether R <= deadline; per bitrate, the total bus utilisation.

Assumption to keep in mind: the event-driven FAULT_CMD (no cycle time) is not in the
analysis, so it does not block the lowest-priority periodic message here; on a real bus it
can, by up to its own C.

Usage: ``python benchmarks/rta_dbc.py`` (pure computation, well under a second).
"""

from __future__ import annotations

import json
import sys

from bench.operator.analysis.rta import messages_from_dbc, response_times
from dbc.database import DBC_PATH, load_database

BITRATES_BPS = (125_000, 500_000, 1_000_000)
US_PER_S = 1_000_000
MS_PER_S = 1_000
DECIMALS = 6  # rounding of printed floats (µs values are multiples of 1 ns anyway)


def main() -> int:
    """Analyse the ICD at each bitrate and print the JSON report to stdout."""
    db = load_database()
    report: dict[str, object] = {"dbc": DBC_PATH.name, "bitrates": {}}
    per_bitrate: dict[str, object] = {}
    for bitrate_bps in BITRATES_BPS:
        specs = messages_from_dbc(db, bitrate_bps)
        results = response_times(specs, bitrate_bps)
        periods_s = {s.name: s.period_s for s in specs}
        messages = {
            name: {
                "can_id": r.can_id,
                "period_ms": round(periods_s[name] * MS_PER_S, DECIMALS),
                "frame_bits": r.frame_bits,
                "C_us": round(r.transmission_time_s * US_PER_S, DECIMALS),
                "R_us": round(r.response_time_s * US_PER_S, DECIMALS),
                "utilisation": round(r.utilisation, DECIMALS),
                "busy_period_us": round(r.busy_period_s * US_PER_S, DECIMALS),
                "instances": r.instances,
                "schedulable": r.schedulable,
            }
            for name, r in results.items()
        }
        bus_u = next(iter(results.values())).bus_utilisation if results else 0.0
        per_bitrate[str(bitrate_bps)] = {
            "bus_utilisation": round(bus_u, DECIMALS),
            "all_schedulable": all(r.schedulable for r in results.values()),
            "messages": messages,
        }
    report["bitrates"] = per_bitrate
    json.dump(report, sys.stdout, indent=2)
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
