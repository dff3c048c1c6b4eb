"""Hill–Clohessy–Wiltshire relative translation about a circular orbit.

What it does
    Propagates the vehicle's position and velocity *relative to a leader* on a circular
    orbit of radius R, in the leader's Hill frame H (x radial, outwards; y along-track;
    z orbit normal), linearised for |r| ≪ R:

        ẍ = 3n²x + 2nẏ + f_x/m
        ÿ = −2nẋ + f_y/m                  n = sqrt(μ / R³)  (mean motion)
        z̈ = −n²z + f_z/m

    (Clohessy & Wiltshire 1960, J. Aerospace Sci. 27(9), eqs. 3; Vallado, "Fundamentals
    of Astrodynamics and Applications", 4th ed., §6.8, eqs. 6-62 and the closed form
    6-66, implemented in ``hcw_closed_form``). Used for seed 000's formation flight
    (leader on a circular orbit of 42,240 km, §V).

Frames
    The attitude state stays relative to the inertial frame I. The Hill frame rotates
    about z_I at n and is aligned with I at t = 0, so C_HI(t) = Rz(n t)ᵀ:
    v_H = (cos nt·v_x + sin nt·v_y, −sin nt·v_x + cos nt·v_y, v_z), and a body force
    enters the equations above as f_H = C_HI(t) C_IB F_B. The flight software may treat
    the navigation frame as inertial for attitude: the Hill frame turns at
    n ≈ 7.3e-5 rad/s (≈ 0.0042 °/s) at R = 42,240 km, i.e. 0.25° in a minute.

Inputs/outputs: t_s [s], r [m], v [m/s], accelerations [m/s²], R [m], μ [m³/s²].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from mypy_extensions import mypyc_attr

from bench.station.dynamics.rigid_body import Vec3
from dbc import validation as check

MU_EARTH_M3_S2 = 3.986004418e14
"""Earth's gravitational parameter GM [m³/s²] (IERS Conventions 2010, Table 1.1)."""
SEED000_ORBIT_RADIUS_M = 42_240_000.0
"""Seed 000 §V: the leader's circular orbit radius, 42,240 km [m]."""
HCW_SECULAR_FACTOR = 3.0
HCW_RADIAL_FACTOR = 4.0
HCW_ALONG_FACTOR = 6.0


def mean_motion_rad_s(orbit_radius_m: float, mu_m3_s2: float = MU_EARTH_M3_S2) -> float:
    """Mean motion n = sqrt(μ / R³) of a circular orbit [rad/s]."""
    return math.sqrt(mu_m3_s2 / orbit_radius_m**3)


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class HcwParams:
    """Circular orbit of the leader: radius [m] and gravitational parameter [m³/s²]."""

    orbit_radius_m: float = SEED000_ORBIT_RADIUS_M
    mu_m3_s2: float = MU_EARTH_M3_S2
    source: str = field(default="HcwParams", compare=False, repr=False, kw_only=True)
    mean_motion_rad_s: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for key in ("orbit_radius_m", "mu_m3_s2"):
            object.__setattr__(self, key, check.positive(self.source, key, getattr(self, key)))
        object.__setattr__(
            self, "mean_motion_rad_s", mean_motion_rad_s(self.orbit_radius_m, self.mu_m3_s2)
        )


def hill_to_inertial(n_rad_s: float, t_s: float, v_H: Vec3) -> Vec3:
    """v_I = C_HI(t)ᵀ v_H: the Hill frame turned by n·t about z_I (aligned at t = 0)."""
    c, s = math.cos(n_rad_s * t_s), math.sin(n_rad_s * t_s)
    return (c * v_H[0] - s * v_H[1], s * v_H[0] + c * v_H[1], v_H[2])


def inertial_to_hill(n_rad_s: float, t_s: float, v_I: Vec3) -> Vec3:
    """v_H = C_HI(t) v_I (inverse of ``hill_to_inertial``)."""
    c, s = math.cos(n_rad_s * t_s), math.sin(n_rad_s * t_s)
    return (c * v_I[0] + s * v_I[1], -s * v_I[0] + c * v_I[1], v_I[2])


def hcw_acceleration(n_rad_s: float, r_H_m: Vec3, v_H_m_s: Vec3, f_H_m_s2: Vec3) -> Vec3:
    """Relative acceleration in H [m/s²] (module docstring), f = force / mass in H."""
    n2 = n_rad_s * n_rad_s
    return (
        HCW_SECULAR_FACTOR * n2 * r_H_m[0] + 2.0 * n_rad_s * v_H_m_s[1] + f_H_m_s2[0],
        -2.0 * n_rad_s * v_H_m_s[0] + f_H_m_s2[1],
        -n2 * r_H_m[2] + f_H_m_s2[2],
    )


def hcw_closed_form(
    n_rad_s: float, r0_H_m: Vec3, v0_H_m_s: Vec3, t_s: float
) -> tuple[Vec3, Vec3]:
    """Free (unforced) HCW motion: (r_H(t) [m], v_H(t) [m/s]) from r0, v0 (Vallado 6-66)."""
    x0, y0, z0 = r0_H_m
    dx0, dy0, dz0 = v0_H_m_s
    n = n_rad_s
    nt = n * t_s
    c, s = math.cos(nt), math.sin(nt)
    k3, k4, k6 = HCW_SECULAR_FACTOR, HCW_RADIAL_FACTOR, HCW_ALONG_FACTOR
    r = (
        (k4 - k3 * c) * x0 + s / n * dx0 + 2.0 / n * (1.0 - c) * dy0,
        k6 * (s - nt) * x0 + y0 - 2.0 / n * (1.0 - c) * dx0 + (k4 * s - k3 * nt) / n * dy0,
        c * z0 + s / n * dz0,
    )
    v = (
        k3 * n * s * x0 + c * dx0 + 2.0 * s * dy0,
        -k6 * n * (1.0 - c) * x0 - 2.0 * s * dx0 + (k4 * c - k3) * dy0,
        -n * s * z0 + c * dz0,
    )
    return r, v


class HcwTranslation:
    """``TranslationModel`` of relative motion in the leader's Hill frame (module docstring)."""

    def __init__(self, params: HcwParams) -> None:
        self.params = params
        self.n_rad_s = params.mean_motion_rad_s

    def acceleration(self, t_s: float, r_m: Vec3, v_m_s: Vec3, a_force_I_m_s2: Vec3) -> Vec3:
        """HCW relative acceleration in H, the wrench's acceleration rotated into H."""
        f_H = inertial_to_hill(self.n_rad_s, t_s, a_force_I_m_s2)
        return hcw_acceleration(self.n_rad_s, r_m, v_m_s, f_H)

    def inertial_to_nav(self, t_s: float, v_I: Vec3) -> Vec3:
        """v_H = C_HI(t) v_I."""
        return inertial_to_hill(self.n_rad_s, t_s, v_I)

    def nav_to_inertial(self, t_s: float, v_nav: Vec3) -> Vec3:
        """v_I = C_HI(t)ᵀ v_H."""
        return hill_to_inertial(self.n_rad_s, t_s, v_nav)
