"""The FDIR's expected-thrust model in array form: the reference the package's is checked
against (tests only).

The same valve model and closed forms as :mod:`flight_sw.fdir.thrust_model` (its
docstring), written the other way: every segment of every thruster in one set of numpy
arrays, each query evaluated over all of them at once (``np.bincount`` per thruster). It
was the package's form until the queries moved to plain floats (issue 23);
``tests/flight_sw/test_fsw_thrust_model.py`` drives both with the same commands and
compares every query.
"""

from __future__ import annotations

import math

import numpy as np

from flight_sw.fdir.valve_timing import ValveTiming

NS_PER_S = 1_000_000_000
S_PER_NS = 1e-9
INF_NS = 2**62
SEGMENT_CAPACITY = 1024  # initial rows of the finished-segment arrays (they grow if needed)
# A rise or tail time constant below this [s] is taken as this (an instant edge: the
# exponentials stay finite).
MIN_TIME_CONSTANT_S = 1e-6


class ReferenceThrustModel:
    """Piecewise-exponential expected thrust per thruster, as arrays (module docstring)."""

    def __init__(
        self, n_thrusters: int, min_on_s: float, timing: ValveTiming, horizon_ns: int
    ) -> None:
        self.n = n_thrusters
        self.timing = timing
        self._min_on_ns = round(min_on_s * NS_PER_S)
        self._delay_ns = round(timing.command_delay_s * NS_PER_S)
        self._od_ns = round(timing.open_delay_s * NS_PER_S)
        self._cd_ns = round(timing.close_delay_s * NS_PER_S)
        self._tau_r = max(timing.rise_tau_s, MIN_TIME_CONSTANT_S)
        self._tau_t = max(timing.tail_tau_s, MIN_TIME_CONSTANT_S)
        self._horizon_ns = horizon_ns
        self.stuck_open = np.zeros(n_thrusters, dtype=bool)
        self.reset()

    def reset(self) -> None:
        """Forget every command (the valves are closed and at rest)."""
        n = self.n
        self._coil_on = [-INF_NS] * n
        self._coil_off = [-INF_NS] * n
        self._drive_on = [-INF_NS] * n  # current (last) drive interval
        self._drive_off = [-INF_NS] * n
        self._f_drive_on = [0.0] * n  # thrust fraction when the last drive interval began
        # finished segments, rows [lo, hi) of: thruster, start_ns, end_ns (int64);
        # F0, target, tau_s (float)
        self._seg_i = np.zeros((SEGMENT_CAPACITY, 3), dtype=np.int64)
        self._seg_f = np.zeros((SEGMENT_CAPACITY, 3))
        self._lo = self._hi = 0
        self.stuck_open[:] = False
        self._t_last = -INF_NS
        self._cache: tuple[np.ndarray, ...] | None = None

    # --- building -----------------------------------------------------------------------

    def _archive(self, k: int, start: int, end: int, f0: float, target: float, tau: float) -> None:
        """Append one finished segment (compacting or growing the arrays when full)."""
        if self._hi == len(self._seg_i):
            live = self._hi - self._lo
            if live > len(self._seg_i) // 2:  # grow
                self._seg_i = np.concatenate((self._seg_i, np.zeros_like(self._seg_i)))
                self._seg_f = np.concatenate((self._seg_f, np.zeros_like(self._seg_f)))
            self._seg_i[:live] = self._seg_i[self._lo : self._hi]
            self._seg_f[:live] = self._seg_f[self._lo : self._hi]
            self._lo, self._hi = 0, live
        i = self._hi
        self._seg_i[i] = (k, start, end)
        self._seg_f[i] = (f0, target, tau)
        self._hi += 1

    def _close_drive(self, k: int, until_ns: int) -> float:
        """Archive thruster k's last drive interval and its tail up to ``until_ns``."""
        on, off, f0 = self._drive_on[k], self._drive_off[k], self._f_drive_on[k]
        if on == -INF_NS:
            return 0.0
        self._archive(k, on, off, f0, 1.0, self._tau_r)
        f_off = 1.0 + (f0 - 1.0) * math.exp(-(off - on) * S_PER_NS / self._tau_r)
        self._archive(k, off, until_ns, f_off, 0.0, self._tau_t)
        return f_off * math.exp(-(until_ns - off) * S_PER_NS / self._tau_t)

    def command(self, t_ns: int, on_time_s: np.ndarray) -> None:
        """The on-times [s] commanded for the period starting at ``t_ns``."""
        t_rx = t_ns + self._delay_ns
        self._t_last = t_rx
        self._cache = None
        d = np.asarray(on_time_s, dtype=float)
        for k in np.flatnonzero(d[: self.n] > 0.0).tolist():
            on_ns = round(float(d[k]) * NS_PER_S)
            if self._coil_on[k] <= t_rx <= self._coil_off[k]:  # continues the pulse
                self._coil_off[k] = max(t_rx + on_ns, self._coil_on[k] + self._min_on_ns)
            else:
                self._coil_on[k] = t_rx
                self._coil_off[k] = t_rx + max(on_ns, self._min_on_ns)
            drive_on = self._coil_on[k] + self._od_ns
            drive_off = self._coil_off[k] + self._cd_ns
            if drive_off <= drive_on:
                continue
            if self._drive_on[k] != -INF_NS and drive_on <= self._drive_off[k]:
                self._drive_off[k] = max(self._drive_off[k], drive_off)  # merge
            else:
                f0 = self._close_drive(k, drive_on)
                self._drive_on[k], self._drive_off[k], self._f_drive_on[k] = (
                    drive_on,
                    drive_off,
                    f0,
                )
        for k in np.flatnonzero(d[: self.n] <= 0.0).tolist():  # a 0 switches the coil off
            if self._coil_on[k] <= t_rx < self._coil_off[k]:
                self._coil_off[k] = t_rx
                self._drive_off[k] = max(self._drive_on[k], t_rx + self._cd_ns)
        horizon = t_ns - self._horizon_ns
        while self._lo < self._hi and self._seg_i[self._lo, 2] < horizon:
            self._lo += 1

    def _segments(self) -> tuple[np.ndarray, ...]:
        """All segments as arrays (thruster, start, end, F0, target, tau); cached."""
        if self._cache is None:
            self._cache = self._build_segments()
        return self._cache

    def _build_segments(self) -> tuple[np.ndarray, ...]:
        on = np.array(self._drive_on, dtype=np.int64)
        off = np.array(self._drive_off, dtype=np.int64)
        f0 = np.array(self._f_drive_on)
        k = np.flatnonzero(on != -INF_NS)
        on, off, f0 = on[k], off[k], f0[k]
        f_off = 1.0 + (f0 - 1.0) * np.exp(-(off - on) * S_PER_NS / self._tau_r)
        seg_i = self._seg_i[self._lo : self._hi]
        seg_f = self._seg_f[self._lo : self._hi]
        ones, zeros = np.ones(k.size), np.zeros(k.size)
        return (
            np.concatenate((seg_i[:, 0], k, k)),
            np.concatenate((seg_i[:, 1], on, off)),
            np.concatenate((seg_i[:, 2], off, np.full(k.size, INF_NS, dtype=np.int64))),
            np.concatenate((seg_f[:, 0], f0, f_off)),
            np.concatenate((seg_f[:, 1], ones, zeros)),
            np.concatenate((seg_f[:, 2], ones * self._tau_r, ones * self._tau_t)),
        )

    # --- queries ------------------------------------------------------------------------

    def thrust_time_s(self, t_a_ns: int, t_b_ns: int) -> np.ndarray:
        """∫ thrust/T_max over [t_a, t_b] per thruster [s] (stuck open: t_b − t_a)."""
        thr, s, e, f0, tgt, tau = self._segments()
        out = np.zeros(self.n)
        if thr.size:
            u1 = np.maximum(s, t_a_ns)
            u2 = np.minimum(e, t_b_ns)
            ok = u2 > u1
            if ok.any():
                thr, s, u1, u2, f0, tgt, tau = (x[ok] for x in (thr, s, u1, u2, f0, tgt, tau))
                x1 = (u1 - s) * S_PER_NS / tau
                x2 = (u2 - s) * S_PER_NS / tau
                val = tgt * (u2 - u1) * S_PER_NS + (f0 - tgt) * tau * (np.exp(-x1) - np.exp(-x2))
                out = np.bincount(thr, weights=val, minlength=self.n).astype(float)
        out[self.stuck_open] = (t_b_ns - t_a_ns) * S_PER_NS
        return out

    def boundary_segments(self, t_ns: int, guard_ns: int) -> np.ndarray:
        """Per thruster, drive intervals with an edge within ``guard_ns`` of ``t_ns``."""
        count = np.zeros(self.n)
        thr, s, e, _, tgt, _ = self._segments()
        if thr.size:
            rising = tgt > 0.0
            near = rising & ((np.abs(s - t_ns) < guard_ns) | (np.abs(e - t_ns) < guard_ns))
            near |= rising & (s < t_ns) & (e > t_ns) & ((e - s) < 2 * guard_ns)
            count = np.bincount(thr[near], minlength=self.n).astype(float)
        count[self.stuck_open] = 0.0
        return count

    def fraction_at(self, t_ns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(F/T_max, |dF/dt|/T_max [1/s]) at the sample times ``t_ns``, shape (samples, n)."""
        ts = np.asarray(t_ns, dtype=np.int64)
        frac = np.zeros((ts.size, self.n))
        rate = np.zeros((ts.size, self.n))
        thr, s, e, f0, tgt, tau = self._segments()
        if thr.size and ts.size:
            near = (e > ts.min()) & (s <= ts.max())  # only the segments around the samples
            thr, s, e, f0, tgt, tau = (x[near] for x in (thr, s, e, f0, tgt, tau))
        if thr.size and ts.size:
            inside = (ts[:, None] >= s[None, :]) & (ts[:, None] < e[None, :])
            x = np.where(inside, (ts[:, None] - s[None, :]) * S_PER_NS / tau[None, :], 0.0)
            f = np.where(inside, tgt + (f0 - tgt) * np.exp(-x), 0.0)
            r = np.where(inside, np.abs(tgt - f) / tau[None, :], 0.0)
            onehot = np.zeros((thr.size, self.n))
            onehot[np.arange(thr.size), thr] = 1.0
            frac = f @ onehot
            rate = r @ onehot
        frac[:, self.stuck_open] = 1.0
        rate[:, self.stuck_open] = 0.0
        return frac, rate
