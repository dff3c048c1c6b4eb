"""Dual-quaternion pose error, its kinematics and the nominal error dynamics, on floats.

What it does: the parts of seed 000's 6-DoF sliding-mode laws that do not depend on the
sliding surface, shared by the NFTSM law (:mod:`flight_sw.control.nftsm_dq`) and the TSM
baseline (:mod:`flight_sw.control.tsm_dq`), written out on Python floats (compiled with
mypyc; the one implementation, tested against the paper's array composition in
``tests/flight_sw/control/dq_reference.py``):

- :func:`error_state`: the error dual quaternion ``q̂_e = q̂_d* ∘ q̂`` (eq. 6), short way
  (``q_e0 ≥ 0``); the error twist ``ω̂_e = ω̂ − q̂_e* ∘ ω̂_d ∘ q̂_e`` (eq. 7); the state
  ``ξ̂ = vec(q̂_e)`` and its rate ``ξ̂̇ = Θ̂ ω̂_e`` with ``Θ̂ = [[Θ, 0], [Θ′, Θ]]`` and ``Θ̂̇``
  (eq. 10; ``q_e0`` floored at :data:`ETA_FLOOR` in ``Θ̂``), or with the attitude part
  replaced by the anti-unwinding ``e_r`` and ``Θ_r`` (eqs. 25–26,
  :func:`flight_sw.control.anti_unwinding.error_state`);
- :func:`theta_dot_nu`: ``Θ̂̇ ω̂_e``;
- :func:`acceleration`: ``ω̂̇* = −Θ̂⁻¹ b`` for a law's bracket ``b`` (Θ̂ block lower
  triangular: two 3×3 solves);
- :func:`wrench`: law (17)'s ``û_c = M̂0 ω̂̇* − F̂ − K̂ ⊙ tanh(Ŝ/w)`` with the drift
  ``F̂ = M̂0 [ω̂_e × (q̂_e* ∘ ω̂_d ∘ q̂_e) − q̂_e* ∘ ω̂̇_d ∘ q̂_e] − ω̂ × M̂0 ω̂ + m0 ĝ`` (eq. 8
  plus gravity), in wrench slots (force [N]; torque [N m]), each 3-vector clipped to its
  norm limit.

Frames (:class:`flight_sw.control.base.PoseController`): N is the navigation frame; with
mean motion ``n > 0`` it is the Hill frame of a leader on a circular orbit of radius
``R = (µ/n²)^(1/3)`` (x radial, y along-track, z orbit normal). Inertial twists:
``ω = ω_BN + C_BN n ẑ``, ``v = C_BN (v_N + n R ŷ + n ẑ × r_N)``, likewise for R with
``r_ref``, ``v_ref``; ``ω̂̇_d`` assumes ``ω_RN`` constant in R and ``v_ref`` constant in N.
Gravity ``ĝ = −µ (R x̂ + r)/|R x̂ + r|³`` (point mass); ``n = 0``: N inertial, no gravity.
Dual-slot convention: ``M̂(ω + ϵ v) = m v + ϵ J ω``; the attitude surface drives the torque
with gain ``K`` [N m], the position surface the force with ``K′`` [N].

Inputs: poses (unit quaternions, positions [m]), rates [rad/s], velocities [m/s],
nominal mass [kg] and inertia [kg m²] (row-major). Outputs: floats, the wrench as a
(6,) array [force_B_N; torque_B_Nm].

Assumptions: unit quaternions; the nominal model (mass, inertia); ``Θ̂`` singular at a
180° attitude error, where its scalar part is floored.

Source: seed 000, eqs. (6)–(10), (17), (25)–(26), Section V (orbit 42,240 km); Filipe &
Tsiotras 2015 (JGCD 38(4) 566–577) for the dual-quaternion relative dynamics with gravity.
"""

from __future__ import annotations

import math

import numpy as np

from flight_sw import dual_quaternion as dq
from flight_sw import vec3
from flight_sw.control import anti_unwinding as au
from flight_sw.quaternion import dcm
from flight_sw.vec3 import Mat3, Vec3, cross, mat_t_vec, mat_vec, solve3

