"""Step C: the stopping position moved to the target for the planned stop angle."""

from __future__ import annotations

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.control.underactuated.invariants import (
    TWO_PI,
    spin_angle_rad,
    stopping_velocity_m_s,
    unwrap,
)
from flight_sw.control.underactuated.step_a import StepA, StepAParams
from flight_sw.control.underactuated.step_b import Phase as PhaseB
from flight_sw.control.underactuated.step_b import StepB, StepBParams
from flight_sw.control.underactuated.step_c import Phase, StepC, StepCParams, choose_stop_turn
from tests.flight_sw.control.underactuated import ffrb_reference as ref

SPIN_RAD_S = -0.2
PSI0_RAD = 0.3
STOP_TURNS_AHEAD = 40
STEP_C_TIME_S = 1500.0


@pytest.mark.slow
@pytest.mark.parametrize("z_stop0_m", [0.8, -0.5])
def test_stopping_position_reaches_zero(z_stop0_m: float) -> None:
    """From Z = 0.8 m and −0.5 m with V_s = 0: |Z| and |V_s| within the tolerances, and
    the stop angle still ahead of the spin."""
    thr = ref.vehicle()
    kappa = thr.kappa_m_s_per_rad_s
    psi_f = PSI0_RAD - STOP_TURNS_AHEAD * TWO_PI
    plant = ref.Plant(ref.spin_dcm(PSI0_RAD), np.array([0.0, 0.0, SPIN_RAD_S]),
                      np.array([0.0, 0.0, z_stop0_m + kappa * (PSI0_RAD - psi_f)]),
                      np.array([0.0, 0.0, kappa * SPIN_RAD_S]), substeps=1)
    step_b = StepB(thr, StepA(thr, StepAParams()), StepBParams(), ref.PERIOD_S)
    step_c = StepC(step_b, StepCParams(), ref.PERIOD_S)
    step_c.start(psi_f)
    state = {"psi": PSI0_RAD}

    def law(p: ref.Plant) -> np.ndarray:
        q = p.q_BR()
        state["psi"] = unwrap(state["psi"], spin_angle_rad(q))
        return step_c.torque_B_Nm(p.t, q, p.w, state["psi"], p.r[2], p.v[2])

    thrusts = np.array(plant.run(law, STEP_C_TIME_S, lambda _p: step_c.phase is Phase.DONE))
    psi = unwrap(state["psi"], spin_angle_rad(plant.q_BR()))  # the plant stepped once more
    assert step_c.phase is Phase.DONE
    assert abs(step_c.z_stop_m(plant.r[2], psi)) <= step_c.p.position_tol_m
    v_stop = stopping_velocity_m_s(plant.v[2], plant.w[2], kappa)
    assert abs(v_stop) <= step_b.p.velocity_tol_m_s
    assert psi > psi_f and thrusts.min() >= -1e-9


def test_params_refuse_bad_values() -> None:
    """Tolerance, move time and speed must be positive; the stop angle finite."""
    with pytest.raises(ConfigError, match="move_time_s"):
        StepCParams(move_time_s=-1.0)
    thr = ref.vehicle()
    step_b = StepB(thr, StepA(thr, StepAParams()), StepBParams(), ref.PERIOD_S)
    with pytest.raises(ConfigError, match="psi_f_rad"):
        StepC(step_b, StepCParams(), ref.PERIOD_S).start(float("inf"))


KAPPA_M = 0.285
RESERVE_TURNS = 4.0
MAX_SPEED_M_S = 0.08
SPIN_CHOICE_RAD_S = -0.15


def _z_n(psi: float, z: float, n: int) -> float:
    """Textbook Z for stop turn n (eqs. 28–32 with ψ_t = 2πn)."""
    return z - KAPPA_M * (psi - TWO_PI * n)


def _left_s(psi: float, n: int) -> float:
    return (psi - TWO_PI * n - RESERVE_TURNS * TWO_PI) / abs(SPIN_CHOICE_RAD_S)


def _z_for(psi: float, z_stop_m: float, n: int) -> float:
    """The z at which stop turn n's Z is ``z_stop_m``."""
    return z_stop_m + KAPPA_M * (psi - TWO_PI * n)


