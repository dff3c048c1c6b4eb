"""The physical thrust of one valve as a piecewise-exponential profile, in closed form.

What it does
    Holds the planned thrust of a valve as a short list of segments, each a first-order
    response from its start, evaluates it at any time (``thrust_N``, and the three RK4
    stage times at once, ``stage_thrusts_N``), re-plans it from the drive edges the valve
    state machine (:mod:`bench.station.valves.valve`) derives from its coil pulses and
    faults (``ThrustProfile.plan``), and gives the closed-form impulse of an isolated
    pulse (``pulse_impulse_Ns``).

Inputs / outputs
    In: ``ValveParams``; per plan, the time ``t_ns``, the thrust then [N], whether the
    valve is driven open then, the later drive edges (time, driven open), the start of
    the history to keep, the thrust factor and the leak [N]. Out: thrust [N] at a time;
    ``idle_from_ns``, from which the thrust is exactly 0 until the next plan.

Model (first-order valve dynamics)
    While driven the thrust rises first order towards Fmax from wherever it is,
    otherwise it decays first order towards 0:

        rising:   F(t) = Fmax + (F(t_a) − Fmax) e^{−(t − t_a)/τr}   (from rest: Fmax(1 − e^{…}))
        decaying: F(t) = F(t_b) e^{−(t − t_b)/τt}

    Below ``THRUST_CUTOFF_FRACTION``·Fmax a decaying thrust is exactly 0 and, once no
    rise is pending, the valve is idle (``idle_from_ns``). Each command re-plans this
    piecewise-exponential future as a short list of segments, so ``thrust_N`` is a
    lookup plus one ``exp``. Valid for any t ≥ min(previous event, newest event −
    ``HISTORY_NS``), events being commands and fault changes (so a caller may deliver
    commands and faults inside an integration step and still sample the step's start).

    Closed-form impulse of an isolated pulse from rest (``pulse_impulse_Ns``, also
    ``Valve.pulse_impulse_Ns``), with D = max(0, on + close_delay − open_delay):
        I = Fmax[D − τr(1 − e^{−D/τr})] + Fmax(1 − e^{−D/τr})·τt
    (integral of the two exponentials above; the cut-off tail below 1e-9·Fmax is ignored).

    Impulse of a step (``stage_thrusts_N``, ``mean_thrust_N``): the RK4 integrator of the
    plant samples the thrust at its stage times t, t + dt/2, t + dt; sampling a drive
    edge that falls inside a 1 ms step books an impulse off by up to ~0.1 % of a 5 ms
    pulse, with the same sign every cycle (commands land at the same phase). So all three
    stages get the *mean* thrust of the step instead, the closed-form integral of the
    segments over [t, t + dt] divided by dt; per segment (t_s, f0, target, k):

        ∫_a^b F dt = target·(b − a) + (f0 − target)·e^{−k(a − t_s)}·(1 − e^{−k(b − a)})/k

    Simpson's booking and RK4's velocity increment then integrate exactly the impulse the
    valve delivered, wherever its edges fall (as ``throttled.ThrottledValve`` does).

    Faults: the segments hold the physical thrust. A driven segment rises (time
    constant τr) towards ``factor``·Fmax + leak, an undriven one decays (τt) towards the
    leak; both keep the piecewise-exponential form, so an inactive fault costs nothing
    and an active one adds no work per step. A segment whose thrust lies above its
    target is decaying, below it rising; ``stage_thrusts_N`` relies on that.

Units: integer nanoseconds for times (``_ns``), newtons for thrust, seconds in
``ValveParams`` (suffix ``_s``). Equation sources: first-order lag response (Ogata,
"Modern Control Engineering", 5th ed., §5-2); pulse-mode thruster model after Wertz &
Larson, "Space Mission Analysis and Design", §11.
"""

from __future__ import annotations

import math

from bench.station.valves.params import NEVER_NS, NS_PER_S, ValveParams

# A thrust segment: (t_start_ns, thrust at t_start [N], target thrust [N], 1/τ [1/ns]).
_Segment = tuple[int, float, float, float]


