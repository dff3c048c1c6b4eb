"""Dual-quaternion non-singular fast terminal sliding-mode (NFTSM) 6-DoF pose control, seed 000.

What it does: one coupled law for force and torque from the pose error of body B relative
to the reference frame R (the desired frame D of the paper), eqs. (6)–(19):
- error dual quaternion ``q̂_e = q̂_d* ∘ q̂`` (eq. 6), short way (``q_e0 ≥ 0``), state
  ``ξ̂ = vec(q̂_e)`` (6,: attitude part ``vec(q_e)``, position part ``vec(q′_e) ≈ ½ p_e``);
  error twist ``ω̂_e = ω̂ − q̂_e* ∘ ω̂_d ∘ q̂_e`` (eq. 7), kinematics ``ξ̂̇ = Θ̂ ω̂_e`` (eq. 10);
- nominal dynamics (eqs. 8, 10) ``M̂0 ω̂̇_e = û_c + F̂`` with the drift
  ``F̂ = M̂0 [ω̂_e × (q̂_e* ∘ ω̂_d ∘ q̂_e) − q̂_e* ∘ ω̂̇_d ∘ q̂_e] − ω̂ × M̂0 ω̂ + m0 ĝ``;
- surface ``Ŝ = ξ̂̇ + α̂1 ⊙ ξ̂ + α̂2 ⊙ Ŝ_a`` (eq. 13) with the switching auxiliary surface
  ``S_a = sig(ξ)^p1`` if ``S̄ = 0`` or ``|ξ| ≥ δ``, else ``r1 ξ + r2 sig(ξ)²`` (eqs. 14–16),
  ``r1 = (2 − p1) δ^(p1−1)``, ``r2 = (p1 − 1) δ^(p1−2)`` (so ``S_a`` and ``W`` are continuous at
  ``|ξ| = δ``; the paper's ``r′2 = (2 − p1)…`` is a misprint), ``W = dS_a/dξ`` (eqs. 18–19);
- law (17), ``tanh(·/w)`` in place of ``sgn`` (as the paper's simulation section does):
  ``û_c = M̂0 ω̂̇* − F̂ − K̂ ⊙ tanh(Ŝ/w)`` with
  ``ω̂̇* = −Θ̂⁻¹ [Θ̂̇ ω̂_e + α̂1 ⊙ ξ̂̇ + α̂2 ⊙ W ⊙ ξ̂̇ + α̂3 ⊙ sig(Ŝ)^p2]``,
  which gives ``Ŝ̇ = −α̂3 ⊙ sig(Ŝ)^p2 − Θ̂ M̂0⁻¹ K̂ tanh(Ŝ/w)`` on the nominal model.

Dual-slot convention made explicit: ``M̂(ω + ϵ v) = m v + ϵ J ω`` maps a twist (angular,
linear) to a wrench (force, torque), so the paper's ``K̂ sgn(Ŝ)`` is applied the same way:
the attitude surface S (real part) drives the torque with gain ``K`` [N m], the position
surface S′ (dual part) drives the force with gain ``K′`` [N]. Then ``[Ŝ | Θ̂ M̂0⁻¹ K̂ ⋯]`` of
the proof (21) is positive, as the proof needs.

Frames (:class:`flight_sw.control.base.PoseController`): N is the navigation frame; with
``mean_motion_rad_s = n > 0`` it is the Hill (LVLH) frame of a leader on a circular orbit
of radius ``R = (µ/n²)^(1/3)`` (x radial, y along-track, z orbit normal, rotating at
``n ẑ`` relative to inertial), ``r_N``/``v_N`` the relative position and its derivative
taken in N, ``ω_BN`` the body rate relative to N. Inertial twists (paper's ``ω̂``, ``ω̂_d``):
``ω = ω_BN + C_BN n ẑ``, ``v = C_BN (v_N + n R ŷ + n ẑ × r_N)`` and likewise for R with
``r_ref``, ``v_ref``; ``ω̂̇_d`` assumes ``ω_RN`` constant in R and ``v_ref`` constant in N
(zero for a reference fixed in N, the formation-keeping case). The leader's orbit enters
only through ``ω̂_d`` and the point-mass gravity ``ĝ = −µ (R x̂ + r)/|R x̂ + r|³`` on the
follower (not in the paper's eq. 8, which has no gravity; without it the law would
supply the 22 N centripetal force of a 100 kg vehicle on the 42,240 km orbit): together
they make the nominal drift the exact nonlinear relative orbital dynamics, to first order
the Hill–Clohessy–Wiltshire terms. ``n = 0``: N inertial, no gravity (free space).
Gravity-gradient torque (< 1e-6 N m here) is neglected.

Anti-unwinding option (Remark 4, eqs. 25–26): the attitude part of ``ξ̂`` becomes
``e_r = g(q_e0) vec(q_e)`` of :mod:`flight_sw.control.anti_unwinding`, with its Jacobian in
the real block of ``Θ̂``. See that module for the singular angle of ``Θ_r`` (103.1° for
µ = 0.01, 99.1° for µ = 0.1): the paper's initial error (102.7°) lies next to it (µ = 0.01:
converges, after a 160 kN initial force demand; µ = 0.1: diverges), hence off by default.

Inputs/outputs: see ``PoseController``; force in body axes [N], torque about the centre
of mass in body axes [N m]. Unbounded unless ``max_force_N``/``max_torque_Nm`` are finite
(then each 3-vector is scaled down, direction preserved); the allocator owns the thruster
limits (5 N in the paper).

Assumptions: unit quaternions; the nominal model is ``mass_kg`` and ``inertia_B_kgm2``
(updated by :meth:`NftsmDq.set_inertia_B_kgm2`); ``Θ̂`` is singular at a 180° attitude
error, where its scalar part is floored at ``ETA_FLOOR`` (bounded but large output);
the branch ``S̄_i = 0`` of eqs. (14)–(19) is taken only on exact equality.

Source: seed 000, eqs. (6)–(19), (24)–(26), Section V (gains: p1 = 0.6, p2 = 0.67,
δ̂ = 0.05 + ϵ 0.001, K̂ = 20 + ϵ 20, α̂1 = α̂2 = 0.05 + ϵ 0.1, α̂3 = 2 + ϵ 2, m0 = 100 kg,
J0 = diag(18, 18, 24) kg m², leader orbit 42,240 km); Filipe & Tsiotras 2015 (JGCD
38(4) 566–577) for the dual-quaternion relative dynamics with gravity.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from mypy_extensions import mypyc_attr

from dbc.errors import ConfigError
from flight_sw import dual_quaternion as dq
from flight_sw.control import anti_unwinding as au
from flight_sw.quaternion import cross as cross3
from flight_sw.quaternion import error_quaternion, to_dcm

N_AXES = 3
# Earth's gravitational parameter [m³/s²] (EGM/WGS-84 value).
MU_EARTH_M3_S2 = 3.986004418e14
# The leader's orbit radius of seed 000, Section V [m], and its mean motion [rad/s].
PAPER_ORBIT_RADIUS_M = 42_240e3
PAPER_MEAN_MOTION_RAD_S = math.sqrt(MU_EARTH_M3_S2 / PAPER_ORBIT_RADIUS_M**3)
# Floor of the scalar part q_e0 in Θ̂ (its inverse is singular at a 180° error).
ETA_FLOOR = 1e-3
# Default width w of tanh(S/w) replacing sgn(S) (the paper gives no value).
DEFAULT_SWITCHING_WIDTH = 0.05
# Default µ of the anti-unwinding error vector (the paper gives no value); with it Θ_r is
# singular at 103.1° (0.1: 99.1°, beyond the paper's initial 102.7°, which then diverges).
DEFAULT_ANTI_UNWINDING_MU = 0.01

_SOURCE = "NftsmDqParams"


def _is_real(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def three_positive(source: str, key: str, value: object) -> tuple[float, float, float]:
    """Validate three finite numbers > 0 (a per-axis gain); ConfigError naming ``key``."""
    expected = "3 finite numbers > 0"
    if not isinstance(value, Iterable):
        raise ConfigError(source, key, value, expected)
    out: list[float] = []
    for v in value:
        if not (_is_real(v) and math.isfinite(float(v)) and float(v) > 0.0):
            raise ConfigError(source, key, value, expected)
        out.append(float(v))
    if len(out) != N_AXES:
        raise ConfigError(source, key, value, expected)
    return out[0], out[1], out[2]


def real_in(source: str, key: str, value: object, lo: float, hi: float, expected: str) -> float:
    """Validate one number in the open interval (lo, hi) (``inf`` allowed as ``hi``)."""
    if not (_is_real(value) and lo < float(value) < hi):  # type: ignore[arg-type]
        raise ConfigError(source, key, value, expected)
    return float(value)  # type: ignore[arg-type]


def validate_limit(source: str, key: str, value: object) -> float:
    """Validate an output limit: a number > 0, ``inf`` for none."""
    if not (_is_real(value) and float(value) > 0.0):  # type: ignore[arg-type]
        raise ConfigError(source, key, value, "a number > 0 (inf: no limit)")
    return float(value)  # type: ignore[arg-type]


def validate_orbit(source: str, mean_motion: object, mu: object) -> tuple[float, float]:
    """Validate the mean motion (finite, ≥ 0) [rad/s] and µ (finite, > 0) [m³/s²]."""
    if not (_is_real(mean_motion) and 0.0 <= float(mean_motion) < math.inf):  # type: ignore[arg-type]
        raise ConfigError(source, "mean_motion_rad_s", mean_motion, "a finite number >= 0")
    mu_f = real_in(source, "mu_m3_s2", mu, 0.0, math.inf, "a finite number > 0")
    return float(mean_motion), mu_f  # type: ignore[arg-type]


def validate_inertia(inertia: object) -> np.ndarray:
    """A 3×3 symmetric positive-definite inertia [kg m²] (or 3 principal moments)."""
    arr = np.asarray(inertia, dtype=float)
    if arr.shape == (N_AXES,):
        arr = np.diag(arr)
    if arr.shape != (N_AXES, N_AXES) or not np.all(np.isfinite(arr)):
        raise ValueError(f"inertia_B_kgm2 = {inertia!r}: expected a finite 3×3 matrix")
    if not np.allclose(arr, arr.T) or np.linalg.eigvalsh(arr).min() <= 0.0:
        raise ValueError(f"inertia_B_kgm2 = {inertia!r}: expected symmetric positive-definite")
    return arr


def sig(x: np.ndarray, power: float) -> np.ndarray:
    """``sig(x)^a = sgn(x) |x|^a`` element-wise."""
    return np.sign(x) * np.abs(x) ** power


def clip_norm(v: np.ndarray, limit: float) -> np.ndarray:
    """``v`` scaled down to norm ``limit`` if longer (direction preserved)."""
    norm = float(np.linalg.norm(v))
    return v * (limit / norm) if norm > limit else v


class RelativeMotion(NamedTuple):
    """The dual-quaternion error state of B relative to the desired frame D (= R).

    ``dq_e`` error dual quaternion (8,), short way; ``twist_e`` ``ω̂_e`` (6,) [rad/s; m/s];
    ``twist_B`` the inertial twist ``ω̂`` of B in B axes (6,); ``twist_d_B`` ``q̂_e* ∘ ω̂_d ∘
    q̂_e`` (6,); ``dtwist_d_B`` ``q̂_e* ∘ ω̂̇_d ∘ q̂_e`` (6,); ``gravity_B_m_s2`` the nominal
    gravitational acceleration of B in B axes (3,).
    """

    dq_e: np.ndarray
    twist_e: np.ndarray
    twist_B: np.ndarray
    twist_d_B: np.ndarray
    dtwist_d_B: np.ndarray
    gravity_B_m_s2: np.ndarray


def relative_motion(
    q_BN: np.ndarray,
    omega_BN_B: np.ndarray,
    r_N_m: np.ndarray,
    v_N_m_s: np.ndarray,
    q_RN: np.ndarray,
    omega_RN_B: np.ndarray,
    r_ref_N_m: np.ndarray,
    v_ref_N_m_s: np.ndarray,
    mean_motion_rad_s: float,
    mu_m3_s2: float,
) -> RelativeMotion:
    """The error state of eqs. (6)–(7) from the PoseController inputs (see module docstring)."""
    r = np.asarray(r_N_m, dtype=float)
    v = np.asarray(v_N_m_s, dtype=float)
    r_ref = np.asarray(r_ref_N_m, dtype=float)
    v_ref = np.asarray(v_ref_N_m_s, dtype=float)
    C_BN = to_dcm(q_BN)
    q_BR = error_quaternion(q_RN, q_BN)
    C_BR = to_dcm(q_BR)
    C_RN = to_dcm(q_RN)
    n = mean_motion_rad_s
    omega_NI_N = np.array([0.0, 0.0, n])
    if n > 0.0:
        radius = (mu_m3_s2 / (n * n)) ** (1.0 / 3.0)
        leader_pos_N = np.array([radius, 0.0, 0.0])
        leader_vel_N = np.array([0.0, n * radius, 0.0])
        pos_N = leader_pos_N + r
        gravity_N = -mu_m3_s2 * pos_N / float(np.linalg.norm(pos_N)) ** 3
    else:
        leader_pos_N = np.zeros(3)
        leader_vel_N = np.zeros(3)
        gravity_N = np.zeros(3)

    # inertial twists: B at its origin in B axes; D (= R) at its origin in R axes
    omega_B = np.asarray(omega_BN_B, dtype=float) + C_BN @ omega_NI_N
    vel_B = C_BN @ (v + leader_vel_N + cross3(omega_NI_N, r))
    twist_B = np.concatenate((omega_B, vel_B))
    omega_RN_R = C_BR.T @ np.asarray(omega_RN_B, dtype=float)
    omega_d = C_RN @ omega_NI_N + omega_RN_R
    vel_d = C_RN @ (v_ref + leader_vel_N + cross3(omega_NI_N, r_ref))
    # derivatives of the R-axes components (ω_RN constant in R, v_ref constant in N)
    domega_d = -cross3(omega_RN_R, C_RN @ omega_NI_N)
    dvel_d = -cross3(omega_RN_R, vel_d) + C_RN @ cross3(omega_NI_N, v_ref)

    dq_e = dq.short_way(dq.from_pose(q_BR, C_BN @ (r - r_ref)))
    twist_d_B = dq.transform_twist(dq_e, np.concatenate((omega_d, vel_d)))
    dtwist_d_B = dq.transform_twist(dq_e, np.concatenate((domega_d, dvel_d)))
    return RelativeMotion(
        dq_e=dq_e,
        twist_e=twist_B - twist_d_B,
        twist_B=twist_B,
        twist_d_B=twist_d_B,
        dtwist_d_B=dtwist_d_B,
        gravity_B_m_s2=C_BN @ gravity_N,
    )


def apply_mass(mass_kg: float, inertia_B_kgm2: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """``M̂ (ω + ϵ v) = m v + ϵ J ω``: twist-shaped (6,) -> wrench-shaped (6,) [force; torque]."""
    return np.concatenate((mass_kg * twist[3:], inertia_B_kgm2 @ twist[:3]))


def drift_wrench(motion: RelativeMotion, mass_kg: float, inertia_B_kgm2: np.ndarray) -> np.ndarray:
    """``F̂`` of the nominal error dynamics ``M̂0 ω̂̇_e = û_c + F̂`` (eq. 8 plus gravity), (6,)."""
    w_e, w, w_d = motion.twist_e, motion.twist_B, motion.twist_d_B
    feed = dq.cross(w_e, w_d) - motion.dtwist_d_B
    gyro = dq.cross(w, apply_mass(mass_kg, inertia_B_kgm2, w))
    gravity = np.concatenate((mass_kg * motion.gravity_B_m_s2, np.zeros(3)))
    return apply_mass(mass_kg, inertia_B_kgm2, feed) - gyro + gravity


def attitude_state(
    motion: RelativeMotion, anti_unwinding: bool, mu: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``ξ̂`` (6,), ``Θ̂`` (6×6) and ``Θ̂̇`` (6×6) of eq. (10); attitude part per eq. (26) if asked."""
    dq_e = motion.dq_e.copy()
    dq_e[0] = max(dq_e[0], ETA_FLOOR)
    xi = dq.vector_part(dq_e)
    theta = dq.kinematics_matrix(dq_e)
    theta_dot = dq.kinematics_matrix_rate(dq_e, motion.twist_e)
    if anti_unwinding:
        q_e = motion.dq_e[:4]
        xi[:3] = au.error_vector(q_e, mu)
        theta[:3, :3] = au.jacobian(q_e, mu)
        theta_dot[:3, :3] = au.jacobian_rate(q_e, motion.twist_e[:3], mu)
    return xi, theta, theta_dot


