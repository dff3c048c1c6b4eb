"""The station's sensor frames: which are due at a time, and their signals.

In: the plant (true state, sensors, valves) at ``t_ns``, the bench's health and fault
acknowledgement for BENCH_STATUS. Out: ``(name, signals)`` records in physical units, in
frame-ID order, for every message the bench sends periodically whose DBC cycle time
divides ``t_ns`` (``NAV_*`` only when the scenario has relative navigation).

Signals: IMU_RATE body rates [rad/s], IMU_ACCEL specific force [m/s^2] (both with their
Valid flag), STR_QUAT q_BN in the DBC's smallest-three encoding, NAV_POS/NAV_VEL the
relative navigation solution [m], [m/s] clipped to the DBC range (a sensor saturates, it
does not wrap; NAV_VEL is the velocity of the NAV_POS solution of the same instant),
THR_STATUS commanded/open/current flags per valve, BENCH_STATUS simulation time [s],
active faults, health flags and the last FAULT_CMD's acknowledgement.
Pure: no clock, socket or file.
"""

from __future__ import annotations

from bench.station.plant import Plant
from dbc.icd import BENCH, Icd
from dbc.quaternion import pack_quaternion

NS_PER_S = 1_000_000_000
NAV_PREFIX = "NAV_"
STATUS_FLAGS = ("Cmd", "Open", "Current")  # THR_STATUS signals per thruster: Cmd_T00 ...
Signals = dict[str, float | int]


def _clip(x: float, limit: float) -> float:
    """``x`` limited to +-``limit``."""
    return min(limit, max(-limit, x))


class SensorFrames:
    """Samples the bench's periodic frames (see the module docstring)."""

    def __init__(self, plant: Plant, icd: Icd, n_thrusters: int, rel_nav: bool) -> None:
        self._plant = plant
        periodic = sorted((icd.frame_id[n], n) for n in icd.sent_by(BENCH)
                          if icd.period_ns[n] and n != "SYNC")
        #: (name, period) of the frames sent, in ID order
        self.schedule = tuple((n, icd.period_ns[n]) for _, n in periodic
                              if rel_nav or not n.startswith(NAV_PREFIX))
        self.periods_ns = {n: icd.period_ns[n] for _, n in periodic}
        self._status_names = [tuple(f"{flag}_T{k:02d}" for flag in STATUS_FLAGS)
                              for k in range(n_thrusters)]
        self._status_signals = icd.payload["THR_STATUS"]
        self._nav_limits = {
            "NAV_POS": icd.limit("NAV_POS", "PosX"), "NAV_VEL": icd.limit("NAV_VEL", "VelX")}
        self._nav_vel: tuple[tuple[float, float, float], bool] = ((0.0, 0.0, 0.0), False)

    def due(self, t_ns: int, health: int, active_faults: int, cmd_counter: int,
            cmd_rejected: bool) -> list[tuple[str, Signals]]:
        """The frames due at ``t_ns`` with their signals, in ID order."""
        out = []
        for name, period in self.schedule:
            if t_ns % period == 0:
                out.append((name, self.sample(name, t_ns, health, active_faults, cmd_counter,
                                              cmd_rejected)))
        return out

    def sample(self, name: str, t_ns: int, health: int, active_faults: int,
               cmd_counter: int, cmd_rejected: bool) -> Signals:
        """The signals of message ``name`` sampled at ``t_ns``."""
        p = self._plant
        s = p.state
        if name == "IMU_RATE":
            w, ok = p.gyro.measure(t_ns, (s[4], s[5], s[6]))
            return {"Valid": int(ok), "RateX": w[0], "RateY": w[1], "RateZ": w[2]}
        if name == "IMU_ACCEL":
            a, ok = p.accel.measure(t_ns, p.specific_force_B())
            return {"Valid": int(ok), "AccelX": a[0], "AccelY": a[1], "AccelZ": a[2]}
        if name == "STR_QUAT":
            q, valid = p.star.sample(t_ns, (s[0], s[1], s[2], s[3]))
            return {"Valid": int(valid), **pack_quaternion(q)}
        if name == "NAV_POS":
            assert p.rel_nav is not None
            pos, vel, ok = p.rel_nav.sample(t_ns, (s[7], s[8], s[9]), (s[10], s[11], s[12]))
            self._nav_vel = (vel, ok)
            lim = self._nav_limits[name]
            return {"Valid": int(ok), "PosX": _clip(pos[0], lim), "PosY": _clip(pos[1], lim),
                    "PosZ": _clip(pos[2], lim)}
        if name == "NAV_VEL":  # sampled with NAV_POS (same solution), sent right after it
            vel, ok = self._nav_vel
            lim = self._nav_limits[name]
            return {"Valid": int(ok), "VelX": _clip(vel[0], lim), "VelY": _clip(vel[1], lim),
                    "VelZ": _clip(vel[2], lim)}
        if name == "THR_STATUS":
            sig: Signals = dict.fromkeys(self._status_signals, 0)
            names = self._status_names
            for k, (cmd, opn, cur) in enumerate(p.thrusters.status(t_ns)):
                sig[names[k][0]], sig[names[k][1]], sig[names[k][2]] = int(cmd), int(opn), int(cur)
            return sig
        # BENCH_STATUS
        return {
            "SimTime": t_ns / NS_PER_S,
            "ActiveFaults": active_faults,
            "Health": health,
            "FaultCmdCounter": cmd_counter,
            "FaultCmdRejected": int(cmd_rejected),
        }
