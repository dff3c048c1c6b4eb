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
Frozen dataclasses; units in the field names (``_s``, ``_ms``, ``_us``, ``_pct``). An empty
statistic is ``nan`` with ``n = 0``, so an assertion ``x < limit`` on it fails.

Assumptions
-----------
* A frame's *seen* time is ``t_rx`` where known, else ``t_ready`` (a realtime bench
  frame whose reception the flight software did not log in ``fsw_rx.csv``; the virtual
  buses deliver within tens of microseconds of sending). Periods use seen times.
* Rows with ``bits == 0`` have no place on the bus time line (the flight software's boot
  heartbeat, recorded before the run's time starts): counted, excluded from all timing.
* Missed cycles: an inter-arrival gap longer than ``missed_gap_periods`` cycle times
  misses ``max(1, round(gap / cycle) - 1)`` instances; an alive-counter jump of d
  (modulo 15, :data:`dbc.e2e.COUNTER_MODULUS`) misses ``d - 1``; each gap counts the
  larger of the two. A repeated counter is not a miss (receivers reject it).
* Bus load: a frame occupies the wire from ``t_start`` to ``t_rx`` when both are known
  (lockstep), else for ``bits / bitrate`` ending at its seen time (realtime, live).
  Windows are aligned to multiples of the window length; the mean is over every window
  from the first frame's to the last frame's.

Sources
-------
* Cycle-time checks as CANoe's test service library does them
  (``ChkStart_MsgAbsCycleTimeViolation``: an inter-arrival time outside [min, max] is a
  violation; ``ChkStart_MsgRelCycleTimeViolation``: the same with the limits given as
  factors of ``GenMsgCycleTime``). Here both windows are symmetric around the DBC cycle
  time, ±``cycle_abs_tolerance_ms`` and ±``cycle_rel_tolerance_pct``; ``None`` disables a
  window, as a limit of 0 does in CANoe. Messages without a cycle time are not checked.
* Worst-case response times: Davis, Burns, Bril, Lukkien, "Controller Area Network (CAN)
  schedulability analysis: Refuted, revisited and revised", Real-Time Systems 35 (2007),
  computed by :mod:`bench.operator.analysis.rta` for the DBC's periodic messages at the run's
  bitrate
  with zero queuing jitter (the bench queues periodic frames on a fixed grid). The bound
  runs from the queuing event to the end of the frame, so it bounds the measured
  ``t_rx - t_ready``. In realtime and live runs the measured latency includes the host's
  transport (hilbus, SocketCAN), not only the wire: a flag there says the transport was
  slower than an ideal bus, not that the analysis is wrong.

No clock is read here.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from bench.operator.analysis.defaults import (
    DEFAULT_CYCLE_ABS_TOLERANCE_MS,
    DEFAULT_CYCLE_REL_TOLERANCE_PCT,
    DEFAULT_MISSED_GAP_PERIODS,
    DEFAULT_WINDOW_MS,
)
from bench.operator.analysis.reception import (
    RX_LOG_COLUMNS,
    RX_LOG_FILE,
    fill_reception,
    receive_log,
)
from bench.operator.analysis.rta import messages_from_dbc, response_times
from bench.results.writers import CHAIN_COLUMNS
from bench.wire.trace import FRAME_COLUMNS
from dbc.codec import BITRATE_ATTRIBUTE, bitrate_bps
from dbc.database import load_database
from dbc.e2e import COUNTER_MODULUS
from dbc.errors import ConfigError, IcdError, RunError

US_PER_S = 1e6
MS_PER_S = 1e3
PCT = 100.0
PERCENTILE_LEVELS = (50.0, 99.0)
NAN = float("nan")

MODES = ("lockstep", "realtime", "live")
UNKNOWN_NODE = "?"
NO_COUNTER = -1  # recorder's counter for frames too short to carry one
OPTIONS_SOURCE = "TimingOptions"
RUN_SOURCE = "RunTiming"
FIRE_COLUMN = "t_fire_cmd_rx_s"  # chains.csv: the first firing command frame received


def _is_real(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _json_num(value: float | None) -> float | None:
    """``nan``/``inf`` -> None (JSON has neither)."""
    return None if value is None or not math.isfinite(value) else value


@dataclass(frozen=True)
class TimingOptions:
    """How the measurements are taken.

    ``window_ms``: bus-load window length. ``cycle_abs_tolerance_ms``: absolute
    cycle-time window, ±ms around the DBC cycle time (None: not checked).
    ``cycle_rel_tolerance_pct``: relative window, ±% of the cycle time (None: not checked).
    ``missed_gap_periods``: an inter-arrival gap longer than this many cycle times misses
    at least one instance.
    """

    window_ms: float = DEFAULT_WINDOW_MS
    cycle_abs_tolerance_ms: float | None = DEFAULT_CYCLE_ABS_TOLERANCE_MS
    cycle_rel_tolerance_pct: float | None = DEFAULT_CYCLE_REL_TOLERANCE_PCT
    missed_gap_periods: float = DEFAULT_MISSED_GAP_PERIODS

    def __post_init__(self) -> None:
        if not _is_real(self.window_ms) or self.window_ms <= 0:
            raise ConfigError(OPTIONS_SOURCE, "window_ms", self.window_ms, "a finite number > 0")
        tol = self.cycle_abs_tolerance_ms
        if tol is not None and (not _is_real(tol) or tol < 0):
            raise ConfigError(
                OPTIONS_SOURCE, "cycle_abs_tolerance_ms", tol, "None or a finite number >= 0"
            )
        rel = self.cycle_rel_tolerance_pct
        if rel is not None and (not _is_real(rel) or not 0 <= rel < PCT):
            raise ConfigError(
                OPTIONS_SOURCE, "cycle_rel_tolerance_pct", rel, "None or a number in [0, 100)"
            )
        gap = self.missed_gap_periods
        if not _is_real(gap) or gap <= 1:
            raise ConfigError(OPTIONS_SOURCE, "missed_gap_periods", gap, "a finite number > 1")


@dataclass(frozen=True)
class Percentiles:
    """p50, p99 and maximum of a sample in microseconds, and the sample size ``n``."""

    p50_us: float
    p99_us: float
    max_us: float
    n: int

    @classmethod
    def of_seconds(cls, samples_s: np.ndarray | Sequence[float]) -> Percentiles:
        """Percentiles (linear interpolation) of the finite samples, given in seconds."""
        a = np.asarray(samples_s, dtype=float)
        a = a[np.isfinite(a)] * US_PER_S
        if a.size == 0:
            return cls(NAN, NAN, NAN, 0)
        p50, p99 = np.percentile(a, PERCENTILE_LEVELS)
        return cls(float(p50), float(p99), float(a.max()), int(a.size))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (nan -> None)."""
        return {
            "p50_us": _json_num(self.p50_us),
            "p99_us": _json_num(self.p99_us),
            "max_us": _json_num(self.max_us),
            "n": self.n,
        }


# -- tables ----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class FrameTable:
    """The columns of ``frames.csv`` as arrays (times in s; ``nan`` where unknown)."""

    t_ready_s: np.ndarray
    t_start_s: np.ndarray
    t_rx_s: np.ndarray
    can_id: np.ndarray
    dlc: np.ndarray
    bits: np.ndarray
    tx: np.ndarray
    counter: np.ndarray

    def __post_init__(self) -> None:
        n = {len(v) for v in vars(self).values()}
        if len(n) > 1:
            raise ConfigError("FrameTable", "columns", sorted(n), "columns of equal length")

    @classmethod
    def from_columns(cls, cols: Mapping[str, Any]) -> FrameTable:
        """From a mapping of the ``frames.csv`` column names to sequences."""

        def f(k: str) -> np.ndarray:
            return np.asarray(cols[k], dtype=float)

        def i(k: str) -> np.ndarray:
            return np.asarray(cols[k], dtype=float).astype(np.int64)

        return cls(
            f("t_ready_s"),
            f("t_start_s"),
            f("t_rx_s"),
            i("id"),
            i("dlc"),
            i("bits"),
            i("tx"),
            i("counter"),
        )

    def __len__(self) -> int:
        return len(self.can_id)

    @property
    def seen_s(self) -> np.ndarray:
        """``t_rx`` where known, else ``t_ready``."""
        return np.where(np.isfinite(self.t_rx_s), self.t_rx_s, self.t_ready_s)

    def select(self, mask: np.ndarray) -> FrameTable:
        """The rows where ``mask`` is true (or at the given indices), in that order."""
        return FrameTable(**{k: v[mask] for k, v in vars(self).items()})


@dataclass(frozen=True, eq=False)
class ChainTable:
    """The columns of ``chains.csv`` as arrays (times in s; ``nan`` where none)."""

    cycle: np.ndarray
    imu_counter: np.ndarray
    t_imu_tx_s: np.ndarray
    t_cmd_rx_s: np.ndarray
    t_fire_cmd_rx_s: np.ndarray
    t_valve_open_s: np.ndarray

    @classmethod
    def from_columns(cls, cols: Mapping[str, Any]) -> ChainTable:
        """From a mapping of the ``chains.csv`` column names to sequences.

        Without ``t_fire_cmd_rx_s`` (older run folders) the last command frame stands in.
        """
        if FIRE_COLUMN not in cols:
            cols = {**cols, FIRE_COLUMN: cols["t_cmd_rx_s"]}
        return cls(*(np.asarray(cols[k], dtype=float) for k in CHAIN_COLUMNS))

    @classmethod
    def read(cls, path: Path) -> ChainTable:
        """``chains.csv`` of a run folder (also one written before ``t_fire_cmd_rx_s``)."""
        with open(path, newline="", encoding="utf-8") as f:
            head = next(csv.reader(f), [])
        cols = [c for c in CHAIN_COLUMNS if c != FIRE_COLUMN or c in head]
        return cls.from_columns(read_csv_columns(path, cols))

    def __len__(self) -> int:
        return len(self.cycle)


def read_csv_columns(path: Path, columns: Sequence[str]) -> dict[str, np.ndarray]:
    """Numeric ``columns`` of a run-folder CSV file as float arrays.

    A row with the wrong number of fields or a non-numeric field (the last line of a file
    whose writer died mid-line) is dropped. Raises :class:`RunError` if the file or a
    column is missing.
    """
    try:
        f = open(path, newline="", encoding="utf-8")  # noqa: SIM115 - closed below
    except FileNotFoundError:
        raise RunError(f"{path}: missing (not a run folder?)") from None
    with f:
        reader = csv.reader(f)
        head = next(reader, None) or []
        missing = [c for c in columns if c not in head]
        if missing:
            raise RunError(f"{path}: no column(s) {', '.join(missing)} (header {head})")
        idx = [head.index(c) for c in columns]
        rows: list[list[float]] = []
        for r in reader:
            if len(r) != len(head):
                continue
            try:
                rows.append([float(r[i]) for i in idx])
            except ValueError:
                continue
    arr = np.array(rows, dtype=float).reshape(-1, len(columns))
    return {c: arr[:, j] for j, c in enumerate(columns)}


# -- pure measurements -------------------------------------------------------------------


def period_stats_s(t_s: np.ndarray) -> tuple[float, float, float]:
    """Mean, standard deviation (population) and max - min of the inter-arrival times [s].

    ``t_s``: times of one message in increasing order. ``nan`` for fewer than two times.
    """
    d = np.diff(np.asarray(t_s, dtype=float))
    if d.size == 0:
        return NAN, NAN, NAN
    return float(d.mean()), float(d.std()), float(d.max() - d.min())


def cycle_time_violations(
    intervals_s: np.ndarray,
    cycle_s: float,
    abs_tolerance_s: float | None,
    rel_tolerance: float | None,
) -> tuple[int | None, int | None]:
    """Inter-arrival times outside the absolute and the relative window (None: not checked).

    Absolute window: [cycle - abs_tolerance, cycle + abs_tolerance]; relative window:
    [cycle (1 - rel_tolerance), cycle (1 + rel_tolerance)], ``rel_tolerance`` a fraction.
    Limits are inclusive, as in CANoe (a violation is strictly shorter or longer).
    """
    d = np.asarray(intervals_s, dtype=float)

    def count(lo: float, hi: float) -> int:
        return int(np.count_nonzero((d < lo) | (d > hi)))

    n_abs = (
        None
        if abs_tolerance_s is None
        else count(cycle_s - abs_tolerance_s, cycle_s + abs_tolerance_s)
    )
    n_rel = (
        None
        if rel_tolerance is None
        else count(cycle_s * (1 - rel_tolerance), cycle_s * (1 + rel_tolerance))
    )
    return n_abs, n_rel


def missed_cycles(
    t_s: np.ndarray, counters: np.ndarray, cycle_s: float | None, gap_periods: float
) -> tuple[int, int]:
    """Instances missed between consecutive frames of one message, and those the counter shows.

    ``t_s`` in increasing order, ``counters`` the alive counters in the same order (-1 =
    none). Per gap: ``max(1, round(gap / cycle) - 1)`` if gap > ``gap_periods`` cycles
    (0 otherwise, and always 0 without a cycle time); counter jump d (mod 15) > 0 gives
    d - 1. Returns (sum over gaps of the larger of the two, sum of the counter figure).
    """
    t = np.asarray(t_s, dtype=float)
    c = np.asarray(counters, dtype=np.int64)
    if t.size < 2:
        return 0, 0
    by_time = np.zeros(t.size - 1, dtype=np.int64)
    if cycle_s is not None and cycle_s > 0:
        ratio = np.diff(t) / cycle_s
        by_time = np.where(
            ratio > gap_periods, np.maximum(1, np.rint(ratio).astype(np.int64) - 1), 0
        )
    valid = (c[:-1] != NO_COUNTER) & (c[1:] != NO_COUNTER)
    jump = (c[1:] - c[:-1]) % COUNTER_MODULUS
    by_counter = np.where(valid & (jump > 0), jump - 1, 0)
    return int(np.maximum(by_time, by_counter).sum()), int(by_counter.sum())


def data_age_s(
    src_seen_s: np.ndarray,
    src_ready_s: np.ndarray,
    dst_ready_s: np.ndarray,
    dst_rx_s: np.ndarray,
) -> np.ndarray:
    """Age of ``src`` data when each ``dst`` frame is received [s].

    For each ``dst`` frame: ``dst_rx - src_ready`` of the newest ``src`` frame seen strictly
    before ``dst`` was queued (``dst_ready``). ``dst`` frames with an unknown time, or with
    no earlier ``src`` frame, give no sample; samples come in ``dst`` order.
    """
    seen = np.asarray(src_seen_s, dtype=float)
    ready = np.asarray(src_ready_s, dtype=float)
    known = np.isfinite(seen)
    seen, ready = seen[known], ready[known]
    order = np.argsort(seen, kind="stable")
    seen, ready = seen[order], ready[order]
    d_ready = np.asarray(dst_ready_s, dtype=float)
    d_rx = np.asarray(dst_rx_s, dtype=float)
    ok = np.isfinite(d_ready) & np.isfinite(d_rx)
    idx = np.searchsorted(seen, d_ready[ok], side="left") - 1
    has = idx >= 0
    age = d_rx[ok][has] - ready[idx[has]]
    return age[np.isfinite(age)]


def busy_intervals_s(
    frames: FrameTable, bitrate_bps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """When each timed frame occupied the wire: (start [s], end [s], row index).

    ``t_start..t_rx`` where both are known (lockstep), else ``bits / bitrate`` ending at
    the frame's seen time. Untimed rows (``bits == 0`` or no time at all) are left out.
    """
    wire_s = frames.bits / bitrate_bps
    seen = frames.seen_s
    modelled = np.isfinite(frames.t_start_s) & np.isfinite(frames.t_rx_s)
    start = np.where(modelled, frames.t_start_s, seen - wire_s)
    end = np.where(modelled, frames.t_rx_s, seen)
    keep = np.isfinite(start) & np.isfinite(end) & (frames.bits > 0)
    return start[keep], end[keep], np.nonzero(keep)[0]


def window_busy_s(
    start_s: np.ndarray, end_s: np.ndarray, t0_s: float, window_s: float, n_windows: int
) -> np.ndarray:
    """Busy time [s] inside each window [t0 + k w, t0 + (k + 1) w), k = 0 .. n - 1.

    An interval spanning several windows is split exactly between them; overlapping
    intervals add up (pass the frames of one wire to get a fraction <= 1). Intervals must
    lie inside [t0, t0 + n w].
    """
    busy = np.zeros(n_windows)
    a = np.asarray(start_s, dtype=float)
    b = np.asarray(end_s, dtype=float)
    if a.size == 0:
        return busy
    last = n_windows - 1
    ka = np.clip(np.floor((a - t0_s) / window_s).astype(np.int64), 0, last)
    kb = np.clip(np.ceil((b - t0_s) / window_s).astype(np.int64) - 1, ka, last)
    same = ka == kb
    np.add.at(busy, ka[same], b[same] - a[same])
    split = ~same
    ka, kb, a, b = ka[split], kb[split], a[split], b[split]
    np.add.at(busy, ka, t0_s + (ka + 1) * window_s - a)
    np.add.at(busy, kb, b - (t0_s + kb * window_s))
    full = np.zeros(n_windows + 1)
    np.add.at(full, ka + 1, 1.0)
    np.add.at(full, kb, -1.0)
    busy += np.cumsum(full)[:n_windows] * window_s
    return busy


def rta_bounds_s(db: Any, bitrate_bps: int) -> dict[str, float]:
    """Worst-case response time [s] of each periodic message of ``db`` (Davis et al. 2007).

    ``math.inf`` for a message whose priority level is overloaded.
    """
    results = response_times(messages_from_dbc(db, bitrate_bps), bitrate_bps)
    return {name: r.response_time_s for name, r in results.items()}


# -- results ---------------------------------------------------------------------------


@dataclass(frozen=True)
class MessageTiming:
    """Timing of one message over a run.

    ``count``: every frame of it; the statistics use its timed frames (``bits > 0``).
    ``time_source``: which time the periods use (``t_rx``, ``t_ready``, ``mixed``, ``none``).
    ``jitter_std_us`` / ``jitter_pp_us``: standard deviation / max - min of inter-arrival.
    ``latency``: ``t_rx - t_ready`` where both are known. ``cycle_violations_*``: None when
    not checked (no cycle time, or the window disabled). ``bound_us``: worst-case response
    time from :mod:`bench.operator.analysis.rta` (None for event-driven messages).
    """

    name: str
    can_id: int
    sender: str
    cycle_time_ms: float | None
    count: int
    time_source: str
    period_mean_ms: float
    jitter_std_us: float
    jitter_pp_us: float
    latency: Percentiles
    missed_cycles: int
    counter_gaps: int
    cycle_violations_abs: int | None
    cycle_violations_rel: int | None
    bound_us: float | None

    @property
    def above_bound(self) -> bool:
        """True when the measured maximum latency exceeds the worst-case bound."""
        return (
            self.bound_us is not None and self.latency.n > 0 and self.latency.max_us > self.bound_us
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (nan -> None)."""
        d = asdict(self)
        for k in ("period_mean_ms", "jitter_std_us", "jitter_pp_us", "bound_us"):
            d[k] = _json_num(d[k])
        d["latency"] = self.latency.to_dict()
        d["above_bound"] = self.above_bound
        return d


@dataclass(frozen=True)
class ChainTiming:
    """IMU sample -> command -> valve opening over the control cycles of a run.

    ``imu_to_command``: last command frame received minus the IMU sample's transmission;
    ``command_to_valve``: first valve opening minus the reception of the command frame
    that opened it (the valve's opening delay, longer under a valve fault); ``imu_to_valve``: the
    age of the IMU data when the first valve opens. Cycles where no valve fired have no
    valve samples (``cycles_without_valve``).
    """

    cycles: int
    imu_to_command: Percentiles
    command_to_valve: Percentiles
    imu_to_valve: Percentiles
    cycles_without_valve: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "cycles": self.cycles,
            "imu_to_command": self.imu_to_command.to_dict(),
            "command_to_valve": self.command_to_valve.to_dict(),
            "imu_to_valve": self.imu_to_valve.to_dict(),
            "cycles_without_valve": self.cycles_without_valve,
        }


def chain_timing(chains: ChainTable) -> ChainTiming:
    """Percentiles of the three stages of the chain over every cycle of ``chains``."""
    fired = np.isfinite(chains.t_valve_open_s)
    return ChainTiming(
        cycles=len(chains),
        imu_to_command=Percentiles.of_seconds(chains.t_cmd_rx_s - chains.t_imu_tx_s),
        command_to_valve=Percentiles.of_seconds(chains.t_valve_open_s - chains.t_fire_cmd_rx_s),
        imu_to_valve=Percentiles.of_seconds(chains.t_valve_open_s - chains.t_imu_tx_s),
        cycles_without_valve=int(np.count_nonzero(~fired)),
    )


@dataclass(frozen=True)
class LoadFigures:
    """Bus load of a set of frames: mean over the windows and the busiest window."""

    mean_pct: float
    peak_pct: float
    peak_window_start_s: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (nan -> None)."""
        return {k: _json_num(v) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class BusLoad:
    """Bus load per window: overall and per sending node (DBC sender; ``?`` if unknown)."""

    window_ms: float
    bitrate_bps: int
    n_windows: int
    total: LoadFigures
    per_node: Mapping[str, LoadFigures]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "window_ms": self.window_ms,
            "bitrate_bps": self.bitrate_bps,
            "n_windows": self.n_windows,
            "total": self.total.to_dict(),
            "per_node": {k: v.to_dict() for k, v in self.per_node.items()},
        }


def _load_figures(busy_s: np.ndarray, t0_s: float, window_s: float) -> LoadFigures:
    if busy_s.size == 0:
        return LoadFigures(NAN, NAN, NAN)
    k = int(np.argmax(busy_s))
    return LoadFigures(
        mean_pct=float(busy_s.mean() / window_s * PCT),
        peak_pct=float(busy_s[k] / window_s * PCT),
        peak_window_start_s=t0_s + k * window_s,
    )


def bus_load(
    frames: FrameTable, nodes: Sequence[str], bitrate_bps: int, window_ms: float
) -> BusLoad:
    """Mean and peak load per ``window_ms`` window, overall and per node.

    ``nodes``: the sending node of each row of ``frames``. Windows are aligned to
    multiples of the window length and span the first to the last busy instant.
    """
    window_s = window_ms / MS_PER_S
    start, end, rows = busy_intervals_s(frames, bitrate_bps)
    if start.size == 0:
        empty = LoadFigures(NAN, NAN, NAN)
        return BusLoad(window_ms, bitrate_bps, 0, empty, {})
    t0 = math.floor(float(start.min()) / window_s) * window_s
    n = max(1, math.ceil((float(end.max()) - t0) / window_s))
    total = _load_figures(window_busy_s(start, end, t0, window_s, n), t0, window_s)
    node_of = np.asarray(nodes, dtype=object)[rows]
    per_node = {}
    for node in sorted(set(node_of.tolist())):
        m = node_of == node
        per_node[node] = _load_figures(
            window_busy_s(start[m], end[m], t0, window_s, n), t0, window_s
        )
    return BusLoad(window_ms, bitrate_bps, n, total, per_node)


# -- a run -----------------------------------------------------------------------------


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
        db = load_database() if db is None else db
        bitrate = summary.get("bitrate_bps") or _dbc_bitrate_bps(db)
        frames = FrameTable.from_columns(read_csv_columns(d / "frames.csv", FRAME_COLUMNS))
        origin = summary.get("wall_clock_origin_s")
        if summary.get("mode") == "realtime" and origin is not None and (d / RX_LOG_FILE).exists():
            log = receive_log(read_csv_columns(d / RX_LOG_FILE, RX_LOG_COLUMNS), float(origin))
            frames = dataclasses.replace(frames, t_rx_s=fill_reception(
                frames.t_ready_s, frames.t_rx_s, frames.can_id, frames.tx, frames.counter, log))
        chains = ChainTable.read(d / "chains.csv") if (d / "chains.csv").exists() else None
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
