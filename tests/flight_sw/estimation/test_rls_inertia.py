"""Tests of the RLS inertia identifier (seed 001 §2) on synthetic rigid-body data."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.estimation.rls_inertia import (
    RlsInertiaIdentifier,
    RlsInertiaParams,
    inertia_matrix,
    inertia_params,
)

from .rls_reference import euler_regressor

# A full tensor (products of inertia included), seed 001 §5 principal moments 25, 20, 15.
J_TRUE = np.array([[25.0, 1.2, -0.8], [1.2, 20.0, 0.5], [-0.8, 0.5, 15.0]])
# After a capture: a stepped tensor (still positive definite).
J_CAPTURE = J_TRUE + np.array([[5.0, -1.0, 0.3], [-1.0, 8.0, 0.0], [0.3, 0.0, 4.0]])
J_GUESS = np.diag([20.0, 20.0, 20.0])
OMEGA0_B = np.array([0.05, -0.03, 0.04])  # [rad/s]
PERIOD_NS = 20_000_000  # 50 Hz control cycle
PERIOD_S = PERIOD_NS / 1e9
RK4_SUBSTEPS = 4  # 5 ms RK4 steps: truncation far below the identifier's own O(h²) error
# Multi-sine excitation [Hz], one row per body axis (non-commensurate frequencies).
EXCITATION_HZ = np.array([[0.11, 0.37, 0.23], [0.19, 0.07, 0.41], [0.29, 0.53, 0.13]])
TORQUE_AMPLITUDE_NM = 1.0
N_SAMPLES = 1000
# The trapezoidal gyroscopic integral leaves a bias of relative order (|ω̇| h)²/12 ~ 1e-7.
NOISE_FREE_RTOL = 1e-6
STEP_LAMBDA = 0.98  # memory ≈ 50 cycles
STEP_RECONVERGE_SAMPLES = 400  # measured 338 with this (slow, ≤ 0.5 Hz) excitation
STEP_RECONVERGE_RTOL = 1e-3
GYRO_NOISE_RAD_S = 2e-5  # per-sample rate noise (ARW ≈ 0.01 deg/√h at 50 Hz)
NOISY_RTOL = 2e-3  # errors-in-variables bias + variance, measured 6–7e-4 over 6 seeds
SYMMETRY_TOL = 0.0
EXACT_RTOL = 1e-10


def relative_error(j: np.ndarray, truth: np.ndarray) -> float:
    """Frobenius relative error."""
    return float(np.linalg.norm(j - truth) / np.linalg.norm(truth))


def torque_B_Nm(k: int) -> np.ndarray:
    """Zero-order-hold multi-sine torque of cycle k [N m]."""
    t_s = k * PERIOD_S
    return TORQUE_AMPLITUDE_NM * np.array(
        [np.sin(2.0 * np.pi * EXCITATION_HZ[i] * t_s + i).sum() for i in range(3)]
    )


def simulate(
    j: np.ndarray, n: int, omega0: np.ndarray, k0: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Rates ω_0..ω_n and the torques held over each period (RK4 of Euler's equation)."""
    j_inv = np.linalg.inv(j)

    def f(w: np.ndarray, tau: np.ndarray) -> np.ndarray:
        return j_inv @ (tau - np.cross(w, j @ w))

    h = PERIOD_S / RK4_SUBSTEPS
    w = np.array(omega0, dtype=float)
    rates, torques = [w.copy()], []
    for k in range(k0, k0 + n):
        tau = torque_B_Nm(k)
        for _ in range(RK4_SUBSTEPS):
            k1 = f(w, tau)
            k2 = f(w + 0.5 * h * k1, tau)
            k3 = f(w + 0.5 * h * k2, tau)
            k4 = f(w + h * k3, tau)
            w = w + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        rates.append(w.copy())
        torques.append(tau)
    return np.array(rates), np.array(torques)


@pytest.fixture(scope="module")
def clean_data() -> tuple[np.ndarray, np.ndarray]:
    """Noise-free rates and torques of J_TRUE."""
    return simulate(J_TRUE, N_SAMPLES, OMEGA0_B)


def feed(
    ident: RlsInertiaIdentifier, rates: np.ndarray, torques: np.ndarray
) -> list[np.ndarray | None]:
    """Call update once per cycle: rate at t_k with the torque held over (t_{k−1}, t_k]."""
    out = [ident.update(0, rates[0], np.zeros(3))]
    for k in range(1, len(rates)):
        out.append(ident.update(k * PERIOD_NS, rates[k], torques[k - 1]))
    return out


