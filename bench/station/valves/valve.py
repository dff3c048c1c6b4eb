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
    wherever it is, otherwise it decays first order towards 0; each command or fault
    event re-plans that piecewise-exponential future from the drive edges
    (:mod:`bench.station.valves.thrust_profile`: the closed forms, the history kept,
    the idle time ``idle_from_ns`` and the impulse of a pulse, ``pulse_impulse_Ns``).

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

    Implementation: the thrust profile holds the physical thrust; a fault changes the
    target and time constant of its segments (``bench.station.valves.thrust_profile``),
    so an inactive fault costs nothing and an active one adds no work per step. The
    fault kinds, their parameters and their validation are in
    ``bench.station.valves.params``.

Units: seconds in parameters (suffix ``_s``), integer nanoseconds for times (``_ns``),
newtons for thrust. Equation sources: first-order lag response (Ogata, "Modern Control
Engineering", 5th ed., §5-2); pulse-mode thruster model after Wertz & Larson, "Space
Mission Analysis and Design", §11.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from bench.station.valves.params import (
    FAULT_DEGRADED,
    FAULT_DELAYED,
    FAULT_INTERMITTENT,
    FAULT_KINDS,
    FAULT_LEAK,
    FAULT_STUCK_CLOSED,
    FAULT_STUCK_OPEN,
    HISTORY_NS,
    NEVER_NS,
    NOMINAL_THRUST_FACTOR,
    NS_PER_S,
    FaultParams,
    ValveParams,
    _ValveFaultParams,
    check_fault_params,
)
from bench.station.valves.thrust_profile import ThrustProfile, pulse_impulse_Ns
from dbc.errors import ConfigError

_STUCK_KINDS = frozenset({FAULT_STUCK_CLOSED, FAULT_STUCK_OPEN})


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
        "_last_event_ns",
        "_leak_N",
        "_past_pulses",
        "_profile",
        "_rng",
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
        # The planned thrust: segments and drive edges from the last event on.
        self._profile = ThrustProfile(params)
        # Faults: recorded parameters by kind (insertion order = order set) and their
        # effect on the model, nominal values when none is active.
        self._faults: dict[str, _ValveFaultParams] = {}
        self._stuck: str | None = None
        self._factor = NOMINAL_THRUST_FACTOR
        self._extra_delay_ns = 0
        self._dropout_p = 0.0
        self._dropout_rng: np.random.Generator | None = None
        self._leak_N = 0.0

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
        return self._profile.thrust_N(t_ns)

    def stage_thrusts_N(self, t_ns: int, dt_ns: int) -> tuple[float, float, float]:
        """The RK4 stage samples of the step [t, t + dt] [N]: its mean thrust three times,
        so the integrated impulse is exact wherever drive edges fall (``ThrustProfile``,
        "Impulse of a step"); one ``exp`` when no segment edge falls inside the step.
        """
        return self._profile.stage_thrusts_N(t_ns, dt_ns)

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
        driven = self._profile.driven_at(t_ns)
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
        """Closed-form impulse [N·s] of an isolated pulse from rest (min_on applied); see
        :func:`bench.station.valves.thrust_profile.pulse_impulse_Ns`."""
        return pulse_impulse_Ns(params, on_time_s)

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
        driven = self._profile.driven_at(t)
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
        profile = self._profile
        profile.plan(t_ns, f_now, drive_now, edges, keep_from, self._factor, self._leak_N)
        self._last_event_ns = t_ns
        self.idle_from_ns = profile.idle_from_ns
