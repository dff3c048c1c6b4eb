"""The RLS identifier's float kernels against their numpy reference forms.

Back to back on random inputs of the identifier's sizes: the written-out gyroscopic
regressor, the window equation (one period and a 50-period window), the RLS step with and
without the trace bound, and the Cholesky gates against eigenvalues. An innovation matrix
too ill-conditioned for Cholesky is solved by the kernel's own SVD path (equal to the
reference's LU solve where the data determine the answer); a non-finite step is refused,
and the identifier counts both.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from flight_sw.estimation import rls_inertia, rls_kernel
from flight_sw.estimation.rls_inertia import (
    RlsInertiaIdentifier,
    RlsInertiaParams,
    inertia_params,
)
from flight_sw.quaternion import skew

from .rls_reference import (
    euler_regressor,
    momentum_regressor,
    rls_step_reference,
    window_equation_reference,
)

SEED = 20261204
CASES = 200
PERIOD_NS = 20_000_000
JITTER_NS = 200_000  # period jitter of the random windows
RATE_SCALE_RAD_S = 0.05
TORQUE_SCALE_NM = 2.0
REGRESSOR_RTOL = 1e-12  # two summation orders of the same sums
STEP_RTOL = 1e-9  # LU vs Cholesky solve of S (condition up to ~1e6 here)
# LU vs Jacobi SVD of an S of condition ~1e15: the step's parts the data determine agree to
# round-off (measured ~6e-16), relative to each result's largest entry.
SINGULAR_STEP_RTOL = 1e-12
SINGULAR_COVARIANCE = 1e16  # P = this × I: λ within round-off of Φ P Φᵀ (~6e14)
NO_TRACE_CAP = 1e30
EIG_MARGIN = 1e-6  # relative distance from the gate's threshold kept by the random cases
WINDOWS = (1, 50)
J_GUESS = np.diag([20.0, 20.0, 20.0])
J_TRUE = np.array([[25.0, 1.2, -0.8], [1.2, 20.0, 0.5], [-0.8, 0.5, 15.0]])
N_CYCLES = 60


def _close(a: object, b: object, rtol: float) -> bool:
    """Equal to ``rtol`` of the reference's largest entry."""
    a_arr, b_arr = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return bool(np.max(np.abs(a_arr - b_arr)) <= rtol * max(float(np.max(np.abs(b_arr))), 1.0))


def _spd(rng: np.random.Generator, n: int, scale: float) -> np.ndarray:
    """A random symmetric positive-definite n×n matrix of the given scale."""
    a = rng.normal(size=(n, n))
    return scale * (a @ a.T / n + 1e-3 * np.eye(n))


def test_gyroscopic_equals_skew_times_regressor() -> None:
    """``[ω×] Ω(ω)`` written out equals the matrix product."""
    rng = np.random.default_rng(SEED)
    for _ in range(CASES):
        w = (RATE_SCALE_RAD_S * rng.normal(size=3)).tolist()
        ref = skew(np.array(w)) @ momentum_regressor(np.array(w))
        assert _close(np.reshape(rls_kernel.gyroscopic(w), (3, 6)), ref, REGRESSOR_RTOL)


