"""Gravity-gradient torque of a rigid body on a circular orbit.

What it does
    τ_B = 3 μ/R³ · r̂_B × (J r̂_B) = 3n² r̂_B × (J r̂_B)   [N·m, body axes]

    with r̂_B the unit radial direction (from the central body to the vehicle, i.e.
    nadir-opposite) in body axes and J the inertia about the centre of mass (seed 001
    §2, T_g = 3ω0² A3(σ) × J A3(σ), A3 the third column of the attitude matrix in its
    orbit-frame convention; Wertz 1978 §17.2.1; Hughes, "Spacecraft Attitude Dynamics",
    §8.2). It is zero when a principal axis lies along r̂.

Orbit and frames
    The orbit is circular, radius R, in the x_I–y_I plane of the inertial frame I; the
    radial direction rotates about z_I at the mean motion n = sqrt(μ/R³) and is x_I at
    t = 0: r̂_I(t) = (cos nt, sin nt, 0) — the x axis of the Hill frame of
    ``bench.station.dynamics.hcw``. r̂_B = C(q_BN) r̂_I. The vehicle's offset from the reference
    orbit (HCW relative position, metres against 42,000 km) is neglected.

Inputs: t_s [s], q_BN (scalar first), J from ``MassProperties`` [kg·m²].
Output: (0, 0, 0, τx, τy, τz) — no force (the orbit's central force is in the
translation model, not here).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from mypy_extensions import mypyc_attr

from bench.station.dynamics.hcw import MU_EARTH_M3_S2, SEED000_ORBIT_RADIUS_M, mean_motion_rad_s
from bench.station.dynamics.rigid_body import MassProperties, Quat, Vec3, Wrench, rotate_N_to_B
from dbc import validation as check

GG_FACTOR = 3.0
"""The 3 of 3μ/R³."""


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class GravityGradientParams:
    """Circular reference orbit: radius [m] and gravitational parameter [m³/s²]."""

    orbit_radius_m: float = SEED000_ORBIT_RADIUS_M
    mu_m3_s2: float = MU_EARTH_M3_S2
    source: str = field(default="GravityGradientParams", compare=False, repr=False, kw_only=True)

    def __post_init__(self) -> None:
        for key in ("orbit_radius_m", "mu_m3_s2"):
            object.__setattr__(self, key, check.positive(self.source, key, getattr(self, key)))


def radial_unit_I(n_rad_s: float, t_s: float) -> Vec3:
    """r̂_I(t) = (cos nt, sin nt, 0) (module docstring)."""
    return (math.cos(n_rad_s * t_s), math.sin(n_rad_s * t_s), 0.0)


def gravity_gradient_torque_B(n_rad_s: float, r_hat_B: Vec3, mp: MassProperties) -> Vec3:
    """3n² r̂_B × (J r̂_B) [N·m] for a unit radial vector in body axes (pure)."""
    j = mp.inertia_flat_B_kgm2
    x, y, z = r_hat_B
    jx = j[0] * x + j[1] * y + j[2] * z
    jy = j[3] * x + j[4] * y + j[5] * z
    jz = j[6] * x + j[7] * y + j[8] * z
    k = GG_FACTOR * n_rad_s * n_rad_s
    return (k * (y * jz - z * jy), k * (z * jx - x * jz), k * (x * jy - y * jx))


class GravityGradient:
    """``EnvironmentModel`` of the gravity-gradient torque (module docstring)."""

    def __init__(self, params: GravityGradientParams) -> None:
        self.params = params
        self.n_rad_s = mean_motion_rad_s(params.orbit_radius_m, params.mu_m3_s2)

    def wrench_B(self, t_s: float, q_BN: Quat, mp: MassProperties) -> Wrench:
        """(0, 0, 0, τ_B) at ``t_s`` [N, N·m]."""
        r_B = rotate_N_to_B(q_BN, radial_unit_I(self.n_rad_s, t_s))
        tx, ty, tz = gravity_gradient_torque_B(self.n_rad_s, r_B, mp)
        return (0.0, 0.0, 0.0, tx, ty, tz)
