"""Step B: repeated planned disturbances bring the stopping velocity to its target."""

from __future__ import annotations

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.control.underactuated.invariants import (
    spin_angle_rad,
    stopping_velocity_m_s,
    unwrap,
)
from flight_sw.control.underactuated.step_a import StepA, StepAParams
from flight_sw.control.underactuated.step_b import Phase, StepB, StepBParams
from tests.flight_sw.control.underactuated import ffrb_reference as ref

SPIN_RAD_S = -0.2
PSI0_RAD = 0.3
STEP_B_TIME_S = 600.0
MAX_KICKS = 8
SPIN_KEPT_FRACTION = 0.75  # of the spin at the start


def run_step_b(v_stop0_m_s: float, target_m_s: float = 0.0):
    """Step B on the DCM plant from single spin with stopping velocity ``v_stop0_m_s``."""
    thr = ref.vehicle()
    kappa = thr.kappa_m_s_per_rad_s
    plant = ref.Plant(ref.spin_dcm(PSI0_RAD), np.array([0.0, 0.0, SPIN_RAD_S]), np.zeros(3),
                      np.array([0.001, -0.002, v_stop0_m_s + kappa * SPIN_RAD_S]),
                      substeps=1)
    hold = StepA(thr, StepAParams())
    step_b = StepB(thr, hold, StepBParams(), ref.PERIOD_S)
    step_b.start(target_m_s)
    state = {"psi": PSI0_RAD}

    def law(p: ref.Plant) -> np.ndarray:
        q = p.q_BR()
        state["psi"] = unwrap(state["psi"], spin_angle_rad(q))
        return step_b.torque_B_Nm(p.t, q, p.w, state["psi"], p.v[2])

    thrusts = plant.run(law, STEP_B_TIME_S, lambda _p: step_b.phase is Phase.DONE)
    return plant, step_b, np.array(thrusts), stopping_velocity_m_s(plant.v[2], plant.w[2],
                                                                   kappa)


@pytest.mark.parametrize("v_stop0_m_s", [0.06, pytest.param(-0.085, marks=pytest.mark.slow)])
def test_stopping_velocity_reaches_zero(v_stop0_m_s: float) -> None:
    """From ±tens of mm/s (what Step A leaves): V_s within the tolerance in a few kicks,
    the spin mostly kept, thrusts ≥ 0."""
    plant, step_b, thrusts, v_stop = run_step_b(v_stop0_m_s)
    assert step_b.phase is Phase.DONE, f"V_s {v_stop:.2e} m/s after {plant.t:.0f} s"
    assert abs(v_stop) <= step_b.p.velocity_tol_m_s
    assert 1 <= step_b.kicks <= MAX_KICKS
    assert plant.w[2] <= SPIN_KEPT_FRACTION * SPIN_RAD_S
    assert thrusts.min() >= -1e-9


def test_already_at_target_does_not_fire_a_kick() -> None:
    """V_s already within the tolerance: done at the first settled cycle, no kick."""
    _plant, step_b, _thrusts, v_stop = run_step_b(0.0)
    assert step_b.phase is Phase.DONE and step_b.kicks == 0 and v_stop == pytest.approx(0.0)


def test_params_refuse_bad_values() -> None:
    """Tolerances must be positive; the target must be a finite number."""
    with pytest.raises(ConfigError, match="velocity_tol_m_s"):
        StepBParams(velocity_tol_m_s=0.0)
    step_b = StepB(ref.vehicle(), StepA(ref.vehicle(), StepAParams()), StepBParams(),
                   ref.PERIOD_S)
    with pytest.raises(ConfigError, match="target_m_s"):
        step_b.start(float("nan"))
