"""Six-degree-of-freedom rigid body: state layout, equations of motion, fixed-step RK4.

What it does
    Propagates one rigid spacecraft: attitude quaternion, body angular rate, inertial
    position and velocity, driven by a body-axes force and torque (a "wrench").
    Pure functions of their arguments: no clock, no module-level mutable state.

State (a plain tuple of 13 floats, hot path friendly; see the ``IDX_*`` constants)
    ``(q0, q1, q2, q3, wx, wy, wz, rx, ry, rz, vx, vy, vz)``
    - ``q_BN``       attitude quaternion, scalar first, unit norm [-]
    - ``omega_BN_B`` angular velocity of B relative to N, in body axes [rad/s]
    - ``r_N``        position of the centre of mass in the inertial frame N [m]
    - ``v_N``        velocity of the centre of mass in N [m/s]
    (Translation is inertial here; HCW relative translation in a Hill frame and
    environment wrenches are in ``bench.station.dynamics.hcw`` and
    ``bench.station.dynamics.stepper``.)

Frames and quaternion convention
    N is inertial, B is body-fixed with its origin at the centre of mass. Quaternions
    are scalar first and multiply with the Hamilton product ``⊗``. ``q_BN`` maps
    coordinates in N to coordinates in B::

        v_B = C(q_BN) v_N,   C(q) = R(q)ᵀ,   i.e.  v_B = q* ⊗ (0, v_N) ⊗ q

    where R(q) is the usual Hamilton rotation matrix (``rotate_B_to_N`` applies R,
    ``rotate_N_to_B`` applies C). With this convention the kinematics are
    ``q̇ = ½ q ⊗ (0, ω_BN_B)`` (Solà 2017, "Quaternion kinematics for the error-state
    Kalman filter", eqs. 101, 205, with his q_GL = our q_BN).

Equations (inputs: force ``F_B`` [N] and torque ``τ_B`` [N·m] about the centre of mass,
both in body axes; mass properties constant over a step)
    ω̇ = J⁻¹ (τ − ω × J ω)          Euler's rotational equations, full inertia tensor
                                    (Wertz, "Spacecraft Attitude Determination and
                                    Control", 1978, §16.1; Markley & Crassidis 2014, §3.3)
    q̇ = ½ q ⊗ (0, ω)               quaternion kinematics (above)
    ṙ = v
    v̇ = C(q)ᵀ F_B / m              Newton's second law in N

Integration
    ``rk4_step`` is the classic fourth-order Runge–Kutta method (Butcher 2016, §23) with
    the wrench supplied by the caller at t, t + dt/2 and t + dt (so valve transients are
    sampled, never stepped across adaptively). The quaternion is renormalised after
    each step. Because v̇ depends only on q and the force, the velocity increment of a
    step is exactly Simpson's rule (1, 4, 1)/6 applied to the three force samples
    when the attitude is constant; ``bench.station.valves.thruster_set`` books thruster impulse
    with the same weights so that propellant matches what the body received.

Assumptions
    Rigid body, constant mass and inertia within a step (propellant mass change is
    handled by the caller swapping ``MassProperties``), wrench expressed about the
    centre of mass, no gravity here (environmental forces are part of the wrench).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from mypy_extensions import mypyc_attr

from dbc import validation as check

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]
Wrench = tuple[float, float, float, float, float, float]
"""(fx, fy, fz, tx, ty, tz): force [N] and torque about the centre of mass [N·m], body axes."""
State = tuple[float, ...]
"""13 floats, layout given by the ``IDX_*`` constants."""

# --- state layout -------------------------------------------------------------------
IDX_Q0, IDX_Q1, IDX_Q2, IDX_Q3 = 0, 1, 2, 3
IDX_WX, IDX_WY, IDX_WZ = 4, 5, 6
IDX_RX, IDX_RY, IDX_RZ = 7, 8, 9
IDX_VX, IDX_VY, IDX_VZ = 10, 11, 12
STATE_SIZE = 13
SL_Q_BN = slice(IDX_Q0, IDX_Q3 + 1)
SL_OMEGA_BN_B = slice(IDX_WX, IDX_WZ + 1)
SL_R_N = slice(IDX_RX, IDX_RZ + 1)
SL_V_N = slice(IDX_VX, IDX_VZ + 1)

QUAT_IDENTITY: Quat = (1.0, 0.0, 0.0, 0.0)
ZERO_VEC3: Vec3 = (0.0, 0.0, 0.0)
ZERO_WRENCH: Wrench = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

# --- validation tolerances ------------------------------------------------------------
QUAT_NORM_TOL = 1e-6
"""Allowed |‖q‖ − 1| for quaternions handed to ``make_state``."""
MATRIX_DIM = 3


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class MassProperties:
    """Mass [kg] and inertia tensor about the centre of mass in body axes [kg·m²].

    ``mass_kg`` is a finite number > 0; ``inertia_B_kgm2`` must be 3×3, finite, symmetric
    within ``dbc.validation.INERTIA_SYMMETRY_RTOL``, positive definite and physically
    realisable (principal moments obey the triangle inequality), as
    :func:`dbc.validation.inertia` checks it. The flat row-major tensor (symmetrised), its
    inverse and 1/m are precomputed for the hot path.
    """

    mass_kg: float
    inertia_B_kgm2: tuple[tuple[float, float, float], ...]
    source: str = field(default="MassProperties", compare=False, repr=False, kw_only=True)
    inertia_flat_B_kgm2: tuple[float, ...] = field(init=False, repr=False, compare=False)
    inertia_inv_flat_B_per_kgm2: tuple[float, ...] = field(init=False, repr=False, compare=False)
    inv_mass_per_kg: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        src = self.source
        # getattr: the fields as given (compiled code would cast a read to its type first)
        m = check.positive(src, "mass_kg", getattr(self, "mass_kg"))  # noqa: B009
        given = getattr(self, "inertia_B_kgm2")  # noqa: B009
        rows = check.matrix(src, "inertia_B_kgm2", given, MATRIX_DIM, MATRIX_DIM)
        j = check.inertia(src, "inertia_B_kgm2", given, physical=True)
        j_inv = np.array(inverse3(j.tolist()))
        j_inv = 0.5 * (j_inv + j_inv.T)
        object.__setattr__(self, "mass_kg", m)
        object.__setattr__(self, "inertia_B_kgm2", tuple(tuple(map(float, r)) for r in rows))
        object.__setattr__(self, "inertia_flat_B_kgm2", tuple(float(x) for x in j.ravel()))
        object.__setattr__(
            self, "inertia_inv_flat_B_per_kgm2", tuple(float(x) for x in j_inv.ravel())
        )
        object.__setattr__(self, "inv_mass_per_kg", 1.0 / m)


# --- quaternion and frame helpers ---------------------------------------------------------
def inverse3(a: list[list[float]]) -> list[list[float]]:
    """``A⁻¹`` of a nonsingular 3×3 matrix by Gauss-Jordan elimination with partial pivoting
    on floats: the same bits on every CPU (LAPACK's inverse runs on the BLAS kernel picked
    for the CPU), and exactly ``1/A_ii`` on a diagonal (the usual principal-axis inertia)."""
    n = MATRIX_DIM
    m = [list(a[i]) + [1.0 if j == i else 0.0 for j in range(n)] for i in range(n)]
    for col in range(n):
        piv = max(range(col, n), key=lambda r: abs(m[r][col]))
        m[col], m[piv] = m[piv], m[col]
        p = m[col][col]
        m[col] = [x / p for x in m[col]]
        for r in range(n):
            f = m[r][col]
            if r != col and f != 0.0:
                m[r] = [x - f * y for x, y in zip(m[r], m[col], strict=True)]
    return [row[n:] for row in m]


def quat_multiply(p: Quat, q: Quat) -> Quat:
    """Hamilton product p ⊗ q of scalar-first quaternions."""
    p0, p1, p2, p3 = p
    q0, q1, q2, q3 = q
    return (
        p0 * q0 - p1 * q1 - p2 * q2 - p3 * q3,
        p0 * q1 + p1 * q0 + p2 * q3 - p3 * q2,
        p0 * q2 - p1 * q3 + p2 * q0 + p3 * q1,
        p0 * q3 + p1 * q2 - p2 * q1 + p3 * q0,
    )


def quat_conjugate(q: Quat) -> Quat:
    """Conjugate (the inverse of a unit quaternion)."""
    return (q[0], -q[1], -q[2], -q[3])


def quat_normalize(q: Quat) -> Quat:
    """Unit quaternion along ``q`` (``q`` must be non-zero)."""
    n = 1.0 / math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return (q[0] * n, q[1] * n, q[2] * n, q[3] * n)


def quat_from_axis_angle(axis: Vec3, angle_rad: float) -> Quat:
    """Quaternion of a rotation by ``angle_rad`` about the unit vector ``axis``."""
    s = math.sin(0.5 * angle_rad)
    return (math.cos(0.5 * angle_rad), axis[0] * s, axis[1] * s, axis[2] * s)


def rotate_B_to_N(q_BN: Quat, v_B: Vec3) -> Vec3:
    """v_N = C(q_BN)ᵀ v_B = R(q_BN) v_B (valid for a unit quaternion)."""
    q0, q1, q2, q3 = q_BN
    x, y, z = v_B
    return (
        (1.0 - 2.0 * (q2 * q2 + q3 * q3)) * x
        + 2.0 * (q1 * q2 - q0 * q3) * y
        + 2.0 * (q1 * q3 + q0 * q2) * z,
        2.0 * (q1 * q2 + q0 * q3) * x
        + (1.0 - 2.0 * (q1 * q1 + q3 * q3)) * y
        + 2.0 * (q2 * q3 - q0 * q1) * z,
        2.0 * (q1 * q3 - q0 * q2) * x
        + 2.0 * (q2 * q3 + q0 * q1) * y
        + (1.0 - 2.0 * (q1 * q1 + q2 * q2)) * z,
    )


def rotate_N_to_B(q_BN: Quat, v_N: Vec3) -> Vec3:
    """v_B = C(q_BN) v_N = R(q_BN)ᵀ v_N (valid for a unit quaternion)."""
    q0, q1, q2, q3 = q_BN
    x, y, z = v_N
    return (
        (1.0 - 2.0 * (q2 * q2 + q3 * q3)) * x
        + 2.0 * (q1 * q2 + q0 * q3) * y
        + 2.0 * (q1 * q3 - q0 * q2) * z,
        2.0 * (q1 * q2 - q0 * q3) * x
        + (1.0 - 2.0 * (q1 * q1 + q3 * q3)) * y
        + 2.0 * (q2 * q3 + q0 * q1) * z,
        2.0 * (q1 * q3 + q0 * q2) * x
        + 2.0 * (q2 * q3 - q0 * q1) * y
        + (1.0 - 2.0 * (q1 * q1 + q2 * q2)) * z,
    )


# --- state helpers -----------------------------------------------------------------------
def make_state(
    q_BN: Sequence[float] = QUAT_IDENTITY,
    omega_BN_B: Sequence[float] = ZERO_VEC3,
    r_N: Sequence[float] = ZERO_VEC3,
    v_N: Sequence[float] = ZERO_VEC3,
) -> State:
    """Pack a state tuple from q_BN [-], ω_BN_B [rad/s], r_N [m], v_N [m/s].

    ``q_BN`` must be unit within ``QUAT_NORM_TOL``; it is renormalised.
    """
    vals = [float(x) for x in q_BN]
    if len(vals) != len(QUAT_IDENTITY):
        raise ValueError(f"q_BN must have 4 components, got {q_BN!r}")
    norm = math.sqrt(vals[0] * vals[0] + vals[1] * vals[1] + vals[2] * vals[2]
                     + vals[3] * vals[3])
    if not abs(norm - 1.0) <= QUAT_NORM_TOL:
        raise ValueError(f"q_BN must be a unit quaternion, got norm {norm!r}")
    parts = (omega_BN_B, r_N, v_N)
    if any(len(p) != MATRIX_DIM for p in parts):
        raise ValueError("omega_BN_B, r_N and v_N must have 3 components")
    out = tuple(x / norm for x in vals) + tuple(float(x) for p in parts for x in p)
    if not all(math.isfinite(x) for x in out):
        raise ValueError(f"state must be finite, got {out!r}")
    return out


def state_q_BN(state: State) -> Quat:
    """Attitude quaternion q_BN of a state."""
    return (state[IDX_Q0], state[IDX_Q1], state[IDX_Q2], state[IDX_Q3])


def state_omega_BN_B(state: State) -> Vec3:
    """Body rate ω_BN_B [rad/s] of a state."""
    return (state[IDX_WX], state[IDX_WY], state[IDX_WZ])


def state_r_N(state: State) -> Vec3:
    """Inertial position r_N [m] of a state."""
    return (state[IDX_RX], state[IDX_RY], state[IDX_RZ])


def state_v_N(state: State) -> Vec3:
    """Inertial velocity v_N [m/s] of a state."""
    return (state[IDX_VX], state[IDX_VY], state[IDX_VZ])


# --- equations of motion -------------------------------------------------------------------
def rates_of(
    q0: float,
    q1: float,
    q2: float,
    q3: float,
    wx: float,
    wy: float,
    wz: float,
    w: Wrench,
    j: tuple[float, ...],
    ji: tuple[float, ...],
    inv_m: float,
) -> tuple[float, float, float, float, float, float, float, float, float, float]:
    """(q̇0..q̇3, ω̇x..ω̇z, v̇x..v̇z) for the given attitude, rate and wrench (see module doc)."""
    fx, fy, fz, tx, ty, tz = w
    j00, j01, j02, j10, j11, j12, j20, j21, j22 = j
    i00, i01, i02, i10, i11, i12, i20, i21, i22 = ji
    # H = J ω; c = τ − ω × H
    hx = j00 * wx + j01 * wy + j02 * wz
    hy = j10 * wx + j11 * wy + j12 * wz
    hz = j20 * wx + j21 * wy + j22 * wz
    cx = tx - (wy * hz - wz * hy)
    cy = ty - (wz * hx - wx * hz)
    cz = tz - (wx * hy - wy * hx)
    # F_N / m = R(q) F_B / m = F' + q0 u + qv × u with u = 2 qv × F', F' = F_B / m
    fx *= inv_m
    fy *= inv_m
    fz *= inv_m
    ux = 2.0 * (q2 * fz - q3 * fy)
    uy = 2.0 * (q3 * fx - q1 * fz)
    uz = 2.0 * (q1 * fy - q2 * fx)
    return (
        -0.5 * (q1 * wx + q2 * wy + q3 * wz),
        0.5 * (q0 * wx + q2 * wz - q3 * wy),
        0.5 * (q0 * wy + q3 * wx - q1 * wz),
        0.5 * (q0 * wz + q1 * wy - q2 * wx),
        i00 * cx + i01 * cy + i02 * cz,
        i10 * cx + i11 * cy + i12 * cz,
        i20 * cx + i21 * cy + i22 * cz,
        fx + q0 * ux + q2 * uz - q3 * uy,
        fy + q0 * uy + q3 * ux - q1 * uz,
        fz + q0 * uz + q1 * uy - q2 * ux,
    )


def derivative(state: State, force_B_N: Vec3, torque_B_Nm: Vec3, mp: MassProperties) -> State:
    """Time derivative of ``state`` under a body-axes force [N] and torque [N·m] (pure)."""
    q0, q1, q2, q3, wx, wy, wz, _rx, _ry, _rz, vx, vy, vz = state
    w: Wrench = (
        force_B_N[0],
        force_B_N[1],
        force_B_N[2],
        torque_B_Nm[0],
        torque_B_Nm[1],
        torque_B_Nm[2],
    )
    d = rates_of(
        q0,
        q1,
        q2,
        q3,
        wx,
        wy,
        wz,
        w,
        mp.inertia_flat_B_kgm2,
        mp.inertia_inv_flat_B_per_kgm2,
        mp.inv_mass_per_kg,
    )
    return (d[0], d[1], d[2], d[3], d[4], d[5], d[6], vx, vy, vz, d[7], d[8], d[9])


def rk4_step(
    state: State,
    dt_s: float,
    wrench0: Wrench,
    wrench_mid: Wrench,
    wrench1: Wrench,
    mp: MassProperties,
) -> State:
    """One classic RK4 step of ``dt_s`` seconds; wrenches are sampled at t, t+dt/2, t+dt.

    Returns the new state with the quaternion renormalised. The four stages run in one
    loop with the equations of ``derivative`` written out on local floats (the hot path:
    no function call or tuple per stage); ``tests/bench/station/test_rigid_body.py`` checks it
    against a textbook RK4 built on ``derivative``.
    """
    j00, j01, j02, j10, j11, j12, j20, j21, j22 = mp.inertia_flat_B_kgm2
    i00, i01, i02, i10, i11, i12, i20, i21, i22 = mp.inertia_inv_flat_B_per_kgm2
    im = mp.inv_mass_per_kg
    q0, q1, q2, q3, wx, wy, wz, rx, ry, rz, vx, vy, vz = state
    h = 0.5 * dt_s
    s = dt_s / 6.0
    s2 = 2.0 * s
    aq0 = aq1 = aq2 = aq3 = aw0 = aw1 = aw2 = ar0 = ar1 = ar2 = av0 = av1 = av2 = 0.0
    dq0 = dq1 = dq2 = dq3 = dwx = dwy = dwz = dvx = dvy = dvz = 0.0
    # stage k: Y_k = y + c_k·dt·k_{k-1}; result y + Σ b_k k_k with b = (1, 2, 2, 1)·dt/6
    stages = ((0.0, s, wrench0), (h, s2, wrench_mid), (h, s2, wrench_mid), (dt_s, s, wrench1))
    for c, wt, wr in stages:
        Q0 = q0 + c * dq0
        Q1 = q1 + c * dq1
        Q2 = q2 + c * dq2
        Q3 = q3 + c * dq3
        Wx = wx + c * dwx
        Wy = wy + c * dwy
        Wz = wz + c * dwz
        Vx = vx + c * dvx
        Vy = vy + c * dvy
        Vz = vz + c * dvz
        fx, fy, fz, tx, ty, tz = wr
        hx = j00 * Wx + j01 * Wy + j02 * Wz
        hy = j10 * Wx + j11 * Wy + j12 * Wz
        hz = j20 * Wx + j21 * Wy + j22 * Wz
        cx = tx - Wy * hz + Wz * hy
        cy = ty - Wz * hx + Wx * hz
        cz = tz - Wx * hy + Wy * hx
        dq0 = -0.5 * (Q1 * Wx + Q2 * Wy + Q3 * Wz)
        dq1 = 0.5 * (Q0 * Wx + Q2 * Wz - Q3 * Wy)
        dq2 = 0.5 * (Q0 * Wy + Q3 * Wx - Q1 * Wz)
        dq3 = 0.5 * (Q0 * Wz + Q1 * Wy - Q2 * Wx)
        dwx = i00 * cx + i01 * cy + i02 * cz
        dwy = i10 * cx + i11 * cy + i12 * cz
        dwz = i20 * cx + i21 * cy + i22 * cz
        # v̇ = R(Q) F/m as F' + Q0 u + Qv × u with u = 2 Qv × F', F' = F/m
        fx *= im
        fy *= im
        fz *= im
        ux = 2.0 * (Q2 * fz - Q3 * fy)
        uy = 2.0 * (Q3 * fx - Q1 * fz)
        uz = 2.0 * (Q1 * fy - Q2 * fx)
        dvx = fx + Q0 * ux + Q2 * uz - Q3 * uy
        dvy = fy + Q0 * uy + Q3 * ux - Q1 * uz
        dvz = fz + Q0 * uz + Q1 * uy - Q2 * ux
        aq0 += wt * dq0
        aq1 += wt * dq1
        aq2 += wt * dq2
        aq3 += wt * dq3
        aw0 += wt * dwx
        aw1 += wt * dwy
        aw2 += wt * dwz
        ar0 += wt * Vx
        ar1 += wt * Vy
        ar2 += wt * Vz
        av0 += wt * dvx
        av1 += wt * dvy
        av2 += wt * dvz
    nq0 = q0 + aq0
    nq1 = q1 + aq1
    nq2 = q2 + aq2
    nq3 = q3 + aq3
    inv_n = 1.0 / math.sqrt(nq0 * nq0 + nq1 * nq1 + nq2 * nq2 + nq3 * nq3)
    return (
        nq0 * inv_n,
        nq1 * inv_n,
        nq2 * inv_n,
        nq3 * inv_n,
        wx + aw0,
        wy + aw1,
        wz + aw2,
        rx + ar0,
        ry + ar1,
        rz + ar2,
        vx + av0,
        vy + av1,
        vz + av2,
    )


# --- conserved quantities ----------------------------------------------------------------
def angular_momentum_B(state: State, mp: MassProperties) -> Vec3:
    """Angular momentum about the centre of mass in body axes, H_B = J ω [N·m·s]."""
    j00, j01, j02, j10, j11, j12, j20, j21, j22 = mp.inertia_flat_B_kgm2
    wx, wy, wz = state[IDX_WX], state[IDX_WY], state[IDX_WZ]
    return (
        j00 * wx + j01 * wy + j02 * wz,
        j10 * wx + j11 * wy + j12 * wz,
        j20 * wx + j21 * wy + j22 * wz,
    )


def angular_momentum_N(state: State, mp: MassProperties) -> Vec3:
    """Angular momentum about the centre of mass in inertial axes, H_N = C(q)ᵀ J ω [N·m·s]."""
    return rotate_B_to_N(state_q_BN(state), angular_momentum_B(state, mp))


def linear_momentum_N(state: State, mp: MassProperties) -> Vec3:
    """Linear momentum in N, p_N = m v_N [N·s]."""
    m = mp.mass_kg
    return (m * state[IDX_VX], m * state[IDX_VY], m * state[IDX_VZ])


def rotational_kinetic_energy(state: State, mp: MassProperties) -> float:
    """½ ωᵀ J ω [J]."""
    hx, hy, hz = angular_momentum_B(state, mp)
    return 0.5 * (state[IDX_WX] * hx + state[IDX_WY] * hy + state[IDX_WZ] * hz)


def kinetic_energy(state: State, mp: MassProperties) -> float:
    """Total kinetic energy, ½ ωᵀ J ω + ½ m ‖v‖² [J]."""
    vx, vy, vz = state[IDX_VX], state[IDX_VY], state[IDX_VZ]
    return rotational_kinetic_energy(state, mp) + 0.5 * mp.mass_kg * (vx * vx + vy * vy + vz * vz)
