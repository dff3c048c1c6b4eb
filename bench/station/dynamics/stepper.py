"""RK4 step with environment wrenches and a translation model (HCW or inertial).

What it does
    The general-purpose counterpart of ``rigid_body.rk4_step``: one classic RK4 step
    (Butcher 2016, §23) of the 13-float rigid-body state where each stage's wrench is
    the thrusters' sample (given at t, t + h/2, t + h like ``rk4_step``) plus the sum of
    the environment models evaluated at the stage's own time and attitude, and where
    the translational part follows a ``TranslationModel``:

        ω̇ = J⁻¹(τ − ω × Jω),  q̇ = ½ q ⊗ (0, ω)          (as ``rigid_body.derivative``)
        ṙ = v,  v̇ = translation.acceleration(t, r, v, C(q)ᵀ F_B / m)

    With no environment model and ``InertialTranslation`` it equals ``rk4_step`` up to
    round-off (``tests/bench/station/test_stepper.py``); the plant uses ``rk4_step`` then, so
    scenarios without environment stay bit-identical.

Inputs: state (``rigid_body`` layout; r, v in the translation model's frame), t_s [s] at
the step start, dt_s [s], three thruster wrenches [N, N·m] (body axes), mass properties.
Output: the state after dt_s, quaternion renormalised.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from bench.station.dynamics.rigid_body import (
    MassProperties,
    Quat,
    State,
    Wrench,
    derivative,
    rates_of,
    rotate_B_to_N,
)
from bench.station.dynamics.translation import TranslationModel
from bench.station.environment.base import EnvironmentModel

RK4_DIVISOR = 6.0
IDX_V = 10
IDX_R = 7


def total_wrench_B(
    t_s: float,
    q_BN: Quat,
    thrust_B: Wrench,
    mp: MassProperties,
    environment: Sequence[EnvironmentModel],
) -> Wrench:
    """Thrusters' wrench plus every environment model's at ``t_s`` and attitude ``q_BN``."""
    f0, f1, f2, t0, t1, t2 = thrust_B
    for env in environment:
        e = env.wrench_B(t_s, q_BN, mp)
        f0 += e[0]
        f1 += e[1]
        f2 += e[2]
        t0 += e[3]
        t1 += e[4]
        t2 += e[5]
    return (f0, f1, f2, t0, t1, t2)


def derivative_env(
    t_s: float,
    state: State,
    thrust_B: Wrench,
    mp: MassProperties,
    translation: TranslationModel,
    environment: Sequence[EnvironmentModel],
) -> State:
    """Time derivative of ``state`` at ``t_s`` (module docstring; pure)."""
    q = (state[0], state[1], state[2], state[3])
    w = total_wrench_B(t_s, q, thrust_B, mp, environment)
    d = derivative(state, (w[0], w[1], w[2]), (w[3], w[4], w[5]), mp)
    im = mp.inv_mass_per_kg
    a_I = rotate_B_to_N(q, (w[0] * im, w[1] * im, w[2] * im))
    r = (state[IDX_R], state[IDX_R + 1], state[IDX_R + 2])
    v = (state[IDX_V], state[IDX_V + 1], state[IDX_V + 2])
    a = translation.acceleration(t_s, r, v, a_I)
    return (*d[:IDX_V], a[0], a[1], a[2])


def rk4_step_env(
    state: State,
    t_s: float,
    dt_s: float,
    wrench0: Wrench,
    wrench_mid: Wrench,
    wrench1: Wrench,
    mp: MassProperties,
    translation: TranslationModel,
    environment: Sequence[EnvironmentModel] = (),
) -> State:
    """One classic RK4 step of ``dt_s`` from ``t_s`` (module docstring).

    The four stages run in one loop on local floats, as ``rigid_body.rk4_step`` does: per
    stage only the environment models (at the stage's time and attitude) and the
    translation model are called; ``derivative_env`` is the same right-hand side as a
    function (``tests/bench/station/test_stepper.py`` checks the step against a textbook RK4 on it).
    """
    j = mp.inertia_flat_B_kgm2
    ji = mp.inertia_inv_flat_B_per_kgm2
    im = mp.inv_mass_per_kg
    q0, q1, q2, q3, wx, wy, wz, rx, ry, rz, vx, vy, vz = state
    h = 0.5 * dt_s
    s = dt_s / RK4_DIVISOR
    s2 = 2.0 * s
    aq0 = aq1 = aq2 = aq3 = aw0 = aw1 = aw2 = ar0 = ar1 = ar2 = av0 = av1 = av2 = 0.0
    dq0 = dq1 = dq2 = dq3 = dwx = dwy = dwz = drx = dry = drz = dvx = dvy = dvz = 0.0
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
        Rx = rx + c * drx
        Ry = ry + c * dry
        Rz = rz + c * drz
        Vx = vx + c * dvx
        Vy = vy + c * dvy
        Vz = vz + c * dvz
        t = t_s + c
        w = wr
        if environment:
            w = total_wrench_B(t, (Q0, Q1, Q2, Q3), wr, mp, environment)
        d = rates_of(Q0, Q1, Q2, Q3, Wx, Wy, Wz, w, j, ji, im)
        a = translation.acceleration(t, (Rx, Ry, Rz), (Vx, Vy, Vz), (d[7], d[8], d[9]))
        dq0, dq1, dq2, dq3, dwx, dwy, dwz = d[0], d[1], d[2], d[3], d[4], d[5], d[6]
        drx, dry, drz = Vx, Vy, Vz
        dvx, dvy, dvz = a[0], a[1], a[2]
        aq0 += wt * dq0
        aq1 += wt * dq1
        aq2 += wt * dq2
        aq3 += wt * dq3
        aw0 += wt * dwx
        aw1 += wt * dwy
        aw2 += wt * dwz
        ar0 += wt * drx
        ar1 += wt * dry
        ar2 += wt * drz
        av0 += wt * dvx
        av1 += wt * dvy
        av2 += wt * dvz
    nq0 = q0 + aq0
    nq1 = q1 + aq1
    nq2 = q2 + aq2
    nq3 = q3 + aq3
    inv_n = 1.0 / math.sqrt(nq0 * nq0 + nq1 * nq1 + nq2 * nq2 + nq3 * nq3)
    return (nq0 * inv_n, nq1 * inv_n, nq2 * inv_n, nq3 * inv_n, wx + aw0, wy + aw1, wz + aw2,
            rx + ar0, ry + ar1, rz + ar2, vx + av0, vy + av1, vz + av2)
