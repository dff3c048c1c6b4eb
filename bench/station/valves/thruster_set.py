"""The vehicle's thruster set: geometry, valves, body wrench and propellant bookkeeping.

What it does
    Holds one ``Valve`` per thruster plus its mounting geometry, routes commands to the
    valves, sums the body-axes wrench of the thrusters that are not idle, and books the
    impulse and propellant of every thruster exactly as the rigid body integrated it.

Inputs / outputs and units
    - ``ThrusterGeometry`` (:mod:`bench.station.valves.geometry`): ``r_thr_B_m`` the
      thrust application point relative to the centre of mass, body axes [m];
      ``d_thr_B`` the unit direction of the force the thruster exerts *on the vehicle*
      (opposite to the plume), body axes [-].
    - ``wrench_B(t_ns)`` → (fx, fy, fz, tx, ty, tz): force [N] and torque about the
      centre of mass [N·m] in body axes: F = Σ Fᵢ dᵢ, τ = Σ Fᵢ (rᵢ × dᵢ) (rᵢ × dᵢ is
      precomputed per thruster).
    - Times are integer nanoseconds of simulation time (``t_ns``), never read from a clock.

Bookkeeping (why it matches the plant exactly)
    ``stage_wrenches(t_ns, dt_ns)`` builds the three wrenches ``rk4_step`` takes from the
    valves' stage samples (each valve's mean thrust over the step, three times: the
    closed-form impulse of the step, :mod:`bench.station.valves.thrust_profile`) and adds
    each thruster's impulse with Simpson weights, Iᵢ += dt·(Fᵢ,0 + 4 Fᵢ,½ + Fᵢ,1)/6. RK4's
    velocity increment is the same weighted sum of the same samples (for constant attitude
    it is identical), so the booked impulse is what the body received and what the valve
    delivered, including pulses that start or end inside a step. Propellant:
    mᵢ = Iᵢ / (Isp,ᵢ · g0) (rocket thrust equation, F = ṁ Isp g0; Sutton & Biblarz,
    "Rocket Propulsion Elements", 9th ed., eq. 2-5), g0 = 9.80665 m/s² (standard gravity,
    CGPM 1901).
    Callers that sample the thrusters themselves (e.g. to add disturbances) can use
    ``thrusts_N`` and ``accumulate`` instead.

Faults (``set_fault(index, kind, t_ns, **params)`` / ``clear_fault(index, kind, t_ns)``)
    Every valve fault of :mod:`bench.station.valves.valve` (``stuck_closed``, ``stuck_open``,
    ``degraded``, ``delayed``, ``intermittent``, ``leak``; parameters and timing there)
    is routed to the thruster's valve, and the thrust it changes is booked like any
    other (a leak's impulse and propellant included). The thruster set adds:
    - ``"misaligned"``, ``angle_deg`` [deg] in [−180, 180] and ``axis_B`` (unit vector,
      body axes [-]): the thrust direction is rotated by the angle about the axis
      (right hand; :mod:`bench.station.valves.geometry`), so both the force row d' and
      the torque row r × d' of that thruster change; models a bent nozzle or a shifted
      mount. A geometry change has no time history: it applies to every wrench
      evaluated after the call (call it at the step boundary ``t_ns``); setting it again
      replaces the angle and axis (it does not compound).
    ``set_fault(index, None, t_ns)`` clears every fault of that thruster. Inactive faults
    cost nothing per step: the valve folds its faults into its thrust segments and a
    misalignment into the precomputed rows of the wrench sum.
    ``rng`` (constructor, optional) seeds one independent generator per valve for the
    ``intermittent`` drop-outs, so a fault on one thruster never shifts another's draws.

Assumptions
    Thrusters are independent (no manifold pressure coupling), geometry is fixed in the
    body (apart from a ``misaligned`` fault), thrust acts along the direction through
    ``r_thr_B_m``. Dispersion of the nominal parameters (DESIGN.md §6) is expressed by
    the caller through the geometry and parameters given.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from bench.station.dynamics.rigid_body import Vec3, Wrench
from bench.station.valves.base import ValveModel
from bench.station.valves.geometry import FAULT_MISALIGNED, ThrusterGeometry, misaligned_geometry
from bench.station.valves.params import FAULT_KINDS, S_PER_NS, FaultParams, ValveParams
from bench.station.valves.valve import Valve
from dbc import validation as check
from dbc.errors import ConfigError

G0_M_S2 = 9.80665
"""Standard gravity [m/s²], used to convert impulse to propellant mass through Isp."""
SIMPSON_MID_WEIGHT = 4.0
SIMPSON_DIVISOR = 6.0
THRUSTER_FAULT_KINDS = FAULT_KINDS | {FAULT_MISALIGNED}
"""Every fault kind ``ThrusterSet.set_fault`` accepts."""
CHILD_SEED_BOUND = 2**63 - 1
"""Exclusive upper bound of the per-valve seeds drawn from the constructor's ``rng``."""

