"""Tests of the multiplicative EKF: initialisation, noise-free convergence, noisy consistency."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from scipy.linalg import expm

from dbc.errors import ConfigError
from flight_sw import quaternion as qt
from flight_sw.estimation.mekf import Mekf, MekfParams

NS_PER_S = 1_000_000_000
GYRO_PERIOD_NS = 10_000_000  # 100 Hz
STAR_TRACKER_EVERY = 20  # one star-tracker sample per 20 gyro samples: 5 Hz
TRUE_RATE_BN_B = np.array([0.01, -0.02, 0.015])  # rad/s
TRUE_BIAS_B = np.array([2e-4, -1e-4, 3e-4])  # rad/s (≈ 40 °/h, 20 °/h, 60 °/h)
Q0_BN = qt.normalise(np.array([0.8, 0.2, -0.4, 0.4]))

SIGMA_V = 1e-5  # rad/√s, gyro angle random walk
SIGMA_U = 1e-7  # rad/s/√s, gyro bias random walk
SIGMA_ST = 5e-5  # rad per axis, star tracker (≈ 10 arcsec)

NOISE_FREE_ATTITUDE_TOL_RAD = 1e-9
NOISE_FREE_BIAS_TOL_RAD_S = 1e-9
THREE_SIGMA_MIN_FRACTION = 0.95  # brief: the 3σ bound holds ≥ 95 % of the time
NOISY_BIAS_TOL_RAD_S = 5e-6  # ≈ 1 °/h, an order of magnitude above the filter's σ
SETTLE_S = 30.0  # transient excluded from the consistency statistics
EXACT_TOL = 1e-12
PROPAGATION_TOL_RAD = 1e-10  # 1000 exact steps accumulate only round-off
COVARIANCE_RTOL = 1e-12  # closed-form Φ vs matrix exponential
COVARIANCE_ATOL = 1e-18  # rad², for entries that are ~0


def params() -> MekfParams:
    """The tuning used by every test (matches the simulated sensors)."""
    return MekfParams(
        gyro_arw_rad_sqrt_s=SIGMA_V,
        gyro_bias_rw_rad_s_sqrt_s=SIGMA_U,
        star_tracker_sigma_rad=SIGMA_ST,
        initial_attitude_sigma_rad=SIGMA_ST,
        initial_bias_sigma_rad_s=1e-3,
    )


@dataclass
class Run:
    """Histories at the star-tracker epochs, after each update."""

    t_s: np.ndarray
    attitude_error_rad: np.ndarray  # (k, 3), Log(q_est* ⊗ q_true)
    attitude_sigma_rad: np.ndarray  # (k, 3)
    bias_error_rad_s: np.ndarray  # (k, 3)
    bias_sigma_rad_s: np.ndarray  # (k, 3)


def simulate(duration_s: float, rng: np.random.Generator | None) -> Run:
    """Constant true rate, biased gyro and star tracker; noise-free when ``rng`` is None."""
    mekf = Mekf(params())
    dt_s = GYRO_PERIOD_NS / NS_PER_S
    bias = TRUE_BIAS_B.copy()
    n_steps = round(duration_s / dt_s)
    rows: list[tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
    for k in range(n_steps + 1):
        t_ns = k * GYRO_PERIOD_NS
        q_true = qt.multiply(Q0_BN, qt.from_rotation_vector(TRUE_RATE_BN_B * k * dt_s))
        gyro = TRUE_RATE_BN_B + bias
        if rng is not None:
            gyro = gyro + rng.normal(0.0, SIGMA_V / np.sqrt(dt_s), 3)
            bias = bias + rng.normal(0.0, SIGMA_U * np.sqrt(dt_s), 3)
        mekf.propagate(t_ns, gyro)
        if k % STAR_TRACKER_EVERY == 0:
            noise = np.zeros(3) if rng is None else rng.normal(0.0, SIGMA_ST, 3)
            mekf.update_star_tracker(t_ns, qt.multiply(q_true, qt.from_rotation_vector(noise)))
            est = mekf.estimate()
            err = qt.to_rotation_vector(qt.error_quaternion(est.q_BN, q_true))
            sig = np.sqrt(est.covariance_diag)
            rows.append((t_ns / NS_PER_S, err, sig[:3], est.gyro_bias_B_rad_s - bias, sig[3:]))
    return Run(
        t_s=np.array([r[0] for r in rows]),
        attitude_error_rad=np.array([r[1] for r in rows]),
        attitude_sigma_rad=np.array([r[2] for r in rows]),
        bias_error_rad_s=np.array([r[3] for r in rows]),
        bias_sigma_rad_s=np.array([r[4] for r in rows]),
    )


def test_not_initialised_before_first_star_tracker_sample() -> None:
    """Gyro samples alone leave the filter uninitialised with an identity attitude."""
    mekf = Mekf(params())
    assert not mekf.estimate().initialised
    mekf.propagate(0, TRUE_RATE_BN_B)
    mekf.propagate(GYRO_PERIOD_NS, TRUE_RATE_BN_B)
    est = mekf.estimate()
    assert not est.initialised
    np.testing.assert_array_equal(est.q_BN, qt.identity())
    np.testing.assert_allclose(est.omega_BN_B, TRUE_RATE_BN_B, atol=EXACT_TOL)


def test_first_star_tracker_sample_initialises_attitude() -> None:
    """The first star-tracker sample sets q_BN (short-way sign) and the initial covariance."""
    mekf = Mekf(params())
    mekf.update_star_tracker(0, -Q0_BN)
    est = mekf.estimate()
    assert est.initialised
    np.testing.assert_allclose(est.q_BN, qt.with_positive_scalar(Q0_BN), atol=EXACT_TOL)
    np.testing.assert_allclose(est.covariance_diag[:3], SIGMA_ST**2)
    assert est.t_ns == 0


def test_propagation_is_exact_for_constant_rate() -> None:
    """With a known bias and constant rate, gyro propagation alone tracks the truth."""
    p = params()
    mekf = Mekf(
        MekfParams(
            gyro_arw_rad_sqrt_s=p.gyro_arw_rad_sqrt_s,
            gyro_bias_rw_rad_s_sqrt_s=p.gyro_bias_rw_rad_s_sqrt_s,
            star_tracker_sigma_rad=p.star_tracker_sigma_rad,
            initial_attitude_sigma_rad=p.initial_attitude_sigma_rad,
            initial_bias_sigma_rad_s=p.initial_bias_sigma_rad_s,
            initial_bias_B_rad_s=tuple(TRUE_BIAS_B),
        )
    )
    mekf.update_star_tracker(0, Q0_BN)
    n = 1000
    for k in range(n + 1):
        mekf.propagate(k * GYRO_PERIOD_NS, TRUE_RATE_BN_B + TRUE_BIAS_B)
    q_true = qt.multiply(
        Q0_BN, qt.from_rotation_vector(TRUE_RATE_BN_B * n * GYRO_PERIOD_NS / NS_PER_S)
    )
    assert (
        qt.rotation_angle_rad(qt.error_quaternion(mekf.estimate().q_BN, q_true))
        < PROPAGATION_TOL_RAD
    )


def test_late_star_tracker_sample_is_carried_forward() -> None:
    """A star-tracker sample stamped 5 ms before the filter time is propagated, not misread."""
    mekf = Mekf(params())
    rate = TRUE_RATE_BN_B * 10.0
    mekf.propagate(0, rate)
    mekf.propagate(GYRO_PERIOD_NS, rate)
    t_meas_ns = GYRO_PERIOD_NS // 2
    q_meas = qt.multiply(Q0_BN, qt.from_rotation_vector(rate * t_meas_ns / NS_PER_S))
    mekf.update_star_tracker(t_meas_ns, q_meas)
    q_true = qt.multiply(Q0_BN, qt.from_rotation_vector(rate * GYRO_PERIOD_NS / NS_PER_S))
    assert qt.rotation_angle_rad(qt.error_quaternion(mekf.estimate().q_BN, q_true)) < EXACT_TOL


def test_noise_free_data_converges_to_truth() -> None:
    """Noise-free constant rate with a constant gyro bias: attitude and bias converge to truth."""
    run = simulate(duration_s=300.0, rng=None)
    assert np.max(np.abs(run.attitude_error_rad[-1])) < NOISE_FREE_ATTITUDE_TOL_RAD
    assert np.max(np.abs(run.bias_error_rad_s[-1])) < NOISE_FREE_BIAS_TOL_RAD_S


def test_noisy_data_is_consistent_and_bias_converges(rng: np.random.Generator) -> None:
    """3σ bounds contain the attitude and bias errors ≥ 95 % of the time; bias converges."""
    run = simulate(duration_s=300.0, rng=rng)
    settled = run.t_s >= SETTLE_S
    inside_att = np.all(
        np.abs(run.attitude_error_rad[settled]) <= 3.0 * run.attitude_sigma_rad[settled], axis=1
    )
    inside_bias = np.all(
        np.abs(run.bias_error_rad_s[settled]) <= 3.0 * run.bias_sigma_rad_s[settled], axis=1
    )
    assert inside_att.mean() >= THREE_SIGMA_MIN_FRACTION
    assert inside_bias.mean() >= THREE_SIGMA_MIN_FRACTION
    assert np.max(np.abs(run.bias_error_rad_s[-1])) < NOISY_BIAS_TOL_RAD_S


def test_out_of_order_and_invalid_samples_are_ignored() -> None:
    """An older gyro sample or a zero quaternion changes nothing and is counted."""
    mekf = Mekf(params())
    mekf.update_star_tracker(0, Q0_BN)
    mekf.propagate(2 * GYRO_PERIOD_NS, TRUE_RATE_BN_B)
    before = mekf.estimate()
    mekf.propagate(GYRO_PERIOD_NS, -TRUE_RATE_BN_B)
    mekf.update_star_tracker(2 * GYRO_PERIOD_NS, np.zeros(4))
    after = mekf.estimate()
    assert mekf.rejected_samples == 2
    np.testing.assert_array_equal(after.q_BN, before.q_BN)
    np.testing.assert_array_equal(after.omega_BN_B, before.omega_BN_B)


def test_estimate_arrays_are_read_only() -> None:
    """The returned estimate cannot be mutated by a caller."""
    mekf = Mekf(params())
    mekf.update_star_tracker(0, Q0_BN)
    with pytest.raises(ValueError):
        mekf.estimate().q_BN[0] = 0.0


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("gyro_arw_rad_sqrt_s", -1.0),
        ("star_tracker_sigma_rad", 0.0),
        ("initial_bias_sigma_rad_s", float("nan")),
        ("initial_bias_B_rad_s", (0.0, 0.0)),
    ],
)
def test_params_validate(key: str, value: object) -> None:
    """Invalid tuning raises ConfigError naming the key."""
    kwargs: dict[str, object] = {
        "gyro_arw_rad_sqrt_s": SIGMA_V,
        "gyro_bias_rw_rad_s_sqrt_s": SIGMA_U,
        "star_tracker_sigma_rad": SIGMA_ST,
        "initial_attitude_sigma_rad": SIGMA_ST,
        "initial_bias_sigma_rad_s": 1e-3,
        key: value,
    }
    with pytest.raises(ConfigError) as info:
        MekfParams(**kwargs)  # type: ignore[arg-type]
    assert info.value.key == key


def test_covariance_transition_matches_matrix_exponential() -> None:
    """With zero process noise, P⁺ = Φ P Φᵀ with Φ = expm(F Δt), F = [[−[ω×], −I], [0, 0]]."""
    p0 = np.diag([1e-4, 2e-4, 3e-4, 1e-6, 2e-6, 3e-6])
    for rate in (np.array([0.3, -0.5, 0.8]), np.array([1e-5, 0.0, -2e-5])):
        mekf = Mekf(
            MekfParams(
                gyro_arw_rad_sqrt_s=0.0,
                gyro_bias_rw_rad_s_sqrt_s=0.0,
                star_tracker_sigma_rad=1e-2,
                initial_attitude_sigma_rad=1e-2,
                initial_bias_sigma_rad_s=1e-3,
            )
        )
        mekf.update_star_tracker(0, Q0_BN)
        mekf._cov = p0.ravel().tolist()  # a full-rank, axis-distinct starting covariance
        dt_ns = 50_000_000
        mekf.propagate(0, rate)
        mekf.propagate(dt_ns, rate)
        f = np.zeros((6, 6))
        f[:3, :3] = -qt.skew(rate)
        f[:3, 3:] = -np.eye(3)
        phi = expm(f * dt_ns / NS_PER_S)
        np.testing.assert_allclose(
            mekf.covariance, phi @ p0 @ phi.T, rtol=COVARIANCE_RTOL, atol=COVARIANCE_ATOL
        )
