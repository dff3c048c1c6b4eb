"""Tests of the step guidance (hold, then target; zero rates)."""

from __future__ import annotations

import numpy as np
import pytest

from flight_sw.guidance.base import AttitudeReference
from flight_sw.guidance.step import StepGuidance

Q_HOLD = np.array([1.0, 0.0, 0.0, 0.0])
Q_TARGET_UNNORMALISED = np.array([2.0, 0.0, 0.0, 2.0])  # 90° about z, scaled by 2√2
T_START_NS = 5_000_000_000
UNIT_TOL = 1e-15


def test_holds_then_steps_with_zero_rates() -> None:
    """Before t_start the hold attitude, from t_start on the (normalised) target; zero rates."""
    g = StepGuidance(Q_HOLD, Q_TARGET_UNNORMALISED, T_START_NS)
    before = g.reference(T_START_NS - 1)
    at = g.reference(T_START_NS)
    after = g.reference(10 * T_START_NS)
    np.testing.assert_array_equal(before.q_RN, Q_HOLD)
    expected = Q_TARGET_UNNORMALISED / np.linalg.norm(Q_TARGET_UNNORMALISED)
    np.testing.assert_allclose(at.q_RN, expected, rtol=0.0, atol=UNIT_TOL)
    np.testing.assert_array_equal(at.q_RN, after.q_RN)
    for ref in (before, at, after):
        np.testing.assert_array_equal(ref.omega_RN_R, np.zeros(3))
        np.testing.assert_array_equal(ref.domega_RN_R, np.zeros(3))


def test_reference_arrays_are_read_only() -> None:
    """The returned arrays cannot be modified by a caller."""
    ref = StepGuidance(Q_HOLD, Q_HOLD).reference(0)
    with pytest.raises(ValueError):
        ref.q_RN[0] = 0.0


@pytest.mark.parametrize(
    ("q_hold", "q_target", "t_start", "name"),
    [
        (np.zeros(4), Q_HOLD, 0, "q_hold_RN"),
        (Q_HOLD, np.array([1.0, 0.0, 0.0]), 0, "q_target_RN"),
        (Q_HOLD, np.array([np.nan, 0.0, 0.0, 1.0]), 0, "q_target_RN"),
        (Q_HOLD, Q_HOLD, 1.5, "t_start_ns"),
    ],
)
def test_invalid_arguments_are_rejected(
    q_hold: np.ndarray, q_target: np.ndarray, t_start: int, name: str
) -> None:
    """Bad quaternions or a non-integer start time raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=name):
        StepGuidance(q_hold, q_target, t_start)


def test_attitude_reference_validates_shapes() -> None:
    """AttitudeReference rejects a wrongly sized rate."""
    with pytest.raises(ValueError, match="omega_RN_R"):
        AttitudeReference(Q_HOLD, np.zeros(2), np.zeros(3))
