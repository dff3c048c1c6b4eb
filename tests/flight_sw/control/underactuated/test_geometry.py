"""Seed 004's three-thruster model and the configuration check (conditions (i)–(iii))."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from bench.station.valves.layouts import LAYOUTS
from dbc.errors import ConfigError
from flight_sw.allocation.effectiveness import effectiveness_matrix
from flight_sw.control.underactuated.geometry import (
    CONTROL_FRAMES,
    ThreeThrusters,
    check_triple,
    qualifying_triples,
)
from tests.flight_sw.control.underactuated import ffrb_reference as ref

TOL = 1e-12
SEED000_NOMINAL_INERTIA = np.diag([18.0, 18.0, 24.0])  # fdir_16thr's [vehicle.nominal]


def test_chosen_body_meets_every_condition() -> None:
    """The seed-004 test body passes (i)–(iii), independence and J_I ≠ J_II."""
    b = ref.effectiveness()
    c = check_triple(b[3:], b[:3], ref.INERTIA_DIAG_KGM2, (0, 1, 2))
    assert c.qualifies and c.why_not() == ""


def test_force_follows_torque() -> None:
    """F_B = P T equals Σ f_i d_i for the thrusts f = M⁻¹ T (eq. 9)."""
    thr = ref.vehicle()
    rng = np.random.default_rng(4)
    for _ in range(20):
        t = rng.normal(size=3)
        f = thr.thrust_N(t)
        np.testing.assert_allclose(thr.force_B_N(t), ref.D_THR_B.T @ f, atol=TOL)
        np.testing.assert_allclose(np.cross(ref.R_THR_B_M, ref.D_THR_B).T @ f, t, atol=TOL)


def test_least_axis_III_torque_is_the_edge_of_the_cone() -> None:
    """At T_III,min every thrust is ≥ 0 and one is 0; any less makes one negative."""
    thr = ref.vehicle()
    rng = np.random.default_rng(5)
    for _ in range(50):
        t1, t2 = rng.normal(size=2)
        t3 = thr.min_torque_III_Nm(t1, t2)
        f = thr.thrust_N(np.array([t1, t2, t3]))
        assert f.min() >= -1e-12 and abs(f.min()) < 1e-12
        assert thr.thrust_N(np.array([t1, t2, t3 - 1e-6])).min() < 0.0


@pytest.mark.parametrize("change, failed", [
    (lambda r, d: (r, -d), "(ii)"),  # every torque reversed: III negative, I/II too
    (lambda r, d: (r, np.column_stack((d[:, :2], np.abs(d[:, 2])))), "(iii)"),  # all push +z
    (lambda r, d: (r * np.array([0.0, 0.0, 1.0]), d), "independent"),
])
def test_known_bad_triples_fail_with_the_reason(change, failed) -> None:
    """Reversed thrusters, one-signed z forces and coplanar torques each fail, named."""
    r, d = change(ref.R_THR_B_M.copy(), ref.D_THR_B.copy())
    c = check_triple(np.cross(r, d).T, d.T, ref.INERTIA_DIAG_KGM2, (0, 1, 2))
    assert not c.qualifies
    assert failed in c.why_not()


def test_equal_transverse_inertias_fail() -> None:
    """J_I = J_II makes axis III uncontrollable (§2.1 (i)): the check says so."""
    b = ref.effectiveness()
    c = check_triple(b[3:], b[:3], np.array([1.0, 1.0, 2.0]), (0, 1, 2))
    assert not c.qualifies and "J_I = J_II" in c.why_not()


def test_model_refuses_a_set_that_does_not_qualify() -> None:
    """ThreeThrusters names the failed condition in its ConfigError."""
    b = ref.effectiveness()
    with pytest.raises(ConfigError, match=r"\(ii\)"):
        ThreeThrusters(-b[3:], -b[:3], ref.INERTIA_DIAG_KGM2, ref.MASS_KG)


def test_check_respects_the_failure_mask() -> None:
    """With a fourth thruster, masking it keeps the triple; masking a member loses it."""
    extra_r, extra_d = np.array([0.3, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    r = np.vstack((ref.R_THR_B_M, extra_r))
    d = np.vstack((ref.D_THR_B, extra_d))
    b = effectiveness_matrix(r, d)
    j = np.diag(ref.INERTIA_DIAG_KGM2)
    good, _ = qualifying_triples(b, j, mask=np.array([True, True, True, False]))
    assert [g.check.thrusters for g in good] == [(0, 1, 2)]
    good, bad = qualifying_triples(b, j, mask=np.array([True, False, True, True]))
    assert good == [] and len(bad) == 1


def test_seed000_vehicle_has_no_qualifying_triple() -> None:
    """The 16-thruster CTC fires along and around body axes: no triple of it qualifies
    in any of the six control frames (every torque has a zero component)."""
    geo = LAYOUTS["seed000_conventional_16"](0.5, 0.3)
    b = effectiveness_matrix(np.array([g[0] for g in geo]), np.array([g[1] for g in geo]))
    good, bad = qualifying_triples(b, np.diag([18.0, 20.0, 24.0]), frames=CONTROL_FRAMES)
    assert good == [] and len(bad) == 560


def test_canted_seed000_vehicle_has_qualifying_triples() -> None:
    """Canted 10° about their quad radius, the CTC's thrusters give triples that qualify
    with the spin axis along ±x or ±y; none along z, only because J_I = J_II there: with
    J_II = 20 kg m², two triples qualify with axis III = +z."""
    geo = LAYOUTS["seed000_canted_16"](0.5, 0.3)
    b = effectiveness_matrix(np.array([g[0] for g in geo]), np.array([g[1] for g in geo]))
    good, _ = qualifying_triples(b, SEED000_NOMINAL_INERTIA, frames=CONTROL_FRAMES)
    assert Counter(g.frame for g in good) == {"III=+x": 8, "III=-x": 8, "III=+y": 2,
                                              "III=-y": 2}
    along_z, failing = qualifying_triples(b, SEED000_NOMINAL_INERTIA)
    assert along_z == [] and all(not f.check.inertia_I_II_distinct for f in failing)
    distinct, _ = qualifying_triples(b, np.diag([18.0, 20.0, 24.0]))
    assert [g.check.thrusters for g in distinct] == [(1, 7, 10), (3, 8, 14)]


def test_control_frames_are_rotations() -> None:
    """Each control frame is a proper rotation of the body axes."""
    for name, k in CONTROL_FRAMES:
        np.testing.assert_allclose(k @ k.T, np.eye(3), atol=TOL, err_msg=name)
        assert np.linalg.det(k) == pytest.approx(1.0)


def test_check_rejects_bad_shapes() -> None:
    """Wrong matrix shapes and a non-diagonal inertia are refused by name."""
    b = ref.effectiveness()
    with pytest.raises(ConfigError, match="effectiveness"):
        qualifying_triples(b[:3], np.eye(3))
    with pytest.raises(ConfigError, match="mask"):
        qualifying_triples(b, np.eye(3), mask=np.array([True]))
    with pytest.raises(ConfigError, match="inertia_B_kgm2"):
        qualifying_triples(b, np.array([[1.0, 0.1, 0.0], [0.1, 1.0, 0.0], [0.0, 0.0, 2.0]]))