@pytest.mark.parametrize("n", WINDOWS)
def test_window_equation_equals_reference(n: int) -> None:
    """``(Φ, y)`` over 1 and 50 periods equals the numpy form."""
    rng = np.random.default_rng(SEED + n)
    for _ in range(CASES // 4):
        t_ns = np.cumsum(PERIOD_NS + rng.integers(-JITTER_NS, JITTER_NS, size=n + 1)).tolist()
        omega = [RATE_SCALE_RAD_S * rng.normal(size=3) for _ in range(n + 1)]
        tau = [TORQUE_SCALE_NM * rng.normal(size=3) for _ in range(n + 1)]
        phi_ref, y_ref = window_equation_reference(t_ns, omega, tau)
        h_s = [(b - a) / 1e9 for a, b in itertools.pairwise(t_ns)]
        phi, y = rls_kernel.window_equation(
            h_s, omega[0].tolist(), omega[-1].tolist(),
            [rls_kernel.gyroscopic(w.tolist()) for w in omega], [x.tolist() for x in tau[1:]],
        )
        assert _close(phi, phi_ref, REGRESSOR_RTOL)
        assert _close(y, y_ref, REGRESSOR_RTOL)


@pytest.mark.parametrize("trace_cap", [1e30, 1.0])
def test_rls_step_equals_reference(trace_cap: float) -> None:
    """One RLS step (gain, θ, P, R), with and without the trace bound, equals numpy's."""
    rng = np.random.default_rng(SEED)
    for _ in range(CASES):
        p = _spd(rng, 6, float(rng.choice([1e-3, 1.0, 1e3])))
        info = _spd(rng, 6, 1e-2)
        theta = rng.normal(size=6) * 20.0
        phi = rng.normal(size=(3, 6)) * 1e-2
        y = rng.normal(size=3)
        lam = float(rng.uniform(0.95, 1.0))
        ref = rls_step_reference(p, theta, info, phi, y, lam, trace_cap)
        out = rls_kernel.rls_step(
            p.tolist(), theta.tolist(), info.tolist(), phi.tolist(), y.tolist(), lam, trace_cap
        )
        assert out is not None and not out[3]  # the Cholesky path
        for got, want in zip(out[:3], ref, strict=True):
            assert _close(got, want, STEP_RTOL)
        assert np.array_equal(np.array(out[0]), np.array(out[0]).T)  # P exactly symmetric


def test_rls_step_solves_a_numerically_singular_innovation_matrix() -> None:
    """Two identical regressor rows and a huge P: S fails the Cholesky gate; the kernel's SVD
    path still gives the reference's step (consistent measurements: y = Φ θ*)."""
    rng = np.random.default_rng(SEED)
    row = rng.normal(size=6) * 1e-1
    for _ in range(CASES // 10):
        phi = np.vstack([row, row, rng.normal(size=6) * 1e-1])
        p = SINGULAR_COVARIANCE * np.eye(6)
        lam = float(rng.uniform(0.95, 1.0))
        theta = rng.normal(size=6) * 20.0
        y = phi @ (theta + rng.normal(size=6))
        info = _spd(rng, 6, 1e-2)
        out = rls_kernel.rls_step(p.tolist(), theta.tolist(), info.tolist(), phi.tolist(),
                                  y.tolist(), lam, NO_TRACE_CAP)
        assert out is not None and out[3]  # S failed the Cholesky gate: the SVD path
        ref = rls_step_reference(p, theta, info, phi, y, lam, NO_TRACE_CAP)
        for got, want in zip(out[:3], ref, strict=True):
            assert _close(got, want, SINGULAR_STEP_RTOL)


def test_rls_step_solves_an_indefinite_innovation_matrix() -> None:
    """``S`` indefinite (an invalid, negative P) but non-singular: the SVD path inverts it
    exactly as LAPACK's LU does."""
    rng = np.random.default_rng(SEED)
    phi = rng.normal(size=(3, 6))
    p = -1e3 * np.eye(6)
    theta, y, info = np.ones(6), rng.normal(size=3), np.zeros((6, 6))
    out = rls_kernel.rls_step(p.tolist(), theta.tolist(), info.tolist(), phi.tolist(),
                              y.tolist(), 0.99, NO_TRACE_CAP)
    assert out is not None and out[3]
    ref = rls_step_reference(p, theta, info, phi, y, 0.99, NO_TRACE_CAP)
    for got, want in zip(out[:3], ref, strict=True):
        assert _close(got, want, STEP_RTOL)


def test_rls_step_refuses_a_non_finite_result() -> None:
    """A covariance at the edge of the float range overflows the step: None (refused)."""
    rng = np.random.default_rng(SEED)
    phi = rng.normal(size=(3, 6)) * 1e3
    p = 1e307 * np.eye(6)
    out = rls_kernel.rls_step(p.tolist(), [1.0] * 6, np.zeros((6, 6)).tolist(), phi.tolist(),
                              [1.0, 2.0, 3.0], 0.99, NO_TRACE_CAP)
    assert out is None


def test_exceeds_matches_the_smallest_eigenvalue() -> None:
    """``exceeds(A, m)`` is ``λ_min(A) > m`` on random symmetric matrices and a known answer."""
    assert rls_kernel.exceeds(np.diag([1.0, 2.0, 3.0]).tolist(), 0.5)
    assert not rls_kernel.exceeds(np.diag([1.0, 2.0, 3.0]).tolist(), 1.0)
    rng = np.random.default_rng(SEED)
    for _ in range(CASES):
        a = _spd(rng, 6, 1.0) - float(rng.uniform(0.0, 1.0)) * np.eye(6)
        m = float(rng.uniform(-0.5, 0.5))
        lam_min = float(np.linalg.eigvalsh(a)[0])
        if abs(lam_min - m) <= EIG_MARGIN * max(abs(m), 1.0):
            continue
        assert rls_kernel.exceeds(a.tolist(), m) == (lam_min > m)


def test_identifier_counts_svd_and_refused_steps(monkeypatch: pytest.MonkeyPatch) -> None:
    """Steps taken by the SVD path are counted and used; refused steps are counted and
    skipped (the estimate keeps its value)."""
    rng = np.random.default_rng(SEED)
    omega = RATE_SCALE_RAD_S * rng.normal(size=(N_CYCLES, 3))
    theta_true = inertia_params(J_TRUE)
    # torques that fit Euler's equation exactly for J_TRUE (one-period regressor)
    torque = [np.zeros(3)] + [
        euler_regressor(omega[k - 1], omega[k], PERIOD_NS / 1e9) @ theta_true
        for k in range(1, N_CYCLES)
    ]
    params = RlsInertiaParams(inertia_guess_B_kgm2=J_GUESS, min_information=0.0)

    def run() -> tuple[RlsInertiaIdentifier, list[np.ndarray | None]]:
        ident = RlsInertiaIdentifier(params)
        return ident, [ident.update(k * PERIOD_NS, omega[k], torque[k]) for k in range(N_CYCLES)]

    step = rls_kernel.rls_step
    ident, plain = run()
    assert (ident.n_svd_steps, ident.n_refused_steps) == (0, 0)
    assert plain[-1] is not None and _close(plain[-1], J_TRUE, STEP_RTOL)
    monkeypatch.setattr(rls_inertia.kernel, "rls_step",
                        lambda *args: (*step(*args)[:3], True))  # type: ignore[misc]
    ident, flagged = run()
    assert ident.n_svd_steps == ident.n_updates == N_CYCLES - 1
    assert all(np.array_equal(a, b) for a, b in zip(plain[1:], flagged[1:], strict=True))
    monkeypatch.setattr(rls_inertia.kernel, "rls_step", lambda *args: None)
    ident, refused = run()
    assert ident.n_refused_steps == N_CYCLES - 1 and ident.n_updates == 0
    assert all(j is None for j in refused)
    np.testing.assert_array_equal(ident.inertia_B_kgm2, J_GUESS)
