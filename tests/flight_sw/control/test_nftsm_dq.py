"""Tests of the dual-quaternion NFTSM pose law of seed 000 (eqs. 6–19) and its closed loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw import quaternion as quat
from flight_sw.control.nftsm_dq import (
    PAPER_MEAN_MOTION_RAD_S,
    NftsmDq,
    NftsmDqParams,
    auxiliary_surface,
)
from flight_sw.control.tsm_dq import TsmDq, TsmDqParams

from .dq_reference import nftsm_wrench_reference, sig

# Seed 000, Section V: the follower's true mass properties and initial error.
ACTUAL_MASS_KG = 95.0
ACTUAL_INERTIA_KGM2 = np.diag([17.0, 17.0, 22.0])
INITIAL_POSITION_M = np.array([-20.0, -10.0, -10.0])
INITIAL_Q = np.array([0.6245, 0.5, 0.5196, 0.3])
DT_S = 0.01
SIM_DURATION_S = 25.0
POSITION_TOL_M = 0.1
ATTITUDE_TOL_RAD = 0.05
TINY_ERRORS = (1e-3, 1e-6, 1e-9, 1e-12)
ZERO_WRENCH_TOL = 1e-9
ZERO3 = np.zeros(3)
NS_PER_S = 1_000_000_000
SEED_AUX = 11
N_AUX_CASES = 200
AUX_RTOL = 1e-15  # the same operations in the same order: round-off at most


def _disturbance(t_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Seed 000's external force [N] and torque [N m] (body axes)."""
    force = np.array(
        [
            0.06 + 0.03 * math.sin(0.6 * t_s),
            0.05 + 0.04 * math.sin(0.9 * t_s),
            0.04 + 0.01 * math.sin(0.5 * t_s),
        ]
    )
    torque = np.array(
        [
            2e-5 + 5e-4 * math.sin(0.8 * t_s),
            3e-5 + 3e-4 * math.sin(0.5 * t_s),
            1e-5 + 7e-4 * math.sin(0.3 * t_s),
        ]
    )
    return force, torque


def _plant(x: np.ndarray, t_s: float, wrench: np.ndarray, n: float) -> np.ndarray:
    """Rigid body (attitude w.r.t. the Hill frame, inertial rate) + HCW relative translation."""
    q, omega_I, r, v = x[:4], x[4:7], x[7:10], x[10:13]
    c_BN = quat.to_dcm(q)
    omega_BN = omega_I - c_BN @ np.array([0.0, 0.0, n])
    f_d, tau_d = _disturbance(t_s)
    dq = 0.5 * quat.multiply(q, np.concatenate(([0.0], omega_BN)))
    inertia = ACTUAL_INERTIA_KGM2
    domega = np.linalg.solve(inertia, wrench[3:] + tau_d - np.cross(omega_I, inertia @ omega_I))
    hcw = np.array([3.0 * n * n * r[0] + 2.0 * n * v[1], -2.0 * n * v[0], -n * n * r[2]])
    acc = hcw + c_BN.T @ (wrench[:3] + f_d) / ACTUAL_MASS_KG
    return np.concatenate((dq, domega, v, acc))


def simulate(controller: NftsmDq | TsmDq, duration_s: float) -> tuple[float, float]:
    """RK4 closed loop from the paper's initial error; final (position error [m], angle [rad])."""
    n = PAPER_MEAN_MOTION_RAD_S
    q0 = quat.normalise(INITIAL_Q)
    x = np.concatenate((q0, quat.rotate(q0, [0.0, 0.0, n]), INITIAL_POSITION_M, ZERO3))
    for k in range(round(duration_s / DT_S)):
        t = k * DT_S
        q = x[:4]
        omega_BN = x[4:7] - quat.rotate(q, [0.0, 0.0, n])
        w = controller.wrench_B(
            k * round(DT_S * NS_PER_S), q, omega_BN, x[7:10], x[10:13],
            quat.identity(), ZERO3, ZERO3, ZERO3,
        )  # fmt: skip
        k1 = _plant(x, t, w, n)
        k2 = _plant(x + 0.5 * DT_S * k1, t + 0.5 * DT_S, w, n)
        k3 = _plant(x + 0.5 * DT_S * k2, t + 0.5 * DT_S, w, n)
        k4 = _plant(x + DT_S * k3, t + DT_S, w, n)
        x = x + DT_S / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        x[:4] = quat.normalise(x[:4])
    return float(np.linalg.norm(x[7:10])), quat.rotation_angle_rad(x[:4])


@pytest.fixture(scope="module")
def nftsm_result() -> tuple[float, float]:
    """The NFTSM closed loop after SIM_DURATION_S (paper: position converged within 22 s)."""
    return simulate(
        NftsmDq(NftsmDqParams(mean_motion_rad_s=PAPER_MEAN_MOTION_RAD_S)), SIM_DURATION_S
    )


def test_closed_loop_converges_from_the_paper_initial_error(
    nftsm_result: tuple[float, float],
) -> None:
    """From ρe(0) = [−20, −10, −10] m, 103° attitude error: |ρe| < 0.1 m within 25 s."""
    position_m, angle_rad = nftsm_result
    assert position_m < POSITION_TOL_M
    assert angle_rad < ATTITUDE_TOL_RAD


