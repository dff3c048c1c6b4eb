"""Named layouts: seed 001 Table 1 as 16 opposing valves; per-thruster maxima."""

from __future__ import annotations

import numpy as np
import pytest

from bench.station.valves.layouts import (
    SEED001_LOWER_BOUND_N,
    SEED001_UPPER_BOUND_N,
    seed001_table1_16,
    seed001_table1_max_thrust_N,
)

TABLE1_R_M = 0.75
TABLE1_L_M = 0.75
ABS_TOL = 1e-12


def test_seed001_table1_positions_and_directions() -> None:
    """Thruster 1 at (0, −0.75, 0.75) along −z; 5 at (0.375√2, −0.75, 0.375√2) along −x."""
    g = seed001_table1_16(TABLE1_R_M, TABLE1_L_M)
    assert len(g) == 16
    assert g[0] == ((0.0, -0.75, 0.75), (0.0, 0.0, -1.0))
    a = 0.375 * np.sqrt(2.0)
    assert g[4][0] == pytest.approx((a, -0.75, a), abs=ABS_TOL)
    assert g[4][1] == (-1.0, 0.0, 0.0)


def test_opposing_pairs_share_position_and_cancel() -> None:
    """Valve i + 8 sits at valve i's position with the opposite direction."""
    g = seed001_table1_16(TABLE1_R_M, TABLE1_L_M)
    for i in range(8):
        assert g[i + 8][0] == g[i][0]
        assert np.add(g[i][1], g[i + 8][1]) == pytest.approx((0.0, 0.0, 0.0), abs=0.0)


def test_torque_rows_span_three_axes() -> None:
    """The 8 actuators' torque columns r × d have rank 3 (the paper's n = 3)."""
    g = seed001_table1_16(TABLE1_R_M, TABLE1_L_M)
    b = np.array([np.cross(r, d) for r, d in g[:8]]).T
    assert np.linalg.matrix_rank(b) == 3


def test_max_thrust_bounds() -> None:
    """2.35 N for valves 0..7 (ū), 2.3 N for the opposing 8..15 (−2.3 N lower bound)."""
    m = seed001_table1_max_thrust_N()
    assert m[:8] == (SEED001_UPPER_BOUND_N,) * 8 and m[8:] == (SEED001_LOWER_BOUND_N,) * 8
