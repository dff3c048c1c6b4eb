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
    round-off (``tests/bench/test_stepper.py``); the plant uses ``rk4_step`` then, so
    scenarios without environment stay bit-identical.

Inputs: state (``rigid_body`` layout; r, v in the translation model's frame), t_s [s] at
the step start, dt_s [s], three thruster wrenches [N, N·m] (body axes), mass properties.
Output: the state after dt_s, quaternion renormalised.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from bench.dynamics.rigid_body import (
    MassProperties,
    State,
    Wrench,
    derivative,
    rotate_B_to_N,
)
from bench.dynamics.translation import TranslationModel
from bench.environment.base import EnvironmentModel

RK4_WEIGHTS = (1.0, 2.0, 2.0, 1.0)
RK4_DIVISOR = 6.0
IDX_V = 10
IDX_R = 7


def total_wrench_B(
    t_s: float,
    state: State,
    thrust_B: Wrench,
    mp: MassProperties,
    environment: Sequence[EnvironmentModel],
) -> Wrench:
    """Thrusters' wrench plus every environment model's at ``t_s`` and the state's attitude."""
    if not environment:
        return thrust_B
    q = (state[0], state[1], state[2], state[3])
    w = list(thrust_B)
    for env in environment:
        e = env.wrench_B(t_s, q, mp)
        for i in range(6):
            w[i] += e[i]
    return (w[0], w[1], w[2], w[3], w[4], w[5])


def derivative_env(
    t_s: float,
    state: State,
    thrust_B: Wrench,
    mp: MassProperties,
    translation: TranslationModel,
    environment: Sequence[EnvironmentModel],
) -> State:
    """Time derivative of ``state`` at ``t_s`` (module docstring; pure)."""
    w = total_wrench_B(t_s, state, thrust_B, mp, environment)
    d = derivative(state, (w[0], w[1], w[2]), (w[3], w[4], w[5]), mp)
    q = (state[0], state[1], state[2], state[3])
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
    """One classic RK4 step of ``dt_s`` from ``t_s`` (module docstring)."""
    h = 0.5 * dt_s

    def f(t: float, y: State, w: Wrench) -> State:
        return derivative_env(t, y, w, mp, translation, environment)

    k1 = f(t_s, state, wrench0)
    k2 = f(t_s + h, tuple(y + h * k for y, k in zip(state, k1, strict=True)), wrench_mid)
    k3 = f(t_s + h, tuple(y + h * k for y, k in zip(state, k2, strict=True)), wrench_mid)
    k4 = f(t_s + dt_s, tuple(y + dt_s * k for y, k in zip(state, k3, strict=True)), wrench1)
    s = dt_s / RK4_DIVISOR
    b1, b2, b3, b4 = RK4_WEIGHTS
    out = [
        y + s * (b1 * a + b2 * b + b3 * c + b4 * d)
        for y, a, b, c, d in zip(state, k1, k2, k3, k4, strict=True)
    ]
    n = 1.0 / math.sqrt(out[0] ** 2 + out[1] ** 2 + out[2] ** 2 + out[3] ** 2)
    out[0:4] = [x * n for x in out[0:4]]
    return tuple(out)
