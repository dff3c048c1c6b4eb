"""summary.json rebuilt from the files a killed bench left behind (flushed as it ran).

In: the run folder's ``telemetry.csv``, ``frames.csv``, ``events.jsonl`` and the flight
software's statistics. Out: a summary marked ``partial`` with the error that ended the
run, the pointing metrics of what was recorded, the frame counts and the faults seen.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from bench.operator.fsw_process import fsw_report, wait_for_exit
from bench.results.counts import frame_table, merge_counts, zero_unheard
from bench.results.metrics import pointing_metrics
from bench.results.writers import write_summary
from bench.scenario.spec import Scenario
from dbc.database import load_database
from dbc.icd import Icd


def plot_folder(out: Path, sc: Scenario) -> None:
    """The run's PNG plots. matplotlib is imported here, after the run: the bench process
    does not carry its heap (tens of thousands of objects the garbage collector would walk)
    while it runs."""
    from bench.operator.plots import plot_run

    plot_run(out, sc.expectations.settling_band_deg)



def partial_summary(
    sc: Scenario, opts: Any, why: str, refused: str | None = None
) -> dict[str, Any]:
    """summary.json rebuilt from the files a killed bench left behind (flushed as it ran).

    ``refused``: the bench refused its input before the run (the error, naming the key).
    """
    out = opts.out
    wait_for_exit(out)
    db = load_database()
    tel = _read_numeric_csv(out / "telemetry.csv")
    t = tel.get("t_s", np.zeros(0))
    pm = pointing_metrics(t, tel.get("att_err_deg", np.zeros(0)),
                          tel.get("rate_err_deg_s", np.zeros(0)),
                          sc.expectations.settling_band_deg, sc.expectations.steady_state_window_s,
                          sc.manoeuvre_start_s)
    frames = frame_table(Icd.from_database(db))
    fr = _read_numeric_csv(out / "frames.csv")
    name_of = {m.frame_id: m.name for m in db.messages}
    sent: dict[str, int] = {}
    received: dict[str, dict[str, Any]] = {}
    for can_id, tx in zip(fr.get("id", []), fr.get("tx", []), strict=True):
        name = name_of.get(int(can_id))
        if name is None:
            continue
        if tx:
            sent[name] = sent.get(name, 0) + 1
        else:
            r = received.setdefault(name, {"received": 0, "gaps": 0, "rejected": {}})
            r["received"] += 1
    other: dict[str, dict[str, int]] = {}
    merge_counts(frames, other, "BENCH", sent, received)
    faults = []
    events = out / "events.jsonl"
    if events.exists():
        for line in events.read_text(encoding="utf-8").splitlines():
            try:
                ev = json.loads(line)
            except json.JSONDecodeError:
                continue  # a line cut by the kill
            if ev.get("event") == "fault_injected":
                faults.append(ev)
    summary: dict[str, Any] = {
        "scenario": sc.name, "scenario_file": sc.path, "mode": opts.mode, "seed": opts.seed,
        "bus": opts.bus, "sim_time_s": float(t[-1]) if len(t) else 0.0, "wall_time_s": None,
        "realtime_factor": None, "converged": pm.converged, "settling_time_s": pm.settling_time_s,
        "steady_state_attitude_error_deg": pm.steady_state_attitude_error_deg,
        "steady_state_rate_error_deg_s": pm.steady_state_rate_error_deg_s,
        "propellant_kg": float(tel["propellant_kg"][-1]) if len(t) else 0.0,
        "valve_openings": None, "frames": frames, "rejected_other": other,
        "latency_us": {"sensor_to_command": {"p50": None, "p99": None, "max": None, "n": 0}},
        "deadline_misses": None, "faults": faults, "expectations": [], "passed": False,
        "error": why, "partial": True,
    }
    if refused is not None:
        summary["refused"] = refused
    summary["fsw"] = fsw_report(out / "fsw_stats.json", None, out)
    merge_counts(frames, other, "FSW", summary["fsw"].get("sent", {}),
                 summary["fsw"].get("received", {}))
    zero_unheard(frames, {"BENCH"} | ({"FSW"} if "received" in summary["fsw"] else set()))
    write_summary(out / "summary.json", summary)
    plot_folder(out, sc)
    return summary


def _read_numeric_csv(path: Path) -> dict[str, np.ndarray]:
    """Columns of a numeric CSV written as the run went; a line cut short at the end is skipped."""
    if not path.exists():
        return {}
    lines = path.read_text(encoding="utf-8").splitlines()
    if not lines:
        return {}
    head = lines[0].split(",")
    rows = []
    for line in lines[1:]:
        parts = line.split(",")
        if len(parts) != len(head):
            continue
        try:
            rows.append([float(x) for x in parts])
        except ValueError:
            continue
    data = np.array(rows, dtype=float).reshape(-1, len(head))
    return {h: data[:, i] for i, h in enumerate(head)}

