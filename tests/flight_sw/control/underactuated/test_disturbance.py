"""Steps B/C's planned disturbance: on an independent plant it moves the stopping velocity
by what was asked and returns to single spin, at the least spin the linear program finds."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.control.underactuated.disturbance import (
    DisturbanceParams,
    end_rows,
    plan_kick,
)
from flight_sw.control.underactuated.invariants import stopping_velocity_m_s
from flight_sw.control.underactuated.step_a import tilt_rad
from tests.flight_sw.control.underactuated import ffrb_reference as ref

SPIN_RAD_S = -0.2
PSI0_RAD = 0.3
DV_STOP_M_S = 0.01
# first-order plan against the full nonlinear plant, for a 10 mm/s kick
DV_REL_TOL = 0.1
END_TILT_MAX_RAD = math.radians(0.5)
END_RATE_MAX_RAD_S = 2e-3
END_VXY_MAX_M_S = 1e-3
LP_REL_TOL = 1e-6  # HiGHS's optimality, relative
THRUST_LIMIT_N = 0.5


def _play(kick) -> ref.Plant:
    plant = ref.Plant(ref.spin_dcm(PSI0_RAD), np.array([0.0, 0.0, SPIN_RAD_S]), np.zeros(3),
                      np.zeros(3))
    n = round(kick.duration_s / ref.PERIOD_S)
    for k in range(n):
        plant.step(kick.thrusts_at((k + 0.5) * ref.PERIOD_S))
    return plant


@pytest.mark.parametrize("dv_m_s", [DV_STOP_M_S, -DV_STOP_M_S])
def test_kick_moves_the_stopping_velocity_and_returns_to_single_spin(dv_m_s: float) -> None:
    """Played on the DCM plant, the kick changes V_s by the request within 10 %, ends with
    axis III within 0.5° of z, transverse rates ≤ 2 mrad/s and x–y velocity ≤ 1 mm/s."""
    thr = ref.vehicle()
    kick = plan_kick(thr, DisturbanceParams(), ref.PERIOD_S, SPIN_RAD_S, PSI0_RAD, dv_m_s)
    plant = _play(kick)
    kappa = thr.kappa_m_s_per_rad_s
    dv_stop = (stopping_velocity_m_s(plant.v[2], plant.w[2], kappa)
               - stopping_velocity_m_s(0.0, SPIN_RAD_S, kappa))
    assert dv_stop == pytest.approx(dv_m_s, rel=DV_REL_TOL)
    assert tilt_rad(plant.q_BR()) <= END_TILT_MAX_RAD
    assert math.hypot(plant.w[0], plant.w[1]) <= END_RATE_MAX_RAD_S
    assert math.hypot(plant.v[0], plant.v[1]) <= END_VXY_MAX_M_S
    assert np.min(kick.thrusts_N) >= 0.0
    assert 0.0 < kick.domega_III_rad_s < abs(SPIN_RAD_S)


def test_plan_meets_its_linear_end_conditions() -> None:
    """The thrusts satisfy the first-order end state exactly: rates, momentum and x–y
    velocity unchanged, ΔV_s as asked."""
    thr = ref.vehicle()
    p = DisturbanceParams()
    kick = plan_kick(thr, p, ref.PERIOD_S, SPIN_RAD_S, PSI0_RAD, DV_STOP_M_S)
    rows = end_rows(thr, SPIN_RAD_S, PSI0_RAD, kick.block_s, len(kick.thrusts_N))
    end = rows @ kick.thrusts_N.reshape(-1)
    expected = np.zeros(len(end))
    expected[4] = DV_STOP_M_S
    np.testing.assert_allclose(end, expected, atol=1e-9)


def test_spin_cost_scales_with_the_request() -> None:
    """The least-spin program is homogeneous: twice the ΔV_s costs twice the spin."""
    thr = ref.vehicle()
    p = DisturbanceParams()
    one = plan_kick(thr, p, ref.PERIOD_S, SPIN_RAD_S, PSI0_RAD, DV_STOP_M_S / 2)
    two = plan_kick(thr, p, ref.PERIOD_S, SPIN_RAD_S, PSI0_RAD, DV_STOP_M_S)
    assert two.domega_III_rad_s == pytest.approx(2 * one.domega_III_rad_s, rel=LP_REL_TOL)


def test_thrust_limit_is_kept_and_costs_no_less() -> None:
    """With real valves' thrust limit no block exceeds it, and the spin cost is at least
    the unbounded one."""
    thr = ref.vehicle()
    free = plan_kick(thr, DisturbanceParams(), ref.PERIOD_S, SPIN_RAD_S, PSI0_RAD,
                     DV_STOP_M_S)
    bounded = plan_kick(thr, DisturbanceParams(max_thrust_N=THRUST_LIMIT_N), ref.PERIOD_S,
                        SPIN_RAD_S, PSI0_RAD, DV_STOP_M_S)
    assert np.max(bounded.thrusts_N) <= THRUST_LIMIT_N * (1 + LP_REL_TOL)
    assert np.max(free.thrusts_N) > THRUST_LIMIT_N
    assert bounded.domega_III_rad_s >= free.domega_III_rad_s * (1 - LP_REL_TOL)


def test_request_is_clipped_to_the_largest_kick() -> None:
    """A request beyond ``max_dv_stop_m_s`` is planned at that limit, with its sign."""
    p = DisturbanceParams(max_dv_stop_m_s=DV_STOP_M_S)
    kick = plan_kick(ref.vehicle(), p, ref.PERIOD_S, SPIN_RAD_S, PSI0_RAD, -5 * DV_STOP_M_S)
    assert kick.dv_stop_m_s == -DV_STOP_M_S


def test_no_spin_and_bad_parameters_are_refused() -> None:
    """Without a spin there is no single spin to disturb; parameters are checked."""
    with pytest.raises(ConfigError, match="omega_III_rad_s"):
        plan_kick(ref.vehicle(), DisturbanceParams(), ref.PERIOD_S, 0.0, 0.0, DV_STOP_M_S)
    with pytest.raises(ConfigError, match="block_periods"):
        DisturbanceParams(block_periods=0)
    with pytest.raises(ConfigError, match="max_thrust_N"):
        DisturbanceParams(max_thrust_N=-1.0)
