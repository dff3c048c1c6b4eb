"""Expected thrust of each thruster from the commands sent: the FDIR's actuator model.

What it does: turns the on-times the flight software commanded into the thrust history it
expects, as a fraction of the maximum thrust, with the valve dynamics of the vehicle's
data sheet, so that a residual FDIR can compare it with what the gyro and accelerometer
saw: :meth:`ThrustModel.thrust_time_s` (∫ thrust/T_max over a window, per thruster [s])
and :meth:`ThrustModel.fraction_at` (thrust/T_max at sample times, and its sensitivity to
timing). It mirrors the valve model of the drive electronics the ICD describes:
- a command of the period starting at t_c with on-time D > 0 energises the coil over
  ``[t_c + δ, t_c + δ + max(D, min_on))`` (δ = ``command_delay_s``, the command's
  transmission); a command arriving while the coil is energised continues the pulse
  (new end ``max(t + D, pulse start + min_on)``, no new opening); a 0 command while it is
  energised switches it off;
- the valve is driven over ``[coil on + open_delay, coil off + close_delay)`` (overlapping
  drive intervals merge); while driven the thrust rises first order towards T_max
  (``rise_tau_s``), otherwise it decays first order towards 0 (``tail_tau_s``).
So the model is piecewise exponential: segments ``(start, end, F0, target, τ)`` with
``F(t) = target + (F0 − target) e^{−(t − start)/τ}``, whose integral over ``[u1, u2]`` is
``target (u2 − u1) + (F0 − target) τ (e^{−(u1 − start)/τ} − e^{−(u2 − start)/τ})``.
A thruster declared stuck open is at full thrust all the time.

Inputs: the valve timing (:class:`flight_sw.fdir.valve_timing.ValveTiming`: command delay
δ, opening and closing delays, rise and tail time constants); ``command(t_ns,
on_time_s)`` per control cycle, in time order. Outputs: see above (numpy arrays, one
entry per thruster); fractions are dimensionless, times integer ns in, seconds out.

Computation: on Python floats, compiled with mypyc (setup.py): each thruster keeps its
finished segments in time order, and a query visits only those that reach its window
(from the newest back), so a cycle's queries cost a few segments each, not all of them
(the FDIR runs every cycle of a 16-thruster vehicle: issue 23). The per-thruster sums
add the segments in time order. ``tests/flight_sw/thrust_model_reference.py`` is the
array form it is checked against, for queries within the horizon (beyond it each drops
old segments its own way).

Assumptions: the valve parameters are the vehicle's nominal ones (a valve that differs
shows up as a residual, which is the point); the command delay is the same for every
thruster (in lockstep it varies by ~0.4 ms with the frame order: the timing term of the
residual's uncertainty covers it); each thruster's segments that ended more than
``horizon_ns`` before the newest command are dropped (a query reaching further back
misses them).

Source: first-order valve with transport delays, as the bench's valve model and e.g.
Wertz & Larson (eds.) 1999, "Space Mission Analysis and Design", 3rd ed. (pulse-mode
thrusters); first-order lag response: Ogata, "Modern Control Engineering", 5th ed., ch. 5.
"""

from __future__ import annotations

import math

import numpy as np

from flight_sw.fdir.valve_timing import ValveTiming

NS_PER_S = 1_000_000_000
S_PER_NS = 1e-9
INF_NS = 2**62
# A rise or tail time constant below this [s] is taken as this (an instant edge: the
# exponentials stay finite).
MIN_TIME_CONSTANT_S = 1e-6

# A segment: (start_ns, end_ns, F0, target, tau_s).
Segment = tuple[int, int, float, float, float]


