"""Step D: the planned de-spin ends on the target angle with x–y at the target."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.control.underactuated.invariants import (
    TWO_PI,
    planned_stop_turn,
    spin_angle_rad,
    unwrap,
)
from flight_sw.control.underactuated.step_a import StepA, StepAParams
from flight_sw.control.underactuated.step_d import Phase, StepD, StepDParams, next_angle_below
from tests.flight_sw.control.underactuated import ffrb_reference as ref

# issue 20's acceptance for ideal thrusters
ATTITUDE_TOL_DEG = 0.5
RATE_TOL_DEG_S = 0.05
POSITION_TOL_M = 0.02
VELOCITY_TOL_M_S = 1e-3
TRANSFER_TURNS = 40  # turns the offset case's transfer to the aim point may take


def _close_loop(plant: ref.Plant, psi0: float, psi_f: float, duration_s: float):
    thr = ref.vehicle()
    hold = StepA(thr, StepAParams())
    step_d = StepD(thr, StepDParams(), ref.PERIOD_S)
    step_d.start(psi_f)
    state = {"psi": psi0}

    def law(p: ref.Plant) -> np.ndarray:
        q = p.q_BR()
        state["psi"] = unwrap(state["psi"], spin_angle_rad(q))
        t3 = step_d.torque_III_Nm(state["psi"], p.w[2], p.r[:2], p.v[:2])
        if step_d.phase is Phase.DONE:
            return np.array([0.0, 0.0, t3])  # the last sliver, then nothing
        return hold.track(p.w, hold.pointing_rate(q), t3)

    thrusts = plant.run(law, duration_s, lambda _p: step_d.phase is Phase.DONE)
    thrusts += plant.run(law, 1.0)  # the stop, then coast
    return step_d, np.array(thrusts)


def _assert_at_target(plant: ref.Plant, thrusts: np.ndarray) -> None:
    angle = math.degrees(math.acos(min(1.0, (np.trace(plant.c) - 1.0) / 2.0)))
    assert angle <= ATTITUDE_TOL_DEG
    assert math.degrees(np.linalg.norm(plant.w)) <= RATE_TOL_DEG_S
    assert np.linalg.norm(plant.r) <= POSITION_TOL_M
    assert np.linalg.norm(plant.v) <= VELOCITY_TOL_M_S
    assert thrusts.min() >= -1e-9  # push only; and these three are all there are


def test_final_turn_from_the_aim_point_lands_on_target() -> None:
    """Velocity 0 at the aim point one turn before ψ_f: the final turn alone ends there."""
    thr = ref.vehicle()
    w0, psi_f = -0.3, 0.0
    psi0 = psi_f + TWO_PI + 0.01
    planner = StepD(thr, StepDParams(), ref.PERIOD_S)
    planner.start(psi_f)
    kappa = thr.kappa_m_s_per_rad_s
    r0 = np.append(planner.aim_m(), kappa * (psi0 - psi_f))  # z consistent with the stop
    plant = ref.Plant(ref.spin_dcm(psi0), np.array([0.0, 0.0, w0]), r0,
                      np.array([0.0, 0.0, kappa * w0]), substeps=1)
    step_d, thrusts = _close_loop(plant, psi0, psi_f, 400.0)
    assert step_d.phase is Phase.DONE and step_d.sequences == 0
    _assert_at_target(plant, thrusts)


@pytest.mark.slow
def test_step_d_from_an_offset_and_drift() -> None:
    """From 5.7 m off the aim with 5.4 mm/s of drift: velocity sequences, coast and the
    final turn reach the target within issue 20's tolerances."""
    thr = ref.vehicle()
    kappa = thr.kappa_m_s_per_rad_s
    psi0, w0 = 1.0, -0.3
    psi_f = TWO_PI * planned_stop_turn(psi0, 0.0, TRANSFER_TURNS * TWO_PI)
    plant = ref.Plant(ref.spin_dcm(psi0), np.array([0.0, 0.0, w0]),
                      np.array([0.3, -0.2, kappa * (psi0 - psi_f)]),
                      np.array([0.005, 0.002, kappa * w0]), substeps=1)
    step_d, thrusts = _close_loop(plant, psi0, psi_f, 1500.0)
    assert step_d.phase is Phase.DONE and step_d.postponed_turns == 0
    assert step_d.sequences >= 2
    _assert_at_target(plant, thrusts)


def test_lead_time_is_at_least_the_spin_periods() -> None:
    """The transfer's lead is ``transfer_lead_s`` at a fast spin and ``lead_turns`` spin
    periods at a slow one (a sequence waits up to a turn for its start)."""
    p = StepDParams()
    step_d = StepD(ref.vehicle(), p, ref.PERIOD_S)
    fast = 2.0 * p.lead_turns * TWO_PI / p.transfer_lead_s  # rad/s: periods well inside
    assert step_d.lead_s(-fast) == p.transfer_lead_s
    slow = 0.05
    assert step_d.lead_s(-slow) == pytest.approx(p.lead_turns * TWO_PI / slow)


def test_a_small_offset_still_gets_a_sequence() -> None:
    """An offset just outside the position tolerance, at rest, at a slow spin: the demanded
    speed is above the velocity tolerance, so a sequence is planned (no dead band)."""
    p = StepDParams()
    step_d = StepD(ref.vehicle(), p, ref.PERIOD_S)
    step_d.start(-1000 * TWO_PI)
    r = step_d.aim_m() + np.array([1.5 * p.position_tol_m, 0.0])
    w3 = -0.05
    assert float(np.linalg.norm(step_d.aim_m() - r)) / step_d.lead_s(w3) < p.velocity_tol_m_s
    step_d.torque_III_Nm(0.0, w3, r, np.zeros(2))
    assert step_d.sequence is not None


def test_a_final_turn_passed_unseen_moves_the_stop_a_turn_later() -> None:
    """Called first after ψ_f + 2π has passed (settled there): no late final turn, the stop
    moves down by whole turns until its final turn is ahead."""
    step_d = StepD(ref.vehicle(), StepDParams(), ref.PERIOD_S)
    psi_f = 0.0
    step_d.start(psi_f)
    psi = psi_f - 0.6 * TWO_PI  # 1.6 turns past the final turn's start
    step_d.torque_III_Nm(psi, -0.1, step_d.aim_m(), np.zeros(2))
    assert step_d.phase is not Phase.FINAL
    assert step_d.postponed_turns == 2 and step_d.psi_f_rad == psi_f - 2 * TWO_PI
    assert step_d.psi_f_rad + TWO_PI < psi


def test_next_angle_below() -> None:
    """The next angle a negative spin reaches, equal to the given one mod 2π."""
    assert next_angle_below(10.0, 1.0) == pytest.approx(10.0 - ((10.0 - 1.0) % TWO_PI))
    assert next_angle_below(1.0, 1.0 + 4 * TWO_PI) == pytest.approx(1.0)
    assert 0.0 <= 3.0 - next_angle_below(3.0, -7.0) < TWO_PI


def test_params_refuse_bad_values() -> None:
    """Tolerances must be positive and the kept spin a fraction."""
    with pytest.raises(ConfigError, match="position_tol_m"):
        StepDParams(position_tol_m=0.0)
    with pytest.raises(ConfigError, match="keep_spin_fraction"):
        StepDParams(keep_spin_fraction=1.0)