ValveFactory = Callable[[ValveParams, "np.random.Generator | None"], ValveModel]
"""Builds one valve model from its parameters and generator (default: the on-off ``Valve``)."""

ThrusterStatus = tuple[bool, bool, bool]
"""(coil_energised, open, current) of one valve, as ``Valve.status``."""


def _per_thruster_params(
    params: ValveParams | Sequence[ValveParams], n: int, source: str
) -> tuple[ValveParams, ...]:
    """One ``ValveParams`` per thruster: ``params`` shared, or a sequence of ``n``."""
    if isinstance(params, ValveParams):
        plist: tuple[ValveParams, ...] = (params,) * n
    else:
        plist = tuple(params)
        if len(plist) != n or not all(isinstance(p, ValveParams) for p in plist):
            raise ConfigError(
                source,
                "params",
                params,
                f"a ValveParams or {n} of them (one per thruster)",
            )
    return plist


def _valve_rngs(
    rng: np.random.Generator | None, n: int, source: str
) -> list[np.random.Generator | None]:
    """One generator per valve, seeded from ``rng`` (None: no generator)."""
    if rng is None:
        rngs: list[np.random.Generator | None] = [None] * n
    elif isinstance(rng, np.random.Generator):
        seeds = rng.integers(0, CHILD_SEED_BOUND, size=n).tolist()
        rngs = [np.random.default_rng(s) for s in seeds]
    else:
        raise ConfigError(source, "rng", rng, "None or a numpy Generator")
    return rngs


def _checked_index(index: int, kind: str | None, n: int, source: str) -> int:
    """``index`` if it names one of ``n`` thrusters and ``kind`` is a fault kind (or None)."""
    if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < n:
        raise ConfigError(
            f"{source}.set_fault({kind!r})", "index", index, f"an integer in [0, {n})"
        )
    if kind is not None and kind not in THRUSTER_FAULT_KINDS:
        raise ConfigError(
            f"{source}.set_fault({kind!r})",
            "kind",
            kind,
            f"None or one of {sorted(THRUSTER_FAULT_KINDS)}",
        )
    return index


