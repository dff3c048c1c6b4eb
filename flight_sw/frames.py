"""The flight software's frames: sensor frames in -> the computer; a cycle's result -> frames out.

In (:func:`feed`): a checked sensor frame of the bench (IMU_RATE [rad/s], IMU_ACCEL
[m/s²], STR_QUAT, NAV_POS [m], NAV_VEL [m/s], THR_STATUS), fed to the flight computer at
its time of receipt; invalid samples (``Valid`` = 0) are not fed.

Out:
a :class:`~flight_sw.computer.CycleResult` (on-times [s] per thruster, mode, flags,
allocation residuals [N m], [N], the FDIR report), the cycle number, the counters the
node keeps, and the ICD's facts (dbc.icd: command frames and their on-time signals, the
cycle counters' widths, signal ranges, the "no thruster" value). Out: physical signal
values per message, every one inside its DBC range (saturated at the range's bound, as a
sensor saturates), ready for :class:`dbc.codec.Encoder`.

Valve commands: THR_CMD_0..m (m = ceil(thrusters / per-frame) - 1) each carry the cycle
number mod the Cycle signal's modulus, the alive counter of the newest IMU_RATE used and
the on-time of each of its thrusters rounded to the on-time signal's LSB; thrusters
beyond the vehicle's count are 0. A full-period on-time is sent ``FULL_ON_OVERLAP_S``
longer, so that consecutive full-on pulses overlap the next command, which continues the
energised coil: no closing and re-opening transient when a command arrives a little
later than the previous one. Pure functions.
"""

from __future__ import annotations

import numpy as np

from dbc.codec import Decoded
from dbc.icd import Icd
from dbc.quaternion import unpack_quaternion
from flight_sw.computer import CycleResult, FlightComputer

# A full-period pulse is sent this much longer, to bridge command-arrival jitter; far
# below the DBC's on-time range and the bench's valve watchdog.
FULL_ON_OVERLAP_S = 0.005
NS_PER_S = 1e9
Signals = dict[str, float | int]


def _clamp(x: float, icd: Icd, message: str, signal: str) -> float:
    """``x`` inside ``message.signal``'s DBC range."""
    lo, hi = icd.signal_range[(message, signal)]
    return min(max(x, lo), hi)


def status_signals(icd: Icd, mode: int, cycle: int, overruns: int,
                   res: CycleResult | None) -> Signals:
    """FSW_STATUS: mode, cycle, overruns, FDIR flags, the allocation's saturation/residual."""
    return {
        "Mode": mode,
        "Cycle": cycle % icd.status_cycle_modulus,
        "Overruns": int(_clamp(overruns, icd, "FSW_STATUS", "Overruns")),
        "FdirFlags": res.fdir_flags if res is not None else 0,
        "AllocSaturated": int(res.saturated) if res is not None else 0,
        "AllocResidual": _clamp(res.residual_Nm if res is not None else 0.0, icd,
                                "FSW_STATUS", "AllocResidual"),
        "AllocForceResidual": _clamp(res.residual_force_N if res is not None else 0.0, icd,
                                     "FSW_STATUS", "AllocForceResidual"),
    }


def fdir_signals(icd: Icd, n_thrusters: int, res: CycleResult | None) -> Signals:
    """FSW_FDIR from the last cycle (all thrusters available before the first cycle)."""
    sensor_flags = res.sensor_flags if res is not None else 0
    rep = res.fdir if res is not None else None
    if rep is None:
        return {"AvailableMask": (1 << n_thrusters) - 1, "FailedThruster": icd.no_failed_thruster,
                "FailureKind": 0, "DetectionTime": 0.0, "IsolationDelay": 0.0,
                "SensorFlags": sensor_flags}
    return {
        "AvailableMask": rep.available_mask,
        "FailedThruster": (icd.no_failed_thruster if rep.failed_thruster is None
                           else rep.failed_thruster),
        "FailureKind": int(rep.failure_kind),
        "DetectionTime": _clamp(rep.detection_time_s, icd, "FSW_FDIR", "DetectionTime"),
        "IsolationDelay": _clamp(rep.isolation_delay_s, icd, "FSW_FDIR", "IsolationDelay"),
        "SensorFlags": sensor_flags,
    }


def command_signals(icd: Icd, cycle: int, res: CycleResult, n_thrusters: int,
                    period_ns: int) -> list[tuple[str, Signals]]:
    """THR_CMD_0..m for one cycle (module docstring)."""
    max_on = period_ns / NS_PER_S
    lsb = icd.on_time_lsb_s
    per = icd.thrusters_per_command
    out = []
    for f, name in enumerate(icd.command_frames_for(n_thrusters)):
        sig: Signals = {"Cycle": cycle % icd.command_cycle_modulus, "ImuCounter": res.imu_counter}
        for k in range(f * per, (f + 1) * per):
            on = min(max(res.on_time_s[k] if k < n_thrusters else 0.0, 0.0), max_on)
            if on >= max_on:
                on = max_on + FULL_ON_OVERLAP_S
            sig[icd.on_time_signals[k]] = round(on / lsb) * lsb
        out.append((name, sig))
    return out


def feed(fc: FlightComputer, d: Decoded, t_ns: int) -> bool:
    """Feed sensor frame ``d`` to ``fc`` at ``t_ns``; True when it is a sample the sensor
    watchdog counts (a valid IMU_RATE or star-tracker sample the computer took)."""
    s = d.signals
    name = d.name
    if name == "IMU_RATE":
        return bool(s["Valid"]) and fc.on_imu_rate(
            t_ns, np.array((s["RateX"], s["RateY"], s["RateZ"])), d.counter, d.gap)
    if name == "IMU_ACCEL":
        if s["Valid"]:
            fc.on_imu_accel(t_ns, np.array((s["AccelX"], s["AccelY"], s["AccelZ"])),
                            d.counter, d.gap)
    elif name == "STR_QUAT":
        payload = (s["Largest"], s["C0"], s["C1"], s["C2"])
        return bool(s["Valid"]) and fc.on_star_tracker(
            t_ns, np.array(unpack_quaternion(s)), payload)
    elif name == "NAV_POS":
        if s["Valid"]:
            fc.on_nav_pos(t_ns, np.array((s["PosX"], s["PosY"], s["PosZ"])))
    elif name == "NAV_VEL":
        if s["Valid"]:
            fc.on_nav_vel(t_ns, np.array((s["VelX"], s["VelY"], s["VelZ"])))
    elif name == "THR_STATUS":
        fc.on_thr_status(t_ns, s)
    return False
