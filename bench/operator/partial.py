"""summary.json rebuilt from the files a killed bench left behind (flushed as it ran).

In: the run folder's ``telemetry.csv``, ``frames.csv``, ``events.jsonl`` and the flight
software's statistics (plain or ``.gz``; compressed files the bench left without their
gzip trailer are sealed first, bench.results.record.seal, and named in ``files_sealed``).
Out: a summary marked ``partial`` with the error that ended the run, the pointing metrics
of what was recorded, the frame counts and the faults seen.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from bench.operator.fsw_process import fsw_report, wait_for_exit
from bench.operator.report_html import read_events
from bench.operator.verdict import abnormal, verdict
from bench.results.counts import frame_table, merge_counts, zero_unheard
from bench.results.error_stats import ErrorStats
from bench.results.record import GZ_SUFFIX, read_lines, run_file, seal, writes_tables
from bench.results.writers import write_summary
from bench.scenario.spec import Scenario
from dbc.database import load_database
from dbc.icd import Icd


def plot_folder(out: Path, sc: Scenario) -> None:
    """The run's PNG plots, events marked, and report.html with them, drawn by the
    supervisor once the bench is done (the bench process never carries matplotlib's heap:
    tens of thousands of objects the garbage collector would walk while it runs)."""
    from bench.operator.plots import plot_run
    from bench.operator.report_html import event_marks, read_events, write_report

    plot_run(out, sc.expectations.settling_band_deg, event_marks(read_events(out)))
    write_report(out)


def preload_plots() -> None:
    """Import matplotlib now (~0.4 s) so that :func:`plot_folder` only draws. A failing
    import is left for :func:`plot_folder` to raise, after the run."""
    with contextlib.suppress(Exception):
        import bench.operator.plots  # noqa: F401


def partial_summary(
    sc: Scenario, opts: Any, why: str, refused: str | None = None, stopped: str | None = None
) -> dict[str, Any]:
    """summary.json rebuilt from the files a killed bench left behind (flushed as it ran).

    ``refused``: the bench refused its input before the run (the error, naming the key).
    ``stopped``: a stop signal's name (SIGTERM...) ended it before the bench wrote its
    summary: that is how it ``ended``, and ``why`` is no error but ``stopped_when``.
    """
    out = opts.out
    wait_for_exit(out)
    # the killed bench left its compressed files without a gzip trailer: make them whole
    sealed = [p.name for p in sorted(out.glob("*" + GZ_SUFFIX)) if seal(p)]
    db = load_database()
    errors = ErrorStats(sc.expectations.settling_band_deg,
                        sc.expectations.steady_state_window_s, sc.manoeuvre_start_s)
    t_last_s, propellant_kg = 0.0, 0.0
    for row in _numeric_rows(run_file(out, "telemetry.csv"),
                             ("t_s", "att_err_deg", "rate_err_deg_s", "propellant_kg")):
        t_last_s, att, rate, propellant_kg = row
        if t_last_s >= sc.manoeuvre_start_s:  # as the bench's own figures (telemetry.py)
            errors.add(t_last_s, att, rate, 0.0)
    pm = errors.pointing()
    frames = frame_table(Icd.from_database(db))
    name_of = {m.frame_id: m.name for m in db.messages}
    sent: dict[str, int] = {}
    received: dict[str, dict[str, Any]] = {}
    for can_id, tx in _numeric_rows(run_file(out, "frames.csv"), ("id", "tx")):
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
    faults = [ev for ev in read_events(out) if ev.get("event") == "fault_injected"]
    summary: dict[str, Any] = {
        "scenario": sc.name, "scenario_file": sc.path, "mode": opts.mode, "seed": opts.seed,
        "record": opts.record, "files_sealed": sealed, "bus": opts.bus,
        "sim_time_s": t_last_s, "wall_time_s": None,
        "realtime_factor": None, "converged": pm.converged, "settling_time_s": pm.settling_time_s,
        "steady_state_attitude_error_deg": pm.steady_state_attitude_error_deg,
        "steady_state_rate_error_deg_s": pm.steady_state_rate_error_deg_s,
        "propellant_kg": propellant_kg,
        "valve_openings": None, "frames": frames, "rejected_other": other,
        "latency_us": {"sensor_to_command": {"p50": None, "p99": None, "max": None, "n": 0}},
        "deadline_misses": None, "faults": faults, "expectations": [], "passed": False,
        "error": why if writes_tables(opts.record) else
        f"{why}; the bench's frame counts are unknown (the lean record level keeps no "
        "frames.csv)", "partial": True,
    }
    if refused is not None:
        summary["refused"] = refused
    if stopped is not None:
        summary["ended"], summary["stopped_when"] = stopped, summary.pop("error")
    summary["fsw"] = fsw_report(out / "fsw_stats.json", None, out)
    merge_counts(frames, other, "FSW", summary["fsw"].get("sent", {}),
                 summary["fsw"].get("received", {}))
    zero_unheard(frames, {"BENCH"} | ({"FSW"} if "received" in summary["fsw"] else set()))
    summary["verdict"], summary["abnormal"] = verdict(summary), abnormal(summary)
    write_summary(out / "summary.json", summary)
    return summary


def _numeric_rows(path: Path, columns: tuple[str, ...]) -> Iterator[list[float]]:
    """The ``columns`` of each row of a numeric CSV written as the run went, read line by
    line (flat memory, however long the run); a line cut short at the end, or one that is
    not numbers, is skipped. Nothing if the file or a column is missing."""
    if not path.exists():
        return
    lines = read_lines(path)
    head = next(lines, "").rstrip("\n").split(",")
    if any(c not in head for c in columns):
        return
    index = [head.index(c) for c in columns]
    for line in lines:
        parts = line.rstrip("\n").split(",")
        if len(parts) != len(head):
            continue
        try:
            yield [float(parts[i]) for i in index]
        except ValueError:
            continue
