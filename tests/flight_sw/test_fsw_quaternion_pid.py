"""Quaternion PID: the integral removes a constant-torque offset; windup guards hold."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.control.quaternion_pd import QuaternionPd, QuaternionPdParams
from flight_sw.control.quaternion_pid import QuaternionPid, QuaternionPidParams
from flight_sw.quaternion import from_rotation_vector, identity, multiply, rotation_angle_rad

INERTIA = (17.0, 17.0, 22.0)
WN, ZETA = 1.0, 0.9
DT_NS = 20_000_000
DISTURBANCE_NM = np.array([0.05, -0.03, 0.02])  # constant, e.g. a countered thruster's error
T_END_S = 80.0
OFFSET_TOL_RAD = 1e-4
ZERO = np.zeros(3)


def pid(band_deg: float = 1.0, clamp: float = math.inf, ti: float = 8.0) -> QuaternionPid:
    """A PID on the seed-000 inertia."""
    pd = QuaternionPdParams.from_bandwidth(INERTIA, WN, ZETA)
    return QuaternionPid(QuaternionPidParams(pd, ti, math.radians(band_deg), clamp))


def settle(ctl: QuaternionPd | QuaternionPid) -> float:
    """Final error angle [rad] of a rigid body under the law plus the disturbance."""
    j = np.array(INERTIA)
    q, w = identity(), ZERO.copy()
    dt = DT_NS / 1e9
    for k in range(round(T_END_S / dt)):
        tau = ctl.torque_B_Nm(k * DT_NS, q, w, identity(), ZERO) + DISTURBANCE_NM
        w = w + dt * tau / j
        q = multiply(q, from_rotation_vector(w * dt))
    return rotation_angle_rad(q)


def test_integral_removes_the_constant_disturbance_offset() -> None:
    """PD alone keeps d/K_p of error; PID converges to zero error."""
    assert settle(QuaternionPd(QuaternionPdParams.from_bandwidth(INERTIA, WN, ZETA))) > 1e-3
    assert settle(pid()) < OFFSET_TOL_RAD


def test_no_integration_outside_the_band() -> None:
    """A 10° error (a slew) leaves the integral at zero."""
    ctl = pid(band_deg=1.0)
    q = from_rotation_vector(np.array([math.radians(10.0), 0.0, 0.0]))
    for k in range(100):
        ctl.torque_B_Nm(k * DT_NS, q, ZERO, identity(), ZERO)
    assert not ctl.x_integral.any()


def test_integral_torque_is_clamped_and_reset() -> None:
    """The integral torque never exceeds its clamp; reset forgets it."""
    clamp = 0.01
    ctl = pid(band_deg=5.0, clamp=clamp, ti=0.1)
    q = from_rotation_vector(np.array([math.radians(0.5), 0.0, 0.0]))
    pd_only = QuaternionPd(ctl.params.pd).torque_B_Nm(0, q, ZERO, identity(), ZERO)
    for k in range(500):
        tau = ctl.torque_B_Nm(k * DT_NS, q, ZERO, identity(), ZERO)
    assert abs(tau[0] - pd_only[0]) == pytest.approx(clamp)
    ctl.reset()
    assert not ctl.x_integral.any()


def test_bad_settings_are_named() -> None:
    """A non-positive integral time raises ConfigError naming it."""
    pd = QuaternionPdParams.from_bandwidth(INERTIA, WN, ZETA)
    with pytest.raises(ConfigError) as err:
        QuaternionPidParams(pd, 0.0, 0.01, 1.0)
    assert err.value.key == "integral_time_s"