HALF = 0.5
# Earth's gravitational parameter [m³/s²] (EGM/WGS-84 value).
MU_EARTH_M3_S2 = 3.986004418e14
# The leader's orbit radius of seed 000, Section V [m], and its mean motion [rad/s].
PAPER_ORBIT_RADIUS_M = 42_240e3
PAPER_MEAN_MOTION_RAD_S = math.sqrt(MU_EARTH_M3_S2 / PAPER_ORBIT_RADIUS_M**3)
# Floor of the scalar part q_e0 in Θ̂ (its inverse is singular at a 180° error).
ETA_FLOOR = 1e-3


class ErrorState:
    """The error state of eqs. (6)–(10) at one instant (floats; see the module docstring).

    Attributes: ``c_bn`` C_BN; ``e`` q̂_e (8); ``nu`` ω̂_e (6: angular, linear); ``om_b``,
    ``vel_b`` B's inertial twist in B axes; ``wd``, ``vd`` and ``dwd``, ``dvd`` the desired
    twist and its rate moved to B (``q̂_e* ∘ · ∘ q̂_e``); ``grav`` the gravitational
    acceleration in N [m/s²]; ``xi``, ``xi_dot`` ξ̂ and ξ̂̇ (6); ``th_r``, ``th``, ``thd``
    the blocks of Θ̂ (``th_r`` the attitude block, Θ or Θ_r) and ``th_r_dot``, ``th_dot``,
    ``thd_dot`` those of Θ̂̇.
    """

    def __init__(self, c_bn: Mat3, e: tuple[float, ...], nu: list[float], om_b: Vec3,
                 vel_b: Vec3, wd: Vec3, vd: Vec3, dwd: Vec3, dvd: Vec3, grav: Vec3) -> None:
        self.c_bn = c_bn
        self.e = e
        self.nu = nu
        self.om_b = om_b
        self.vel_b = vel_b
        self.wd = wd
        self.vd = vd
        self.dwd = dwd
        self.dvd = dvd
        self.grav = grav
        zero: Mat3 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        self.xi: list[float] = []
        self.xi_dot: list[float] = []
        self.th_r = zero
        self.th = zero
        self.thd = zero
        self.th_r_dot = zero
        self.th_dot = zero
        self.thd_dot = zero


def _relative_motion(q_BN: tuple[float, ...], w_bn: Vec3, r: Vec3, v: Vec3,
                     q_RN: tuple[float, ...], w_rn: Vec3, r_ref: Vec3, v_ref: Vec3,
                     n: float, mu: float) -> ErrorState:
    """Eqs. (6)–(7): the error dual quaternion and twists (module docstring)."""
    b0, b1, b2, b3 = q_BN[0], q_BN[1], q_BN[2], q_BN[3]
    n0, n1, n2, n3 = q_RN[0], q_RN[1], q_RN[2], q_RN[3]
    c_bn = dcm(b0, b1, b2, b3)
    qe = dq._mul(n0, -n1, -n2, -n3, 0.0, 0.0, 0.0, 0.0, b0, b1, b2, b3, 0.0, 0.0, 0.0, 0.0)
    c_br = dcm(qe[0], qe[1], qe[2], qe[3])
    c_rn = dcm(n0, n1, n2, n3)
    w_ni: Vec3 = (0.0, 0.0, n)
    lead_v: Vec3 = (0.0, 0.0, 0.0)
    grav: Vec3 = (0.0, 0.0, 0.0)
    if n > 0.0:
        radius = (mu / (n * n)) ** (1.0 / 3.0)
        lead_v = (0.0, n * radius, 0.0)
        px, py, pz = radius + r[0], r[1], r[2]
        k = -mu / math.sqrt(px * px + py * py + pz * pz) ** 3
        grav = (k * px, k * py, k * pz)
    w_ni_b = mat_vec(c_bn, w_ni[0], w_ni[1], w_ni[2])
    om_b: Vec3 = (w_bn[0] + w_ni_b[0], w_bn[1] + w_ni_b[1], w_bn[2] + w_ni_b[2])
    cr = cross(w_ni, r)
    vel_b = mat_vec(c_bn, v[0] + lead_v[0] + cr[0], v[1] + lead_v[1] + cr[1],
                    v[2] + lead_v[2] + cr[2])
    om_rn_r = mat_t_vec(c_br, w_rn[0], w_rn[1], w_rn[2])
    w_ni_r = mat_vec(c_rn, w_ni[0], w_ni[1], w_ni[2])
    om_d: Vec3 = (w_ni_r[0] + om_rn_r[0], w_ni_r[1] + om_rn_r[1], w_ni_r[2] + om_rn_r[2])
    cr = cross(w_ni, r_ref)
    vel_d = mat_vec(c_rn, v_ref[0] + lead_v[0] + cr[0], v_ref[1] + lead_v[1] + cr[1],
                    v_ref[2] + lead_v[2] + cr[2])
    dom = cross(om_rn_r, w_ni_r)
    dom_d: Vec3 = (-dom[0], -dom[1], -dom[2])
    cv = cross(om_rn_r, vel_d)
    cr = cross(w_ni, v_ref)
    cn = mat_vec(c_rn, cr[0], cr[1], cr[2])
    dvel_d: Vec3 = (-cv[0] + cn[0], -cv[1] + cn[1], -cv[2] + cn[2])
    pe = mat_vec(c_bn, r[0] - r_ref[0], r[1] - r_ref[1], r[2] - r_ref[2])
    half = dq._mul(qe[0], qe[1], qe[2], qe[3], 0.0, 0.0, 0.0, 0.0,
                   0.0, pe[0], pe[1], pe[2], 0.0, 0.0, 0.0, 0.0)
    e: tuple[float, ...] = (qe[0], qe[1], qe[2], qe[3], HALF * half[0], HALF * half[1],
                            HALF * half[2], HALF * half[3])
    if e[0] < 0.0:
        e = tuple(-x for x in e)
    wd, vd = dq.transform(e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7], om_d, vel_d)
    dwd, dvd = dq.transform(e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7], dom_d, dvel_d)
    nu = [om_b[0] - wd[0], om_b[1] - wd[1], om_b[2] - wd[2],
          vel_b[0] - vd[0], vel_b[1] - vd[1], vel_b[2] - vd[2]]
    return ErrorState(c_bn, e, nu, om_b, vel_b, wd, vd, dwd, dvd, grav)


