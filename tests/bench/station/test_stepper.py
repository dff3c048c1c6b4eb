"""The environment-aware RK4 step: the fast rigid-body RK4 without environment, textbook RK4
on its own right-hand side with one."""

from __future__ import annotations

from typing import Any

import pytest

from bench.station.dynamics.hcw import HcwParams, HcwTranslation
from bench.station.dynamics.rigid_body import MassProperties, make_state, quat_normalize, rk4_step
from bench.station.dynamics.stepper import derivative_env, rk4_step_env
from bench.station.dynamics.translation import InertialTranslation
from bench.station.environment.disturbance import Disturbance, DisturbanceParams, Sinusoid
from bench.station.environment.gravity_gradient import GravityGradient, GravityGradientParams

ROUNDOFF_TOL = 1e-13
DT_S = 1e-3


def test_matches_rk4_step_without_environment() -> None:
    """Same state after 200 tumbling, thrusting steps (up to round-off)."""
    mp = MassProperties(180.0, ((12.0, -0.8, 0.4), (-0.8, 9.0, 0.6), (0.4, 0.6, 7.0)))
    s0 = make_state(quat_normalize((0.8, 0.3, -0.4, 0.2)), (0.4, -0.3, 0.5), (1.0, 2.0, 3.0),
                    (0.1, 0.0, -0.1))
    w0 = (1.0, -2.0, 0.5, 0.1, 0.2, -0.3)
    wm = (1.5, -1.0, 0.0, 0.0, 0.3, -0.1)
    w1 = (2.0, 0.0, -0.5, -0.1, 0.4, 0.1)
    a = b = s0
    for k in range(200):
        a = rk4_step(a, DT_S, w0, wm, w1, mp)
        b = rk4_step_env(b, k * DT_S, DT_S, w0, wm, w1, mp, InertialTranslation())
    assert b == pytest.approx(a, abs=ROUNDOFF_TOL)


def _textbook_rk4(state: tuple[float, ...], t_s: float, dt_s: float, w0: tuple[float, ...],
                  wm: tuple[float, ...], w1: tuple[float, ...], mp: MassProperties,
                  translation: HcwTranslation, env: list[Any]) -> tuple[float, ...]:
    """RK4 on derivative_env, stage by stage (the reference)."""
    def f(t: float, y: tuple[float, ...], w: tuple[float, ...]) -> tuple[float, ...]:
        return derivative_env(t, y, w, mp, translation, env)  # type: ignore[arg-type]

    h = 0.5 * dt_s
    k1 = f(t_s, state, w0)
    k2 = f(t_s + h, tuple(y + h * k for y, k in zip(state, k1, strict=True)), wm)
    k3 = f(t_s + h, tuple(y + h * k for y, k in zip(state, k2, strict=True)), wm)
    k4 = f(t_s + dt_s, tuple(y + dt_s * k for y, k in zip(state, k3, strict=True)), w1)
    out = [y + dt_s / 6.0 * (a + 2.0 * b + 2.0 * c + d)
           for y, a, b, c, d in zip(state, k1, k2, k3, k4, strict=True)]
    return (*quat_normalize((out[0], out[1], out[2], out[3])), *out[4:])


def test_matches_textbook_rk4_with_environment_and_hcw() -> None:
    """With disturbances (force in the Hill frame), gravity gradient and HCW translation, the
    written-out step equals RK4 on derivative_env to round-off over 200 steps."""
    mp = MassProperties(95.0, ((17.0, 0.3, 0.0), (0.3, 17.0, 0.1), (0.0, 0.1, 22.0)))
    hcw = HcwTranslation(HcwParams())
    dist = Disturbance(DisturbanceParams(
        force_N=(0.06, 0.05, 0.04), force_frame="nav",
        force_sinusoids=(Sinusoid((0.03, 0.04, 0.01), 0.6, 0.2),),
        torque_Nm=(2e-5, 3e-5, 1e-5), torque_sinusoids=(Sinusoid((5e-4, 3e-4, 7e-4), 0.8),)),
        hcw)
    env = [dist, GravityGradient(GravityGradientParams())]
    s0 = make_state(quat_normalize((0.62, 0.5, 0.52, 0.3)), (0.02, -0.03, 0.05),
                    (-20.0, -10.0, -10.0), (0.01, 0.0, -0.02))
    w0 = (1.0, -2.0, 0.5, 0.1, 0.2, -0.3)
    wm = (1.5, -1.0, 0.0, 0.0, 0.3, -0.1)
    w1 = (2.0, 0.0, -0.5, -0.1, 0.4, 0.1)
    a = b = s0
    for k in range(200):
        a = _textbook_rk4(a, 100.0 + k * DT_S, DT_S, w0, wm, w1, mp, hcw, env)
        b = rk4_step_env(b, 100.0 + k * DT_S, DT_S, w0, wm, w1, mp, hcw, env)
    assert b == pytest.approx(a, abs=ROUNDOFF_TOL)
    assert b != s0