def test_noise_free_converges_to_truth(clean_data: tuple[np.ndarray, np.ndarray]) -> None:
    """Persistently excited noise-free data: estimate within 1e-6 relative, symmetric."""
    ident = RlsInertiaIdentifier(RlsInertiaParams(J_GUESS, forgetting_factor=1.0))
    out = feed(ident, *clean_data)
    assert out[0] is None and out[1] is None  # no estimate before any excitation
    final = out[-1]
    assert final is not None
    assert relative_error(final, J_TRUE) < NOISE_FREE_RTOL
    np.testing.assert_array_equal(final, final.T)
    for j in out:
        if j is not None:
            assert np.max(np.abs(j - j.T)) <= SYMMETRY_TOL


# Measurement-model data (y = Φ θ exactly): random rates, a wide prior.
EXACT_DATA_SEED = 11
EXACT_RATE_SIGMA_RAD_S = 0.2
EXACT_SAMPLES = 60
EXACT_INITIAL_COVARIANCE = 1e8


def _fit_exactly(j: np.ndarray) -> tuple[RlsInertiaIdentifier, list[np.ndarray | None]]:
    """The identifier fed measurement-model data of ``j`` (recovers it to round-off)."""
    rng = np.random.default_rng(EXACT_DATA_SEED)
    ident = RlsInertiaIdentifier(
        RlsInertiaParams(J_GUESS, forgetting_factor=1.0,
                         initial_covariance=EXACT_INITIAL_COVARIANCE)
    )
    theta = inertia_params(j)
    rates = rng.normal(0.0, EXACT_RATE_SIGMA_RAD_S, (EXACT_SAMPLES, 3))
    out = [ident.update(0, rates[0], np.zeros(3))]
    for k in range(1, len(rates)):
        y = euler_regressor(rates[k - 1], rates[k], PERIOD_S) @ theta
        out.append(ident.update(k * PERIOD_NS, rates[k], y))
    return ident, out


def test_exact_regression_data_is_fitted_to_round_off() -> None:
    """With y = Φ θ exactly (the measurement model itself), RLS recovers θ to round-off."""
    ident, _ = _fit_exactly(J_TRUE)
    assert relative_error(ident.inertia_B_kgm2, J_TRUE) < EXACT_RTOL


def test_step_change_reconverges_with_forgetting() -> None:
    """With λ = 0.98 the estimate tracks a capture within STEP_RECONVERGE_SAMPLES cycles."""
    rates_a, torques_a = simulate(J_TRUE, N_SAMPLES, OMEGA0_B)
    rates_b, torques_b = simulate(J_CAPTURE, N_SAMPLES, rates_a[-1], k0=N_SAMPLES)
    rates = np.vstack((rates_a, rates_b[1:]))
    torques = np.vstack((torques_a, torques_b))
    ident = RlsInertiaIdentifier(RlsInertiaParams(J_GUESS, forgetting_factor=STEP_LAMBDA))
    errors = []
    for k, j in enumerate(feed(ident, rates, torques)):
        truth = J_TRUE if k <= N_SAMPLES else J_CAPTURE
        errors.append(math.inf if j is None else relative_error(j, truth))
    assert errors[N_SAMPLES] < STEP_RECONVERGE_RTOL  # converged before the step
    assert errors[N_SAMPLES + 1] > STEP_RECONVERGE_RTOL  # the step is seen
    settled = errors[N_SAMPLES + STEP_RECONVERGE_SAMPLES :]
    assert max(settled) < STEP_RECONVERGE_RTOL


def test_reset_on_capture_restarts_from_guess(
    clean_data: tuple[np.ndarray, np.ndarray],
) -> None:
    """reset(guess) replaces the estimate and withholds output until re-excited."""
    ident = RlsInertiaIdentifier(RlsInertiaParams(J_GUESS, forgetting_factor=1.0))
    feed(ident, *clean_data)
    ident.reset(J_CAPTURE)
    np.testing.assert_array_equal(ident.inertia_B_kgm2, J_CAPTURE)
    assert ident.n_updates == 0
    rates, _ = clean_data
    assert ident.update(0, rates[0], np.zeros(3)) is None
    ident.reset()  # covariance only: the estimate is kept
    np.testing.assert_array_equal(ident.inertia_B_kgm2, J_CAPTURE)


