"""What the live monitor knows of a bus: every frame decoded and checked, counted, summed up.

In: frames as they arrive (any python-can bus: a run's portable-bus channel, SocketCAN, an
adapter to real hardware), each with the receiver's time [ns] (``feed``). The checks are
the receivers' own (dbc.codec.FrameChecker: known ID, length, alive counter, CRC, range),
so rejects are counted by the same causes as in summary.json. Out (:meth:`snapshot`, a
plain dict the UI draws): per message its count, period and jitter [ms] over the last
:data:`INTERVALS` arrivals, last decoded signals and rejects by cause; the vehicle as the
bus tells it (flight-software mode, FDIR flags and failed thruster, the estimated attitude
quaternion, body rates [deg/s], position [m], the bench's simulated time, health and active
faults); per thruster its commanded and actual valve state (THR_STATUS) and how many
commands opened it; the bus load over the last second of the receiver's clock (exact
frame bits with stuffing, bench.wire.timing.classic, against the DBC's bitrate: on a real
or realtime bus its load; a lockstep run, faster than real time, shows more than 100 %);
and an event log (mode and flag changes, the first reject of each message and cause).
Pure: time is an argument.
"""

from __future__ import annotations

import itertools
import math
import statistics
from collections import defaultdict, deque
from typing import Any

import can
from cantools.database.can import Database

from bench.wire.timing.classic import frame_bits
from dbc.codec import FrameChecker, bitrate_bps
from dbc.icd import Icd
from dbc.quaternion import unpack_quaternion

INTERVALS = 50  # arrivals a period and its jitter are taken over
LOAD_WINDOW_NS = 1_000_000_000
MAX_EVENTS = 200  # event log lines kept
NS_PER_MS = 1e6
RAD_DEG = 180.0 / math.pi
ON_TIME_PREFIX = "OnTime_T"  # THR_CMD_n's per-thruster on-time signals, OnTime_Tkk


