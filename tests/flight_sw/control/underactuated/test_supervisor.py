"""The seed-004 supervisor: Steps A, stop drift, transfer and Step C in turn, each entered
at its predecessor's exit condition (the final de-spin after them is not converged yet:
docs/reproductions.md)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dbc.errors import ConfigError
from flight_sw.control.underactuated.invariants import stopping_velocity_m_s
from flight_sw.control.underactuated.supervisor import Mode, Supervisor, SupervisorParams
from tests.flight_sw.control.underactuated import ffrb_reference as ref

CASE_1_EULER_ZYX_DEG = (0.0, 30.0, 60.0)
PREFIX_TIME_S = 2000.0
ORDER = [Mode.A, Mode.STOP_DRIFT, Mode.TRANSFER, Mode.C, Mode.D]


@pytest.mark.slow
def test_steps_follow_each_other_at_their_exit_conditions() -> None:
    """From rest at case 1's attitude: single spin, then the drift stopped, the aim point
    reached at rest, then the stopping position within Step C's coarse tolerance with the
    stopping velocity within Step B's; every thrust ≥ 0."""
    thr = ref.vehicle()
    params = SupervisorParams()
    sup = Supervisor(thr, params, ref.PERIOD_S)
    c0 = Rotation.from_euler("ZYX", CASE_1_EULER_ZYX_DEG, degrees=True).as_matrix()
    plant = ref.Plant(c0, np.zeros(3), np.zeros(3), np.zeros(3), substeps=1)
    seen: dict[Mode, tuple[np.ndarray, np.ndarray, float, float]] = {}

    def law(p: ref.Plant) -> np.ndarray:
        torque = sup.torque_B_Nm(p.t, p.q_BR(), p.w, p.r, p.v)
        seen.setdefault(sup.mode, (p.r.copy(), p.v.copy(), p.w[2], sup.psi_rad))
        return torque

    thrusts = np.array(plant.run(law, PREFIX_TIME_S, lambda _p: sup.mode is Mode.D))
    assert [Mode(name) for _, name in sup.switches] == ORDER
    r_c, v_c, _, _ = seen[Mode.C]
    assert sup.step_d.settled(r_c[:2], v_c[:2])
    r_d, v_d, w_d, psi_d = seen[Mode.D]
    assert abs(sup.step_c.z_stop_m(r_d[2], psi_d)) <= params.coarse_z_tol_m
    kappa = thr.kappa_m_s_per_rad_s
    assert abs(stopping_velocity_m_s(v_d[2], w_d, kappa)) <= params.step_b.velocity_tol_m_s
    assert thrusts.min() >= -1e-9


def test_params_refuse_bad_values() -> None:
    """Margins and tolerances are checked by name."""
    with pytest.raises(ConfigError, match="stop_margin_turns"):
        SupervisorParams(stop_margin_turns=1)
    with pytest.raises(ConfigError, match="coarse_z_tol_m"):
        SupervisorParams(coarse_z_tol_m=0.0)
