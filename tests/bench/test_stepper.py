"""The environment-aware RK4 step equals the fast rigid-body RK4 when there is no environment."""

from __future__ import annotations

import pytest

from bench.dynamics.rigid_body import MassProperties, make_state, quat_normalize, rk4_step
from bench.dynamics.stepper import rk4_step_env
from bench.dynamics.translation import InertialTranslation

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
