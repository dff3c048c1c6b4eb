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
from flight_sw.control.underactuated.step_b import StepB, StepBParams
from flight_sw.control.underactuated.step_c import Phase, StepC, StepCParams
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
