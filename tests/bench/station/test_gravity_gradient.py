"""Gravity-gradient torque: zero along a principal axis, known value at 45 degrees."""

from __future__ import annotations

import math

import pytest

from bench.station.dynamics.hcw import mean_motion_rad_s
from bench.station.dynamics.rigid_body import QUAT_IDENTITY, MassProperties, quat_from_axis_angle
from bench.station.environment.gravity_gradient import (
    GravityGradient,
    GravityGradientParams,
    gravity_gradient_torque_B,
)

ORBIT_RADIUS_M = 7_000_000.0
JX, JY, JZ = 25.0, 20.0, 15.0  # seed 001 §5
ABS_TOL_NM = 1e-18
REL_TOL = 1e-12


def _mp() -> MassProperties:
    return MassProperties(100.0, ((JX, 0.0, 0.0), (0.0, JY, 0.0), (0.0, 0.0, JZ)))


def test_zero_for_principal_axis_along_radial() -> None:
    """Body aligned with I at t = 0 (x_B radial), and at t = T/4 after turning with the orbit."""
    gg = GravityGradient(GravityGradientParams(ORBIT_RADIUS_M))
    assert gg.wrench_B(0.0, QUAT_IDENTITY, _mp()) == pytest.approx((0.0,) * 6, abs=ABS_TOL_NM)
    t = math.pi / 2 / gg.n_rad_s  # radial is now +y_I; turn the body by 90 deg about z
    q = quat_from_axis_angle((0.0, 0.0, 1.0), math.pi / 2)
    assert gg.wrench_B(t, q, _mp()) == pytest.approx((0.0,) * 6, abs=1e-16)


def test_known_value_at_45_degrees_about_z() -> None:
    """45 deg about z: r̂_B = (c, −s, 0) and τ_z = 3n² c s (Jx − Jy), the other components 0."""
    n = mean_motion_rad_s(ORBIT_RADIUS_M)
    q = quat_from_axis_angle((0.0, 0.0, 1.0), math.pi / 4)
    w = GravityGradient(GravityGradientParams(ORBIT_RADIUS_M)).wrench_B(0.0, q, _mp())
    c = s = math.sqrt(0.5)
    # r̂ = (c, −s, 0), J r̂ = (Jx c, −Jy s, 0): (r̂ × J r̂)_z = c(−Jy s) − (−s)(Jx c) = cs(Jx − Jy)
    expected_z = 3.0 * n * n * c * s * (JX - JY)
    assert w[5] == pytest.approx(expected_z, rel=REL_TOL)
    assert w[:5] == pytest.approx((0.0,) * 5, abs=ABS_TOL_NM)


def test_torque_is_orthogonal_to_radial() -> None:
    """r̂ · τ = 0 for any radial direction (a cross product with r̂)."""
    n = 1e-3
    r = (0.48, -0.6, 0.64)
    tq = gravity_gradient_torque_B(n, r, _mp())
    assert sum(a * b for a, b in zip(r, tq, strict=True)) == pytest.approx(0.0, abs=1e-20)
