"""Tests of the dual-quaternion TSM baseline law of seed 000 (eq. 12)."""

from __future__ import annotations

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw import quaternion as quat
from flight_sw.control.nftsm_dq import PAPER_MEAN_MOTION_RAD_S
from flight_sw.control.tsm_dq import TsmDq, TsmDqParams

from .dq_reference import tsm_wrench_reference

ZERO3 = np.zeros(3)
ZERO_WRENCH_TOL = 1e-9
TINY_ERRORS = (1e-3, 1e-6, 1e-9, 1e-12)
INITIAL_Q = np.array([0.6245, 0.5, 0.5196, 0.3])
INITIAL_POSITION_M = np.array([-20.0, -10.0, -10.0])
N_LAW_CASES = 300
LAW_RTOL = 1e-9  # the float form against the array form: round-off of different orders
SEED_LAW = 13


@pytest.mark.parametrize("n", [0.0, PAPER_MEAN_MOTION_RAD_S])
def test_zero_error_gives_zero_wrench(n: float) -> None:
    """At the reference pose, at rest in N, the TSM demand is zero."""
    ctrl = TsmDq(TsmDqParams(mean_motion_rad_s=n))
    w = ctrl.wrench_B(0, quat.identity(), ZERO3, ZERO3, ZERO3, quat.identity(), ZERO3, ZERO3, ZERO3)
    np.testing.assert_allclose(w, np.zeros(6), atol=ZERO_WRENCH_TOL)


def test_surface_is_eq_12() -> None:
    """Ŝ = ξ̂̇ + b̂ ⊙ sig(ξ̂)^α: zero at zero error, b sig(ξ)^α for ξ̇ = 0."""
    ctrl = TsmDq(TsmDqParams())
    np.testing.assert_array_equal(ctrl.surface(np.zeros(6), np.zeros(6)), np.zeros(6))
    xi = np.array([0.1, -0.2, 0.3, -1.0, 2.0, -3.0])
    b = np.array([0.05] * 3 + [0.1] * 3)
    expected = b * np.sign(xi) * np.abs(xi) ** 0.67
    np.testing.assert_allclose(ctrl.surface(xi, np.zeros(6)), expected, rtol=1e-12)


@pytest.mark.parametrize("err", TINY_ERRORS)
def test_singularity_guard_keeps_output_finite(err: float) -> None:
    """Tiny errors with non-zero rates (the TSM singular set) still give a finite wrench."""
    ctrl = TsmDq(TsmDqParams())
    q = quat.normalise(np.array([1.0, err, -err, err]))
    rates = np.array([1e-3, -1e-3, 0.0])
    w = ctrl.wrench_B(0, q, rates, err * np.ones(3), -rates, quat.identity(), ZERO3, ZERO3, ZERO3)
    assert np.all(np.isfinite(w))


def test_output_limits_and_inertia_update() -> None:
    """Clip parameters bound the wrench halves; set_inertia_B_kgm2 replaces the nominal inertia."""
    ctrl = TsmDq(TsmDqParams(max_force_N=5.0, max_torque_Nm=1.0))
    q = quat.normalise(INITIAL_Q)
    w = ctrl.wrench_B(0, q, ZERO3, INITIAL_POSITION_M, ZERO3, quat.identity(), ZERO3, ZERO3, ZERO3)
    assert np.linalg.norm(w[:3]) == pytest.approx(5.0)
    assert np.linalg.norm(w[3:]) == pytest.approx(1.0)
    ctrl.set_inertia_B_kgm2(np.array([20.0, 21.0, 22.0]))
    np.testing.assert_allclose(ctrl.inertia_B_kgm2, np.diag([20.0, 21.0, 22.0]))


@pytest.mark.parametrize(("key", "value"), [("alpha", 0.5), ("alpha", 1.0), ("b_pos", (0, 1, 1))])
def test_params_reject_bad_values(key: str, value: object) -> None:
    """TsmDqParams raises ConfigError naming the bad key."""
    with pytest.raises(ConfigError, match=key):
        TsmDqParams(**{key: value})  # type: ignore[arg-type]


@pytest.mark.parametrize("anti_unwinding", [False, True])
@pytest.mark.parametrize("n", [0.0, PAPER_MEAN_MOTION_RAD_S])
def test_float_law_equals_the_array_reference(anti_unwinding: bool, n: float) -> None:
    """wrench_B (floats) equals the paper's terms composed as arrays (dq_reference) on random
    poses, twists and references, with and without orbit terms and anti-unwinding."""
    rng = np.random.default_rng(SEED_LAW)
    law = TsmDq(TsmDqParams(mean_motion_rad_s=n, anti_unwinding=anti_unwinding,
                            inertia_B_kgm2=(18.0, 19.0, 24.0), max_force_N=300.0))
    law.set_inertia_B_kgm2(np.array([[18.0, 0.4, 0.1], [0.4, 19.0, -0.3], [0.1, -0.3, 24.0]]))
    for _ in range(N_LAW_CASES):
        q = quat.normalise(rng.normal(size=4))
        q_ref = (quat.multiply(q, quat.from_rotation_vector(rng.normal(size=3) * 0.4))
                 if anti_unwinding else quat.normalise(rng.normal(size=4)))
        args = (0, q, rng.normal(size=3) * 0.1, rng.normal(size=3) * 10.0,
                rng.normal(size=3) * 0.1, q_ref, rng.normal(size=3) * 0.01,
                rng.normal(size=3), rng.normal(size=3) * 0.01)
        ref = tsm_wrench_reference(law, *args)
        np.testing.assert_allclose(law.wrench_B(*args), ref, rtol=0.0,
                                   atol=LAW_RTOL * max(1.0, float(np.abs(ref).max())))