def test_tsm_baseline_is_slower(nftsm_result: tuple[float, float]) -> None:
    """The TSM law of eq. (12) is still far from the target when NFTSM has converged."""
    tsm_position_m, _ = simulate(
        TsmDq(TsmDqParams(mean_motion_rad_s=PAPER_MEAN_MOTION_RAD_S)), SIM_DURATION_S
    )
    assert tsm_position_m > POSITION_TOL_M
    assert tsm_position_m > 10.0 * nftsm_result[0]


def _controller(**kwargs: float) -> NftsmDq:
    return NftsmDq(NftsmDqParams(**kwargs))  # type: ignore[arg-type]


@pytest.mark.parametrize("n", [0.0, PAPER_MEAN_MOTION_RAD_S])
def test_zero_error_gives_zero_wrench(n: float) -> None:
    """At the reference pose (on the leader, Hill-aligned), at rest in N, the demand is zero."""
    w = _controller(mean_motion_rad_s=n).wrench_B(
        0, quat.identity(), ZERO3, ZERO3, ZERO3, quat.identity(), ZERO3, ZERO3, ZERO3
    )
    np.testing.assert_allclose(w, np.zeros(6), atol=ZERO_WRENCH_TOL)


def test_orbital_terms_hold_an_offset_station_with_the_hcw_force() -> None:
    """At rest at r ≠ 0 in the Hill frame, the force cancels the HCW drift −m0 (3n²x, 0, −n²z)."""
    n = PAPER_MEAN_MOTION_RAD_S
    q = quat.normalise(np.array([0.9, 0.1, -0.3, 0.2]))
    r = np.array([5.0, -3.0, 2.0])
    ctrl = _controller(mean_motion_rad_s=n)
    w = ctrl.wrench_B(0, q, ZERO3, r, ZERO3, q, ZERO3, r, ZERO3)
    expected_N = -ctrl.params.mass_kg * np.array([3.0 * n * n * r[0], 0.0, -n * n * r[2]])
    np.testing.assert_allclose(quat.rotate(quat.conjugate(q), w[:3]), expected_N, atol=1e-10)


def test_surface_zero_at_zero_error() -> None:
    """Ŝ = 0 for ξ̂ = 0 and ξ̂̇ = 0 (eq. 13)."""
    s = _controller().surface(np.zeros(6), np.zeros(6))
    np.testing.assert_array_equal(s, np.zeros(6))


@pytest.mark.parametrize("err", TINY_ERRORS)
def test_finite_output_for_tiny_errors(err: float) -> None:
    """No singularity: errors down to 1e-12 (position [m] and attitude) give a finite wrench."""
    ctrl = _controller()
    q = quat.normalise(np.array([1.0, err, -err, err]))
    rates = np.array([err, -err, 0.0])
    w = ctrl.wrench_B(0, q, rates, err * np.ones(3), -rates, quat.identity(), ZERO3, ZERO3, ZERO3)
    assert np.all(np.isfinite(w))
    s = ctrl.surface(err * np.ones(6), -err * np.ones(6))
    assert np.all(np.isfinite(s))


def test_auxiliary_surface_continuous_at_the_switch() -> None:
    """S_a and W ξ̇ of eqs. (14)–(19) agree on both sides of |ξ| = δ (r1, r2 matching)."""
    p1, delta = 0.6, 0.05
    ones = np.ones(6)
    xi_dot = ones  # S̄ ≠ 0: the polynomial branch is active below δ
    below = auxiliary_surface((delta - 1e-12) * ones, xi_dot, 0.05 * ones, 0.05 * ones, p1, delta)
    above = auxiliary_surface(delta * ones, xi_dot, 0.05 * ones, 0.05 * ones, p1, delta)
    np.testing.assert_allclose(below[0], above[0], rtol=1e-9)
    np.testing.assert_allclose(below[1], above[1], rtol=1e-9)


def test_output_limits_clip_force_and_torque() -> None:
    """max_force_N / max_torque_Nm bound the norms of the two halves of the wrench."""
    ctrl = _controller(max_force_N=5.0, max_torque_Nm=1.0)
    q = quat.normalise(INITIAL_Q)
    w = ctrl.wrench_B(0, q, ZERO3, INITIAL_POSITION_M, ZERO3, quat.identity(), ZERO3, ZERO3, ZERO3)
    assert np.linalg.norm(w[:3]) == pytest.approx(5.0)
    assert np.linalg.norm(w[3:]) == pytest.approx(1.0)


