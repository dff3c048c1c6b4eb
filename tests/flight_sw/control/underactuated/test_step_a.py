"""Step A: from rest to single spin about axis III along the target z (exit condition)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dbc.errors import ConfigError
from flight_sw.control.underactuated.step_a import StepA, StepAParams, tilt_rad
from tests.flight_sw.control.underactuated import ffrb_reference as ref

TILT_DONE_RAD = math.radians(0.05)
RATE_DONE_RAD_S = 1e-4
STEP_A_TIME_S = 150.0


@pytest.mark.parametrize("euler_zyx_deg", [(0.0, 30.0, 60.0), (120.0, -40.0, 150.0),
                                           (-60.0, 80.0, 10.0)])
def test_reaches_single_spin_from_rest(euler_zyx_deg) -> None:
    """From rest at three attitudes: tilt ≤ 0.05°, |ω_I,II| ≤ 1e-4 rad/s, a negative
    spin of at least spin_min, every thrust ≥ 0 on the way."""
    params = StepAParams()
    law = StepA(ref.vehicle(), params)
    c0 = Rotation.from_euler("ZYX", euler_zyx_deg, degrees=True).as_matrix()
    plant = ref.Plant(c0, np.zeros(3), np.zeros(3), np.zeros(3), substeps=2)

    def done(p: ref.Plant) -> bool:
        return (not law.spinning_up and tilt_rad(p.q_BR()) <= TILT_DONE_RAD
                and math.hypot(p.w[0], p.w[1]) <= RATE_DONE_RAD_S)

    thrusts = plant.run(lambda p: law.torque_B_Nm(p.q_BR(), p.w), STEP_A_TIME_S, done)
    assert done(plant), f"not in single spin after {plant.t:.0f} s"
    assert plant.w[2] <= -params.spin_min_rad_s
    assert np.min(thrusts) >= -1e-9


def test_pointing_rate_turns_axis_III_toward_z() -> None:
    """The pointing demand decreases the tilt to first order: d(cos θ)/dt > 0."""
    law = StepA(ref.vehicle(), StepAParams())
    rng = np.random.default_rng(3)
    for _ in range(20):
        c = Rotation.random(random_state=rng).as_matrix()
        q = ref.q_BR_of(c)
        w = np.append(law.pointing_rate(q), 0.0)
        z_B = c.T[:, 2]  # target z in body axes
        assert np.cross(z_B, w)[2] >= -1e-15  # dẑ/dt = ẑ × ω raises its III component


def test_params_refuse_bad_values() -> None:
    """Non-positive gains and a spin target below the minimum are refused by name."""
    with pytest.raises(ConfigError, match="rate_gain_per_s"):
        StepAParams(rate_gain_per_s=0.0)
    with pytest.raises(ConfigError, match="spin_target_rad_s"):
        StepAParams(spin_min_rad_s=0.3, spin_target_rad_s=0.2)
