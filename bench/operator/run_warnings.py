"""What a run's summary warns about: the scenario, the run's length, the bus, second senders.

In: the scenario and the run's summary (so far). Out: one-line warnings for the console
and ``summary.json``'s ``warnings``, and the ``compromised`` record (evidence that another
node sent frames of the ICD). Pure functions.
"""

from __future__ import annotations

from typing import Any

from bench.operator.plausibility import mass_warnings
from bench.scenario.spec import Scenario


def overrun_warning(
    from_bench: dict[int, int], from_fsw: dict[int, int], bench_pid: int,
    fsw_pid: int | None, stall_s: float,
) -> str:
    """The warning for frames the portable bus dropped for members that stopped reading.

    ``from_bench``/``from_fsw``: frames each process dropped, by the receiving member's
    pid. Naming the member matters: in realtime the one that stalled is often the bench or
    the flight software itself (a long pause), not a monitor.
    """
    def who(pid: int) -> str:
        if pid == bench_pid:
            return f"the bench (pid {pid})"
        if pid == fsw_pid:
            return f"the flight software (pid {pid})"
        return f"another member (pid {pid}, e.g. a paused can.logger)"

    parts = [f"{n} from the {src} to {who(pid)}"
             for src, table in (("bench", from_bench), ("flight software", from_fsw))
             for pid, n in sorted(table.items())]
    total = sum(from_bench.values()) + sum(from_fsw.values())
    return (f"{total} frames were dropped for bus members that did not read for "
            f"{stall_s * 1000:g} ms ({'; '.join(parts) or 'members unknown'}): only those "
            "members missed them")



def scenario_warnings(sc: Scenario) -> list[str]:
    """Mass properties of the scenario's vehicle that look like a unit slip
    (:mod:`bench.operator.plausibility`). What its thrusters cannot push about or along is
    the flight software's to say (its statistics' ``warnings``): it alone knows which
    degrees of freedom it controls."""
    r_thr = [t.r_thr_B_m for t in sc.thrusters]
    out = mass_warnings("[vehicle]", sc.actual.mass_kg, sc.actual.inertia_B_kgm2, r_thr)
    if sc.nominal != sc.actual:
        out += mass_warnings("[vehicle.nominal]", sc.nominal.mass_kg,
                             sc.nominal.inertia_B_kgm2, r_thr)
    return out


def duration_warnings(sc: Scenario, duration_s: float) -> list[str]:
    """A run too short for its scenario: the steady-state window holds the transient.

    The window is the last ``steady_state_window_s`` of the run; it should start after the
    manoeuvre's start plus its allowed settling time.

    Also: scheduled faults and events that a shortened run (``--duration``) ends before;
    they never act, and the run's figures are those of a run without them.
    """
    out: list[str] = []
    e = sc.expectations
    settled_s = sc.manoeuvre_start_s + (e.settling_time_s_max or 0.0)
    window_start_s = duration_s - e.steady_state_window_s
    if window_start_s < settled_s:
        out.append(f"the run is {duration_s:g} s: its steady-state window (the last "
                   f"{e.steady_state_window_s:g} s) starts before the manoeuvre may have "
                   f"settled ({settled_s:g} s), so steady-state figures include the transient; "
                   f"run at least {settled_s + e.steady_state_window_s:g} s (the scenario's "
                   f"own duration is {sc.duration_s:g} s)")
    for kind, items in (("[[faults]]", sc.faults), ("[[events]]", sc.events)):
        late = [x for x in items if x.t_s >= duration_s]
        if late:
            what = ", ".join(
                f"{getattr(x, 'kind', 'capture')} at {x.t_s:g} s" for x in late)
            out.append(f"the run is {duration_s:g} s: {len(late)} of the scenario's {kind} "
                       f"never act ({what}); run longer than {max(x.t_s for x in late):g} s")
    return out



def compromised(summary: dict[str, Any]) -> dict[str, Any] | None:
    """Evidence that a second sender spoke the ICD on this bus, or None.

    Each side's evidence (its own messages heard well-formed from another node, alive
    counters gone back, a second different command for one cycle), by message; ``messages``
    names them all. A run with any is compromised: its results may hold another node's
    frames, so it does not pass.
    """
    bench = dict(summary.get("second_sender_evidence") or {})
    fsw = dict((summary.get("fsw") or {}).get("second_sender_evidence") or {})
    names = sorted(set(bench) | set(fsw))
    if not names:
        return None
    return {"messages": names, "evidence": {"BENCH": bench, "FSW": fsw}}


def bus_warnings(summary: dict[str, Any]) -> list[str]:
    """Signs that something else shares the bus: a second sender, stale frames, refused
    restarts."""
    out = []
    comp = summary.get("compromised")
    if comp is not None:
        ev = comp["evidence"]
        counts = ", ".join(f"{n} ({ev['BENCH'].get(n, 0) + ev['FSW'].get(n, 0)})"
                           for n in comp["messages"])
        out.append(f"run compromised: another node sends frames of the ICD on this bus: "
                   f"{counts}. A second bench or flight software, or forged frames? "
                   "Use a bus of your own (--bus).")
    for name, f in summary["frames"].items():
        rej = f.get("rejected") or {}
        if rej.get("stale"):
            out.append(f"{rej['stale']} stale {name} frames (for another cycle, or older "
                       "than the last one taken)")
    refused = int((summary.get("fsw") or {}).get("restarts_refused") or 0)
    if refused:
        out.append(f"the flight software refused {refused} bench restarts (SYNC or "
                   "BENCH_STATUS going back while the bench was live: replayed frames?)")
    if summary.get("fsw_restarts_refused"):
        out.append(f"the bench refused {summary['fsw_restarts_refused']} flight-software "
                   "restarts (FSW_STATUS in BOOT mode while it was live: replayed frames?)")
    return out


