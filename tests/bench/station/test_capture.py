"""Capture (mass-property change): momentum about the CoM conserved; thruster arms re-referred."""

from __future__ import annotations

import pytest

from bench.station.dynamics.capture import capture_state
from bench.station.dynamics.rigid_body import (
    MassProperties,
    Vec3,
    angular_momentum_N,
    make_state,
    quat_normalize,
    rotate_B_to_N,
)
from bench.station.dynamics.translation import InertialTranslation
from bench.station.valves.params import ValveParams
from bench.station.valves.thruster_set import ThrusterGeometry, ThrusterSet

REL_TOL = 1e-12
ABS_TOL = 1e-12
MP_BEFORE = MassProperties(95.0, ((17.0, 0.0, 0.0), (0.0, 17.0, 0.0), (0.0, 0.0, 22.0)))
MP_AFTER = MassProperties(140.0, ((25.0, 0.5, 0.0), (0.5, 20.0, 0.0), (0.0, 0.0, 15.0)))
COM_SHIFT_B_M: Vec3 = (0.1, -0.2, 0.05)


def _cross(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _h_about_point(state: tuple[float, ...], mp: MassProperties, point_N: Vec3) -> Vec3:
    """Angular momentum about a fixed point: H_cm + (r − p) × m v (inertial axes)."""
    h = angular_momentum_N(state, mp)
    r = (state[7] - point_N[0], state[8] - point_N[1], state[9] - point_N[2])
    m = mp.mass_kg
    t = _cross(r, (m * state[10], m * state[11], m * state[12]))
    return (h[0] + t[0], h[1] + t[1], h[2] + t[2])


def test_momenta_conserved_across_capture() -> None:
    """Linear momentum and angular momentum about the new CoM (hence any point) are unchanged."""
    s0 = make_state(quat_normalize((0.9, 0.1, -0.3, 0.2)), (0.05, -0.02, 0.03), (1.0, 2.0, 3.0),
                    (0.02, -0.01, 0.03))
    s1 = capture_state(s0, 0.0, MP_BEFORE, MP_AFTER, COM_SHIFT_B_M, InertialTranslation())
    p0 = [MP_BEFORE.mass_kg * x for x in s0[10:13]]
    p1 = [MP_AFTER.mass_kg * x for x in s1[10:13]]
    assert p1 == pytest.approx(p0, rel=REL_TOL)
    origin = (0.0, 0.0, 0.0)
    assert _h_about_point(s1, MP_AFTER, origin) == pytest.approx(
        _h_about_point(s0, MP_BEFORE, origin), abs=ABS_TOL)
    dc_N = rotate_B_to_N(s0[0:4], COM_SHIFT_B_M)  # type: ignore[arg-type]
    assert s1[7:10] == pytest.approx([a + b for a, b in zip(s0[7:10], dc_N, strict=True)])
    assert s1[0:4] == s0[0:4]


def test_free_body_angular_momentum_about_com_conserved() -> None:
    """At rest translationally, H_B = J ω is the same before and after: ω⁺ = J⁺⁻¹ J⁻ ω⁻."""
    s0 = make_state(omega_BN_B=(0.1, 0.2, -0.1))
    s1 = capture_state(s0, 0.0, MP_BEFORE, MP_AFTER, COM_SHIFT_B_M, InertialTranslation())
    assert angular_momentum_N(s1, MP_AFTER) == pytest.approx(
        angular_momentum_N(s0, MP_BEFORE), rel=REL_TOL)


def test_thruster_torque_arms_follow_the_com() -> None:
    """After set_com_offset(c) the torque arm of a thruster is (r − c) × d."""
    r, d = (0.5, 0.0, 0.0), (0.0, 1.0, 0.0)
    ts = ThrusterSet([ThrusterGeometry(r, d)], ValveParams(5.0, 220.0, 0.0, 0.0, 1e-6, 1e-6, 0.0))
    assert ts.geometries[0].torque_arm_B_m == pytest.approx((0.0, 0.0, 0.5))
    c = (0.2, 0.0, 0.1)
    ts.set_com_offset(c)
    rc = (r[0] - c[0], r[1] - c[1], r[2] - c[2])
    assert ts.geometries[0].torque_arm_B_m == pytest.approx(_cross(rc, d))
    ts.set_com_offset((0.0, 0.0, 0.0))  # not cumulative: back to the reference point
    assert ts.geometries[0].torque_arm_B_m == pytest.approx((0.0, 0.0, 0.5))