def test_set_inertia_changes_the_torque() -> None:
    """set_inertia_B_kgm2 replaces the nominal inertia used by the law (InertiaAware)."""
    ctrl = _controller()
    q = quat.normalise(INITIAL_Q)
    args = (0, q, np.array([0.1, 0.0, 0.0]), ZERO3, ZERO3, quat.identity(), ZERO3, ZERO3, ZERO3)
    before = ctrl.wrench_B(*args)
    ctrl.set_inertia_B_kgm2(np.diag([36.0, 36.0, 48.0]))
    after = ctrl.wrench_B(*args)
    np.testing.assert_allclose(ctrl.inertia_B_kgm2, np.diag([36.0, 36.0, 48.0]))
    assert not np.allclose(before[3:], after[3:])
    with pytest.raises(ValueError, match="inertia"):
        ctrl.set_inertia_B_kgm2(-np.eye(3))


@pytest.mark.parametrize(
    ("key", "value"),
    [("p1", 0.5), ("p1", 1.0), ("p2", 1.2), ("mass_kg", 0.0), ("k_pos_N", (1.0, 2.0)),
     ("delta_pos", -1.0), ("mean_motion_rad_s", -1e-4), ("max_force_N", 0.0)],
)  # fmt: skip
def test_params_reject_bad_values(key: str, value: object) -> None:
    """NftsmDqParams raises ConfigError naming the bad key."""
    with pytest.raises(ConfigError, match=key):
        NftsmDqParams(**{key: value})  # type: ignore[arg-type]


def _auxiliary_surface_vectorised(
    xi: np.ndarray, xi_dot: np.ndarray, alpha1: np.ndarray, alpha2: np.ndarray, p1: float,
    delta: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. (14)-(16), (18)-(19) as whole-array operations: the oracle of the float version."""
    abs_xi = np.abs(xi)
    s_bar = xi_dot + alpha1 * xi + alpha2 * sig(xi, p1)
    power = (s_bar == 0.0) | (abs_xi >= delta)
    r1 = (2.0 - p1) * delta ** (p1 - 1.0)
    r2 = (p1 - 1.0) * delta ** (p1 - 2.0)
    s_a = np.where(power, sig(xi, p1), r1 * xi + r2 * sig(xi, 2.0))
    safe = np.where(abs_xi > 0.0, abs_xi, 1.0)
    w_power = np.where(abs_xi > 0.0, p1 * safe ** (p1 - 1.0) * xi_dot, 0.0)
    return s_a, np.where(power, w_power, (r1 + 2.0 * r2 * abs_xi) * xi_dot)


def test_auxiliary_surface_matches_the_vectorised_equations() -> None:
    """Both branches, zeros and signs: the per-component version equals the array form."""
    rng = np.random.default_rng(SEED_AUX)
    delta = np.array([0.05] * 3 + [0.001] * 3)
    for _ in range(N_AUX_CASES):
        xi = rng.normal(size=6) * rng.choice([1e-4, 1e-2, 1.0], size=6)
        xi[rng.integers(6)] = 0.0
        xi_dot = rng.normal(size=6)
        a1, a2 = rng.uniform(0.01, 1.0, size=6), rng.uniform(0.01, 1.0, size=6)
        got = auxiliary_surface(xi, xi_dot, a1, a2, 0.6, delta)
        want = _auxiliary_surface_vectorised(xi, xi_dot, a1, a2, 0.6, delta)
        np.testing.assert_allclose(got[0], want[0], rtol=AUX_RTOL, atol=0.0)
        np.testing.assert_allclose(got[1], want[1], rtol=AUX_RTOL, atol=0.0)


N_LAW_CASES = 300
LAW_RTOL = 1e-9  # the float form against the array form: round-off of different orders
SEED_LAW = 12


@pytest.mark.parametrize("anti_unwinding", [False, True])
@pytest.mark.parametrize("n", [0.0, PAPER_MEAN_MOTION_RAD_S])
def test_float_law_equals_the_array_reference(anti_unwinding: bool, n: float) -> None:
    """wrench_B (floats) equals the paper's terms composed as arrays (dq_reference) on random
    poses, twists and references, with and without orbit terms and anti-unwinding."""
    rng = np.random.default_rng(SEED_LAW)
    law = NftsmDq(NftsmDqParams(mean_motion_rad_s=n, anti_unwinding=anti_unwinding,
                                inertia_B_kgm2=(18.0, 19.0, 24.0), max_force_N=300.0))
    law.set_inertia_B_kgm2(np.array([[18.0, 0.4, 0.1], [0.4, 19.0, -0.3], [0.1, -0.3, 24.0]]))
    for _ in range(N_LAW_CASES):
        q = quat.normalise(rng.normal(size=4))
        # anti-unwinding: errors well inside its singular angle (module docstring)
        q_ref = (quat.multiply(q, quat.from_rotation_vector(rng.normal(size=3) * 0.4))
                 if anti_unwinding else quat.normalise(rng.normal(size=4)))
        args = (0, q, rng.normal(size=3) * 0.1, rng.normal(size=3) * 10.0,
                rng.normal(size=3) * 0.1, q_ref, rng.normal(size=3) * 0.01,
                rng.normal(size=3), rng.normal(size=3) * 0.01)
        ref = nftsm_wrench_reference(law, *args)
        np.testing.assert_allclose(law.wrench_B(*args), ref, rtol=0.0,
                                   atol=LAW_RTOL * max(1.0, float(np.abs(ref).max())))
