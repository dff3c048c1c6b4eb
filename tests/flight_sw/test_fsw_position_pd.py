"""Position PD: force towards the reference in N, in body axes, with force and speed limits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.control.position_pd import PositionPd, PositionPdParams
from flight_sw.quaternion import from_rotation_vector, identity, to_dcm

MASS_KG = 100.0
WN_RAD_S = 0.4
ZETA = 1.0
FORCE_TOL_N = 1e-12
ZERO = np.zeros(3)


def test_bandwidth_gains() -> None:
    """K_p = m ω_n², K_d = 2 ζ ω_n m on every axis."""
    p = PositionPdParams.from_bandwidth(MASS_KG, WN_RAD_S, ZETA)
    assert p.kp_N_m == pytest.approx((MASS_KG * WN_RAD_S**2,) * 3)
    assert p.kd_N_s_m == pytest.approx((2 * ZETA * WN_RAD_S * MASS_KG,) * 3)


def test_force_pulls_towards_the_reference_and_damps_velocity() -> None:
    """At identity attitude F_B = −K_p (r − r_ref) − K_d (v − v_ref)."""
    pd = PositionPd(PositionPdParams((2.0, 3.0, 4.0), (10.0, 20.0, 30.0)))
    f = pd.force_B_N(
        0, identity(), np.array([1.0, -1.0, 0.5]), np.array([0.1, 0.0, -0.1]), ZERO, ZERO
    )
    assert f == pytest.approx([-2.0 - 1.0, 3.0, -2.0 + 3.0], abs=FORCE_TOL_N)


def test_force_is_expressed_in_body_axes() -> None:
    """After a 90° yaw the force towards the reference is C(q_BN) F_N, same magnitude."""
    pd = PositionPd(PositionPdParams((1.0, 1.0, 1.0), (0.0, 0.0, 0.0)))
    q = from_rotation_vector(np.array([0.0, 0.0, math.pi / 2]))
    f_b = pd.force_B_N(0, q, np.array([1.0, 0.0, 0.0]), ZERO, ZERO, ZERO)
    assert f_b == pytest.approx(to_dcm(q) @ np.array([-1.0, 0.0, 0.0]), abs=FORCE_TOL_N)
    assert np.linalg.norm(f_b) == pytest.approx(1.0)


def test_force_magnitude_is_limited_direction_preserved() -> None:
    """A large error gives |F| = max_force_N along the unlimited direction."""
    pd = PositionPd(PositionPdParams((10.0, 10.0, 10.0), (0.0, 0.0, 0.0), max_force_N=3.0))
    f = pd.force_N_N(np.array([3.0, 4.0, 0.0]), ZERO, ZERO, ZERO)
    assert np.linalg.norm(f) == pytest.approx(3.0)
    assert f / np.linalg.norm(f) == pytest.approx([-0.6, -0.8, 0.0])


def test_speed_limit_holds_the_approach_speed() -> None:
    """Far away, moving at v_max towards the reference, the force is zero on that axis."""
    v_max = 0.05
    p = PositionPdParams.from_bandwidth(MASS_KG, WN_RAD_S, ZETA, max_speed_m_s=v_max)
    pd = PositionPd(p)
    f = pd.force_N_N(np.array([20.0, 0.0, 0.0]), np.array([-v_max, 0.0, 0.0]), ZERO, ZERO)
    assert f == pytest.approx([0.0, 0.0, 0.0], abs=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"kp_N_m": (1.0, -1.0, 1.0), "kd_N_s_m": (1.0, 1.0, 1.0)}, "kp_N_m"),
        ({"kp_N_m": (1.0, 1.0, 1.0), "kd_N_s_m": (1.0, 1.0)}, "kd_N_s_m"),
        (
            {"kp_N_m": (1.0, 1.0, 1.0), "kd_N_s_m": (1.0, 1.0, 1.0), "max_force_N": 0.0},
            "max_force_N",
        ),
    ],
)
def test_bad_parameters_are_named(kwargs: dict[str, object], key: str) -> None:
    """Invalid gains and limits raise ConfigError naming the parameter."""
    with pytest.raises(ConfigError) as err:
        PositionPdParams(**kwargs)  # type: ignore[arg-type]
    assert err.value.key == key