class ThrusterSet:
    """N thrusters: geometry + one ``Valve`` each; wrench, status and propellant bookkeeping.

    ``params`` is one ``ValveParams`` shared by all thrusters or a sequence of one per
    thruster. ``g0_m_s2`` is the Isp reference gravity (standard gravity by default).
    ``rng`` (optional) seeds each valve's generator for ``intermittent`` drop-outs.
    ``valve_factory`` (optional) builds each valve model (default ``Valve``, the on-off
    valve; e.g. ``bench.station.valves.throttled.ThrottledValve`` with its period bound).
    """

    __slots__ = (
        "_com_B_m",
        "_geometries_ref",
        "_impulse_Ns",
        "_misalignment",
        "_rows",
        "_source",
        "g0_m_s2",
        "geometries",
        "valves",
    )

    def __init__(
        self,
        geometries: Sequence[ThrusterGeometry],
        params: ValveParams | Sequence[ValveParams],
        g0_m_s2: float = G0_M_S2,
        *,
        source: str = "ThrusterSet",
        rng: np.random.Generator | None = None,
        valve_factory: ValveFactory | None = None,
    ) -> None:
        geoms = tuple(geometries)
        if not geoms or not all(isinstance(g, ThrusterGeometry) for g in geoms):
            raise ConfigError(source, "geometries", geometries, "one or more ThrusterGeometry")
        plist = _per_thruster_params(params, len(geoms), source)
        g0 = check.positive(source, "g0_m_s2", g0_m_s2)
        rngs = _valve_rngs(rng, len(geoms), source)
        self._source = source
        self.geometries = geoms
        self._geometries_ref = geoms
        self._com_B_m: Vec3 = (0.0, 0.0, 0.0)
        make: ValveFactory = valve_factory if valve_factory is not None else Valve
        self.valves: tuple[ValveModel, ...] = tuple(
            make(p, r) for p, r in zip(plist, rngs, strict=True)
        )
        self.g0_m_s2 = g0
        self._impulse_Ns = [0.0] * len(geoms)
        # Active misalignments: index → (recorded parameters, rotated geometry).
        self._misalignment: dict[int, tuple[FaultParams, ThrusterGeometry]] = {}
        self._rows: tuple[
            tuple[int, ValveModel, float, float, float, float, float, float], ...
        ] = ()
        self._build_rows()

    def _build_rows(self) -> None:
        """Hot-path rows: (index, valve, dx, dy, dz, (r×d)x, (r×d)y, (r×d)z), faults applied."""
        self._rows = tuple(
            (i, v, *g.d_thr_B, *g.torque_arm_B_m)
            for i, (v, g) in enumerate(zip(self.valves, self.effective_geometries, strict=True))
        )

    def __len__(self) -> int:
        return len(self.valves)

    @property
    def com_B_m(self) -> Vec3:
        """Centre of mass the thruster positions are referred to, relative to the reference
        point the geometries were given about (body axes) [m]."""
        return self._com_B_m

    def set_com_offset(self, com_B_m: Vec3) -> None:
        """Refer every thruster position to a centre of mass at ``com_B_m`` [m, body axes].

        ``com_B_m`` is relative to the point the constructor's geometries were given
        about (not cumulative): r_i ← r_i,ref − com_B_m, so the torque arms r × d are
        about the new centre of mass (a mass-property change, ``bench.station.dynamics.capture``).
        Directions and active misalignments are kept. Applies to every wrench evaluated
        after the call (call it at a step boundary).
        """
        c = check.triple(self._source, "com_B_m", com_B_m)
        self._com_B_m = c
        self.geometries = tuple(
            ThrusterGeometry(
                (g.r_thr_B_m[0] - c[0], g.r_thr_B_m[1] - c[1], g.r_thr_B_m[2] - c[2]),
                g.d_thr_B,
                source=g.source,
            )
            for g in self._geometries_ref
        )
        self._misalignment = {
            i: (p, ThrusterGeometry(self.geometries[i].r_thr_B_m, g.d_thr_B, source=g.source))
            for i, (p, g) in self._misalignment.items()
        }
        self._build_rows()

    # --- commands -------------------------------------------------------------------
    def command(self, t_ns: int, index: int, on_time_ns: int) -> None:
        """Command thruster ``index`` at ``t_ns`` with ``on_time_ns`` (see ``Valve.command``)."""
        self.valves[index].command(t_ns, on_time_ns)

    def close_all(self, t_ns: int) -> None:
        """Watchdog action: de-energise every coil now."""
        for v in self.valves:
            v.command(t_ns, 0)

    def set_fault(
        self, index: int, kind: str | None, t_ns: int | None = None, **params: object
    ) -> None:
        """Inject fault ``kind`` with ``params`` on thruster ``index`` at ``t_ns``, or clear all.

        Valve kinds go to ``Valve.set_fault`` (same ``t_ns`` default and parameters);
        ``"misaligned"`` takes ``angle_deg`` and ``axis_B`` (module docstring). ``None``
        clears every fault of the thruster. Bad index, kind or parameters: ``ConfigError``.
        """
        i = _checked_index(index, kind, len(self.valves), self._source)
        if kind is None:
            self.valves[i].set_fault(None, t_ns, **params)
            if self._misalignment.pop(i, None) is not None:
                self._build_rows()
        elif kind == FAULT_MISALIGNED:
            source = f"{self._source}.set_fault({FAULT_MISALIGNED!r})"
            self._misalignment[i] = misaligned_geometry(self.geometries[i], params, source)
            self._build_rows()
        else:
            self.valves[i].set_fault(kind, t_ns, **params)

    def clear_fault(self, index: int, kind: str, t_ns: int | None = None) -> None:
        """Clear fault ``kind`` of thruster ``index`` at ``t_ns``; a no-op if it is inactive."""
        i = _checked_index(index, kind, len(self.valves), self._source)
        if kind == FAULT_MISALIGNED:
            if self._misalignment.pop(i, None) is not None:
                self._build_rows()
        else:
            self.valves[i].clear_fault(kind, t_ns)

    @property
    def faults_active(self) -> dict[int, dict[str, FaultParams]]:
        """Active faults of the faulty thrusters: index → kind → recorded parameters."""
        out: dict[int, dict[str, FaultParams]] = {}
        for i, v in enumerate(self.valves):
            faults = v.faults_active
            if i in self._misalignment:
                faults[FAULT_MISALIGNED] = dict(self._misalignment[i][0])
            if faults:
                out[i] = faults
        return out

    @property
    def effective_geometries(self) -> tuple[ThrusterGeometry, ...]:
        """Geometry per thruster as the wrench uses it (nominal unless ``misaligned``)."""
        mis = self._misalignment
        return tuple(mis[i][1] if i in mis else g for i, g in enumerate(self.geometries))

    @property
    def dropped_pulses(self) -> tuple[int, ...]:
        """Coil pulses dropped by ``intermittent`` faults so far, per thruster."""
        return tuple(v.dropped_pulses for v in self.valves)

    # --- the plant's inputs ---------------------------------------------------------
    def wrench_B(self, t_ns: int) -> Wrench:
        """Body wrench (fx, fy, fz, tx, ty, tz) [N, N·m] at ``t_ns`` (pure; no bookkeeping)."""
        fx = fy = fz = tx = ty = tz = 0.0
        for _i, v, dx, dy, dz, ax, ay, az in self._rows:
            if t_ns < v.idle_from_ns:
                f = v.thrust_N(t_ns)
                fx += f * dx
                fy += f * dy
                fz += f * dz
                tx += f * ax
                ty += f * ay
                tz += f * az
        return (fx, fy, fz, tx, ty, tz)

    def stage_wrenches(self, t_ns: int, dt_ns: int) -> tuple[Wrench, Wrench, Wrench]:
        """The three stage wrenches of [t, t + dt] for ``rk4_step``, booking the step's impulse.

        Call once per integration step, with the step actually taken; ``dt_ns`` must be
        positive and even (so that the midpoint is an exact nanosecond).
        """
        if dt_ns <= 0 or dt_ns % 2:
            raise ValueError(f"dt_ns must be positive and even, got {dt_ns!r}")
        w = dt_ns * S_PER_NS / SIMPSON_DIVISOR
        imp = self._impulse_Ns
        ax0 = ay0 = az0 = bx0 = by0 = bz0 = 0.0
        ax1 = ay1 = az1 = bx1 = by1 = bz1 = 0.0
        ax2 = ay2 = az2 = bx2 = by2 = bz2 = 0.0
        for i, v, dx, dy, dz, rx, ry, rz in self._rows:
            if t_ns < v.idle_from_ns:
                f0, f1, f2 = v.stage_thrusts_N(t_ns, dt_ns)
                imp[i] += w * (f0 + SIMPSON_MID_WEIGHT * f1 + f2)
                ax0 += f0 * dx
                ay0 += f0 * dy
                az0 += f0 * dz
                bx0 += f0 * rx
                by0 += f0 * ry
                bz0 += f0 * rz
                ax1 += f1 * dx
                ay1 += f1 * dy
                az1 += f1 * dz
                bx1 += f1 * rx
                by1 += f1 * ry
                bz1 += f1 * rz
                ax2 += f2 * dx
                ay2 += f2 * dy
                az2 += f2 * dz
                bx2 += f2 * rx
                by2 += f2 * ry
                bz2 += f2 * rz
        return (
            (ax0, ay0, az0, bx0, by0, bz0),
            (ax1, ay1, az1, bx1, by1, bz1),
            (ax2, ay2, az2, bx2, by2, bz2),
        )

    def account(self, t_ns: int, dt_ns: int) -> None:
        """Book the impulse of the step [t, t + dt] from thrusts re-sampled at its RK4 stages.

        The booking of ``stage_wrenches`` for a caller that builds its own wrenches; it
        samples every active valve a second time, so ``stage_wrenches`` is cheaper.
        """
        if dt_ns <= 0 or dt_ns % 2:
            raise ValueError(f"dt_ns must be positive and even, got {dt_ns!r}")
        w = dt_ns * S_PER_NS / SIMPSON_DIVISOR
        imp = self._impulse_Ns
        for i, v, *_geometry in self._rows:
            if t_ns < v.idle_from_ns:
                f0, f1, f2 = v.stage_thrusts_N(t_ns, dt_ns)
                imp[i] += w * (f0 + SIMPSON_MID_WEIGHT * f1 + f2)

    def thrusts_N(self, t_ns: int) -> tuple[float, ...]:
        """Thrust of every thruster at ``t_ns`` [N]."""
        return tuple(v.thrust_N(t_ns) for v in self.valves)

    def accumulate(
        self,
        dt_s: float,
        thrusts0_N: Sequence[float],
        thrusts_mid_N: Sequence[float],
        thrusts1_N: Sequence[float],
    ) -> None:
        """Book one RK4 step's impulse from thrusts sampled at t, t + dt/2, t + dt (Simpson)."""
        w = dt_s / SIMPSON_DIVISOR
        imp = self._impulse_Ns
        for i, (f0, f1, f2) in enumerate(zip(thrusts0_N, thrusts_mid_N, thrusts1_N, strict=True)):
            imp[i] += w * (f0 + SIMPSON_MID_WEIGHT * f1 + f2)

    # --- bookkeeping and status -------------------------------------------------------
    @property
    def impulse_Ns(self) -> tuple[float, ...]:
        """Impulse booked per thruster so far [N·s]."""
        return tuple(self._impulse_Ns)

    @property
    def propellant_kg(self) -> tuple[float, ...]:
        """Propellant used per thruster so far, impulse / (Isp · g0) [kg]."""
        return tuple(self._propellant_list())

    def _propellant_list(self) -> list[float]:
        """:attr:`propellant_kg` as a list, by index (telemetry reads it every 10 ms)."""
        g0 = self.g0_m_s2
        valves, impulse = self.valves, self._impulse_Ns
        return [impulse[k] / (valves[k].params.isp_s * g0) for k in range(len(valves))]

    @property
    def total_propellant_kg(self) -> float:
        """Propellant used by all thrusters so far [kg]."""
        return math.fsum(self._propellant_list())

    @property
    def openings(self) -> tuple[int, ...]:
        """Coil openings (rising edges) per thruster so far."""
        return tuple(v.openings for v in self.valves)

    def status(self, t_ns: int) -> list[ThrusterStatus]:
        """(coil_energised, open, current) per thruster at ``t_ns``."""
        return [v.status(t_ns) for v in self.valves]

    def is_idle(self, t_ns: int) -> bool:
        """True if every valve is idle at ``t_ns``."""
        return all(t_ns >= v.idle_from_ns for v in self.valves)