def _attitude_state(st: ErrorState, anti_unwinding: bool, au_mu: float) -> None:
    """Eq. (10) (or eqs. 25–26 for the attitude part): ξ̂, Θ̂, Θ̂̇ and ξ̂̇ into ``st``."""
    e = st.e
    nu = st.nu
    f0 = max(e[0], ETA_FLOOR)
    th, thd = dq.theta_blocks(f0, e[1], e[2], e[3], e[4], e[5], e[6], e[7])
    de = dq._mul(f0, e[1], e[2], e[3], e[4], e[5], e[6], e[7],
                 0.0, nu[0], nu[1], nu[2], 0.0, nu[3], nu[4], nu[5])
    th_dot, thd_dot = dq.theta_blocks(HALF * de[0], HALF * de[1], HALF * de[2],
                                      HALF * de[3], HALF * de[4], HALF * de[5],
                                      HALF * de[6], HALF * de[7])
    xi = [e[1], e[2], e[3], e[5], e[6], e[7]]
    th_r = th
    th_r_dot = th_dot
    if anti_unwinding:
        er, th_r, th_r_dot = au.error_state(e[0], e[1], e[2], e[3], (nu[0], nu[1], nu[2]),
                                            au_mu)
        xi[0], xi[1], xi[2] = er
    x_r = mat_vec(th_r, nu[0], nu[1], nu[2])
    x_d1 = mat_vec(thd, nu[0], nu[1], nu[2])
    x_d2 = mat_vec(th, nu[3], nu[4], nu[5])
    st.xi = xi
    st.xi_dot = [x_r[0], x_r[1], x_r[2], x_d1[0] + x_d2[0], x_d1[1] + x_d2[1],
                 x_d1[2] + x_d2[2]]
    st.th_r, st.th, st.thd = th_r, th, thd
    st.th_r_dot, st.th_dot, st.thd_dot = th_r_dot, th_dot, thd_dot


def error_state(q_BN: np.ndarray, omega_BN_B: np.ndarray, r_N_m: np.ndarray,
                v_N_m_s: np.ndarray, q_RN: np.ndarray, omega_RN_B: np.ndarray,
                r_ref_N_m: np.ndarray, v_ref_N_m_s: np.ndarray, mean_motion_rad_s: float,
                mu_m3_s2: float, anti_unwinding: bool, au_mu: float) -> ErrorState:
    """The error state of eqs. (6)–(10) from the PoseController inputs (module docstring)."""
    b = np.asarray(q_BN, dtype=float).tolist()
    n = np.asarray(q_RN, dtype=float).tolist()
    st = _relative_motion(
        (b[0], b[1], b[2], b[3]), vec3.vec3(omega_BN_B), vec3.vec3(r_N_m), vec3.vec3(v_N_m_s),
        (n[0], n[1], n[2], n[3]), vec3.vec3(omega_RN_B), vec3.vec3(r_ref_N_m),
        vec3.vec3(v_ref_N_m_s), mean_motion_rad_s, mu_m3_s2,
    )
    _attitude_state(st, anti_unwinding, au_mu)
    return st


