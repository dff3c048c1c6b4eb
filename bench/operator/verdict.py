"""The run's verdict and everything abnormal in it, in words: summary.json and the console.

In: a run's summary (the dict written as ``summary.json``). Out: :func:`verdict` (one word
and its reason: PASS, FAIL, STOPPED, ERROR) and :func:`abnormal` (one line per abnormal
thing: how the run ended, a second sender, the flight software's mode changes (a SAFE
latch with its time and FDIR flags), its exit code, restarts and refused restarts, valve
watchdog trips, stalls, overruns and late steps, frames dropped at a full receiver,
bus-fault effects, frames rejected by message and cause, faults applied and what FDIR
made of them). The orchestrator stores both in ``summary.json`` (``verdict``,
``abnormal``); ``thruster-hil run`` and ``report`` print them as one block at the end, so
nothing that went wrong is only in a file.
"""

from __future__ import annotations

from typing import Any

NOMINAL_MODES = ("NOMINAL",)
BOOT_MODE = "BOOT"
MAX_REJECT_LINES = 6  # messages named in the rejected-frames line before "..."


def _rejections(s: dict[str, Any]) -> list[str]:
    """``MESSAGE cause N`` for every frame rejected by the bench or the flight software."""
    out = []
    for name, row in (s.get("frames") or {}).items():
        for side in ("rejected", "at_sender"):
            for cause, n in sorted((row.get(side) or {}).items()):
                if n:
                    who = "bench" if (side == "rejected") == (row.get("sender") != "BENCH") \
                        else "flight software"
                    out.append(f"{name} {cause} {n} (at the {who})")
    for node, causes in (s.get("rejected_other") or {}).items():
        for cause, n in sorted((causes or {}).items()):
            if n:
                out.append(f"unknown or foreign frames {cause} {n} (at {node})")
    return out


def _modes(s: dict[str, Any]) -> list[str]:
    out = []
    changes = s.get("fsw_mode_changes") or {}
    for c in changes.get("first") or []:
        if c.get("mode") in NOMINAL_MODES and c.get("previous") == BOOT_MODE:
            continue  # the boot
        flags = ", ".join(c.get("fdir_flags") or []) or "none"
        out.append(f"flight software mode {c.get('previous')} -> {c.get('mode')} at "
                   f"{c.get('t_s', 0.0):.2f} s (FDIR flags: {flags})")
    more = int(changes.get("count") or 0) - len(changes.get("first") or [])
    if more > 0:
        out.append(f"... and {more} more mode changes")
    final = (s.get("fsw") or {}).get("mode")
    if final is not None and final not in NOMINAL_MODES:
        out.append(f"flight software ended in mode {final}")
    return out


def _faults(s: dict[str, Any]) -> list[str]:
    out = []
    for f in s.get("faults") or []:
        target = next((f"{k} {f[k]}" for k in ("thruster", "sensor", "message", "node")
                       if f.get(k) is not None), "")
        where = f" ({f['source']})" if f.get("source") not in (None, "scenario") else ""
        applied = "" if f.get("applied", True) else f" NOT APPLIED: {f.get('why')}"
        out.append(f"fault {f.get('kind')} {target} at {f.get('t_s', 0.0):.2f} s{where}"
                   f"{applied}".replace("  ", " "))
    fdir = s.get("fdir") or {}
    if fdir.get("failed_thruster") is not None:
        t_s = fdir.get("detection_time_s")
        when = "?" if t_s is None else f"{t_s:.2f}"
        out.append(f"FDIR isolated thruster {fdir['failed_thruster']} "
                   f"({fdir.get('failure_kind')}) detected at {when} s")
    return out


def abnormal(s: dict[str, Any]) -> list[str]:
    """Every abnormal thing in summary ``s``, one line each (empty for a clean run)."""
    return abnormal_events(s) + _faults(s)


def abnormal_events(s: dict[str, Any]) -> list[str]:
    """What :func:`abnormal` lists except the faults themselves (those the scenario or an
    operator asked for) and FDIR's isolation of them: what went wrong on its own, or
    because of a fault (a SAFE latch, deadline misses, watchdog trips, rejected frames)."""
    out = []
    ended = s.get("ended", "completed")
    if s.get("refused"):
        out.append(f"refused: {s['refused']}")
    if ended not in ("completed", "error", "refused"):
        out.append(f"stopped by {ended} at {s.get('sim_time_s', 0.0):.2f} s simulated")
    if s.get("supervisor_died"):
        out.append("the thruster-hil command died (killed?): the bench stopped the run itself")
    if s.get("error"):
        out.append(f"run error: {s['error']}")
    if s.get("files_sealed"):
        out.append("files left unfinished by the bench, sealed: " + ", ".join(s["files_sealed"]))
    comp = s.get("compromised")
    if comp:
        out.append("compromised: another node sent " + ", ".join(comp.get("messages", [])))
    fsw = s.get("fsw") or {}
    if fsw.get("exit_code") not in (None, 0):
        out.append(f"flight software exited with code {fsw['exit_code']}")
    out += _modes(s)
    for key, what in (("fsw_restarts", "flight-software restarts"),
                      ("fsw_restarts_refused", "flight-software restarts refused by the bench"),
                      ("valve_watchdog_trips", "valve watchdog trips"),
                      ("bus_overrun_drops", "frames dropped at a receiver that stopped "
                                            "reading")):
        if s.get(key):
            out.append(f"{what}: {s[key]}")
    if fsw.get("restarts_refused"):
        out.append(f"bench restarts refused by the flight software: {fsw['restarts_refused']}")
    dm = s.get("deadline_misses") or {}
    misses = [f"{k} {dm[k]}" for k in ("stalls", "fsw_overruns", "bench_late") if dm.get(k)]
    if misses:
        out.append("deadline misses: " + ", ".join(misses))
    effects = [f"{k} {v}" for k, v in (s.get("fault_effects") or {}).items() if v]
    if effects:
        out.append("bus-fault effects: " + ", ".join(effects))
    rejects = _rejections(s)
    if rejects:
        cut = rejects[:MAX_REJECT_LINES] + (["..."] if len(rejects) > MAX_REJECT_LINES else [])
        out.append("frames rejected: " + "; ".join(cut))
    return out


def verdict(s: dict[str, Any]) -> str:
    """``PASS``, ``FAIL: reasons``, ``STOPPED by SIG...`` or ``ERROR``, from summary ``s``."""
    ended = s.get("ended", "completed")
    if ended == "refused":
        return "REFUSED: the run did not start (see below)"
    if ended == "error" or s.get("error"):
        return "ERROR: the run could not go on (see below)"
    if ended != "completed":
        return f"STOPPED by {ended} (the figures cover what ran)"
    why = [e["name"] for e in s.get("expectations") or [] if not e.get("pass")]
    passed = s.get("passed", bool(s.get("converged")) and not why and not s.get("compromised"))
    if passed:
        return "PASS"
    if not s.get("converged"):
        why.insert(0, "not converged")
    if s.get("compromised"):
        why.append("compromised")
    return "FAIL: " + (", ".join(why) or "see below")
