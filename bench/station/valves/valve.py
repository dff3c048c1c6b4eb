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
    lookup plus one ``exp``. Valid for any t ≥ min(previous event, newest event −
    ``HISTORY_NS``), events being commands and fault changes (so a caller may deliver
    commands and faults inside an integration step and still sample the step's start).

    Closed-form impulse of an isolated pulse from rest (``Valve.pulse_impulse_Ns``), with
    D = max(0, on + close_delay − open_delay):
        I = Fmax[D − τr(1 − e^{−D/τr})] + Fmax(1 − e^{−D/τr})·τt
    (integral of the two exponentials above; the cut-off tail below 1e-9·Fmax is ignored).

Faults (``set_fault`` / ``clear_fault``; DESIGN.md §7)
    Each fault is set and cleared at a simulation time ``t_ns`` (default: the time of the
    last command or fault event); several may be active at once and combine. Setting an
    active kind again replaces its parameters. The thrust below is the *physical* thrust
    of the nozzle: the one ``thrust_N``/``stage_thrusts_N`` return, the rigid body feels
    and the impulse and propellant bookkeeping integrates.

    - ``"stuck_closed"`` (no parameter): the valve is driven closed from the fault time
      on and never opens (any thrust in progress decays with the tail); the coil still
      energises and reports current. Setting it clears ``stuck_open``.
    - ``"stuck_open"`` (no parameter): the valve fails open: from the fault time (after
      the opening delay, unless it is already open) it never closes, whatever is
      commanded: full thrust after the opening transient; ``status`` reports it open with
      the coil off. Setting it clears ``stuck_closed``.
    - ``"degraded"``, ``factor`` [-] in [0, 1]: from the fault time the thrust is
      exactly ``factor`` × the nominal thrust (rise and tail included, so a pulse gives
      ``factor`` × ``pulse_impulse_Ns``); models a partly blocked injector or a low feed
      pressure. The thrust in progress is scaled at once; from a factor of 0 a later
      factor restarts the transient from zero thrust.
    - ``"delayed"``, ``extra_delay_s`` [s] ≥ 0: added to ``open_delay_s`` for every
      opening not yet begun at the fault time (coil pulses starting later, and a pulse
      still in its opening delay); models a sticky poppet or a weak drive voltage.
      Clearing it lets a pending opening happen at max(clear time, nominal opening).
    - ``"intermittent"``, ``dropout_probability`` [-] in [0, 1] (optional ``rng``, a
      ``numpy.random.Generator``, else the one given to the constructor): each coil
      pulse that starts (rising edge) while the fault is active is dropped with that
      probability — one uniform draw per pulse, only while the fault is active, so runs
      are reproducible from the seed. A dropped pulse gives no thrust, but its coil
      energises and reports current (``status`` = (True, False, True)); counted in
      ``dropped_pulses``. Clearing it lets the pulse in progress open.
    - ``"leak"``, ``thrust_N`` [N] in (0, max_thrust_N]: a constant thrust added to the
      valve's thrust, commanded or not, from the fault time (a step) until cleared;
      the valve is then never idle, its impulse and propellant are booked like any
      thrust, and ``status`` reports it open only above 10 % of Fmax.
    - ``set_fault(None, t_ns)`` clears every fault; the valve then follows the coil
      schedule again.
    Misalignment changes the thrust *direction*, so it belongs to the thruster set
    (``bench.station.valves.thruster_set``), not to the valve.

    Implementation: the segments hold the physical thrust. A driven segment rises (time
    constant τr) towards ``factor``·Fmax + leak, an undriven one decays (τt) towards the
    leak; both keep the piecewise-exponential form, so an inactive fault costs nothing
    and an active one adds no work per step. A segment whose thrust lies above its
    target is decaying, below it rising; ``stage_thrusts_N`` relies on that.

Units: seconds in parameters (suffix ``_s``), integer nanoseconds for times (``_ns``),
newtons for thrust. Equation sources: first-order lag response (Ogata, "Modern Control
Engineering", 5th ed., §5-2); pulse-mode thruster model after Wertz & Larson, "Space
Mission Analysis and Design", §11.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from mypy_extensions import mypyc_attr

from dbc.errors import ConfigError
from dbc.faults import DEGRADED, DELAYED, INTERMITTENT, LEAK, STUCK_CLOSED, STUCK_OPEN

NS_PER_S = 1_000_000_000
S_PER_NS = 1e-9
THRUST_CUTOFF_FRACTION = 1e-9
"""A decaying thrust below this fraction of Fmax is exactly zero (the valve is idle)."""
OPEN_THRESHOLD_FRACTION = 0.1
"""``status`` reports the valve open while the thrust exceeds this fraction of Fmax."""
HISTORY_NS = 10_000_000
"""Thrust history kept before the newest event [ns] (10 plant steps at 1 kHz), so that a
step may be sampled from its start after several events inside it (commands, faults)."""
NEVER_NS = 2**63 - 1
"""A time later than any simulation (idle_from_ns of a valve that never stops)."""
FAULT_STUCK_CLOSED = STUCK_CLOSED
FAULT_STUCK_OPEN = STUCK_OPEN
FAULT_DEGRADED = DEGRADED
FAULT_DELAYED = DELAYED
FAULT_INTERMITTENT = INTERMITTENT
FAULT_LEAK = LEAK
FAULT_PARAMS: Mapping[str, tuple[str, ...]] = {
    FAULT_STUCK_CLOSED: (),
    FAULT_STUCK_OPEN: (),
    FAULT_DEGRADED: ("factor",),
    FAULT_DELAYED: ("extra_delay_s",),
    FAULT_INTERMITTENT: ("dropout_probability",),
    FAULT_LEAK: ("thrust_N",),
}
"""Valve fault kinds and their required parameters (see the module docstring)."""
FAULT_OPTIONAL_PARAMS: Mapping[str, tuple[str, ...]] = {FAULT_INTERMITTENT: ("rng",)}
"""Optional parameters (not recorded in ``faults_active``)."""
FAULT_KINDS = frozenset(FAULT_PARAMS)
_STUCK_KINDS = frozenset({FAULT_STUCK_CLOSED, FAULT_STUCK_OPEN})
NOMINAL_THRUST_FACTOR = 1.0
FaultParams = dict[str, float | tuple[float, ...]]
"""Recorded parameters of one active fault: name → value (number or vector) in the units
of its name (a copy, safe to log; generators are not recorded)."""
_ValveFaultParams = dict[str, float]

# A thrust segment: (t_start_ns, thrust at t_start [N], target thrust [N], 1/τ [1/ns]).
_Segment = tuple[int, float, float, float]


def _require(ok: bool, source: str, key: str, value: object, expected: str) -> None:
    if not ok:
        raise ConfigError(source, key, value, expected)


def _is_real(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _fault_number(
    source: str, key: str, value: object, lo: float, hi: float, expected: str = ""
) -> float:
    """``value`` as a finite float in [lo, hi], or ConfigError naming ``key``."""
    x = float(value) if _is_real(value) else math.nan  # type: ignore[arg-type]
    _require(
        math.isfinite(x) and lo <= x <= hi,
        source,
        key,
        value,
        expected or f"a number in [{lo:g}, {hi:g}]",
    )
    return x


def check_fault_params(
    kind: str, params: Mapping[str, object], source: str, max_thrust_N: float
) -> _ValveFaultParams:
    """Validate the parameters of a valve fault ``kind``; returns the recorded ones.

    Unknown or missing names and out-of-range values raise ``ConfigError(source, name,
    value, expected)``; the optional ``rng`` is checked to be a numpy Generator but not
    returned.
    """
    _require(kind in FAULT_KINDS, source, "kind", kind, f"None or one of {sorted(FAULT_KINDS)}")
    required = FAULT_PARAMS[kind]
    allowed = required + FAULT_OPTIONAL_PARAMS.get(kind, ())
    for key, value in params.items():
        _require(
            key in allowed,
            source,
            key,
            value,
            f"no such parameter for {kind!r} (its parameters: {list(allowed) or 'none'})",
        )
    for key in required:
        _require(key in params, source, key, None, f"a value (required by {kind!r})")
    if "rng" in params:
        rng = params["rng"]
        _require(isinstance(rng, np.random.Generator), source, "rng", rng, "a numpy Generator")
    out: _ValveFaultParams = {}
    if kind == FAULT_DEGRADED:
        out["factor"] = _fault_number(source, "factor", params["factor"], 0.0, 1.0)
    elif kind == FAULT_DELAYED:
        out["extra_delay_s"] = _fault_number(
            source, "extra_delay_s", params["extra_delay_s"], 0.0, math.inf, "a finite number >= 0"
        )
    elif kind == FAULT_INTERMITTENT:
        out["dropout_probability"] = _fault_number(
            source, "dropout_probability", params["dropout_probability"], 0.0, 1.0
        )
    elif kind == FAULT_LEAK:
        value = params["thrust_N"]
        expected = f"a number in (0, {max_thrust_N:g}] (at most max_thrust_N)"
        out["thrust_N"] = _fault_number(source, "thrust_N", value, 0.0, max_thrust_N, expected)
        _require(out["thrust_N"] > 0.0, source, "thrust_N", value, expected)
    return out


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
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

    ``rng`` (optional) is the generator of the ``intermittent`` fault's drop-outs when
    ``set_fault`` is not given one.

    Attributes (read-only for callers):
        params          the ``ValveParams``
        openings        number of coil rising edges so far
        dropped_pulses  coil pulses dropped by the ``intermittent`` fault so far
        idle_from_ns    from this time on the thrust is exactly 0 unless a new command
                        arrives (``NEVER_NS`` while a rise is pending, the valve is stuck
                        open or leaking)
    """

    __slots__ = (
        "_coil_dropped",
        "_coil_od_ns",
        "_coil_off_ns",
        "_coil_on_ns",
        "_drive_plan",
        "_dropout_p",
        "_dropout_rng",
        "_extra_delay_ns",
        "_factor",
        "_faults",
        "_half_ns",
        "_half_rise",
        "_half_tail",
        "_last_event_ns",
        "_leak_N",
        "_past_pulses",
        "_rng",
        "_segments",
        "_stuck",
        "dropped_pulses",
        "idle_from_ns",
        "openings",
        "params",
    )

    def __init__(self, params: ValveParams, rng: np.random.Generator | None = None) -> None:
        if rng is not None and not isinstance(rng, np.random.Generator):
            raise ConfigError("Valve", "rng", rng, "None or a numpy Generator")
        self.params = params
        self._rng = rng
        self.openings = 0
        self.dropped_pulses = 0
        self.idle_from_ns = -NEVER_NS
        self._coil_on_ns = -NEVER_NS
        self._coil_off_ns = -NEVER_NS
        self._coil_od_ns = params.open_delay_ns  # opening delay of the coil pulse
        self._coil_dropped = False  # the coil pulse was dropped (intermittent)
        self._last_event_ns = -NEVER_NS
        # Earlier coil pulses whose delayed closing may still lie in the future:
        # (coil on, coil off, opening delay [ns], dropped).
        self._past_pulses: list[tuple[int, int, int, bool]] = []
        self._segments: list[_Segment] = [(-NEVER_NS, 0.0, 0.0, params.inv_tail_tau_per_ns)]
        # Planned drive state from the last event on: (time, driven open) edges.
        self._drive_plan: list[tuple[int, bool]] = [(-NEVER_NS, False)]
        # Faults: recorded parameters by kind (insertion order = order set) and their
        # effect on the model, nominal values when none is active.
        self._faults: dict[str, _ValveFaultParams] = {}
        self._stuck: str | None = None
        self._factor = NOMINAL_THRUST_FACTOR
        self._extra_delay_ns = 0
        self._dropout_p = 0.0
        self._dropout_rng: np.random.Generator | None = None
        self._leak_N = 0.0
        # Cache of stage_thrusts_N: half step [ns] and its decay factors e^{-half/τ}.
        self._half_ns = 0
        self._half_rise = 1.0
        self._half_tail = 1.0

    @property
    def fault(self) -> str | None:
        """None without fault, else the active kinds joined by ``+`` in the order set."""
        return "+".join(self._faults) if self._faults else None

    @property
    def faults_active(self) -> dict[str, FaultParams]:
        """Active faults: kind → recorded parameters (a copy; empty when healthy)."""
        return {k: dict(v) for k, v in self._faults.items()}

    # --- queries --------------------------------------------------------------------
    def thrust_N(self, t_ns: int) -> float:
        """Physical thrust [N] at ``t_ns`` (any t within the kept history, module docstring)."""
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
                self._past_pulses.append((on_ns, off_ns, self._coil_od_ns, self._coil_dropped))
            self._coil_on_ns = t_ns
            self._coil_off_ns = t_ns + max(on_time_ns, self.params.min_on_ns)
            self._coil_od_ns = self.params.open_delay_ns + self._extra_delay_ns
            dropped = False
            if self._dropout_rng is not None:  # intermittent: one draw per coil pulse
                dropped = float(self._dropout_rng.random()) < self._dropout_p
                self.dropped_pulses += int(dropped)
            self._coil_dropped = dropped
            self.openings += 1
        self._replan(t_ns, f_now, driven)

    def set_fault(self, kind: str | None, t_ns: int | None = None, **params: object) -> None:
        """Inject fault ``kind`` with its ``params`` at ``t_ns``, or clear all faults (None).

        Kinds and parameters: see the module docstring (``FAULT_PARAMS``); bad ones raise
        ``ConfigError``. The fault takes effect at ``t_ns`` (default: the time of the last
        command or fault event, i.e. retroactively since then); ``t_ns`` must not precede
        it. Setting an active kind again replaces its parameters.
        """
        source = f"Valve.set_fault({kind!r})"
        if kind is None:
            if params:
                key = next(iter(params))
                raise ConfigError(source, key, params[key], "no parameter when clearing (None)")
            self._event(t_ns, {k: None for k in self._faults})
            return
        recorded = check_fault_params(kind, params, source, self.params.max_thrust_N)
        rng: np.random.Generator | None = None
        if kind == FAULT_INTERMITTENT:
            given = params.get("rng", self._rng)
            if not isinstance(given, np.random.Generator):
                raise ConfigError(
                    source, "rng", given, "a numpy Generator (to set_fault or to Valve())"
                )
            rng = given
        self._event(t_ns, {kind: recorded}, rng)

    def clear_fault(self, kind: str, t_ns: int | None = None) -> None:
        """Clear fault ``kind`` at ``t_ns`` (default as ``set_fault``); a no-op if inactive."""
        if kind not in FAULT_KINDS:
            raise ConfigError(
                f"Valve.clear_fault({kind!r})", "kind", kind, f"one of {sorted(FAULT_KINDS)}"
            )
        self._event(t_ns, {kind: None})

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

    def _event(
        self,
        t_ns: int | None,
        changes: Mapping[str, _ValveFaultParams | None],
        rng: np.random.Generator | None = None,
    ) -> None:
        """Apply fault changes (kind → new parameters, None = clear) at ``t_ns`` and replan.

        The thrust in progress is carried over: its valve part (thrust − leak) is scaled
        by the ratio of the thrust factors, and the new leak is added.
        """
        t = self._last_event_ns if t_ns is None else t_ns
        self._check_time(t)
        f_now = self.thrust_N(t)
        driven = self._driven_at(t)
        factor_before, leak_before = self._factor, self._leak_N
        faults = self._faults
        for kind, recorded in changes.items():
            faults.pop(kind, None)
            if recorded is not None:
                if kind in _STUCK_KINDS:
                    faults.pop(FAULT_STUCK_OPEN, None)
                    faults.pop(FAULT_STUCK_CLOSED, None)
                faults[kind] = recorded
        self._stuck = next((k for k in faults if k in _STUCK_KINDS), None)
        self._factor = (
            faults[FAULT_DEGRADED]["factor"] if FAULT_DEGRADED in faults else NOMINAL_THRUST_FACTOR
        )
        self._leak_N = faults[FAULT_LEAK]["thrust_N"] if FAULT_LEAK in faults else 0.0
        extra_s = faults[FAULT_DELAYED]["extra_delay_s"] if FAULT_DELAYED in faults else 0.0
        extra_ns = round(extra_s * NS_PER_S)
        if extra_ns != self._extra_delay_ns:
            self._extra_delay_ns = extra_ns
            self._retime_pending_openings(t)
        if FAULT_INTERMITTENT in faults:
            self._dropout_p = faults[FAULT_INTERMITTENT]["dropout_probability"]
            if rng is not None:
                self._dropout_rng = rng
        else:
            self._dropout_p = 0.0
            self._dropout_rng = None
            if self._coil_on_ns <= t < self._coil_off_ns:
                self._coil_dropped = False  # the pulse in progress may now open
        valve_part = max(0.0, f_now - leak_before)
        if self._factor != factor_before:
            valve_part = valve_part * (self._factor / factor_before) if factor_before > 0.0 else 0.0
        self._replan(t, valve_part + self._leak_N, driven)

    def _retime_pending_openings(self, t_ns: int) -> None:
        """Give the current opening delay to every coil pulse not yet open at ``t_ns``."""
        od = self.params.open_delay_ns + self._extra_delay_ns
        self._past_pulses = [
            (on, off, od if on + d > t_ns else d, dropped)
            for on, off, d, dropped in self._past_pulses
        ]
        if self._coil_on_ns + self._coil_od_ns > t_ns:
            self._coil_od_ns = od

    def _driven_at(self, t_ns: int) -> bool:
        """Whether the current plan drives the valve open at ``t_ns``."""
        for t_e, driven in reversed(self._drive_plan):
            if t_ns >= t_e:
                return driven
        return False

    def _drive_intervals(self, t_ns: int) -> list[tuple[int, int]]:
        """Merged physical drive intervals [a, b) still ending after ``t_ns``."""
        cd = self.params.close_delay_ns
        self._past_pulses = [p for p in self._past_pulses if p[1] + cd > t_ns]
        current = (self._coil_on_ns, self._coil_off_ns, self._coil_od_ns, self._coil_dropped)
        spans: list[tuple[int, int]] = []
        for on_ns, off_ns, od, dropped in (*self._past_pulses, current):
            a, b = on_ns + od, off_ns + cd
            if dropped or off_ns <= on_ns or b <= a or b <= t_ns:
                continue
            spans.append((a, b))
        spans.sort()  # opening delays may differ between pulses (delayed fault)
        merged: list[tuple[int, int]] = []
        for a, b in spans:
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
        if self._stuck == FAULT_STUCK_CLOSED:
            drive_now, edges = False, []
        elif self._stuck == FAULT_STUCK_OPEN:
            drive_now = drive_now or driven_before
            if drive_now:
                edges = []
            else:  # fails open: opens one opening delay after the fault, or earlier if driven
                fails_open = t_ns + prm.open_delay_ns + self._extra_delay_ns
                commanded = [e[0] for e in edges if e[1]][:1]
                edges = [(min([fails_open, *commanded]), True)]

        # Keep the segments needed for t in [min(previous event, t_ns − history), t_ns),
        # then plan from t_ns.
        keep_from = min(self._last_event_ns, t_ns - HISTORY_NS)
        old = self._segments
        first = 0
        for i in range(len(old) - 1, -1, -1):
            if old[i][0] <= keep_from:
                first = i
                break
        segs = [s for s in old[first:] if s[0] < t_ns]
        kr, kt = prm.inv_rise_tau_per_ns, prm.inv_tail_tau_per_ns
        # Driven: rise towards factor·Fmax + leak (a factor of 0 is never driven open);
        # undriven: decay towards the leak.
        leak = self._leak_N
        drive_target = self._factor * prm.max_thrust_N + leak
        drive_k = kr if self._factor > 0.0 else kt
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
        self._segments = segs
        self._drive_plan = [(t_ns, drive_now), *edges]
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
