"""Timing of a run: per-message periods, jitter, latency, cycle-time checks, chains, bus load.

What
----
Measurements over the timing files of a run folder (written by :mod:`bench.wire.trace` and
:mod:`bench.results.writers`):

* per message: count, period mean and jitter (standard deviation and max - min of the
  inter-arrival times), latency ``t_rx - t_ready`` p50/p99/max, missed cycles and
  cycle-time violations against the DBC's ``GenMsgCycleTime``;
* data age between two messages (:meth:`RunTiming.latency`): for each frame of ``dst``,
  its reception minus the queuing time of the newest ``src`` frame seen before ``dst``
  was queued (the age of ``src``'s data when ``dst`` arrives);
* the chain IMU sample -> command -> valve opening per control cycle
  (:meth:`RunTiming.chain`);
* bus load per window, mean and peak, overall and per sending node
  (:meth:`RunTiming.bus_load`);
* the worst-case response-time bound of each periodic message next to its measured
  maximum latency, flagged when the measurement exceeds the bound.

Inputs
------
``frames.csv`` (``t_ready_s, t_start_s, t_rx_s, id, dlc, bits, tx, counter``),
``chains.csv`` (``cycle, imu_counter, t_imu_tx_s, t_cmd_rx_s, t_fire_cmd_rx_s,
t_valve_open_s``; run folders written before ``t_fire_cmd_rx_s`` existed read it as
``t_cmd_rx_s``) and
``summary.json`` (``mode``, ``bitrate_bps``). Time base: lockstep = simulated seconds
(modelled times), realtime = seconds since the bench started (measured), live = seconds
since the first frame heard. Names, senders and cycle times come from the DBC.

Outputs
-------
:class:`RunTiming`, whose measurements are the frozen records of
:mod:`bench.operator.analysis.records` (units in the field names; an empty statistic is
``nan`` with ``n = 0``, so an assertion ``x < limit`` on it fails).

Assumptions
-----------
* A frame's *seen* time is ``t_rx`` where known, else ``t_ready`` (a realtime bench
  frame whose reception the flight software did not log in ``fsw_rx.csv``; the virtual
  buses deliver within tens of microseconds of sending). Periods use seen times.
* Rows with ``bits == 0`` have no place on the bus time line (the flight software's boot
  heartbeat, recorded before the run's time starts): counted, excluded from all timing.
* Missed cycles and bus load as :mod:`bench.operator.analysis.measures` computes them
  (its docstring), with its sources: CANoe's cycle-time checks, and worst-case response
  times after Davis, Burns, Bril and Lukkien (2007) computed by
  :mod:`bench.operator.analysis.rta`.

Modules
-------
:mod:`~bench.operator.analysis.tables` reads the files into column arrays,
:mod:`~bench.operator.analysis.measures` holds the pure measurements,
:mod:`~bench.operator.analysis.records` the options and result records; this module
holds :class:`RunTiming`, which applies the measurements to one run, and
:func:`dbc_bitrate_bps`.

No clock is read here.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping
from dataclasses import asdict
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from bench.operator.analysis.measures import (
    bus_load,
    chain_timing,
    cycle_time_violations,
    data_age_s,
    missed_cycles,
    period_stats_s,
    rta_bounds_s,
)
from bench.operator.analysis.reception import (
    RX_LOG_COLUMNS,
    RX_LOG_FILE,
    fill_reception,
    receive_log,
)
from bench.operator.analysis.records import (
    MS_PER_S,
    PCT,
    US_PER_S,
    BusLoad,
    ChainTiming,
    MessageTiming,
    Percentiles,
    TimingOptions,
    _is_real,
)
from bench.operator.analysis.tables import ChainTable, FrameTable, read_csv_columns
from bench.results.record import RECORD_LEAN, run_file
from bench.results.writers import CHAIN_COLUMNS
from bench.wire.trace import FRAME_COLUMNS
from dbc.codec import BITRATE_ATTRIBUTE, bitrate_bps
from dbc.database import load_database
from dbc.errors import ConfigError, IcdError, RunError

MODES = ("lockstep", "realtime", "live")
UNKNOWN_NODE = "?"
# GenMsgSendType of a message sent cyclically and also at once on an event (the flight
# software's status frames on a mode or flag change): shorter intervals are no violation
SEND_CYCLIC_AND_EVENT = "CyclicAndSpontanX"
RUN_SOURCE = "RunTiming"


def _time_source(frames: FrameTable) -> str:
    rx = np.isfinite(frames.t_rx_s)
    if rx.size == 0:
        return "none"
    if rx.all():
        return "t_rx"
    return "t_ready" if not rx.any() else "mixed"


class RunTiming:
    """The timing of one run (or one live capture), measured on demand.

    Build it with :meth:`load` from a run folder, or directly from tables (a live
    capture, synthetic data). ``mode``: lockstep, realtime or live; ``bitrate_bps``: the
    bus bitrate (for bus load and bounds); ``db``: the DBC (the project's by default).
    """

    def __init__(
        self,
        frames: FrameTable,
        chains: ChainTable | None = None,
        *,
        mode: str,
        bitrate_bps: int,
        db: Any = None,
        options: TimingOptions | None = None,
        run_dir: Path | None = None,
        sent: Mapping[str, int] | None = None,
    ) -> None:
        if mode not in MODES:
            raise ConfigError(RUN_SOURCE, "mode", mode, f"one of {', '.join(MODES)}")
        if isinstance(bitrate_bps, bool) or not isinstance(bitrate_bps, int) or bitrate_bps <= 0:
            raise ConfigError(RUN_SOURCE, "bitrate_bps", bitrate_bps, "a positive integer")
        self.frames = frames
        self.chains = chains
        self.mode = mode
        self.bitrate_bps = bitrate_bps
        self.db = load_database() if db is None else db
        self.options = options or TimingOptions()
        self.run_dir = run_dir
        # frames each message's sender says it sent (summary.json): a message sent but never
        # on the trace is reported with all of them missed, not left out
        self.sent = {k: int(v) for k, v in (sent or {}).items() if v}

    @classmethod
    def load(
        cls, run_dir: Path | str, options: TimingOptions | None = None, db: Any = None
    ) -> RunTiming:
        """Read ``frames.csv``, ``chains.csv`` (optional) and ``summary.json`` of a run folder.

        Realtime: with the flight software's receive log (``fsw_rx.csv``) the bench's frames
        get their reception times from it (:mod:`bench.operator.analysis.reception`).
        """
        d = Path(run_dir)
        summary_path = d / "summary.json"
        try:
            summary = json.loads(summary_path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise RunError(f"{summary_path}: missing (not a run folder?)") from None
        except json.JSONDecodeError as exc:
            raise RunError(f"{summary_path}: not JSON ({exc})") from exc
        if summary.get("record") == RECORD_LEAN:
            raise ConfigError(str(d), "record", RECORD_LEAN, "a run recorded at the standard or "
                              "full level: a lean one (a campaign's case) keeps no frames.csv "
                              "(`thruster-hil campaign rerun CAMPAIGN_DIR CASE` makes the case's "
                              "whole folder, frames.csv included)")
        db = load_database() if db is None else db
        bitrate = summary.get("bitrate_bps") or _dbc_bitrate_bps(db)
        frames = FrameTable.from_columns(read_csv_columns(run_file(d, "frames.csv"),
                                                          FRAME_COLUMNS))
        origin = summary.get("wall_clock_origin_s")
        if summary.get("mode") == "realtime" and origin is not None and (d / RX_LOG_FILE).exists():
            log = receive_log(read_csv_columns(d / RX_LOG_FILE, RX_LOG_COLUMNS), float(origin))
            frames = dataclasses.replace(frames, t_rx_s=fill_reception(
                frames.t_ready_s, frames.t_rx_s, frames.can_id, frames.tx, frames.counter, log))
        chains_path = run_file(d, "chains.csv")
        chains = ChainTable.read(chains_path) if chains_path.exists() else None
        return cls(
            frames,
            chains,
            mode=summary.get("mode", "lockstep"),
            bitrate_bps=int(bitrate),
            db=db,
            options=options,
            run_dir=d,
            sent={n: r["sent"] for n, r in summary.get("frames", {}).items()
                  if isinstance(r, dict) and r.get("sent")},
        )

    # -- names -------------------------------------------------------------------------
    @cached_property
    def _names(self) -> dict[int, tuple[str, str, float | None]]:
        """CAN ID -> (name, sender, cycle time ms) for every ID in the frames."""
        out: dict[int, tuple[str, str, float | None]] = {}
        for can_id in sorted(set(self.frames.can_id.tolist())):
            try:
                m = self.db.get_message_by_frame_id(can_id)
            except KeyError:
                out[can_id] = (f"0x{can_id:03X}", UNKNOWN_NODE, None)
                continue
            cycle = m.cycle_time if m.cycle_time else None
            out[can_id] = (m.name, m.senders[0] if m.senders else UNKNOWN_NODE, cycle)
        return out

    def _send_type(self, can_id: int) -> str | None:
        """The DBC's ``GenMsgSendType`` of ``can_id`` (None: not in the DBC, or none)."""
        try:
            return self.db.get_message_by_frame_id(can_id).send_type
        except KeyError:
            return None

    def _id_of(self, name: str) -> int:
        for can_id, (n, _, _) in self._names.items():
            if n == name:
                return can_id
        try:
            return int(self.db.get_message_by_name(name).frame_id)
        except KeyError:
            known = ", ".join(n for n, _, _ in self._names.values())
            raise ConfigError(
                RUN_SOURCE, "message", name, f"a message of the DBC (in this run: {known})"
            ) from None

    def _rows(self, name: str, timed: bool = True) -> FrameTable:
        """Rows of one message, in order of their seen time; only timed rows by default."""
        f = self.frames
        mask = f.can_id == self._id_of(name)
        if timed:
            mask &= f.bits > 0
        rows = f.select(mask)
        return rows.select(np.argsort(rows.seen_s, kind="stable"))

    @property
    def nodes(self) -> list[str]:
        """The sending node of each row of the frames."""
        names = self._names
        return [names[i][1] for i in self.frames.can_id.tolist()]

    # -- measurements ------------------------------------------------------------------
    @cached_property
    def bounds_s(self) -> dict[str, float]:
        """Worst-case response time [s] of each periodic DBC message at the run's bitrate."""
        return rta_bounds_s(self.db, self.bitrate_bps)

    @cached_property
    def messages(self) -> dict[str, MessageTiming]:
        """Timing of every message seen in the run, or sent in it, by name, in ID order.

        A DBC message its sender sent but that never reached the trace (e.g. dropped by a
        fault) is included with ``count`` 0 and every sent frame a missed cycle.
        """
        names = dict(self._names)
        for name in self.sent:
            try:
                m = self.db.get_message_by_name(name)
            except KeyError:
                continue
            if m.frame_id not in names:
                names[m.frame_id] = (m.name, m.senders[0] if m.senders else UNKNOWN_NODE,
                                     m.cycle_time or None)
        return {info[0]: self._message(can_id, info) for can_id, info in sorted(names.items())}

    def message(self, name: str) -> MessageTiming:
        """Timing of one message (a DBC name, or ``0x...`` for an ID outside the DBC).

        A DBC message that never appeared in the run has ``count == 0``.
        """
        can_id = self._id_of(name)
        if name in self.messages:
            return self.messages[name]
        m = self.db.get_message_by_frame_id(can_id)
        return self._message(
            can_id, (m.name, m.senders[0] if m.senders else UNKNOWN_NODE, m.cycle_time or None)
        )

    def _message(self, can_id: int, info: tuple[str, str, float | None]) -> MessageTiming:
        name, sender, cycle_ms = info
        o = self.options
        all_rows = self.frames.can_id == can_id
        rows = self._rows(name)
        t = rows.seen_s
        t = t[np.isfinite(t)]
        mean_s, std_s, pp_s = period_stats_s(t)
        cycle_s = None if cycle_ms is None else cycle_ms / MS_PER_S
        n_abs: int | None = None
        n_rel: int | None = None
        if cycle_s is not None:
            n_abs, n_rel = cycle_time_violations(
                np.diff(t),
                cycle_s,
                None if o.cycle_abs_tolerance_ms is None else o.cycle_abs_tolerance_ms / MS_PER_S,
                None if o.cycle_rel_tolerance_pct is None else o.cycle_rel_tolerance_pct / PCT,
                early_allowed=self._send_type(can_id) == SEND_CYCLIC_AND_EVENT,
            )
        finite = np.isfinite(rows.seen_s)
        missed, gaps = missed_cycles(t, rows.counter[finite], cycle_s, o.missed_gap_periods)
        count = int(np.count_nonzero(all_rows))
        if count == 0:  # sent, never heard: each one missed
            missed = self.sent.get(name, 0)
        bound = self.bounds_s.get(name)
        return MessageTiming(
            name=name,
            can_id=can_id,
            sender=sender,
            cycle_time_ms=cycle_ms,
            count=count,
            time_source=_time_source(rows),
            period_mean_ms=mean_s * MS_PER_S,
            jitter_std_us=std_s * US_PER_S,
            jitter_pp_us=pp_s * US_PER_S,
            latency=Percentiles.of_seconds(rows.t_rx_s - rows.t_ready_s),
            missed_cycles=missed,
            counter_gaps=gaps,
            cycle_violations_abs=n_abs,
            cycle_violations_rel=n_rel,
            bound_us=None if bound is None else bound * US_PER_S,
        )

    def message_latency_s(self, name: str) -> np.ndarray:
        """``t_rx - t_ready`` [s] of every frame of ``name`` where both are known."""
        rows = self._rows(name)
        lat = rows.t_rx_s - rows.t_ready_s
        return lat[np.isfinite(lat)]

    def latency_samples_s(self, src: str, dst: str) -> np.ndarray:
        """Age [s] of ``src`` data at each reception of ``dst`` (see :func:`data_age_s`)."""
        s, d = self._rows(src), self._rows(dst)
        return data_age_s(s.seen_s, s.t_ready_s, d.t_ready_s, d.t_rx_s)

    def latency(self, src: str, dst: str) -> Percentiles:
        """Percentiles of the age of ``src`` data at reception of ``dst`` (µs).

        For each ``dst`` frame: its ``t_rx`` minus ``t_ready`` of the newest ``src`` frame
        received before ``dst`` was queued, e.g. ``latency("IMU_RATE", "THR_CMD_0")``.
        """
        return Percentiles.of_seconds(self.latency_samples_s(src, dst))

    def chain(self) -> ChainTiming:
        """IMU sample -> command -> valve opening percentiles (from ``chains.csv``)."""
        if self.chains is None:
            return chain_timing(ChainTable.from_columns({k: [] for k in CHAIN_COLUMNS}))
        return chain_timing(self.chains)

    def chain_age_s(self) -> np.ndarray:
        """Age [s] of the IMU data at each first valve opening (cycles that fired)."""
        if self.chains is None:
            return np.zeros(0)
        age = self.chains.t_valve_open_s - self.chains.t_imu_tx_s
        return age[np.isfinite(age)]

    def bus_load(self, window_ms: float | None = None) -> BusLoad:
        """Bus load per window (``options.window_ms`` by default), overall and per node."""
        w = self.options.window_ms if window_ms is None else window_ms
        if not _is_real(w) or w <= 0:
            raise ConfigError(RUN_SOURCE, "window_ms", w, "a finite number > 0")
        return bus_load(self.frames, self.nodes, self.bitrate_bps, w)

    def flagged(self) -> list[str]:
        """Names of the messages whose measured maximum latency exceeds their bound."""
        return [n for n, m in self.messages.items() if m.above_bound]

    def unheard(self) -> list[str]:
        """Names of the messages their sender sent that never reached the trace."""
        return [n for n, m in self.messages.items() if m.count == 0 and self.sent.get(n)]

    def to_dict(self) -> dict[str, Any]:
        """Everything, JSON-ready (the content of ``timing.json``)."""
        return {
            "run_dir": None if self.run_dir is None else str(self.run_dir),
            "mode": self.mode,
            "bitrate_bps": self.bitrate_bps,
            "options": asdict(self.options),
            "messages": {n: m.to_dict() for n, m in self.messages.items()},
            "chain": self.chain().to_dict(),
            "bus_load": self.bus_load().to_dict(),
            "flags": self.flagged(),
            "unheard": self.unheard(),
        }


def _dbc_bitrate_bps(db: Any) -> int:
    """The DBC's ``Baudrate`` attribute (bit/s)."""
    try:
        return bitrate_bps(db)
    except IcdError as exc:
        raise ConfigError("DBC", BITRATE_ATTRIBUTE, None, "a Baudrate attribute (bit/s)") from exc


def dbc_bitrate_bps(db: Any = None) -> int:
    """The bitrate the DBC declares (``Baudrate`` attribute, bit/s)."""
    return _dbc_bitrate_bps(load_database() if db is None else db)
