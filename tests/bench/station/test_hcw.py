"""HCW relative translation: RK4 against the closed form; natural periodic orbits stay bounded."""

from __future__ import annotations

import math

import pytest

from bench.station.dynamics.hcw import (
    MU_EARTH_M3_S2,
    SEED000_ORBIT_RADIUS_M,
    HcwParams,
    HcwTranslation,
    hcw_closed_form,
    hill_to_inertial,
    inertial_to_hill,
    mean_motion_rad_s,
)
from bench.station.dynamics.rigid_body import ZERO_WRENCH, MassProperties, make_state
from bench.station.dynamics.stepper import rk4_step_env
from dbc.errors import ConfigError

DT_S = 1.0
HOUR_S = 3600
POS_ABS_TOL_M = 1e-9
VEL_ABS_TOL_M_S = 1e-12
R0_H_M = (-20.0, -10.0, -10.0)  # seed 000 §V initial relative position
V0_H_M_S = (0.01, -0.02, 0.005)
PERIODIC_X0_M = 10.0
BOUND_FACTOR = 2.1  # the natural ellipse spans ±2 x0 along-track


def _mp() -> MassProperties:
    return MassProperties(95.0, ((17.0, 0.0, 0.0), (0.0, 17.0, 0.0), (0.0, 0.0, 22.0)))


def _run(r0: tuple[float, float, float], v0: tuple[float, float, float], n_steps: int,
         hcw: HcwTranslation) -> list[tuple[float, ...]]:
    s = make_state(r_N=r0, v_N=v0)
    out = [s]
    for k in range(n_steps):
        s = rk4_step_env(s, k * DT_S, DT_S, ZERO_WRENCH, ZERO_WRENCH, ZERO_WRENCH, _mp(), hcw)
        out.append(s)
    return out


def test_mean_motion_at_seed000_orbit() -> None:
    """n = sqrt(μ/R³) ≈ 7.29e-5 rad/s at 42,240 km (about 0.0042 deg/s)."""
    n = mean_motion_rad_s(SEED000_ORBIT_RADIUS_M)
    assert n == pytest.approx(math.sqrt(MU_EARTH_M3_S2 / SEED000_ORBIT_RADIUS_M**3))
    assert math.degrees(n) == pytest.approx(0.0042, abs=5e-5)


def test_free_motion_matches_closed_form_over_one_hour() -> None:
    """RK4 (1 s steps) of the HCW equations equals the closed-form solution after 1 h."""
    hcw = HcwTranslation(HcwParams())
    s = _run(R0_H_M, V0_H_M_S, HOUR_S, hcw)[-1]
    r, v = hcw_closed_form(hcw.n_rad_s, R0_H_M, V0_H_M_S, float(HOUR_S))
    assert s[7:10] == pytest.approx(r, abs=POS_ABS_TOL_M)
    assert s[10:13] == pytest.approx(v, abs=VEL_ABS_TOL_M_S)


def test_natural_periodic_orbit_stays_bounded() -> None:
    """ẏ0 = −2 n x0 gives no along-track drift: |y| ≤ 2 x0 and back to x0 after one orbit."""
    hcw = HcwTranslation(HcwParams())
    n = hcw.n_rad_s
    r0 = (PERIODIC_X0_M, 0.0, 0.0)
    v0 = (0.0, -2.0 * n * PERIODIC_X0_M, 0.0)
    period_s = 2.0 * math.pi / n
    r, _v = hcw_closed_form(n, r0, v0, period_s)
    assert r == pytest.approx(r0, abs=1e-6)
    states = _run(r0, v0, HOUR_S, hcw)
    assert max(abs(s[8]) for s in states) <= BOUND_FACTOR * PERIODIC_X0_M
    assert max(abs(s[7]) for s in states) <= PERIODIC_X0_M * (1.0 + 1e-9)


def test_hill_rotation_round_trip_and_direction() -> None:
    """C_HI(t) rotates the radial axis to (cos nt, sin nt, 0) in I, and inverts exactly."""
    n, t = 1e-3, 500.0
    assert hill_to_inertial(n, t, (1.0, 0.0, 0.0)) == pytest.approx(
        (math.cos(n * t), math.sin(n * t), 0.0))
    v = (0.3, -0.2, 0.7)
    assert inertial_to_hill(n, t, hill_to_inertial(n, t, v)) == pytest.approx(v, abs=1e-15)


def test_bad_radius_is_config_error() -> None:
    """A non-positive orbit radius is a ConfigError on orbit_radius_m."""
    with pytest.raises(ConfigError, match="orbit_radius_m"):
        HcwParams(orbit_radius_m=0.0)