def pulse_impulse_Ns(params: ValveParams, on_time_s: float) -> float:
    """Closed-form impulse [N·s] of an isolated pulse from rest (min_on applied).

    D = max(0, on + close_delay − open_delay); I = Fmax[D − τr(1 − e^{−D/τr})]
    + Fmax(1 − e^{−D/τr})·τt. Zero for ``on_time_s <= 0``.
    """
    if on_time_s <= 0.0:
        return 0.0
    on_s = max(on_time_s, params.min_on_s)
    d = max(0.0, on_s + params.close_delay_s - params.open_delay_s)
    tr, tt = params.rise_tau_s, params.tail_tau_s
    rise = -math.expm1(-d / tr)  # 1 − e^{−D/τr}, accurate for small D
    return params.max_thrust_N * (d - tr * rise + rise * tt)


def _step_mean_factor(k_per_ns: float, dt_ns: int) -> float:
    """(1 − e^{−k·dt})/(k·dt): the mean of e^{−k(t − t0)} over [t0, t0 + dt] [-]."""
    x = k_per_ns * dt_ns
    return -math.expm1(-x) / x


class ThrustProfile:
    """The planned physical thrust of one valve (module docstring).

    Attributes (read-only for callers):
        params        the ``ValveParams``
        segments      (t_start_ns, thrust at t_start [N], target [N], 1/τ [1/ns]), in time
                      order, from the kept history on
        drive_plan    (time, driven open) edges from the last plan on
        idle_from_ns  from this time on the thrust is exactly 0 until the next plan
                      (``NEVER_NS`` while it targets a thrust above 0)
    """

    __slots__ = (
        "_dt_ns",
        "_mean_rise",
        "_mean_tail",
        "drive_plan",
        "idle_from_ns",
        "params",
        "segments",
    )

    def __init__(self, params: ValveParams) -> None:
        self.params = params
        self.idle_from_ns = -NEVER_NS
        self.segments: list[_Segment] = [(-NEVER_NS, 0.0, 0.0, params.inv_tail_tau_per_ns)]
        # Planned drive state from the last event on: (time, driven open) edges.
        self.drive_plan: list[tuple[int, bool]] = [(-NEVER_NS, False)]
        # Cache of stage_thrusts_N: the step [ns] and its mean factors (1 − e^{−k·dt})/(k·dt).
        self._dt_ns = 0
        self._mean_rise = 1.0
        self._mean_tail = 1.0

    def thrust_N(self, t_ns: int) -> float:
        """Physical thrust [N] at ``t_ns`` (any t within the kept history, module docstring)."""
        if t_ns >= self.idle_from_ns:
            return 0.0
        t0, f0, target, k = self.segments[-1]
        if t_ns >= t0:  # fast path: the newest segment
            f = target + (f0 - target) * math.exp((t0 - t_ns) * k)
            if target == 0.0 and f <= self.params.cutoff_N:
                return 0.0
            return f
        for t0, f0, target, k in reversed(self.segments):
            if t_ns >= t0:
                f = target + (f0 - target) * math.exp((t0 - t_ns) * k)
                if target == 0.0 and f <= self.params.cutoff_N:
                    return 0.0
                return f
        return 0.0

    def mean_thrust_N(self, t0_ns: int, t1_ns: int) -> float:
        """Mean physical thrust [N] over [t0, t1] (t1 > t0): the closed-form integral of the
        piecewise-exponential profile divided by the span (module docstring, "Impulse of
        a step"). Exact whatever segment edges fall inside the span."""
        end = t1_ns if t1_ns < self.idle_from_ns else self.idle_from_ns
        if t0_ns >= end:
            return 0.0
        segs = self.segments
        i = len(segs) - 1
        while i > 0 and segs[i][0] > t0_ns:
            i -= 1
        a = t0_ns if t0_ns > segs[i][0] else segs[i][0]  # no thrust before the first segment
        total = 0.0  # [N·ns]
        n = len(segs)
        while a < end:
            ts, f0, target, k = segs[i]
            b = segs[i + 1][0] if i + 1 < n and segs[i + 1][0] < end else end
            # ∫_a^b target + (f0 − target) e^{−k(t − ts)} dt
            total += target * (b - a) + (f0 - target) * math.exp((ts - a) * k) * (
                -math.expm1((a - b) * k)) / k
            a = b
            i += 1
        return total / (t1_ns - t0_ns)

    def stage_thrusts_N(self, t_ns: int, dt_ns: int) -> tuple[float, float, float]:
        """The mean thrust over [t, t + dt], three times: the RK4 stage samples (module
        docstring, "Impulse of a step"). One ``exp`` when no segment edge or idle time
        falls inside the step (the step's factor (1 − e^{−k·dt})/(k·dt) is cached per step
        size), else :meth:`mean_thrust_N`."""
        t1 = t_ns + dt_ns
        if t1 > self.idle_from_ns:
            f = self.mean_thrust_N(t_ns, t1)
            return (f, f, f)
        segs = self.segments
        ts, f0, target, k = segs[-1]
        if t_ns < ts:
            f = self.mean_thrust_N(t_ns, t1)
            return (f, f, f)
        if dt_ns != self._dt_ns:
            prm = self.params
            self._dt_ns = dt_ns
            self._mean_rise = _step_mean_factor(prm.inv_rise_tau_per_ns, dt_ns)
            self._mean_tail = _step_mean_factor(prm.inv_tail_tau_per_ns, dt_ns)
        c = self._mean_tail if k == self.params.inv_tail_tau_per_ns else self._mean_rise
        f = target + (f0 - target) * math.exp((ts - t_ns) * k) * c
        return (f, f, f)

    def driven_at(self, t_ns: int) -> bool:
        """Whether the current plan drives the valve open at ``t_ns``."""
        for t_e, driven in reversed(self.drive_plan):
            if t_ns >= t_e:
                return driven
        return False

    def plan(
        self,
        t_ns: int,
        f_now: float,
        drive_now: bool,
        edges: list[tuple[int, bool]],
        keep_from: int,
        factor: float,
        leak: float,
    ) -> None:
        """Rebuild the segments from ``t_ns`` on, history from ``keep_from`` on kept.

        ``f_now`` is the thrust at ``t_ns`` [N], ``drive_now`` whether the valve is driven
        open then, ``edges`` the later (time, driven open) changes in time order,
        ``factor`` the thrust factor and ``leak`` the leak thrust [N] of the active faults.
        """
        prm = self.params
        old = self.segments
        first = 0
        for i in range(len(old) - 1, -1, -1):
            if old[i][0] <= keep_from:
                first = i
                break
        segs = [s for s in old[first:] if s[0] < t_ns]
        kr, kt = prm.inv_rise_tau_per_ns, prm.inv_tail_tau_per_ns
        # Driven: rise towards factor·Fmax + leak (a factor of 0 is never driven open);
        # undriven: decay towards the leak.
        drive_target = factor * prm.max_thrust_N + leak
        drive_k = kr if factor > 0.0 else kt
        seg: _Segment = (
            (t_ns, f_now, drive_target, drive_k) if drive_now else (t_ns, f_now, leak, kt)
        )
        segs.append(seg)
        for t_e, rising in edges:
            t0, f0, target, k = seg
            f_e = target + (f0 - target) * math.exp((t0 - t_e) * k)
            if target == 0.0 and f_e <= prm.cutoff_N:
                f_e = 0.0
            seg = (t_e, f_e, drive_target, drive_k) if rising else (t_e, f_e, leak, kt)
            segs.append(seg)
        self.segments = segs
        self.drive_plan = [(t_ns, drive_now), *edges]

        t0, f0, target, _k = seg
        if target > 0.0:
            self.idle_from_ns = NEVER_NS
        elif f0 <= prm.cutoff_N:
            self.idle_from_ns = t0
        else:
            self.idle_from_ns = t0 + math.ceil(
                prm.tail_tau_s * math.log(f0 / prm.cutoff_N) * NS_PER_S
            )