@pytest.mark.parametrize("v_stop_m_s", [0.05, -0.05])
def test_stop_turn_rides_the_drift_it_has(v_stop_m_s: float) -> None:
    """V_s carrying Z_n to 0 within the earliest turn's time: that turn, no go kick, the
    move time −Z_n/V_s."""
    psi, first = 3.0, -10
    z = _z_for(psi, -10.0 * np.sign(v_stop_m_s), first)
    n, move_s = choose_stop_turn(psi, z, SPIN_CHOICE_RAD_S, v_stop_m_s, KAPPA_M, first,
                                 RESERVE_TURNS, MAX_SPEED_M_S)
    assert n == first and move_s == pytest.approx(10.0 / abs(v_stop_m_s))
    assert move_s <= _left_s(psi, n)


@pytest.mark.parametrize("v_stop_m_s", [0.005, 0.1])
def test_stop_turn_does_not_ride_a_drift_too_slow_or_too_fast(v_stop_m_s: float) -> None:
    """Z_n of the sign the drift closes, but the drift too slow to close it in time
    (5 mm/s) or faster than Step C's largest speed (0.1 m/s): Step C's own speed."""
    psi, first = 3.0, -10
    z = _z_for(psi, -10.0, first)
    n, move_s = choose_stop_turn(psi, z, SPIN_CHOICE_RAD_S, v_stop_m_s, KAPPA_M, first,
                                 RESERVE_TURNS, MAX_SPEED_M_S)
    assert move_s is None
    assert n == first and abs(_z_n(psi, z, n)) <= MAX_SPEED_M_S * _left_s(psi, n)


def test_stop_turn_at_its_own_speed_against_the_drift() -> None:
    """V_s moving Z away: the earliest turn Step C's largest speed reaches (a few turns
    after the first: Z_n shrinks by 2πκ a turn while the time grows), no move time."""
    psi, first = 3.0, -10
    z = _z_for(psi, 30.0, first)
    n, move_s = choose_stop_turn(psi, z, SPIN_CHOICE_RAD_S, 0.05, KAPPA_M, first,
                                 RESERVE_TURNS, MAX_SPEED_M_S)
    assert move_s is None and n < first
    assert abs(_z_n(psi, z, n)) <= MAX_SPEED_M_S * _left_s(psi, n)
    assert all(abs(_z_n(psi, z, m)) > MAX_SPEED_M_S * _left_s(psi, m)
               for m in range(first, n, -1))


def _step_c() -> StepC:
    thr = ref.vehicle()
    step_b = StepB(thr, StepA(thr, StepAParams()), StepBParams(), ref.PERIOD_S)
    return StepC(step_b, StepCParams(), ref.PERIOD_S)


def test_first_round_takes_the_move_time_it_is_given() -> None:
    """start(move_time_s=T): the first go asks V_s = −Z/T (in single spin, far from the stop)."""
    step_c, psi, move_s = _step_c(), 0.0, 200.0
    z = 0.5 + step_c.thr.kappa_m_s_per_rad_s * 40 * TWO_PI  # Z = 0.5 m, 40 turns ahead
    step_c.start(psi - 40 * TWO_PI, move_time_s=move_s)
    w = np.array([0.0, 0.0, SPIN_CHOICE_RAD_S])
    v_z = step_c.thr.kappa_m_s_per_rad_s * SPIN_CHOICE_RAD_S  # V_s = 0
    step_c.torque_B_Nm(0.0, ref.q_BR_of(ref.spin_dcm(psi)), w, psi, z, v_z)
    target = -step_c.z_stop_m(z, psi) / move_s
    assert step_c.phase is Phase.GO and step_c.b.target_m_s == pytest.approx(target)


@pytest.mark.parametrize("coast_fraction", [-0.5, 0.5])
def test_no_round_without_time_for_it(coast_fraction: float) -> None:
    """Less than a settle's time left before the reserve (inside it, or a half settle
    before it): Step C leaves Z as it is, says so, and starts no Step B sequence."""
    step_c, psi = _step_c(), 0.0
    coast_rad = coast_fraction * step_c.p.settle_s * abs(SPIN_CHOICE_RAD_S)
    step_c.start(psi - step_c.p.reserve_turns * TWO_PI - coast_rad)
    w = np.array([0.0, 0.0, SPIN_CHOICE_RAD_S])
    step_c.torque_B_Nm(0.0, ref.q_BR_of(ref.spin_dcm(psi)), w, psi, 1.0, 0.0)
    assert step_c.phase is Phase.DONE and step_c.out_of_turns
    assert step_c.b.phase is PhaseB.DONE and step_c.b.kicks == 0
