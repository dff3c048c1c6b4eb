"""Disturbance model: constant + sinusoids, known answers through the RK4 plant stepper."""

from __future__ import annotations

import math

import pytest

from bench.station.dynamics.hcw import HcwParams, HcwTranslation
from bench.station.dynamics.rigid_body import (
    ZERO_WRENCH,
    MassProperties,
    make_state,
    quat_from_axis_angle,
    rotate_B_to_N,
)
from bench.station.dynamics.stepper import rk4_step_env
from bench.station.dynamics.translation import InertialTranslation
from bench.station.environment.disturbance import (
    Disturbance,
    DisturbanceParams,
    Sinusoid,
    sinusoid_sum,
    sinusoid_sum_integral,
)
from dbc.errors import ConfigError

DT_S = 0.01
N_STEPS = 500
J_AXIS_KGM2 = 20.0
MASS_KG = 95.0
TORQUE_NM = 0.002
REL_TOL = 1e-12
SINE_ABS_TOL = 1e-12
# seed 000 §V, x components: 0.06 + 0.03 sin(0.6 t) N
SEED000_FX_CONST_N = 0.06
SEED000_FX_AMP_N = 0.03
SEED000_FX_OMEGA = 0.6


def _mp() -> MassProperties:
    j = J_AXIS_KGM2
    return MassProperties(MASS_KG, ((j, 0.0, 0.0), (0.0, j, 0.0), (0.0, 0.0, j)))


def _propagate(dist: Disturbance, n: int = N_STEPS) -> tuple[float, ...]:
    s = make_state()
    for k in range(n):
        s = rk4_step_env(s, k * DT_S, DT_S, ZERO_WRENCH, ZERO_WRENCH, ZERO_WRENCH, _mp(),
                         InertialTranslation(), (dist,))
    return s


def test_constant_torque_spins_up_linearly() -> None:
    """A free body about a principal axis under a constant torque gains ω = τ t / J."""
    dist = Disturbance(DisturbanceParams(torque_Nm=(0.0, 0.0, TORQUE_NM)))
    s = _propagate(dist)
    expected = TORQUE_NM * N_STEPS * DT_S / J_AXIS_KGM2
    assert s[6] == pytest.approx(expected, rel=REL_TOL)
    assert abs(s[4]) < SINE_ABS_TOL and abs(s[5]) < SINE_ABS_TOL


def test_sinusoidal_force_integrates_to_its_analytic_velocity() -> None:
    """Seed 000's x force, body frame, fixed attitude: v(t) = ∫ F dt / m (RK4 is exact to 1e-12)."""
    params = DisturbanceParams(
        force_N=(SEED000_FX_CONST_N, 0.0, 0.0),
        force_sinusoids=(Sinusoid((SEED000_FX_AMP_N, 0.0, 0.0), SEED000_FX_OMEGA),),
    )
    s = _propagate(Disturbance(params))
    t1 = N_STEPS * DT_S
    dv = sinusoid_sum_integral(0.0, t1, params.force_N, params.force_sinusoids)[0] / MASS_KG
    assert s[10] == pytest.approx(dv, rel=1e-10)


def test_sinusoid_sum_known_value_and_phase() -> None:
    """c + a sin(ω t + φ) at ω t + φ = π/2 is c + a."""
    s = Sinusoid((1.0, -2.0, 0.5), 2.0, math.pi / 4)
    v = sinusoid_sum(math.pi / 8, (1.0, 1.0, 1.0), (s,))
    assert v == pytest.approx((2.0, -1.0, 1.5), abs=SINE_ABS_TOL)


def test_nav_force_is_rotated_into_body_axes() -> None:
    """A nav-frame force seen in body axes rotates back to the same nav vector."""
    q = quat_from_axis_angle((0.0, 0.0, 1.0), 0.7)
    f_nav = (0.1, 0.2, -0.3)
    d = Disturbance(DisturbanceParams(force_N=f_nav, force_frame="nav"))
    w = d.wrench_B(0.0, q, _mp())
    assert rotate_B_to_N(q, (w[0], w[1], w[2])) == pytest.approx(f_nav, abs=SINE_ABS_TOL)
    hcw = HcwTranslation(HcwParams())
    t = 1000.0
    d_h = Disturbance(DisturbanceParams(force_N=f_nav, force_frame="nav"), hcw)
    w_h = d_h.wrench_B(t, q, _mp())
    back = hcw.inertial_to_nav(t, rotate_B_to_N(q, (w_h[0], w_h[1], w_h[2])))
    assert back == pytest.approx(f_nav, abs=SINE_ABS_TOL)


def test_bad_parameters_raise_config_error() -> None:
    """An unknown force frame or a non-finite amplitude is a ConfigError naming the key."""
    with pytest.raises(ConfigError, match="force_frame"):
        DisturbanceParams(force_frame="hill")
    with pytest.raises(ConfigError, match="amplitude"):
        Sinusoid((math.nan, 0.0, 0.0), 1.0)
