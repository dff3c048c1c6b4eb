"""Known-answer tests of the thruster effectiveness matrix on the seed-003 layout."""

from __future__ import annotations

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.allocation.effectiveness import (
    FORCE_ROWS,
    TORQUE_ROWS,
    effectiveness_matrix,
)

EXACT_TOL = 1e-15
R_M, L_M = 0.45, 0.22  # seed 003 arm and length


def test_columns_of_seed003_layout(layout: tuple[np.ndarray, np.ndarray]) -> None:
    """Each column is [d_i; r_i × d_i], worked out by hand for the 8 thrusters."""
    b = effectiveness_matrix(*layout)
    expected_torque = np.array(
        [
            (-L_M, 0.0, R_M),
            (-L_M, 0.0, -R_M),
            (L_M, -R_M, 0.0),
            (L_M, R_M, 0.0),
            (L_M, 0.0, R_M),
            (L_M, 0.0, -R_M),
            (-L_M, -R_M, 0.0),
            (-L_M, R_M, 0.0),
        ]
    ).T
    assert b.shape == (6, 8)
    np.testing.assert_allclose(b[TORQUE_ROWS], expected_torque, atol=EXACT_TOL)
    np.testing.assert_allclose(b[FORCE_ROWS], layout[1].T, atol=EXACT_TOL)


@pytest.mark.parametrize(
    ("pair", "torque_per_N"),
    [
        ((3, 4), (2 * L_M, 0.0, 0.0)),
        ((1, 2), (-2 * L_M, 0.0, 0.0)),
        ((4, 8), (0.0, 2 * R_M, 0.0)),
        ((3, 7), (0.0, -2 * R_M, 0.0)),
        ((1, 5), (0.0, 0.0, 2 * R_M)),
        ((2, 6), (0.0, 0.0, -2 * R_M)),
    ],
)
def test_thruster_pairs_give_pure_torques(
    layout: tuple[np.ndarray, np.ndarray], pair: tuple[int, int], torque_per_N: tuple[float, ...]
) -> None:
    """The seed-003 pairs (1-based) produce pure roll, pitch and yaw torques."""
    b = effectiveness_matrix(*layout)
    thrust = np.zeros(8)
    thrust[[pair[0] - 1, pair[1] - 1]] = 1.0
    np.testing.assert_allclose(b[TORQUE_ROWS] @ thrust, torque_per_N, atol=EXACT_TOL)


def test_all_ones_is_in_the_null_space(layout: tuple[np.ndarray, np.ndarray]) -> None:
    """Firing all eight thrusters equally gives zero force and zero torque."""
    np.testing.assert_allclose(effectiveness_matrix(*layout) @ np.ones(8), 0.0, atol=EXACT_TOL)


def test_rejects_non_unit_direction(layout: tuple[np.ndarray, np.ndarray]) -> None:
    """A direction that is not a unit vector raises ConfigError naming the thruster."""
    r, d = layout
    d = d.copy()
    d[4] *= 2.0
    with pytest.raises(ConfigError) as info:
        effectiveness_matrix(r, d)
    assert info.value.key == "d_thr_B[4]"


def test_rejects_mismatched_shapes(layout: tuple[np.ndarray, np.ndarray]) -> None:
    """Positions and directions must both be n×3."""
    r, d = layout
    with pytest.raises(ConfigError):
        effectiveness_matrix(r, d[:7])
    with pytest.raises(ConfigError):
        effectiveness_matrix(r[:, :2], d[:, :2])
