"""Pure timing measurements over arrays of times: periods, cycle-time checks, missed
cycles, data age, bus load, response-time bounds, the control chain.

What
----
Functions of numpy arrays (times in seconds) and of the tables of
:mod:`bench.operator.analysis.tables`, giving numbers or the records of
:mod:`bench.operator.analysis.records`. :class:`bench.operator.analysis.timing.RunTiming`
applies them to a run. No clock is read, no file is opened.

Assumptions
-----------
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
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from bench.operator.analysis.records import (
    MS_PER_S,
    NAN,
    OPTIONS_SOURCE,
    PCT,
    BusLoad,
    ChainTiming,
    LoadFigures,
    Percentiles,
)
from bench.operator.analysis.rta import messages_from_dbc, response_times
from bench.operator.analysis.tables import NO_COUNTER, ChainTable, FrameTable
from dbc.e2e import COUNTER_MODULUS
from dbc.errors import ConfigError

# Most bus-load windows in one analysis (a float each, per node): 10 million = 80 MB.
MAX_LOAD_WINDOWS = 10_000_000


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
    early_allowed: bool = False,
) -> tuple[int | None, int | None]:
    """Inter-arrival times outside the absolute and the relative window (None: not checked).

    Absolute window: [cycle - abs_tolerance, cycle + abs_tolerance]; relative window:
    [cycle (1 - rel_tolerance), cycle (1 + rel_tolerance)], ``rel_tolerance`` a fraction.
    Limits are inclusive, as in CANoe (a violation is strictly shorter or longer).
    ``early_allowed``: a message sent cyclically and also on an event (the DBC's
    ``GenMsgSendType`` "CyclicAndSpontanX"): a shorter interval is an event's frame, and
    only a longer one is a violation.
    """
    d = np.asarray(intervals_s, dtype=float)

    def count(lo: float, hi: float) -> int:
        if early_allowed:
            return int(np.count_nonzero(d > hi))
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
    if n > MAX_LOAD_WINDOWS:  # each window is a float per node: refuse, do not exhaust memory
        span_s = float(end.max()) - t0
        raise ConfigError(OPTIONS_SOURCE, "window_ms (--window-ms)", window_ms,
                          f"at least {span_s * MS_PER_S / MAX_LOAD_WINDOWS:.3g} ms for this "
                          f"{span_s:g} s run (at most {MAX_LOAD_WINDOWS} windows)")
    total = _load_figures(window_busy_s(start, end, t0, window_s, n), t0, window_s)
    node_of = np.asarray(nodes, dtype=object)[rows]
    per_node = {}
    for node in sorted(set(node_of.tolist())):
        m = node_of == node
        per_node[node] = _load_figures(
            window_busy_s(start[m], end[m], t0, window_s, n), t0, window_s
        )
    return BusLoad(window_ms, bitrate_bps, n, total, per_node)
