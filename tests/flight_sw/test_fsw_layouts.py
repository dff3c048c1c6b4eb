"""The reconstructed seed-000 16-thruster layouts (conventional and canted) span all six DoF,
even after one failure."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from bench.station.valves.layouts import (
    LAYOUTS,
    SEED000_CANT_DEG,
    seed000_canted_16,
    seed000_conventional_16,
)
from flight_sw.allocation.effectiveness import effectiveness_matrix

N_THRUSTERS = 16
UNIT_TOL = 1e-12
# Smallest component of a unit-sum strictly positive null vector accepted as "positive".
POSITIVE_TOL = 1e-6
RANK_RTOL = 1e-10
LAYOUTS_16 = ("seed000_conventional_16", "seed000_canted_16")
ARM_R_M, LENGTH_L_M = 0.5, 0.1  # the seed-000 scenarios' dimensions


def geometry(name: str) -> tuple[np.ndarray, np.ndarray]:
    """Positions and directions of a named 16-thruster layout at the seed-000 dimensions."""
    geo = LAYOUTS[name](ARM_R_M, LENGTH_L_M)
    return np.array([g[0] for g in geo]), np.array([g[1] for g in geo])


def positive_null_margin(b: np.ndarray) -> float:
    """max t such that B v = 0, Σ v = 1, v ≥ t (> 0: the columns positively span range B)."""
    m, n = b.shape
    a_eq = np.zeros((m + 1, n + 1))
    a_eq[:m, :n] = b
    a_eq[m, :n] = 1.0
    b_eq = np.zeros(m + 1)
    b_eq[m] = 1.0
    a_ub = np.hstack([-np.eye(n), np.ones((n, 1))])
    cost = np.zeros(n + 1)
    cost[-1] = -1.0
    res = linprog(
        cost,
        A_ub=a_ub,
        b_ub=np.zeros(n),
        A_eq=a_eq,
        b_eq=b_eq,
        bounds=[(0.0, None)] * n + [(None, None)],
    )
    assert res.status == 0
    return float(res.x[-1])


def test_layout_is_registered_and_has_16_unit_thrusters() -> None:
    """16 thrusters, unit directions, four per quad sharing one mounting point."""
    geo = LAYOUTS["seed000_conventional_16"](0.5, 0.1)
    assert len(geo) == N_THRUSTERS
    for k, (r, d) in enumerate(geo):
        assert abs(np.linalg.norm(d) - 1.0) < UNIT_TOL
        assert r == geo[4 * (k // 4)][0]
        assert abs(r[0] - 0.1) < UNIT_TOL and abs(np.hypot(r[1], r[2]) - 0.5) < UNIT_TOL


def test_every_thruster_has_its_opposite_in_its_quad() -> None:
    """Pair-mounted: thrusters 4q and 4q+1, 4q+2 and 4q+3 fire in opposite directions."""
    geo = seed000_conventional_16(0.5, 0.1)
    for q in range(4):
        for a, b in ((0, 1), (2, 3)):
            assert np.allclose(np.add(geo[4 * q + a][1], geo[4 * q + b][1]), 0.0)


@pytest.mark.parametrize("name", LAYOUTS_16)
def test_wrench_matrix_has_full_rank_and_positive_span(name: str) -> None:
    """Rank 6 and a strictly positive null vector: every wrench is reachable with T ≥ 0."""
    b = effectiveness_matrix(*geometry(name))
    s = np.linalg.svd(b, compute_uv=False)
    assert int(np.sum(s > RANK_RTOL * s[0])) == 6
    assert positive_null_margin(b) > POSITIVE_TOL


@pytest.mark.parametrize("name", LAYOUTS_16)
@pytest.mark.parametrize("failed", range(N_THRUSTERS))
def test_positive_span_survives_any_single_failure(name: str, failed: int) -> None:
    """Removing any one thruster keeps rank 6 and the positive span (reconfiguration works)."""
    b = np.delete(effectiveness_matrix(*geometry(name)), failed, axis=1)
    s = np.linalg.svd(b, compute_uv=False)
    assert int(np.sum(s > RANK_RTOL * s[0])) == 6
    assert positive_null_margin(b) > POSITIVE_TOL


def test_canted_layout_turns_each_thruster_about_its_quad_radius() -> None:
    """Same mounting points; each direction is the conventional one turned by the cant
    about the quad's radial axis (unit, at the cant angle, perpendicular to that axis)."""
    cos_cant = np.cos(np.radians(SEED000_CANT_DEG))
    for (r0, d0), (r1, d1) in zip(seed000_conventional_16(ARM_R_M, LENGTH_L_M),
                                  seed000_canted_16(ARM_R_M, LENGTH_L_M), strict=True):
        radial = np.array([0.0, r0[1], r0[2]]) / np.hypot(r0[1], r0[2])
        assert r1 == r0
        assert abs(np.linalg.norm(d1) - 1.0) < UNIT_TOL
        assert np.dot(d0, d1) == pytest.approx(cos_cant, abs=UNIT_TOL)
        assert abs(np.dot(d1, radial)) < UNIT_TOL
