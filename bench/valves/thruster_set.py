"""The vehicle's thruster set: geometry, valves, body wrench and propellant bookkeeping.

What it does
    Holds one ``Valve`` per thruster plus its mounting geometry, routes commands to the
    valves, sums the body-axes wrench of the thrusters that are not idle, and books the
    impulse and propellant of every thruster exactly as the rigid body integrated it.

Inputs / outputs and units
    - ``ThrusterGeometry``: ``r_thr_B_m`` the thrust application point relative to the
      centre of mass, body axes [m]; ``d_thr_B`` the unit direction of the force the
      thruster exerts *on the vehicle* (opposite to the plume), body axes [-].
    - ``wrench_B(t_ns)`` → (fx, fy, fz, tx, ty, tz): force [N] and torque about the
      centre of mass [N·m] in body axes: F = Σ Fᵢ dᵢ, τ = Σ Fᵢ (rᵢ × dᵢ) (rᵢ × dᵢ is
      precomputed per thruster).
    - Times are integer nanoseconds of simulation time (``t_ns``), never read from a clock.

Bookkeeping (why it matches the plant exactly)
    ``stage_wrenches(t_ns, dt_ns)`` evaluates the wrench at t, t + dt/2 and t + dt — the
    three samples ``rk4_step`` takes — and adds each thruster's impulse with Simpson
    weights, Iᵢ += dt·(Fᵢ(t) + 4 Fᵢ(t + dt/2) + Fᵢ(t + dt))/6. RK4's velocity increment
    is the same weighted sum of the same samples (for constant attitude it is identical),
    so the booked impulse is what the body received, including pulses that start or end
    inside a step. Propellant: mᵢ = Iᵢ / (Isp,ᵢ · g0) (rocket thrust equation,
    F = ṁ Isp g0; Sutton & Biblarz, "Rocket Propulsion Elements", 9th ed., eq. 2-5),
    g0 = 9.80665 m/s² (standard gravity, CGPM 1901).
    Callers that sample the thrusters themselves (e.g. to add disturbances) can use
    ``thrusts_N`` and ``accumulate`` instead.

Assumptions
    Thrusters are independent (no manifold pressure coupling), geometry is fixed in the
    body, thrust acts along ``d_thr_B`` through ``r_thr_B_m``. Dispersion and misalignment
    (DESIGN.md §6) are expressed by the caller through the geometry and parameters given.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from bench.dynamics.rigid_body import Vec3, Wrench
from bench.valves.valve import S_PER_NS, Valve, ValveParams
from dbc.errors import ConfigError

G0_M_S2 = 9.80665
"""Standard gravity [m/s²], used to convert impulse to propellant mass through Isp."""
UNIT_NORM_TOL = 1e-6
"""Allowed |‖d_thr_B‖ − 1|."""
VEC3_LEN = 3
SIMPSON_MID_WEIGHT = 4.0
SIMPSON_DIVISOR = 6.0

ThrusterStatus = tuple[bool, bool, bool]
"""(coil_energised, open, current) of one valve, as ``Valve.status``."""


def _vec3(value: object, source: str, key: str) -> Vec3:
    expected = "3 finite numbers"
    try:
        seq = tuple(float(x) for x in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise ConfigError(source, key, value, expected) from None
    if len(seq) != VEC3_LEN or not all(math.isfinite(x) for x in seq):
        raise ConfigError(source, key, value, expected)
    return (seq[0], seq[1], seq[2])


@dataclass(frozen=True)
class ThrusterGeometry:
    """Mounting of one thruster: application point [m] and unit force direction, body axes."""

    r_thr_B_m: Vec3
    d_thr_B: Vec3
    source: str = field(default="ThrusterGeometry", compare=False, repr=False, kw_only=True)
    torque_arm_B_m: Vec3 = field(init=False, repr=False, compare=False)
    """r × d [m]: torque per newton of thrust."""

    def __post_init__(self) -> None:
        r = _vec3(self.r_thr_B_m, self.source, "r_thr_B_m")
        d = _vec3(self.d_thr_B, self.source, "d_thr_B")
        norm = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        if not abs(norm - 1.0) <= UNIT_NORM_TOL:
            raise ConfigError(
                self.source,
                "d_thr_B",
                self.d_thr_B,
                f"a unit vector (|norm - 1| <= {UNIT_NORM_TOL:g})",
            )
        object.__setattr__(self, "r_thr_B_m", r)
        object.__setattr__(self, "d_thr_B", d)
        object.__setattr__(
            self,
            "torque_arm_B_m",
            (r[1] * d[2] - r[2] * d[1], r[2] * d[0] - r[0] * d[2], r[0] * d[1] - r[1] * d[0]),
        )


class ThrusterSet:
    """N thrusters: geometry + one ``Valve`` each; wrench, status and propellant bookkeeping.

    ``params`` is one ``ValveParams`` shared by all thrusters or a sequence of one per
    thruster. ``g0_m_s2`` is the Isp reference gravity (standard gravity by default).
    """

    __slots__ = ("_impulse_Ns", "_rows", "g0_m_s2", "geometries", "valves")

    def __init__(
        self,
        geometries: Sequence[ThrusterGeometry],
        params: ValveParams | Sequence[ValveParams],
        g0_m_s2: float = G0_M_S2,
        *,
        source: str = "ThrusterSet",
    ) -> None:
        geoms = tuple(geometries)
        if not geoms or not all(isinstance(g, ThrusterGeometry) for g in geoms):
            raise ConfigError(source, "geometries", geometries, "one or more ThrusterGeometry")
        if isinstance(params, ValveParams):
            plist: tuple[ValveParams, ...] = (params,) * len(geoms)
        else:
            plist = tuple(params)
            if len(plist) != len(geoms) or not all(isinstance(p, ValveParams) for p in plist):
                raise ConfigError(
                    source,
                    "params",
                    params,
                    f"a ValveParams or {len(geoms)} of them (one per thruster)",
                )
        if isinstance(g0_m_s2, bool) or not (math.isfinite(g0_m_s2) and g0_m_s2 > 0.0):
            raise ConfigError(source, "g0_m_s2", g0_m_s2, "a finite number > 0")
        self.geometries = geoms
        self.valves = tuple(Valve(p) for p in plist)
        self.g0_m_s2 = float(g0_m_s2)
        self._impulse_Ns = [0.0] * len(geoms)
        # Hot-path rows: (index, valve, dx, dy, dz, (r×d)x, (r×d)y, (r×d)z)
        self._rows = tuple(
            (i, v, *g.d_thr_B, *g.torque_arm_B_m)
            for i, (v, g) in enumerate(zip(self.valves, geoms, strict=True))
        )

    def __len__(self) -> int:
        return len(self.valves)

    # --- commands -------------------------------------------------------------------
    def command(self, t_ns: int, index: int, on_time_ns: int) -> None:
        """Command thruster ``index`` at ``t_ns`` with ``on_time_ns`` (see ``Valve.command``)."""
        self.valves[index].command(t_ns, on_time_ns)

    def close_all(self, t_ns: int) -> None:
        """Watchdog action: de-energise every coil now."""
        for v in self.valves:
            v.command(t_ns, 0)

    def set_fault(self, index: int, kind: str | None, t_ns: int | None = None) -> None:
        """Inject or clear a fault on valve ``index`` (see ``Valve.set_fault``)."""
        self.valves[index].set_fault(kind, t_ns)

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
        """Wrenches at t, t + dt/2, t + dt for ``rk4_step``, booking the step's impulse.

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

        Equivalent to the booking of ``stage_wrenches`` for a caller that built the
        wrenches with ``wrench_B`` at t, t + dt/2, t + dt (with no command in between;
        equal up to round-off); it samples every active valve a second time, so
        ``stage_wrenches`` is cheaper.
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
        g0 = self.g0_m_s2
        return tuple(
            i / (v.params.isp_s * g0) for i, v in zip(self._impulse_Ns, self.valves, strict=True)
        )

    @property
    def total_propellant_kg(self) -> float:
        """Propellant used by all thrusters so far [kg]."""
        return math.fsum(self.propellant_kg)

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