def test_measurement_noise_error_within_tolerance(
    clean_data: tuple[np.ndarray, np.ndarray],
) -> None:
    """Gaussian rate noise (2e-5 rad/s per sample): relative error below NOISY_RTOL."""
    rates, torques = clean_data
    noisy = rates + np.random.default_rng(1).normal(0.0, GYRO_NOISE_RAD_S, rates.shape)
    ident = RlsInertiaIdentifier(RlsInertiaParams(J_GUESS, forgetting_factor=1.0))
    final = feed(ident, noisy, torques)[-1]
    assert final is not None
    assert relative_error(final, J_TRUE) < NOISY_RTOL


def test_no_output_without_excitation() -> None:
    """A body at rest with zero torque never yields an estimate."""
    ident = RlsInertiaIdentifier(RlsInertiaParams(J_GUESS))
    for k in range(200):
        assert ident.update(k * PERIOD_NS, np.zeros(3), np.zeros(3)) is None
    np.testing.assert_array_equal(ident.inertia_B_kgm2, J_GUESS)


def test_covariance_stays_bounded_without_excitation() -> None:
    """With λ < 1 and no excitation the covariance trace stays at most 6 α (anti wind-up)."""
    alpha = 10.0
    ident = RlsInertiaIdentifier(
        RlsInertiaParams(J_GUESS, forgetting_factor=0.9, initial_covariance=alpha)
    )
    w = np.array([0.01, 0.0, 0.0])  # constant spin about x: excites only part of θ
    for k in range(2000):
        ident.update(k * PERIOD_NS, w, np.cross(w, J_GUESS @ w))
    assert np.trace(ident.covariance) <= 6.0 * alpha * (1.0 + 1e-12)
    assert np.all(np.isfinite(ident.covariance))


def test_gap_and_non_finite_samples_restart_differencing(
    clean_data: tuple[np.ndarray, np.ndarray],
) -> None:
    """A NaN rate, a repeated time or a long gap takes no RLS step."""
    rates, torques = clean_data
    ident = RlsInertiaIdentifier(RlsInertiaParams(J_GUESS, max_gap_s=0.1))
    ident.update(0, rates[0], np.zeros(3))
    ident.update(0, rates[1], torques[0])  # same time
    ident.update(PERIOD_NS, np.array([math.nan, 0.0, 0.0]), torques[0])
    ident.update(2 * PERIOD_NS, rates[2], torques[1])  # first sample after the NaN
    ident.update(2 * PERIOD_NS + 10**9, rates[3], torques[2])  # 1 s gap
    assert ident.n_updates == 0
    ident.update(3 * PERIOD_NS + 10**9, rates[4], torques[3])
    assert ident.n_updates == 1


def test_theta_layout_round_trip() -> None:
    """inertia_params and inertia_matrix are inverse (upper triangle, row order)."""
    theta = inertia_params(J_TRUE)
    np.testing.assert_array_equal(theta, [25.0, 1.2, -0.8, 20.0, 0.5, 15.0])
    np.testing.assert_array_equal(inertia_matrix(theta), J_TRUE)


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"inertia_guess_B_kgm2": [[1.0, 0.0], [0.0, 1.0]]}, "inertia_guess_B_kgm2"),
        ({"inertia_guess_B_kgm2": [[1, 2, 0], [0, 1, 0], [0, 0, 1]]}, "inertia_guess_B_kgm2"),
        ({"inertia_guess_B_kgm2": np.diag([1.0, -1.0, 1.0])}, "inertia_guess_B_kgm2"),
        ({"forgetting_factor": 0.0}, "forgetting_factor"),
        ({"forgetting_factor": 1.01}, "forgetting_factor"),
        ({"initial_covariance": -1.0}, "initial_covariance"),
        ({"min_information": -1e-3}, "min_information"),
        ({"min_regressor_norm": math.nan}, "min_regressor_norm"),
        ({"max_gap_s": 0.0}, "max_gap_s"),
    ],
)
def test_invalid_params_are_rejected(kwargs: dict[str, object], key: str) -> None:
    """Each invalid parameter raises a ConfigError naming it."""
    args: dict[str, object] = {"inertia_guess_B_kgm2": J_GUESS, **kwargs}
    with pytest.raises(ConfigError) as info:
        RlsInertiaParams(**args)  # type: ignore[arg-type]
    assert info.value.key == key


WINDOW_CYCLES = 10
LARGE_NOISE_RAD_S = 2e-4  # 10x the gyro noise above: the single-period regressor suffers