def robust_wrench(k_att: np.ndarray, k_pos: np.ndarray, s: np.ndarray, width: float) -> np.ndarray:
    """``K̂ ⊙ tanh(Ŝ/w)`` in wrench slots: position surface -> force, attitude -> torque."""
    t = np.tanh(s / width)
    return np.concatenate((k_pos * t[3:], k_att * t[:3]))


def auxiliary_surface(
    xi: np.ndarray,
    xi_dot: np.ndarray,
    alpha1: np.ndarray,
    alpha2: np.ndarray,
    p1: float,
    delta: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``(S_a, W ⊙ ξ̇)`` of eqs. (14)–(16), (18)–(19), element-wise over the 6 components.

    On the exact-zero branch with ``ξ_i = 0`` the product ``W_i ξ̇_i`` is 0 (there
    ``S̄_i = 0`` forces ``ξ̇_i = 0``; its limit is ``p1 α2 sig(ξ)^(2p1−1)`` → 0, Remark 2).
    """
    s_a: list[float] = []
    w_xi_dot: list[float] = []
    # per component, on floats (6 of them: cheaper than a dozen array operations)
    n = np.shape(xi)[0]
    for x, xd, a1, a2, d in zip(*(_floats(v, n) for v in (xi, xi_dot, alpha1, alpha2, delta)),
                                strict=True):
        ax = abs(x)
        sig_p = _sig1(x, ax, p1)
        s_bar = xd + a1 * x + a2 * sig_p
        r1 = (2.0 - p1) * d ** (p1 - 1.0)
        r2 = (p1 - 1.0) * d ** (p1 - 2.0)
        if s_bar == 0.0 or ax >= d:  # the power branch
            s_a.append(sig_p)
            w_xi_dot.append(p1 * ax ** (p1 - 1.0) * xd if ax > 0.0 else 0.0)
        else:  # the polynomial branch near ξ = 0
            s_a.append(r1 * x + r2 * _sig1(x, ax, 2.0))
            w_xi_dot.append((r1 + 2.0 * r2 * ax) * xd)
    return np.array(s_a), np.array(w_xi_dot)


def _floats(v: np.ndarray | float, n: int) -> list[float]:
    """``v`` (an (n,) array, or a scalar broadcast to n) as a list of n floats."""
    arr = np.asarray(v, dtype=float)
    return (arr if arr.shape == (n,) else np.broadcast_to(arr, (n,))).tolist()


def _sig1(x: float, abs_x: float, power: float) -> float:
    """``sig(x)^a`` of one float (as :func:`sig`: 0 at 0)."""
    if x > 0.0:
        return abs_x**power
    if x < 0.0:
        return -(abs_x**power)
    return 0.0 * x


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class NftsmDqParams:
    """Gains and nominal model of the NFTSM law; defaults are seed 000, Section V.

    Attributes (``_att``: real part, attitude, 3 body axes; ``_pos``: dual part, position):
        mass_kg: nominal mass m0 [kg] (> 0).
        inertia_B_kgm2: nominal principal moments J0 [kg m²] (3 numbers > 0).
        alpha1_att, alpha1_pos: α̂1 of eq. (13) [1/s].
        alpha2_att, alpha2_pos: α̂2 of eq. (13) [1/s].
        alpha3_att, alpha3_pos: α̂3 of eq. (17) (reaching gain).
        k_att_Nm: K, torque gain of the attitude surface [N m]; k_pos_N: K′ [N].
        p1: exponent of the auxiliary surface, in (0.5, 1); p2: reaching exponent, (0, 1).
        delta_att, delta_pos: δ, δ′ switching thresholds of eqs. (14)–(15) (> 0).
        switching_width: w of tanh(S/w) replacing sgn(S) (> 0).
        mean_motion_rad_s: n of the leader's circular orbit (0: N inertial, no gravity).
        mu_m3_s2: gravitational parameter [m³/s²].
        anti_unwinding: use e_r of eq. (26) as the attitude state.
        anti_unwinding_mu: µ of eqs. (25)–(26) (> 0).
        max_force_N, max_torque_Nm: optional output norm limits (inf: unbounded).
    """

    mass_kg: float = 100.0
    inertia_B_kgm2: tuple[float, float, float] = (18.0, 18.0, 24.0)
    alpha1_att: tuple[float, float, float] = (0.05, 0.05, 0.05)
    alpha1_pos: tuple[float, float, float] = (0.1, 0.1, 0.1)
    alpha2_att: tuple[float, float, float] = (0.05, 0.05, 0.05)
    alpha2_pos: tuple[float, float, float] = (0.1, 0.1, 0.1)
    alpha3_att: tuple[float, float, float] = (2.0, 2.0, 2.0)
    alpha3_pos: tuple[float, float, float] = (2.0, 2.0, 2.0)
    k_att_Nm: tuple[float, float, float] = (20.0, 20.0, 20.0)
    k_pos_N: tuple[float, float, float] = (20.0, 20.0, 20.0)
    p1: float = 0.6
    p2: float = 0.67
    delta_att: float = 0.05
    delta_pos: float = 0.001
    switching_width: float = DEFAULT_SWITCHING_WIDTH
    mean_motion_rad_s: float = 0.0
    mu_m3_s2: float = MU_EARTH_M3_S2
    anti_unwinding: bool = False
    anti_unwinding_mu: float = DEFAULT_ANTI_UNWINDING_MU
    max_force_N: float = math.inf
    max_torque_Nm: float = math.inf

    def __post_init__(self) -> None:
        s = _SOURCE
        real_in(s, "mass_kg", self.mass_kg, 0.0, math.inf, "a finite number > 0")
        object.__setattr__(
            self, "inertia_B_kgm2", three_positive(s, "inertia_B_kgm2", self.inertia_B_kgm2)
        )
        for key in (
            "alpha1_att",
            "alpha1_pos",
            "alpha2_att",
            "alpha2_pos",
            "alpha3_att",
            "alpha3_pos",
            "k_att_Nm",
            "k_pos_N",
        ):
            object.__setattr__(self, key, three_positive(s, key, getattr(self, key)))
        real_in(s, "p1", self.p1, 0.5, 1.0, "a number in (0.5, 1)")
        real_in(s, "p2", self.p2, 0.0, 1.0, "a number in (0, 1)")
        for key in ("delta_att", "delta_pos", "switching_width", "anti_unwinding_mu"):
            real_in(s, key, getattr(self, key), 0.0, math.inf, "a finite number > 0")
        validate_orbit(s, self.mean_motion_rad_s, self.mu_m3_s2)
        if not isinstance(self.anti_unwinding, bool):
            raise ConfigError(s, "anti_unwinding", self.anti_unwinding, "true or false")
        validate_limit(s, "max_force_N", self.max_force_N)
        validate_limit(s, "max_torque_Nm", self.max_torque_Nm)


def _dual_gain(att: tuple[float, float, float], pos: tuple[float, float, float]) -> np.ndarray:
    return np.array(att + pos, dtype=float)


class NftsmDq:
    """Dual-quaternion NFTSM pose controller (implements ``PoseController``, ``InertiaAware``).

    Stateless apart from the nominal inertia, which :meth:`set_inertia_B_kgm2` replaces.
    """

    def __init__(self, params: NftsmDqParams) -> None:
        self._params = params
        self._inertia = validate_inertia(params.inertia_B_kgm2)
        p = params
        self._alpha1 = _dual_gain(p.alpha1_att, p.alpha1_pos)
        self._alpha2 = _dual_gain(p.alpha2_att, p.alpha2_pos)
        self._alpha3 = _dual_gain(p.alpha3_att, p.alpha3_pos)
        self._k_att = np.array(p.k_att_Nm, dtype=float)
        self._k_pos = np.array(p.k_pos_N, dtype=float)
        self._delta = np.array([p.delta_att] * N_AXES + [p.delta_pos] * N_AXES)

    @property
    def params(self) -> NftsmDqParams:
        """The gains this controller was built with."""
        return self._params

    @property
    def inertia_B_kgm2(self) -> np.ndarray:
        """The nominal inertia in use (3×3) [kg m²]."""
        return self._inertia.copy()

    def set_inertia_B_kgm2(self, inertia_B_kgm2: np.ndarray) -> None:
        """Use ``inertia_B_kgm2`` (3×3 SPD, or 3 principal moments) [kg m²] from now on."""
        self._inertia = validate_inertia(inertia_B_kgm2)

    def surface(self, xi: np.ndarray, xi_dot: np.ndarray) -> np.ndarray:
        """``Ŝ = ξ̂̇ + α̂1 ⊙ ξ̂ + α̂2 ⊙ Ŝ_a`` (eq. 13), (6,)."""
        s_a, _ = auxiliary_surface(
            xi, xi_dot, self._alpha1, self._alpha2, self._params.p1, self._delta
        )
        return np.asarray(xi_dot + self._alpha1 * xi + self._alpha2 * s_a)

    def wrench_B(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        r_N_m: np.ndarray,
        v_N_m_s: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
        r_ref_N_m: np.ndarray,
        v_ref_N_m_s: np.ndarray,
    ) -> np.ndarray:
        """Law (17): the demanded wrench [force_B_N; torque_B_Nm], shape (6,)."""
        p = self._params
        motion = relative_motion(
            q_BN,
            omega_BN_B,
            r_N_m,
            v_N_m_s,
            q_RN,
            omega_RN_B,
            r_ref_N_m,
            v_ref_N_m_s,
            p.mean_motion_rad_s,
            p.mu_m3_s2,
        )
        xi, theta, theta_dot = attitude_state(motion, p.anti_unwinding, p.anti_unwinding_mu)
        nu = motion.twist_e
        xi_dot = theta @ nu
        s_a, w_xi_dot = auxiliary_surface(xi, xi_dot, self._alpha1, self._alpha2, p.p1, self._delta)
        s = xi_dot + self._alpha1 * xi + self._alpha2 * s_a
        bracket = (
            theta_dot @ nu
            + self._alpha1 * xi_dot
            + self._alpha2 * w_xi_dot
            + self._alpha3 * sig(s, p.p2)
        )
        accel = -np.linalg.solve(theta, bracket)
        wrench = (
            apply_mass(p.mass_kg, self._inertia, accel)
            - drift_wrench(motion, p.mass_kg, self._inertia)
            - robust_wrench(self._k_att, self._k_pos, s, p.switching_width)
        )
        return np.concatenate(
            (clip_norm(wrench[:3], p.max_force_N), clip_norm(wrench[3:], p.max_torque_Nm))
        )
