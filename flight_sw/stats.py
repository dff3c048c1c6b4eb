"""The flight software's statistics file (``--stats``): what it did, for the bench's summary.

In: the node's counters (cycles, overruns, restarts and refused restarts, frames sent per
message, cycle times [ns], allocation residuals [N m], [N]), the receive statistics of
its frame checker (dbc.codec.FrameChecker.summary), the flight computer's final state.
Out: one JSON object, written atomically (a reader never sees half a file), at the end
of a run and every ten status periods in realtime (dbc.records.write_record). The bench
merges it into
``summary.json`` under ``fsw`` (see docs/icd.md for the fields).
"""

from __future__ import annotations

from array import array
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from dbc.contract import STATS_SCHEMA, VERSION
from dbc.records import percentile_summary
from flight_sw.computer import CycleResult, FlightComputer
from flight_sw.control.fine_hold import FineHold

NS_PER_US = 1e3
NS_PER_S = 1e9
CYCLE_TIME_DIGITS = 1  # 0.1 us
INT64, FLOAT64 = "q", "d"  # array type codes of the per-cycle series
EVIDENCE = ("unexpected", "sequence")  # receive causes that show a second sender


@dataclass
class NodeStats:
    """Counters the node reports at exit."""

    cycles: int = 0
    overruns: int = 0
    restarts: int = 0
    sent: dict[str, int] = field(default_factory=dict)
    # per cycle, packed (8 bytes a value, not a Python object each: a 2 h run's 360 000
    # cycles keep 2.9 MB a series): cycle start -> last frame sent [ns], the allocation's
    # torque [N m] and force [N] residuals
    cycle_ns: array[int] = field(default_factory=lambda: array(INT64))
    residual_Nm: array[float] = field(default_factory=lambda: array(FLOAT64))
    residual_N: array[float] = field(default_factory=lambda: array(FLOAT64))
    saturated_cycles: int = 0


def spread(values: Sequence[float]) -> dict[str, float | int | None]:
    """p50, p99, max (full precision; the bus carries 0.05 steps) and the count."""
    return percentile_summary(values)


def percentiles_us(samples_ns: Sequence[int]) -> dict[str, float | int | None]:
    """p50, p99 and max of ``samples_ns`` in microseconds (0.1 us), and the count."""
    return percentile_summary(samples_ns, NS_PER_US, CYCLE_TIME_DIGITS)


def second_sender_evidence(received: dict[str, dict[str, Any]]) -> dict[str, int]:
    """Per message, frames that show a second sender (our own messages heard, counter
    regressions) in a receive summary."""
    out = {}
    for name, r in received.items():
        n = sum(int(r["rejected"].get(c, 0)) for c in EVIDENCE)
        if n:
            out[name] = n
    return out


def _fdir(fc: FlightComputer, res: CycleResult | None) -> dict[str, Any]:
    """Isolated thruster failures (times relative to the bench's time 0) and flags."""
    out: dict[str, Any] = {
        "sensor_flags": res.sensor_flags if res is not None else 0,
        "fdir_flags": res.fdir_flags if res is not None else 0,
        "failures": [],
    }
    fdir = fc.thruster_fdir
    if fdir is not None:
        base = fdir.time_base_ns
        out["available_mask"] = int(sum(1 << k for k in range(fdir.n) if fdir.mask[k]))
        out["failures"] = [
            {"thruster": f.thruster, "kind": f.kind.name.lower(),
             "t_detect_s": (f.t_detect_ns - base) / NS_PER_S,
             "t_isolate_s": (f.t_isolate_ns - base) / NS_PER_S, "source": f.source}
            for f in fdir.failures
        ]
    return out


def stats_record(st: NodeStats, received: dict[str, dict[str, Any]], fc: FlightComputer,
                 res: CycleResult | None, bus: Any, restarts_refused: int) -> dict[str, Any]:
    """The statistics record (``thruster-hil/fsw-stats``, docs/icd.md): the node's
    counters, its receive statistics, the computer's final state and, on the portable
    bus, the frames not delivered to a member that stopped reading."""
    return {
        "schema": STATS_SCHEMA,
        "version": VERSION,
        "cycles": st.cycles,
        "overruns": st.overruns,
        "sent": dict(sorted(st.sent.items())),
        "received": received,
        "second_sender_evidence": second_sender_evidence(received),
        "mode": fc.mode.name,
        "cycle_time_us": percentiles_us(st.cycle_ns),
        "allocation": {"residual_torque_Nm": spread(st.residual_Nm),
                       "residual_force_N": spread(st.residual_N),
                       "saturated_cycles": st.saturated_cycles, "cycles": st.cycles},
        "fine_hold": None if not isinstance(fc.pose, FineHold) else {
            "active": fc.pose.in_fine_hold, "switches": fc.pose.switches},
        "inertia_estimate_B_kgm2": (
            None if fc.inertia_B_kgm2 is None else fc.inertia_B_kgm2.tolist()),
        "inertia_identification": None if fc.inertia_id is None else {
            "updates": fc.inertia_id.n_updates,
            "withheld_unphysical": fc.inertia_id.n_unphysical},
        "restarts": st.restarts,
        "restarts_refused": restarts_refused,
        "warnings": list(fc.warnings) + fc.layout_notes,
        "fdir": _fdir(fc, res),
        "bus_overrun_drops": getattr(bus, "overrun_drops", 0),
        "bus_overrun_drops_by_pid": {
            str(k): v for k, v in getattr(bus, "overrun_drops_by_pid", {}).items()},
    }