def test_window_noise_free_converges_to_truth(clean_data: tuple[np.ndarray, np.ndarray]) -> None:
    """Integrated over a window of periods, noise-free data still give the exact inertia."""
    params = RlsInertiaParams(J_GUESS, forgetting_factor=1.0, window_cycles=WINDOW_CYCLES)
    out = feed(RlsInertiaIdentifier(params), *clean_data)
    assert all(j is None for j in out[:WINDOW_CYCLES])  # no estimate before a full window
    final = out[-1]
    assert final is not None
    assert relative_error(final, J_TRUE) < NOISE_FREE_RTOL


def test_window_reduces_the_noise_bias(clean_data: tuple[np.ndarray, np.ndarray]) -> None:
    """With large rate noise, the windowed regressor's error is smaller than one period's."""
    rates, torques = clean_data
    noisy = rates + np.random.default_rng(2).normal(0.0, LARGE_NOISE_RAD_S, rates.shape)
    errors = []
    for window in (1, WINDOW_CYCLES):
        params = RlsInertiaParams(J_GUESS, forgetting_factor=1.0, window_cycles=window)
        final = feed(RlsInertiaIdentifier(params), noisy, torques)[-1]
        assert final is not None
        errors.append(relative_error(final, J_TRUE))
    assert errors[1] < errors[0]


@pytest.mark.parametrize("bad", [0, -1, 2.5, True])
def test_window_cycles_validated(bad: object) -> None:
    """window_cycles must be an integer >= 1; the error names the key."""
    with pytest.raises(ConfigError, match="window_cycles"):
        RlsInertiaParams(J_GUESS, window_cycles=bad)  # type: ignore[arg-type]


# Positive definite but no body's: principal moments (6, 9, 18), 6 + 9 < 18 (a rotated
# diagonal, so its products of inertia are not zero).
J_UNPHYSICAL_PRINCIPAL = (6.0, 9.0, 18.0)
# its identification error (noise-free, measured 2.3e-6) far below its distance from the
# nearest physical inertia (principal moments (7, 10, 17): 8 %)
UNPHYSICAL_FIT_RTOL = 1e-4
TRIANGLE_MARGIN = 1e-3  # relative: J3 = (J1 + J2)(1 ± this) either side of the boundary
ROTATION_RAD = (0.4, -0.7, 0.25)  # an arbitrary rotation vector for the principal axes


def _rotated(principal: tuple[float, float, float]) -> np.ndarray:
    """``C diag(principal) Cᵀ`` for the rotation :data:`ROTATION_RAD` (Rodrigues)."""
    v = np.array(ROTATION_RAD)
    angle = float(np.linalg.norm(v))
    k = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]) / angle
    c = np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)
    return c @ np.diag(principal) @ c.T


def test_unphysical_estimate_is_withheld(clean_data: tuple[np.ndarray, np.ndarray]) -> None:
    """Data of a positive definite J no body has: identified, but never handed out."""
    j_bad = _rotated(J_UNPHYSICAL_PRINCIPAL)
    assert np.all(np.linalg.eigvalsh(j_bad) > 0.0)
    ident = RlsInertiaIdentifier(RlsInertiaParams(J_GUESS, forgetting_factor=1.0))
    out = feed(ident, *simulate(j_bad, N_SAMPLES, OMEGA0_B))
    assert relative_error(ident.inertia_B_kgm2, j_bad) < UNPHYSICAL_FIT_RTOL  # identified
    assert out[-1] is None
    assert ident.n_unphysical > 0
    good = RlsInertiaIdentifier(RlsInertiaParams(J_GUESS, forgetting_factor=1.0))
    assert feed(good, *clean_data)[-1] is not None and good.n_unphysical == 0


@pytest.mark.parametrize("side", [-1.0, 1.0])
def test_physical_inertia_boundary_is_the_triangle_inequality(side: float) -> None:
    """J3 just under J1 + J2 is handed out; just over it is withheld (rotated axes)."""
    j1, j2 = 7.0, 11.0
    j = _rotated((j1, j2, (j1 + j2) * (1.0 + side * TRIANGLE_MARGIN)))
    ident, out = _fit_exactly(j)
    assert relative_error(ident.inertia_B_kgm2, j) < EXACT_RTOL
    assert (out[-1] is None) == (side > 0.0)
    assert (ident.n_unphysical > 0) == (side > 0.0)
