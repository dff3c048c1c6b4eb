"""The seed-004 supervisor from rest to rest at the target, on the independent plant: Step A,
the drift stopped, the x–y transfer with Step C moving the stopping position alongside,
then Step D's final turn (issue 20's ideal-thruster tolerances)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dbc.errors import ConfigError
from flight_sw.control.underactuated.supervisor import Mode, Supervisor, SupervisorParams
from tests.flight_sw.control.underactuated import ffrb_reference as ref

# seed 004 §4: case 2 starts at another attitude, case 3 at another position (ours: the
# paper's initial states were lost from the text); all at rest, the target at the origin
CASES = {
    "case 1": ((0.0, 30.0, 60.0), (0.0, 0.0, 0.0)),
    "case 2": ((120.0, -40.0, 150.0), (0.0, 0.0, 0.0)),
    "case 3": ((0.0, 30.0, 60.0), (-2.0, 1.0, -0.5)),
}
RUN_LIMIT_S = 6000.0
ATTITUDE_TOL_DEG = 0.5
RATE_TOL_DEG_S = 0.05
POSITION_TOL_M = 0.02
VELOCITY_TOL_M_S = 1e-3
FIRST_MODES = [Mode.A, Mode.STOP_DRIFT, Mode.TRANSFER]


@pytest.mark.slow
@pytest.mark.parametrize("case", sorted(CASES))
def test_reaches_the_target_at_rest(case: str) -> None:
    """Each case ends at rest on the target within issue 20's tolerances, every thrust ≥ 0,
    through Step A, the drift stop and the transfer, with Step D's final turn last."""
    euler_zyx_deg, r0_m = CASES[case]
    sup = Supervisor(ref.vehicle(), SupervisorParams(), ref.PERIOD_S)
    c0 = Rotation.from_euler("ZYX", euler_zyx_deg, degrees=True).as_matrix()
    plant = ref.Plant(c0, np.zeros(3), np.array(r0_m), np.zeros(3), substeps=1)
    thrusts = np.array(plant.run(lambda p: sup.torque_B_Nm(p.t, p.q_BR(), p.w, p.r, p.v),
                                 RUN_LIMIT_S, lambda _p: sup.mode is Mode.DONE))
    modes = [Mode(name) for _, name in sup.switches]
    assert modes[:3] == FIRST_MODES and modes[-2:] == [Mode.D, Mode.DONE], modes
    attitude_deg = math.degrees(Rotation.from_matrix(plant.c).magnitude())
    assert attitude_deg <= ATTITUDE_TOL_DEG
    assert math.degrees(float(np.linalg.norm(plant.w))) <= RATE_TOL_DEG_S
    assert float(np.linalg.norm(plant.r)) <= POSITION_TOL_M
    assert float(np.linalg.norm(plant.v)) <= VELOCITY_TOL_M_S
    assert thrusts.min() >= -1e-9


def test_params_refuse_bad_values() -> None:
    """Margins and tolerances are checked by name."""
    with pytest.raises(ConfigError, match="stop_reserve_turns"):
        SupervisorParams(stop_reserve_turns=1.0)
    with pytest.raises(ConfigError, match="final_reserve_turns"):
        SupervisorParams(final_reserve_turns=30.0)
    with pytest.raises(ConfigError, match="coarse_z_tol_m"):
        SupervisorParams(coarse_z_tol_m=0.0)
    with pytest.raises(ConfigError, match="z_tol_m"):
        SupervisorParams(z_tol_m=-1.0)
