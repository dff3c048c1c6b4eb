"""One thruster valve with its drive electronics: commanded coil pulses → physical thrust.

What it does
    Turns on-time commands (as received from the ``THR_CMD_n`` frames) into the thrust
    the nozzle produces, as a pure function of simulation time and the stored command
    history, plus what the drive electronics report (``THR_STATUS_n``: coil energised,
    valve open, coil current) and counters (coil openings). No clock is read: every
    method takes the time ``t_ns`` [integer nanoseconds of simulation time].

Command semantics (``Valve.command(t_ns, on_time_ns)``)
    - The coil is energised over the half-open interval [t_ns, t_ns + on).
    - On-times in (0, min_on) are extended by the drive electronics so that a coil pulse
      always lasts at least ``min_on_s`` from its rising edge. A command arriving while
      the coil is energised (or at the very instant it de-energises) continues the pulse
      without a new opening transient: the close time becomes
      max(t_ns + on, pulse start + min_on) (it may shorten the pulse, never below min_on).
    - ``on_time_ns == 0`` de-energises the coil now (a cancel overrides min_on), and is a
      no-op when the coil is already off. ``close_all``-style watchdogs use it.
    - Commands must arrive in non-decreasing time.

Physical model (first-order valve dynamics with transport delays)
    Every coil pulse [t_on, t_off) maps to a physical "drive" interval
    [t_on + open_delay, t_off + close_delay) (empty if that is negative: the valve never
    opens); overlapping intervals merge (a valve re-commanded before its delayed closing
    simply stays open). While driven the thrust rises first order towards Fmax from
    wherever it is, otherwise it decays first order towards 0:

        rising:   F(t) = Fmax + (F(t_a) − Fmax) e^{−(t − t_a)/τr}   (from rest: Fmax(1 − e^{…}))
        decaying: F(t) = F(t_b) e^{−(t − t_b)/τt}

    Below ``THRUST_CUTOFF_FRACTION``·Fmax a decaying thrust is exactly 0 and, once no
    rise is pending, the valve is idle (``idle_from_ns``). Each command re-plans this
    piecewise-exponential future as a short list of segments, so ``thrust_N`` is a
    lookup plus one ``exp``. Valid for any t ≥ the previous command's time (so a caller
    may deliver a command inside an integration step and still sample the step's start).

    Closed-form impulse of an isolated pulse from rest (``Valve.pulse_impulse_Ns``), with
    D = max(0, on + close_delay − open_delay):
        I = Fmax[D − τr(1 − e^{−D/τr})] + Fmax(1 − e^{−D/τr})·τt
    (integral of the two exponentials above; the cut-off tail below 1e-9·Fmax is ignored).

Faults (``set_fault``; DESIGN.md §7)
    - ``"stuck_closed"``: the valve is driven closed from the fault time on and never
      opens (any thrust in progress decays with the tail); the coil still energises and
      reports current.
    - ``"stuck_open"``: once the valve is (or next becomes) driven open it never closes,
      whatever is commanded: full thrust after the opening transient.
    - ``None`` clears the fault; the valve then follows the coil schedule again.

Units: seconds in parameters (suffix ``_s``), integer nanoseconds for times (``_ns``),
newtons for thrust. Equation sources: first-order lag response (Ogata, "Modern Control
Engineering", 5th ed., §5-2); pulse-mode thruster model after Wertz & Larson, "Space
Mission Analysis and Design", §11.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from dbc.errors import ConfigError

NS_PER_S = 1_000_000_000
S_PER_NS = 1e-9
THRUST_CUTOFF_FRACTION = 1e-9
"""A decaying thrust below this fraction of Fmax is exactly zero (the valve is idle)."""
OPEN_THRESHOLD_FRACTION = 0.1
"""``status`` reports the valve open while the thrust exceeds this fraction of Fmax."""
NEVER_NS = 2**63 - 1
"""A time later than any simulation (idle_from_ns of a valve that never stops)."""
FAULT_STUCK_CLOSED = "stuck_closed"
FAULT_STUCK_OPEN = "stuck_open"
FAULT_KINDS = frozenset({FAULT_STUCK_CLOSED, FAULT_STUCK_OPEN})

# A thrust segment: (t_start_ns, thrust at t_start [N], target thrust [N], 1/τ [1/ns]).
_Segment = tuple[int, float, float, float]


def _require(ok: bool, source: str, key: str, value: object, expected: str) -> None:
    if not ok:
        raise ConfigError(source, key, value, expected)


def _is_real(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


@dataclass(frozen=True)
class ValveParams:
    """Parameters of one thruster valve; times in seconds, validated on construction.

    ``max_thrust_N`` and ``isp_s`` > 0; ``open_delay_s``, ``close_delay_s`` and
    ``min_on_s`` ≥ 0; ``rise_tau_s`` and ``tail_tau_s`` > 0 (use a small value, e.g.
    1e-6 s, for an ideal valve). Derived nanosecond/inverse fields are precomputed.
    """

    max_thrust_N: float
    isp_s: float
    open_delay_s: float
    close_delay_s: float
    rise_tau_s: float
    tail_tau_s: float
    min_on_s: float
    source: str = field(default="ValveParams", compare=False, repr=False, kw_only=True)
    open_delay_ns: int = field(init=False, repr=False, compare=False)
    close_delay_ns: int = field(init=False, repr=False, compare=False)
    min_on_ns: int = field(init=False, repr=False, compare=False)
    inv_rise_tau_per_ns: float = field(init=False, repr=False, compare=False)
    inv_tail_tau_per_ns: float = field(init=False, repr=False, compare=False)
    cutoff_N: float = field(init=False, repr=False, compare=False)
    open_threshold_N: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        src = self.source
        for key in ("max_thrust_N", "isp_s", "rise_tau_s", "tail_tau_s"):
            v = getattr(self, key)
            _require(
                _is_real(v) and math.isfinite(v) and v > 0.0, src, key, v, "a finite number > 0"
            )
        for key in ("open_delay_s", "close_delay_s", "min_on_s"):
            v = getattr(self, key)
            _require(
                _is_real(v) and math.isfinite(v) and v >= 0.0, src, key, v, "a finite number >= 0"
            )
        put = object.__setattr__
        put(self, "open_delay_ns", round(self.open_delay_s * NS_PER_S))
        put(self, "close_delay_ns", round(self.close_delay_s * NS_PER_S))
        put(self, "min_on_ns", round(self.min_on_s * NS_PER_S))
        put(self, "inv_rise_tau_per_ns", 1.0 / (self.rise_tau_s * NS_PER_S))
        put(self, "inv_tail_tau_per_ns", 1.0 / (self.tail_tau_s * NS_PER_S))
        put(self, "cutoff_N", THRUST_CUTOFF_FRACTION * self.max_thrust_N)
        put(self, "open_threshold_N", OPEN_THRESHOLD_FRACTION * self.max_thrust_N)


class Valve:
    """One valve and its drive electronics (see the module docstring for the semantics).

    Attributes (read-only for callers):
        params        the ``ValveParams``
        fault         None, ``"stuck_closed"`` or ``"stuck_open"``
        openings      number of coil rising edges so far
        idle_from_ns  from this time on the thrust is exactly 0 unless a new command
                      arrives (``NEVER_NS`` while a rise is pending or the valve is stuck open)
    """

    __slots__ = (
        "_coil_off_ns",
        "_coil_on_ns",
        "_half_ns",
        "_half_rise",
        "_half_tail",
        "_last_event_ns",
        "_past_pulses",
        "_segments",
        "fault",
        "idle_from_ns",
        "openings",
        "params",
    )

    def __init__(self, params: ValveParams) -> None:
        self.params = params
        self.fault: str | None = None
        self.openings = 0
        self.idle_from_ns = -NEVER_NS
        self._coil_on_ns = -NEVER_NS
        self._coil_off_ns = -NEVER_NS
        self._last_event_ns = -NEVER_NS
        # Earlier coil pulses whose delayed closing may still lie in the future.
        self._past_pulses: list[tuple[int, int]] = []
        self._segments: list[_Segment] = [(-NEVER_NS, 0.0, 0.0, params.inv_tail_tau_per_ns)]
        # Cache of stage_thrusts_N: half step [ns] and its decay factors e^{-half/τ}.
        self._half_ns = 0
        self._half_rise = 1.0
        self._half_tail = 1.0

    # --- queries --------------------------------------------------------------------
    def thrust_N(self, t_ns: int) -> float:
        """Physical thrust [N] at ``t_ns`` (any t ≥ the previous command's time)."""
        if t_ns >= self.idle_from_ns:
            return 0.0
        t0, f0, target, k = self._segments[-1]
        if t_ns >= t0:  # fast path: the newest segment
            f = target + (f0 - target) * math.exp((t0 - t_ns) * k)
            if target == 0.0 and f <= self.params.cutoff_N:
                return 0.0
            return f
        for t0, f0, target, k in reversed(self._segments):
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
        segs = self._segments
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
        if target == 0.0:
            e = self._half_tail
            cut = self.params.cutoff_N
            fa = a if a > cut else 0.0
            fm = a * e
            fb = fm * e
            return (fa, fm if fm > cut else 0.0, fb if fb > cut else 0.0)
        e = self._half_rise
        am = a * e
        return (target + a, target + am, target + am * e)

    def is_idle(self, t_ns: int) -> bool:
        """True if the thrust is exactly 0 at ``t_ns`` and stays 0 until the next command."""
        return t_ns >= self.idle_from_ns

    def coil_energised(self, t_ns: int) -> bool:
        """True while the coil is energised at ``t_ns`` (as commanded, faults regardless)."""
        return self._coil_on_ns <= t_ns < self._coil_off_ns

    def status(self, t_ns: int) -> tuple[bool, bool, bool]:
        """(coil_energised, open: thrust > 10 % Fmax, current flowing) at ``t_ns``."""
        coil = self.coil_energised(t_ns)
        return (coil, self.thrust_N(t_ns) > self.params.open_threshold_N, coil)

    # --- commands -------------------------------------------------------------------
    def command(self, t_ns: int, on_time_ns: int) -> None:
        """A command received at ``t_ns``: energise the coil for ``on_time_ns`` (0 = off now)."""
        self._check_time(t_ns)
        if on_time_ns < 0:
            raise ValueError(f"on_time_ns must be >= 0, got {on_time_ns!r}")
        f_now = self.thrust_N(t_ns)
        driven = self._driven_at(t_ns)
        on_ns, off_ns = self._coil_on_ns, self._coil_off_ns
        if on_time_ns == 0:
            if not on_ns <= t_ns < off_ns:
                self._last_event_ns = t_ns
                return
            self._coil_off_ns = t_ns
        elif on_ns <= t_ns <= off_ns and off_ns > on_ns:
            self._coil_off_ns = max(t_ns + on_time_ns, on_ns + self.params.min_on_ns)
        else:
            if off_ns > on_ns:
                self._past_pulses.append((on_ns, off_ns))
            self._coil_on_ns = t_ns
            self._coil_off_ns = t_ns + max(on_time_ns, self.params.min_on_ns)
            self.openings += 1
        self._replan(t_ns, f_now, driven)

    def set_fault(self, kind: str | None, t_ns: int | None = None) -> None:
        """Inject (``"stuck_closed"``, ``"stuck_open"``) or clear (None) a valve fault.

        The fault takes effect at ``t_ns`` (default: the time of the last command or
        fault event, i.e. retroactively since then); ``t_ns`` must not precede it.
        """
        if kind is not None and kind not in FAULT_KINDS:
            raise ConfigError(
                "Valve.set_fault", "kind", kind, f"None or one of {sorted(FAULT_KINDS)}"
            )
        t = self._last_event_ns if t_ns is None else t_ns
        self._check_time(t)
        f_now = self.thrust_N(t)
        driven = self._driven_at(t)
        self.fault = kind
        self._replan(t, f_now, driven)

    @staticmethod
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

    # --- internals ------------------------------------------------------------------
    def _check_time(self, t_ns: int) -> None:
        if t_ns < self._last_event_ns:
            raise ValueError(
                f"valve events must be in time order: t_ns={t_ns} < last {self._last_event_ns}"
            )

    def _driven_at(self, t_ns: int) -> bool:
        """Whether the current plan drives the valve open at ``t_ns``."""
        for t0, _f0, target, _k in reversed(self._segments):
            if t_ns >= t0:
                return target > 0.0
        return False

    def _drive_intervals(self, t_ns: int) -> list[tuple[int, int]]:
        """Merged physical drive intervals [a, b) still ending after ``t_ns``."""
        od = self.params.open_delay_ns
        cd = self.params.close_delay_ns
        self._past_pulses = [p for p in self._past_pulses if p[1] + cd > t_ns]
        pulses = [*self._past_pulses, (self._coil_on_ns, self._coil_off_ns)]
        merged: list[tuple[int, int]] = []
        for on_ns, off_ns in pulses:
            a, b = on_ns + od, off_ns + cd
            if off_ns <= on_ns or b <= a or b <= t_ns:
                continue
            if merged and a <= merged[-1][1]:
                merged[-1] = (merged[-1][0], max(merged[-1][1], b))
            else:
                merged.append((a, b))
        return merged

    def _replan(self, t_ns: int, f_now: float, driven_before: bool) -> None:
        """Rebuild the thrust segments from ``t_ns`` on (history before it is kept)."""
        prm = self.params
        edges: list[tuple[int, bool]] = []
        drive_now = False
        for a, b in self._drive_intervals(t_ns):
            if a <= t_ns:
                drive_now = True
            else:
                edges.append((a, True))
            edges.append((b, False))
        if self.fault == FAULT_STUCK_CLOSED:
            drive_now, edges = False, []
        elif self.fault == FAULT_STUCK_OPEN:
            drive_now = drive_now or driven_before
            edges = [] if drive_now else [e for e in edges if e[1]][:1]

        # Keep the segments needed for t in [previous event, t_ns), then plan from t_ns.
        keep_from = self._last_event_ns
        old = self._segments
        first = 0
        for i in range(len(old) - 1, -1, -1):
            if old[i][0] <= keep_from:
                first = i
                break
        segs = [s for s in old[first:] if s[0] < t_ns]
        fmax, kr, kt = prm.max_thrust_N, prm.inv_rise_tau_per_ns, prm.inv_tail_tau_per_ns
        seg: _Segment = (t_ns, f_now, fmax, kr) if drive_now else (t_ns, f_now, 0.0, kt)
        segs.append(seg)
        for t_e, rising in edges:
            t0, f0, target, k = seg
            f_e = target + (f0 - target) * math.exp((t0 - t_e) * k)
            if target == 0.0 and f_e <= prm.cutoff_N:
                f_e = 0.0
            seg = (t_e, f_e, fmax, kr) if rising else (t_e, f_e, 0.0, kt)
            segs.append(seg)
        self._segments = segs
        self._last_event_ns = t_ns

        t0, f0, target, _k = seg
        if target > 0.0:
            self.idle_from_ns = NEVER_NS
        elif f0 <= prm.cutoff_N:
            self.idle_from_ns = t0
        else:
            self.idle_from_ns = t0 + math.ceil(
                prm.tail_tau_s * math.log(f0 / prm.cutoff_N) * NS_PER_S
            )