class ThrustModel:
    """Piecewise-exponential expected thrust per thruster (see the module docstring)."""

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
        #: True = known stuck open (set by the FDIR; read at each query)
        self.stuck_open: np.ndarray = np.zeros(n_thrusters, dtype=bool)
        self._coil_on: list[int] = []
        self._coil_off: list[int] = []
        self._drive_on: list[int] = []
        self._drive_off: list[int] = []
        self._f_drive_on: list[float] = []
        self._done: list[list[Segment]] = []
        self.reset()

    def reset(self) -> None:
        """Forget every command (the valves are closed and at rest)."""
        n = self.n
        self._coil_on = [-INF_NS] * n
        self._coil_off = [-INF_NS] * n
        self._drive_on = [-INF_NS] * n  # current (last) drive interval
        self._drive_off = [-INF_NS] * n
        self._f_drive_on = [0.0] * n  # thrust fraction when the last drive interval began
        self._done = [[] for _ in range(n)]  # finished segments per thruster, in time order
        self.stuck_open[:] = False

    # --- building -----------------------------------------------------------------------

    def _close_drive(self, k: int, until_ns: int) -> float:
        """Archive thruster k's last drive interval and its tail up to ``until_ns``."""
        on, off, f0 = self._drive_on[k], self._drive_off[k], self._f_drive_on[k]
        if on == -INF_NS:
            return 0.0
        done = self._done[k]
        done.append((on, off, f0, 1.0, self._tau_r))
        f_off = self._f_off(k)
        done.append((off, until_ns, f_off, 0.0, self._tau_t))
        return f_off * math.exp(-(until_ns - off) * S_PER_NS / self._tau_t)

    def command(self, t_ns: int, on_time_s: np.ndarray) -> None:
        """The on-times [s] commanded for the period starting at ``t_ns``."""
        t_rx = t_ns + self._delay_ns
        d: list[float] = np.asarray(on_time_s, dtype=float)[: self.n].tolist()
        for k in range(len(d)):
            if d[k] > 0.0:
                self._fire(k, t_rx, round(d[k] * NS_PER_S))
        for k in range(len(d)):  # a 0 switches the coil off
            if d[k] <= 0.0 and self._coil_on[k] <= t_rx < self._coil_off[k]:
                self._coil_off[k] = t_rx
                self._drive_off[k] = max(self._drive_on[k], t_rx + self._cd_ns)
        horizon = t_ns - self._horizon_ns
        for done in self._done:
            drop = 0
            while drop < len(done) and done[drop][1] < horizon:
                drop += 1
            if drop:
                del done[:drop]

    def _fire(self, k: int, t_rx: int, on_ns: int) -> None:
        """Thruster k commanded on for ``on_ns`` from ``t_rx`` (module docstring)."""
        if self._coil_on[k] <= t_rx <= self._coil_off[k]:  # continues the pulse
            self._coil_off[k] = max(t_rx + on_ns, self._coil_on[k] + self._min_on_ns)
        else:
            self._coil_on[k] = t_rx
            self._coil_off[k] = t_rx + max(on_ns, self._min_on_ns)
        drive_on = self._coil_on[k] + self._od_ns
        drive_off = self._coil_off[k] + self._cd_ns
        if drive_off <= drive_on:
            return
        if self._drive_on[k] != -INF_NS and drive_on <= self._drive_off[k]:
            self._drive_off[k] = max(self._drive_off[k], drive_off)  # merge
        else:
            f0 = self._close_drive(k, drive_on)
            self._drive_on[k] = drive_on
            self._drive_off[k] = drive_off
            self._f_drive_on[k] = f0

    def _first_ending_after(self, k: int, t_ns: int) -> int:
        """Index of thruster k's first finished segment that ends after ``t_ns``: the
        finished ones end in time order, so those are a tail of the list."""
        done = self._done[k]
        i = len(done)
        while i > 0 and done[i - 1][1] > t_ns:
            i -= 1
        return i

    def _f_off(self, k: int) -> float:
        """Thruster k's thrust fraction where its current drive interval ends."""
        on, off, f0 = self._drive_on[k], self._drive_off[k], self._f_drive_on[k]
        return 1.0 + (f0 - 1.0) * math.exp(-(off - on) * S_PER_NS / self._tau_r)

    # --- queries ------------------------------------------------------------------------

    def thrust_time_s(self, t_a_ns: int, t_b_ns: int) -> np.ndarray:
        """∫ thrust/T_max over [t_a, t_b] per thruster [s] (stuck open: t_b − t_a)."""
        stuck: list[bool] = self.stuck_open.tolist()
        out = [0.0] * self.n
        for k in range(self.n):
            if stuck[k]:
                out[k] = (t_b_ns - t_a_ns) * S_PER_NS
                continue
            if t_b_ns <= t_a_ns:  # an empty (or reversed) window holds no thrust
                continue
            done = self._done[k]
            acc = 0.0
            later = False  # a segment starts at or after t_b: so do all that follow
            for j in range(self._first_ending_after(k, t_a_ns), len(done)):
                s, e, f0, tgt, tau = done[j]
                if s >= t_b_ns:
                    later = True
                    break
                acc += _integral(s, e, f0, tgt, tau, t_a_ns, t_b_ns)
            on = self._drive_on[k]
            if not later and on != -INF_NS and on < t_b_ns:  # the current drive interval
                off, f0 = self._drive_off[k], self._f_drive_on[k]
                if off > t_a_ns:  # it may have ended before t_a
                    acc += _integral(on, off, f0, 1.0, self._tau_r, t_a_ns, t_b_ns)
                if off < t_b_ns:  # and its tail, open-ended
                    acc += _integral(off, INF_NS, self._f_off(k), 0.0, self._tau_t, t_a_ns,
                                     t_b_ns)
            out[k] = acc
        return np.array(out)

    def boundary_segments(self, t_ns: int, guard_ns: int) -> np.ndarray:
        """Per thruster, drive intervals with an edge within ``guard_ns`` of ``t_ns``."""
        stuck: list[bool] = self.stuck_open.tolist()
        count = [0.0] * self.n
        for k in range(self.n):
            if stuck[k]:
                continue
            c = 0
            # a drive interval near t ends after t − guard (edges near t, or t inside it)
            done = self._done[k]
            for j in range(self._first_ending_after(k, t_ns - guard_ns), len(done)):
                s, e, _f0, tgt, _tau = done[j]
                if tgt > 0.0 and _near(s, e, t_ns, guard_ns):
                    c += 1
            on = self._drive_on[k]  # the current drive interval (its tail drives nothing)
            if on != -INF_NS and _near(on, self._drive_off[k], t_ns, guard_ns):
                c += 1
            count[k] = float(c)
        return np.array(count)

    def fraction_at(self, t_ns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(F/T_max, |dF/dt|/T_max [1/s]) at the sample times ``t_ns``, shape (samples, n)."""
        ts: list[int] = [int(t) for t in np.asarray(t_ns, dtype=np.int64).tolist()]
        n = self.n
        if not ts:
            return np.zeros((0, n)), np.zeros((0, n))
        stuck: list[bool] = self.stuck_open.tolist()
        frac = [[0.0] * n for _ in ts]
        rate = [[0.0] * n for _ in ts]
        for k in range(n):
            if stuck[k]:
                for row in frac:
                    row[k] = 1.0
                continue
            done = self._done[k]
            on = self._drive_on[k]
            for m in range(len(ts)):
                t = ts[m]
                # the one segment holding t (they follow each other without overlap): the
                # current drive interval or its tail, else the last finished one starting
                # at or before t
                if on != -INF_NS and t >= on:
                    off = self._drive_off[k]
                    if t < off:
                        f = _value(on, self._f_drive_on[k], 1.0, self._tau_r, t)
                        frac[m][k], rate[m][k] = f, abs(1.0 - f) / self._tau_r
                    else:
                        f = _value(off, self._f_off(k), 0.0, self._tau_t, t)
                        frac[m][k], rate[m][k] = f, abs(0.0 - f) / self._tau_t
                    continue
                for j in range(len(done) - 1, -1, -1):
                    s, e, f0, tgt, tau = done[j]
                    if s <= t:
                        if t < e:
                            f = _value(s, f0, tgt, tau, t)
                            frac[m][k], rate[m][k] = f, abs(tgt - f) / tau
                        break
        return np.array(frac), np.array(rate)


def _integral(s: int, e: int, f0: float, tgt: float, tau: float, t_a_ns: int,
              t_b_ns: int) -> float:
    """∫ F/T_max over the part of segment (s, e, F0, target, τ) inside [t_a, t_b] [s]
    (module docstring; the segment must overlap the window)."""
    u1 = s if s > t_a_ns else t_a_ns
    u2 = e if e < t_b_ns else t_b_ns
    x1 = (u1 - s) * S_PER_NS / tau
    x2 = (u2 - s) * S_PER_NS / tau
    return tgt * (u2 - u1) * S_PER_NS + (f0 - tgt) * tau * (math.exp(-x1) - math.exp(-x2))


def _value(s: int, f0: float, tgt: float, tau: float, t_ns: int) -> float:
    """F/T_max at ``t_ns`` on the segment starting at ``s`` (module docstring)."""
    return tgt + (f0 - tgt) * math.exp(-((t_ns - s) * S_PER_NS / tau))


def _near(s: int, e: int, t_ns: int, guard_ns: int) -> bool:
    """Has the drive interval [s, e) an edge within ``guard_ns`` of ``t_ns``, or is it
    shorter than two guards with ``t_ns`` inside?"""
    return (abs(s - t_ns) < guard_ns or abs(e - t_ns) < guard_ns
            or (s < t_ns < e and e - s < 2 * guard_ns))
