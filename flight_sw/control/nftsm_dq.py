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

Implementation: :meth:`NftsmDq.wrench_B` evaluates the law on floats (a few µs compiled):
the surface-independent parts (error state, kinematics, drift, wrench assembly) are
:mod:`flight_sw.control.dq_error_state`'s, shared with the TSM baseline; this module adds
the NFTSM surface (eqs. 13–16, 18–19) and the bracket of law (17). The parameters are
:class:`flight_sw.control.nftsm_dq_params.NftsmDqParams`. The tests hold the law to the
paper's terms composed as arrays (``tests/flight_sw/control/dq_reference.py``).

Source: seed 000, eqs. (6)–(19), (24)–(26), Section V (gains: p1 = 0.6, p2 = 0.67,
δ̂ = 0.05 + ϵ 0.001, K̂ = 20 + ϵ 20, α̂1 = α̂2 = 0.05 + ϵ 0.1, α̂3 = 2 + ϵ 2, m0 = 100 kg,
J0 = diag(18, 18, 24) kg m², leader orbit 42,240 km); Filipe & Tsiotras 2015 (JGCD
38(4) 566–577) for the dual-quaternion relative dynamics with gravity.
"""

from __future__ import annotations

import numpy as np

from flight_sw import vec3
from flight_sw.control import dq_error_state as es
from flight_sw.control.dq_error_state import (
    ETA_FLOOR,
    MU_EARTH_M3_S2,
    PAPER_MEAN_MOTION_RAD_S,
    PAPER_ORBIT_RADIUS_M,
)
from flight_sw.control.nftsm_dq_params import (
    DEFAULT_ANTI_UNWINDING_MU,
    DEFAULT_SWITCHING_WIDTH,
    N_AXES,
    NftsmDqParams,
    validate_inertia,
)

__all__ = [
    "DEFAULT_ANTI_UNWINDING_MU",
    "DEFAULT_SWITCHING_WIDTH",
    "ETA_FLOOR",
    "MU_EARTH_M3_S2",
    "PAPER_MEAN_MOTION_RAD_S",
    "PAPER_ORBIT_RADIUS_M",
    "NftsmDq",
    "NftsmDqParams",
    "auxiliary_surface",
    "auxiliary_surface_f",
    "sig_vec",
]


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
    n = np.shape(xi)[0]
    s_a, w_xi_dot = auxiliary_surface_f(_floats(xi, n), _floats(xi_dot, n), _floats(alpha1, n),
                                        _floats(alpha2, n), p1, _floats(delta, n))
    return np.array(s_a), np.array(w_xi_dot)


def auxiliary_surface_f(
    xi: list[float],
    xi_dot: list[float],
    alpha1: list[float],
    alpha2: list[float],
    p1: float,
    delta: list[float],
) -> tuple[list[float], list[float]]:
    """:func:`auxiliary_surface` on lists of floats (one entry per component)."""
    s_a: list[float] = []
    w_xi_dot: list[float] = []
    for x, xd, a1, a2, d in zip(xi, xi_dot, alpha1, alpha2, delta, strict=True):
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
    return s_a, w_xi_dot


def _floats(v: np.ndarray | float, n: int) -> list[float]:
    """``v`` (an (n,) array, or a scalar broadcast to n) as a list of n floats."""
    arr = np.asarray(v, dtype=float)
    return (arr if arr.shape == (n,) else np.broadcast_to(arr, (n,))).tolist()


def _sig1(x: float, abs_x: float, power: float) -> float:
    """``sig(x)^a = sgn(x) |x|^a`` of one float (0 at 0); ``abs_x = |x|``."""
    if x > 0.0:
        return abs_x**power
    if x < 0.0:
        return -(abs_x**power)
    return 0.0 * x


def sig_vec(v: list[float], power: float) -> list[float]:
    """``sig(v)^a`` element-wise on floats (0 at 0)."""
    return [_sig1(x, abs(x), power) for x in v]


def _dual_gain(att: tuple[float, float, float], pos: tuple[float, float, float]) -> list[float]:
    return [float(x) for x in att + pos]


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
        self._k_att = [float(x) for x in p.k_att_Nm]
        self._k_pos = [float(x) for x in p.k_pos_N]
        self._delta = [float(p.delta_att)] * N_AXES + [float(p.delta_pos)] * N_AXES
        self._inertia_f = vec3.mat3(self._inertia)

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
        self._inertia_f = vec3.mat3(self._inertia)

    def _surface(self, xi: list[float], xi_dot: list[float]) -> tuple[list[float], list[float]]:
        """``Ŝ = ξ̂̇ + α̂1 ⊙ ξ̂ + α̂2 ⊙ Ŝ_a`` (eq. 13) and ``W ⊙ ξ̂̇`` (eqs. 18–19)."""
        a1 = self._alpha1
        a2 = self._alpha2
        s_a, w_xd = auxiliary_surface_f(xi, xi_dot, a1, a2, self._params.p1, self._delta)
        return [xi_dot[i] + a1[i] * xi[i] + a2[i] * s_a[i] for i in range(6)], w_xd

    def surface(self, xi: np.ndarray, xi_dot: np.ndarray) -> np.ndarray:
        """``Ŝ = ξ̂̇ + α̂1 ⊙ ξ̂ + α̂2 ⊙ Ŝ_a`` (eq. 13), (6,)."""
        s, _ = self._surface(np.asarray(xi, dtype=float).tolist(),
                             np.asarray(xi_dot, dtype=float).tolist())
        return np.array(s)

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
        """Law (17): the demanded wrench [force_B_N; torque_B_Nm], shape (6,).

        ``ω̂̇* = −Θ̂⁻¹ [Θ̂̇ ω̂_e + α̂1 ⊙ ξ̂̇ + α̂2 ⊙ W ⊙ ξ̂̇ + α̂3 ⊙ sig(Ŝ)^p2]``, then
        ``û_c = M̂0 ω̂̇* − F̂ − K̂ ⊙ tanh(Ŝ/w)`` (module docstring).
        """
        p = self._params
        st = es.error_state(q_BN, omega_BN_B, r_N_m, v_N_m_s, q_RN, omega_RN_B, r_ref_N_m,
                            v_ref_N_m_s, p.mean_motion_rad_s, p.mu_m3_s2, p.anti_unwinding,
                            p.anti_unwinding_mu)
        xi_dot = st.xi_dot
        a1 = self._alpha1
        a2 = self._alpha2
        a3 = self._alpha3
        s_sl, w_xd = self._surface(st.xi, xi_dot)
        sp = sig_vec(s_sl, p.p2)
        tdot_nu = es.theta_dot_nu(st)
        br = [tdot_nu[i] + a1[i] * xi_dot[i] + a2[i] * w_xd[i] + a3[i] * sp[i]
              for i in range(6)]
        acc_w, acc_v = es.acceleration(st, br)
        return es.wrench(st, p.mass_kg, self._inertia_f, acc_w, acc_v, s_sl, self._k_att,
                         self._k_pos, p.switching_width, p.max_force_N, p.max_torque_Nm)