def theta_dot_nu(st: ErrorState) -> list[float]:
    """``Θ̂̇ ω̂_e`` (6)."""
    nu = st.nu
    t_r = mat_vec(st.th_r_dot, nu[0], nu[1], nu[2])
    t_d1 = mat_vec(st.thd_dot, nu[0], nu[1], nu[2])
    t_d2 = mat_vec(st.th_dot, nu[3], nu[4], nu[5])
    return [t_r[0], t_r[1], t_r[2], t_d1[0] + t_d2[0], t_d1[1] + t_d2[1], t_d1[2] + t_d2[2]]


def acceleration(st: ErrorState, br: list[float]) -> tuple[Vec3, Vec3]:
    """``ω̂̇* = −Θ̂⁻¹ b`` by blocks: ``Θ_r x = b_r``, ``Θ y = b_d − Θ′ x`` (angular, linear)."""
    acc_w = solve3(st.th_r, (br[0], br[1], br[2]))
    tx = mat_vec(st.thd, acc_w[0], acc_w[1], acc_w[2])
    acc_v = solve3(st.th, (br[3] - tx[0], br[4] - tx[1], br[5] - tx[2]))
    return (-acc_w[0], -acc_w[1], -acc_w[2]), (-acc_v[0], -acc_v[1], -acc_v[2])


def wrench(st: ErrorState, mass_kg: float, inertia: Mat3, acc_w: Vec3, acc_v: Vec3,
           s: list[float], k_att: list[float], k_pos: list[float], width: float,
           max_force_N: float, max_torque_Nm: float) -> np.ndarray:
    """Law (17) in wrench slots, each half clipped (module docstring): (6,) array."""
    m = mass_kg
    jm = inertia
    nu_w: Vec3 = (st.nu[0], st.nu[1], st.nu[2])
    nu_v: Vec3 = (st.nu[3], st.nu[4], st.nu[5])
    wd, vd, dwd, dvd, om_b, vel_b = st.wd, st.vd, st.dwd, st.dvd, st.om_b, st.vel_b
    # drift (eq. 8 + gravity): M̂ [ω̂_e × ω̂_d' − ω̂̇_d'] − ω̂ × M̂ ω̂ + m ĝ
    fa = cross(nu_w, wd)
    fb = cross(nu_w, vd)
    fc = cross(nu_v, wd)
    feed_w: Vec3 = (fa[0] - dwd[0], fa[1] - dwd[1], fa[2] - dwd[2])
    feed_v: Vec3 = (fb[0] + fc[0] - dvd[0], fb[1] + fc[1] - dvd[1], fb[2] + fc[2] - dvd[2])
    h_b = mat_vec(jm, om_b[0], om_b[1], om_b[2])
    g_w = cross(om_b, (m * vel_b[0], m * vel_b[1], m * vel_b[2]))
    g_v1 = cross(om_b, h_b)
    g_v2 = cross(vel_b, (m * vel_b[0], m * vel_b[1], m * vel_b[2]))
    j_feed = mat_vec(jm, feed_w[0], feed_w[1], feed_w[2])
    j_acc = mat_vec(jm, acc_w[0], acc_w[1], acc_w[2])
    g_b = mat_vec(st.c_bn, st.grav[0], st.grav[1], st.grav[2])
    tk = [math.tanh(x / width) for x in s]
    force = [m * acc_v[i] - (m * feed_v[i] - g_w[i] + m * g_b[i]) - k_pos[i] * tk[3 + i]
             for i in range(3)]
    torque = [j_acc[i] - (j_feed[i] - (g_v1[i] + g_v2[i])) - k_att[i] * tk[i]
              for i in range(3)]
    fo = vec3.clip(force[0], force[1], force[2], max_force_N)
    to = vec3.clip(torque[0], torque[1], torque[2], max_torque_Nm)
    return np.array((fo[0], fo[1], fo[2], to[0], to[1], to[2]))
