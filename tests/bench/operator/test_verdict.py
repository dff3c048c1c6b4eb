"""The verdict and the abnormal lines name what went wrong in a run, and nothing in a clean one."""

from __future__ import annotations

from typing import Any

from bench.operator.verdict import MAX_REJECT_LINES, abnormal, abnormal_events, verdict


def _clean(**changes: Any) -> dict[str, Any]:
    s: dict[str, Any] = {
        "ended": "completed", "passed": True, "converged": True, "expectations": [],
        "sim_time_s": 60.0, "compromised": None, "fsw": {"exit_code": 0, "mode": "NOMINAL"},
        "fsw_mode_changes": {"count": 1, "first": [
            {"t_s": 0.001, "mode": "NOMINAL", "previous": "BOOT", "fdir_flags": []}]},
        "fsw_restarts": 0, "fsw_restarts_refused": 0, "valve_watchdog_trips": 0,
        "bus_overrun_drops": 0, "deadline_misses": {"stalls": 0, "fsw_overruns": 0},
        "fault_effects": {"dropped": 0}, "faults": [], "fdir": {"failed_thruster": None},
        "frames": {"THR_CMD_0": {"sender": "FSW", "rejected": {}, "at_sender": {}}},
        "rejected_other": {"BENCH": {}, "FSW": {}},
    }
    s.update(changes)
    return s


def test_a_clean_run_passes_with_nothing_abnormal() -> None:
    """PASS, and the boot's BOOT -> NOMINAL is not abnormal."""
    assert verdict(_clean()) == "PASS"
    assert abnormal(_clean()) == []


def test_a_safe_latch_is_named_with_its_time_and_flags() -> None:
    """A mode change to SAFE and the final mode are both reported."""
    s = _clean(fsw={"exit_code": 0, "mode": "SAFE"}, fsw_mode_changes={"count": 2, "first": [
        {"t_s": 0.001, "mode": "NOMINAL", "previous": "BOOT", "fdir_flags": []},
        {"t_s": 8.041, "mode": "SAFE", "previous": "NOMINAL",
         "fdir_flags": ["imu_lost", "safe_latched"]}]})
    assert abnormal(s) == [
        "flight software mode NOMINAL -> SAFE at 8.04 s (FDIR flags: imu_lost, safe_latched)",
        "flight software ended in mode SAFE"]


def test_rejects_name_message_cause_and_receiver() -> None:
    """A rejected command is counted at the bench; a bench frame at the flight software."""
    s = _clean(frames={
        "THR_CMD_0": {"sender": "FSW", "rejected": {"crc": 60}, "at_sender": {}},
        "SYNC": {"sender": "BENCH", "rejected": {"counter": 2}, "at_sender": {"unexpected": 1}},
    })
    (line,) = abnormal(s)
    assert line == ("frames rejected: THR_CMD_0 crc 60 (at the bench); SYNC counter 2 (at the "
                    "flight software); SYNC unexpected 1 (at the bench)")


def test_many_rejects_are_cut() -> None:
    """More messages with rejects than MAX_REJECT_LINES: the line ends with '...'."""
    frames = {f"M{i}": {"sender": "FSW", "rejected": {"dlc": 1}} for i in range(10)}
    (line,) = abnormal(_clean(frames=frames))
    assert line.count("dlc 1") == MAX_REJECT_LINES and line.endswith("; ...")


def test_stops_errors_deaths_and_counters_are_each_a_line() -> None:
    """Every abnormal counter of the summary gives its own line."""
    s = _clean(ended="SIGTERM", sim_time_s=12.5, fsw={"exit_code": -9, "mode": "NOMINAL",
                                                       "restarts_refused": 3},
               compromised={"messages": ["SYNC", "THR_CMD_0"]}, fsw_restarts=1,
               valve_watchdog_trips=2, bus_overrun_drops=7,
               deadline_misses={"stalls": 4, "fsw_overruns": 0, "bench_late": 1},
               fault_effects={"dropped": 28, "delayed": 0})
    assert abnormal(s) == [
        "stopped by SIGTERM at 12.50 s simulated",
        "compromised: another node sent SYNC, THR_CMD_0",
        "flight software exited with code -9",
        "flight-software restarts: 1",
        "valve watchdog trips: 2",
        "frames dropped at a receiver that stopped reading: 7",
        "bench restarts refused by the flight software: 3",
        "deadline misses: stalls 4, bench_late 1",
        "bus-fault effects: dropped 28",
    ]
    assert verdict(s) == "STOPPED by SIGTERM (the figures cover what ran)"


def test_faults_and_their_isolation_are_listed() -> None:
    """Each fault with its target and time; a fault not applied says why; FDIR's isolation
    at the same 0.01 s as the faults (no float's full repr)."""
    s = _clean(faults=[
        {"kind": "stuck_open", "thruster": 2, "t_s": 5.0, "source": "scenario"},
        {"kind": "drop", "message": "IMU_RATE", "t_s": 8.0, "source": "FAULT_CMD",
         "applied": False, "why": "lockstep only"}],
        fdir={"failed_thruster": 2, "failure_kind": "stuck_open",
              "detection_time_s": 6.0600000000000005})
    assert abnormal(s) == [
        "fault stuck_open thruster 2 at 5.00 s",
        "fault drop message IMU_RATE at 8.00 s (FAULT_CMD) NOT APPLIED: lockstep only",
        "FDIR isolated thruster 2 (stuck_open) detected at 6.06 s"]


def test_abnormal_events_leave_out_the_faults_asked_for_not_what_they_caused() -> None:
    """An injected fault and its isolation are not events; the SAFE latch it caused is."""
    s = _clean(faults=[{"kind": "stuck_open", "thruster": 2, "t_s": 5.0, "source": "scenario"}],
               fdir={"failed_thruster": 2, "failure_kind": "stuck_open", "detection_time_s": 5.3})
    assert abnormal_events(s) == [] and len(abnormal(s)) == 2
    s["fsw"] = {"exit_code": 0, "mode": "SAFE"}
    assert abnormal_events(s) == ["flight software ended in mode SAFE"]


def test_failures_are_named_in_the_verdict() -> None:
    """FAIL lists non-convergence and each failed expectation; an error outranks all."""
    s = _clean(passed=False, converged=False, expectations=[
        {"name": "settling_time_s", "pass": False}, {"name": "x", "pass": True}])
    assert verdict(s) == "FAIL: not converged, settling_time_s"
    assert verdict(_clean(ended="error", error="boom")).startswith("ERROR")
    assert "run error: boom" in abnormal(_clean(ended="error", error="boom"))