class MonitorState:
    """The monitor's picture of the bus (module docstring)."""

    def __init__(self, db: Database) -> None:
        self.db = db
        self.icd = Icd.from_database(db)
        self.checker = FrameChecker(db)
        self.bitrate_bps = bitrate_bps(db)
        self.counts: dict[str, int] = defaultdict(int)
        self.arrivals: dict[str, deque[int]] = defaultdict(lambda: deque(maxlen=INTERVALS + 1))
        self.last: dict[str, dict[str, float]] = {}
        self.bits: deque[tuple[int, int]] = deque()  # (t_ns, bits) of the last second
        self.events: deque[str] = deque(maxlen=MAX_EVENTS)
        self.openings: dict[int, int] = defaultdict(int)
        self._rejects_seen: set[tuple[str, str]] = set()
        self.frames = 0
        modes = {v: k for k, v in self.icd.modes.items()}
        self._mode_name = lambda v: modes.get(int(v), str(int(v)))

    def feed(self, msg: can.Message, t_ns: int) -> None:
        """Take one frame received at ``t_ns``."""
        self.frames += 1
        if not msg.is_error_frame:
            self.bits.append((t_ns, frame_bits(msg.arbitration_id, bytes(msg.data),
                                               msg.is_extended_id, msg.is_remote_frame)))
        while self.bits and self.bits[0][0] < t_ns - LOAD_WINDOW_NS:
            self.bits.popleft()
        d = self.checker.check(msg, t_ns)
        if d is None:
            self._new_rejects(t_ns)
            return
        self.counts[d.name] += 1
        self.arrivals[d.name].append(t_ns)
        previous = self.last.get(d.name)
        self.last[d.name] = dict(d.signals)
        self._events(d.name, d.signals, previous, t_ns)
        if d.name in self.icd.command_frames:
            for sig, value in d.signals.items():
                if sig.startswith(ON_TIME_PREFIX) and value > 0.0:
                    self.openings[int(sig[len(ON_TIME_PREFIX):])] += 1

    def _new_rejects(self, t_ns: int) -> None:
        for name, st in self.checker.stats.items():
            for cause in st.rejected:
                if (name, cause) not in self._rejects_seen:
                    self._rejects_seen.add((name, cause))
                    self.events.append(f"{t_ns / 1e9:10.3f}  {name} rejected: {cause}")

    def _events(self, name: str, sig: dict[str, float], prev: dict[str, float] | None,
                t_ns: int) -> None:
        stamp = f"{t_ns / 1e9:10.3f}  "
        if name == "FSW_STATUS":
            if prev is None or prev["Mode"] != sig["Mode"]:
                self.events.append(f"{stamp}flight software mode {self._mode_name(sig['Mode'])}")
            if prev is not None and prev["FdirFlags"] != sig["FdirFlags"]:
                self.events.append(f"{stamp}FDIR flags {self._flags(sig['FdirFlags'])}")
        elif name == "BENCH_STATUS" and prev is not None:
            for key in ("ActiveFaults", "Health"):
                if prev[key] != sig[key]:
                    self.events.append(f"{stamp}bench {key} {int(sig[key])}")
        elif (name == "FSW_FDIR"
              and (prev is None or prev["FailedThruster"] != sig["FailedThruster"])
              and int(sig["FailedThruster"]) != self.icd.no_failed_thruster):
            self.events.append(f"{stamp}FDIR isolated thruster {int(sig['FailedThruster'])}")

    def _flags(self, value: float) -> str:
        on = [n for n, bit in self.icd.fdir_flags.items() if int(value) & (1 << bit)]
        return ", ".join(on) or "none"

    def _period(self, name: str) -> tuple[float | None, float | None]:
        t = list(self.arrivals[name])
        if len(t) < 3:
            return None, None
        dt = [(b - a) / NS_PER_MS for a, b in itertools.pairwise(t)]
        return statistics.fmean(dt), statistics.pstdev(dt)

    def snapshot(self) -> dict[str, Any]:
        """The plain picture the UI draws (module docstring)."""
        messages = []
        for m in self.db.messages:
            n = self.counts.get(m.name, 0)
            st = self.checker.stats.get(m.name)
            rejects = dict(st.rejected) if st is not None else {}
            if not n and not rejects:
                continue
            period, jitter = self._period(m.name)
            messages.append({"id": m.frame_id, "name": m.name, "count": n, "period_ms": period,
                             "jitter_ms": jitter, "last": self.last.get(m.name, {}),
                             "rejected": rejects})
        other = {k: dict(v.rejected) for k, v in self.checker.stats.items()
                 if k not in self.icd.sender}  # not a message of the DBC
        return {"frames": self.frames, "messages": messages, "other_rejects": other,
                "vehicle": self._vehicle(), "thrusters": self._thrusters(),
                "bus_load": sum(b for _, b in self.bits) / self.bitrate_bps,
                "events": list(self.events)}

    def _vehicle(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        st = self.last.get("FSW_STATUS")
        if st is not None:
            out.update(mode=self._mode_name(st["Mode"]), fdir=self._flags(st["FdirFlags"]),
                       cycle=int(st["Cycle"]))
        est = self.last.get("FSW_ATT_EST")
        if est is not None:
            out["q_est"] = unpack_quaternion(est)
        rate = self.last.get("IMU_RATE")
        if rate is not None:
            out["rate_deg_s"] = tuple(rate[k] * RAD_DEG for k in ("RateX", "RateY", "RateZ"))
        pos = self.last.get("NAV_POS")
        if pos is not None:
            out["pos_m"] = (pos["PosX"], pos["PosY"], pos["PosZ"])
        bench = self.last.get("BENCH_STATUS")
        if bench is not None:
            out.update(sim_time_s=bench["SimTime"], health=int(bench["Health"]),
                       active_faults=int(bench["ActiveFaults"]))
        fdir = self.last.get("FSW_FDIR")
        if fdir is not None and int(fdir["FailedThruster"]) != self.icd.no_failed_thruster:
            out["failed_thruster"] = int(fdir["FailedThruster"])
        return out

    def _thrusters(self) -> list[dict[str, Any]]:
        status = self.last.get("THR_STATUS", {})
        active = [k for k in range(len(status)) if status.get(f"Cmd_T{k:02d}")
                  or status.get(f"Open_T{k:02d}")] + list(self.openings)
        return [{"thruster": k, "commanded": bool(status.get(f"Cmd_T{k:02d}", 0)),
                 "open": bool(status.get(f"Open_T{k:02d}", 0)),
                 "openings": self.openings.get(k, 0)}
                for k in range(max(active, default=-1) + 1)]
