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
        "_half_ns",
        "_half_rise",
        "_half_tail",
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
        # Cache of stage_thrusts_N: half step [ns] and its decay factors e^{-half/τ}.
        self._half_ns = 0
        self._half_rise = 1.0
        self._half_tail = 1.0

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

    def stage_thrusts_N(self, t_ns: int, dt_ns: int) -> tuple[float, float, float]:
        """Thrust at t, t + dt/2 and t + dt (the RK4 stage times) [N], ``dt_ns`` even.

        Equal to three ``thrust_N`` calls up to round-off; when no segment boundary or
        cut-off falls inside the step it costs one ``exp`` (the half-step decay factors
        e^{−k·dt/2} are cached per step size).
        """
        t1 = t_ns + dt_ns
        if t1 >= self.idle_from_ns:
            if t_ns >= self.idle_from_ns:
                return (0.0, 0.0, 0.0)
            return (self.thrust_N(t_ns), self.thrust_N(t_ns + dt_ns // 2), self.thrust_N(t1))
        segs = self.segments
        t0, f0, target, k = segs[-1]
        if t_ns < t0:
            i = len(segs) - 2
            while i > 0 and segs[i][0] > t_ns:
                i -= 1
            if segs[i + 1][0] <= t1 or segs[i][0] > t_ns:
                return (self.thrust_N(t_ns), self.thrust_N(t_ns + dt_ns // 2), self.thrust_N(t1))
            t0, f0, target, k = segs[i]
        half = dt_ns // 2
        if half != self._half_ns:
            self._half_ns = half
            self._half_rise = math.exp(-half * self.params.inv_rise_tau_per_ns)
            self._half_tail = math.exp(-half * self.params.inv_tail_tau_per_ns)
        a = (f0 - target) * math.exp((t0 - t_ns) * k)
        if a > 0.0:  # above the target: decaying, towards 0 or a leak (module docstring)
            e = self._half_tail
            if target == 0.0:
                cut = self.params.cutoff_N
                fa = a if a > cut else 0.0
                fm = a * e
                fb = fm * e
                return (fa, fm if fm > cut else 0.0, fb if fb > cut else 0.0)
            am = a * e
            return (target + a, target + am, target + am * e)
        e = self._half_rise  # rising (or constant: a == 0)
        am = a * e
        return (target + a, target + am, target + am * e)

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
