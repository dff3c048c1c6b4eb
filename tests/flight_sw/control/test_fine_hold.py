"""Fine hold: the coarse 6-DoF law far from the target, the PD pair near it, with hysteresis."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw import quaternion as qt
from flight_sw.control.fine_hold import FineHold, FineHoldParams
from flight_sw.control.nftsm_dq import NftsmDq
from flight_sw.control.nftsm_dq_params import NftsmDqParams
from flight_sw.control.position_pd import PositionPd, PositionPdParams
from flight_sw.control.quaternion_pd import QuaternionPd, QuaternionPdParams

MASS_KG = 100.0
INERTIA = (18.0, 18.0, 24.0)
ATT_W_RAD_S, POS_W_RAD_S, ZETA = 2.0, 0.4, 0.7
PARAMS = FineHoldParams()
ZERO3 = np.zeros(3)
Q_ID = qt.identity()


def make() -> tuple[FineHold, NftsmDq, QuaternionPd, PositionPd]:
    """A fine hold over the seed-000 NFTSM with the scenario's PD pair."""
    coarse = NftsmDq(NftsmDqParams())
    att = QuaternionPd(QuaternionPdParams.from_bandwidth(list(INERTIA), ATT_W_RAD_S, ZETA,
                                                          math.inf))
    pos = PositionPd(PositionPdParams.from_bandwidth(MASS_KG, POS_W_RAD_S, ZETA, math.inf,
                                                     math.inf))
    return FineHold(coarse, att, pos, PARAMS), coarse, att, pos


def q_about_x(angle_deg: float) -> np.ndarray:
    """A rotation of ``angle_deg`` about body x."""
    return qt.from_rotation_vector(np.array([math.radians(angle_deg), 0.0, 0.0]))


def wrench(law: FineHold | NftsmDq, q: np.ndarray, r: np.ndarray,
           v: np.ndarray = ZERO3) -> np.ndarray:
    """The law's wrench at attitude ``q``, position ``r``, velocity ``v`` (reference at rest)."""
    return law.wrench_B(0, q, ZERO3, r, v, Q_ID, ZERO3, ZERO3, ZERO3)


def test_far_from_the_target_the_coarse_law_acts() -> None:
    """1 m and 3° away: the NFTSM's wrench, bit for bit, and no hand-over."""
    hold, coarse, _, _ = make()
    q, r = q_about_x(3.0), np.array([1.0, 0.0, 0.0])
    assert np.array_equal(wrench(hold, q, r), wrench(coarse, q, r))
    assert not hold.in_fine_hold and hold.switches == 0


def test_near_the_target_the_pd_pair_acts() -> None:
    """Inside every enter threshold: force of the position PD, torque of the attitude PD."""
    hold, _, att, pos = make()
    q, r = q_about_x(0.2), np.array([0.1, -0.05, 0.0])
    got = wrench(hold, q, r)
    assert hold.in_fine_hold and hold.switches == 1
    np.testing.assert_array_equal(got[:3], pos.force_B_N(0, q, r, ZERO3, ZERO3, ZERO3))
    np.testing.assert_array_equal(got[3:], att.torque_B_Nm(0, q, ZERO3, Q_ID, ZERO3))


def test_speed_above_its_threshold_keeps_the_coarse_law() -> None:
    """Close but moving faster than enter_speed_m_s: no hand-over yet."""
    hold, _, _, _ = make()
    wrench(hold, Q_ID, np.array([0.1, 0.0, 0.0]), np.array([2.0 * PARAMS.enter_speed_m_s, 0, 0]))
    assert not hold.in_fine_hold


def test_hysteresis_between_enter_and_leave() -> None:
    """Once fine, an error between the enter and leave thresholds keeps it fine; beyond
    leave it returns to the coarse law; each hand-over is counted."""
    hold, _, _, _ = make()
    wrench(hold, Q_ID, ZERO3)
    assert hold.in_fine_hold
    between_m = 0.5 * (PARAMS.enter_position_m + PARAMS.leave_position_m)
    between_deg = 0.5 * (PARAMS.enter_attitude_deg + PARAMS.leave_attitude_deg)
    wrench(hold, q_about_x(between_deg), np.array([between_m, 0.0, 0.0]))
    assert hold.in_fine_hold and hold.switches == 1
    wrench(hold, Q_ID, np.array([1.5 * PARAMS.leave_position_m, 0.0, 0.0]))
    assert not hold.in_fine_hold and hold.switches == 2
    wrench(hold, q_about_x(between_deg), np.array([between_m, 0.0, 0.0]))
    assert not hold.in_fine_hold  # not yet inside enter
    wrench(hold, Q_ID, ZERO3)
    wrench(hold, q_about_x(1.5 * PARAMS.leave_attitude_deg), ZERO3)
    assert not hold.in_fine_hold and hold.switches == 4


def test_reset_returns_to_the_coarse_law() -> None:
    """A restart hands control back to the coarse law."""
    hold, _, _, _ = make()
    wrench(hold, Q_ID, ZERO3)
    hold.reset()
    assert not hold.in_fine_hold


@pytest.mark.parametrize(("kwargs", "key"), [
    ({"enter_position_m": 0.5, "leave_position_m": 0.5}, "leave_position_m"),
    ({"enter_attitude_deg": 3.0, "leave_attitude_deg": 2.0}, "leave_attitude_deg"),
    ({"enter_speed_m_s": 0.0}, "enter_speed_m_s"),
    ({"enter_rate_deg_s": -1.0}, "enter_rate_deg_s"),
])
def test_thresholds_without_hysteresis_are_refused(kwargs: dict[str, float], key: str) -> None:
    """leave ≤ enter, or a threshold ≤ 0: ConfigError naming the key."""
    with pytest.raises(ConfigError) as info:
        FineHoldParams(**kwargs)
    assert info.value.key == key
