"""Known answers and closed-loop properties of the direct parametric MRP law (seed 001 §3)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from scipy.linalg import expm

from dbc.errors import ConfigError
from flight_sw import mrp
from flight_sw import quaternion as qt
from flight_sw.control.mrp_direct_parametric import (
    MrpDirectParametric,
    MrpDirectParametricParams,
    seed001_e,
)

EXACT_TOL = 1e-12
T_NS = 0
ZERO = np.zeros(3)
# Seed 001 section 5: identified inertia, initial MRP and rate, reference polynomials.
SEED001_INERTIA_KGM2 = np.diag([25.0, 20.0, 15.0])
SEED001_SIGMA0 = np.array([0.08381, 0.101, 0.1205])
SEED001_OMEGA0_RAD_S = np.array([0.087266, 0.043633, 0.05236])
# Coefficients, highest power first. σd3's t² term is printed without its "t²" in the seed.
SEED001_SIGMA_D_POLY = (
    (-1.475e-8, 4.559e-6, -5.105e-4, 0.02439, 0.08381),
    (0.0, 1.136e-6, -2.5e-4, 0.01768, 0.101),
    (0.0, 8.899e-7, -2.088e-4, 0.01578, 0.1205),
)
# A full (non-diagonal) inertia for the exact closed-loop test [kg m²].
FULL_INERTIA_KGM2 = np.array([[25.0, 1.2, -0.8], [1.2, 20.0, 0.5], [-0.8, 0.5, 15.0]])
RK4_STEP_S = 0.005
TRACK_STEP_S = 0.02
EXACT_LOOP_DURATION_S = 4.0
EXACT_LOOP_TOL = 1e-6
TRACK_DURATION_S = 16.0
TRACK_SETTLED_AFTER_S = 12.0
TRACK_SETTLED_TOL = 1e-4  # MRP, about 0.02°
JACOBIAN_STEP = 1e-7
EIGENVALUE_TOL = 1e-5

Reference = Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]]


def seed001_reference(t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q_RN, ω_RN_R, ω̇_RN_R of the seed-001 polynomial MRP trajectory σd(t)."""
    polys = [np.poly1d(c) for c in SEED001_SIGMA_D_POLY]
    sigma = np.array([p(t_s) for p in polys])
    sigma_dot = np.array([p.deriv()(t_s) for p in polys])
    sigma_ddot = np.array([p.deriv(2)(t_s) for p in polys])
    g = mrp.kinematics_matrix_inverse(sigma)
    omega_R = g @ sigma_dot
    domega_R = g @ (sigma_ddot - mrp.kinematics_matrix_rate(sigma, sigma_dot) @ omega_R)
    return mrp.to_quaternion(sigma), omega_R, domega_R


def _body_reference(
    reference: Reference, t_s: float, q_BN: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    q_RN, omega_R, domega_R = reference(t_s)
    c_BR = qt.to_dcm(qt.error_quaternion(q_RN, q_BN))
    return q_RN, c_BR @ omega_R, c_BR @ domega_R


def simulate(
    ctrl: MrpDirectParametric,
    inertia: np.ndarray,
    reference: Reference,
    q0: np.ndarray,
    omega0: np.ndarray,
    duration_s: float,
    dt_s: float,
) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """RK4 of the rigid body under the (continuous) law; returns (t, q_BN, ω_BN_B) samples."""
    j_inv = np.linalg.inv(inertia)

    def deriv(t: float, q: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q_RN, w_ref, dw_ref = _body_reference(reference, t, q)
        tau = ctrl.torque_B_Nm(T_NS, q, w, q_RN, w_ref, dw_ref)
        q_dot = 0.5 * qt.multiply(q, np.concatenate(([0.0], w)))
        return q_dot, j_inv @ (tau - np.cross(w, inertia @ w))

    q, w, t = q0.copy(), omega0.copy(), 0.0
    out = [(t, q, w)]
    for _ in range(round(duration_s / dt_s)):
        k1 = deriv(t, q, w)
        k2 = deriv(t + dt_s / 2, q + dt_s / 2 * k1[0], w + dt_s / 2 * k1[1])
        k3 = deriv(t + dt_s / 2, q + dt_s / 2 * k2[0], w + dt_s / 2 * k2[1])
        k4 = deriv(t + dt_s, q + dt_s * k3[0], w + dt_s * k3[1])
        q = qt.normalise(q + dt_s / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]))
        w = w + dt_s / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        t += dt_s
        out.append((t, q, w))
    return out


def error_state(reference: Reference, t_s: float, q: np.ndarray, w: np.ndarray) -> np.ndarray:
    """X = [ε; ε̇] with ε = σ_BR (short way) and ε̇ = F(ε)(ω − ω_RN_B)."""
    q_RN, w_ref, _ = _body_reference(reference, t_s, q)
    eps = mrp.from_quaternion(qt.error_quaternion(q_RN, q))
    return np.concatenate((eps, mrp.kinematics_matrix(eps) @ (w - w_ref)))


@pytest.mark.parametrize("case", [1, 2, 3])
def test_closed_loop_error_is_exactly_linear(case: int) -> None:
    """With the exact model V⁻¹X(t) = e^{F0 t} V⁻¹X(0) along a 50° tracking transient."""
    params = MrpDirectParametricParams.from_case(case)
    ctrl = MrpDirectParametric(params, FULL_INERTIA_KGM2)
    q_RN0, _, _ = seed001_reference(0.0)
    q0 = qt.multiply(q_RN0, qt.from_rotation_vector(np.radians([30.0, -25.0, 30.0])))
    omega0 = np.array([0.05, -0.1, 0.08])
    run = simulate(
        ctrl, FULL_INERTIA_KGM2, seed001_reference, q0, omega0, EXACT_LOOP_DURATION_S, RK4_STEP_S
    )
    v_inv = np.linalg.inv(params.v_matrix())
    f0 = np.array(params.f0)
    y0 = v_inv @ error_state(seed001_reference, 0.0, q0, omega0)
    for t, q, w in run[:: len(run) // 8]:
        y = v_inv @ error_state(seed001_reference, t, q, w)
        np.testing.assert_allclose(y, expm(f0 * t) @ y0, atol=EXACT_LOOP_TOL)


def test_linearised_closed_loop_has_the_eigenvalues_of_f0() -> None:
    """The Jacobian of the closed-loop error dynamics at X = 0 has the spectrum of F0 (case 1)."""
    params = MrpDirectParametricParams.from_case(1)
    ctrl = MrpDirectParametric(params, SEED001_INERTIA_KGM2)
    j_inv = np.linalg.inv(SEED001_INERTIA_KGM2)

    def x_dot(x: np.ndarray) -> np.ndarray:
        eps, eps_dot = x[:3], x[3:]
        w = mrp.kinematics_matrix_inverse(eps) @ eps_dot
        tau = ctrl.torque_B_Nm(T_NS, mrp.to_quaternion(eps), w, qt.identity(), ZERO)
        w_dot = j_inv @ (tau - np.cross(w, SEED001_INERTIA_KGM2 @ w))
        f = mrp.kinematics_matrix(eps)
        eps_ddot = f @ w_dot + mrp.kinematics_matrix_rate(eps, eps_dot) @ w
        return np.concatenate((eps_dot, eps_ddot))

    jac = np.column_stack(
        [
            (x_dot(JACOBIAN_STEP * e) - x_dot(-JACOBIAN_STEP * e)) / (2 * JACOBIAN_STEP)
            for e in np.eye(6)
        ]
    )
    got = np.sort_complex(np.linalg.eigvals(jac))
    want = np.sort_complex(np.linalg.eigvals(seed001_e()))
    np.testing.assert_allclose(got, want, atol=EIGENVALUE_TOL)


def test_zero_error_and_zero_reference_gives_zero_torque() -> None:
    """At rest on a fixed reference the torque is exactly zero."""
    ctrl = MrpDirectParametric(MrpDirectParametricParams.from_case(1), SEED001_INERTIA_KGM2)
    q = qt.normalise(np.array([0.3, 0.1, -0.9, 0.2]))
    np.testing.assert_allclose(ctrl.torque_B_Nm(T_NS, q, ZERO, q, ZERO), 0.0, atol=EXACT_TOL)


def test_on_a_spinning_reference_only_the_feed_forward_remains() -> None:
    """Zero error on a reference spinning at ω with acceleration α: τ = ω × Jω + J α."""
    ctrl = MrpDirectParametric(MrpDirectParametricParams.from_case(2), FULL_INERTIA_KGM2)
    q = qt.normalise(np.array([0.3, 0.1, -0.9, 0.2]))
    w = np.array([0.1, -0.2, 0.05])
    alpha = np.array([0.01, 0.0, -0.02])
    expected = np.cross(w, FULL_INERTIA_KGM2 @ w) + FULL_INERTIA_KGM2 @ alpha
    np.testing.assert_allclose(ctrl.torque_B_Nm(T_NS, q, w, q, w, alpha), expected, atol=EXACT_TOL)


def test_sign_of_quaternions_does_not_matter() -> None:
    """q and −q (body or reference) give the same torque."""
    ctrl = MrpDirectParametric(MrpDirectParametricParams.from_case(1), SEED001_INERTIA_KGM2)
    q_BN = qt.from_rotation_vector(np.array([1.2, -0.7, 0.4]))
    q_RN = qt.from_rotation_vector(np.array([-0.3, 0.2, 0.9]))
    w = np.array([0.02, 0.01, -0.03])
    t0 = ctrl.torque_B_Nm(T_NS, q_BN, w, q_RN, ZERO)
    np.testing.assert_allclose(ctrl.torque_B_Nm(T_NS, -q_BN, w, q_RN, ZERO), t0, atol=EXACT_TOL)
    np.testing.assert_allclose(ctrl.torque_B_Nm(T_NS, q_BN, w, -q_RN, ZERO), t0, atol=EXACT_TOL)


def test_tracks_the_seed001_trajectory_and_larger_f0_tracks_tighter() -> None:
    """Seed 001 §5: all cases converge to σd; peak error shrinks from case 2 to 1 to 3."""
    q0 = mrp.to_quaternion(SEED001_SIGMA0)
    peaks = {}
    for case in (2, 1, 3):
        ctrl = MrpDirectParametric(MrpDirectParametricParams.from_case(case), SEED001_INERTIA_KGM2)
        run = simulate(
            ctrl,
            SEED001_INERTIA_KGM2,
            seed001_reference,
            q0,
            SEED001_OMEGA0_RAD_S,
            TRACK_DURATION_S,
            TRACK_STEP_S,
        )
        # the seed's error ε = σ − σd (both MRPs of N-relative attitudes)
        errors = [
            (t, mrp.from_quaternion(q) - mrp.from_quaternion(seed001_reference(t)[0]))
            for t, q, _ in run
        ]
        peaks[case] = max(float(np.max(np.abs(e))) for _, e in errors)
        settled = max(float(np.max(np.abs(e))) for t, e in errors if t >= TRACK_SETTLED_AFTER_S)
        assert settled < TRACK_SETTLED_TOL, (case, settled)
    assert peaks[3] < peaks[1] < peaks[2]


def test_set_inertia_equals_building_with_that_inertia() -> None:
    """After set_inertia_B_kgm2(J) the law is the one built with J."""
    params = MrpDirectParametricParams.from_case(3)
    updated = MrpDirectParametric(params, SEED001_INERTIA_KGM2)
    updated.set_inertia_B_kgm2(FULL_INERTIA_KGM2)
    direct = MrpDirectParametric(params, FULL_INERTIA_KGM2)
    args = (
        T_NS,
        qt.from_rotation_vector(np.array([0.5, -0.2, 0.1])),
        np.array([0.03, -0.02, 0.01]),
        qt.identity(),
        np.array([0.0, 0.01, 0.0]),
        np.array([0.001, 0.0, 0.0]),
    )
    np.testing.assert_allclose(updated.torque_B_Nm(*args), direct.torque_B_Nm(*args))
    np.testing.assert_allclose(updated.inertia_B_kgm2, FULL_INERTIA_KGM2)


def test_cases_match_the_seed() -> None:
    """Case k has F0 = scale·E (1, 0.5, 2) and Z = [I3 I3]; E has eigenvalues −1±i, −3…−6."""
    e = seed001_e()
    want_eigs = np.sort_complex(np.array([-1 + 1j, -1 - 1j, -3, -4, -5, -6], dtype=complex))
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(e)), want_eigs, atol=EXACT_TOL)
    for case, scale in ((1, 1.0), (2, 0.5), (3, 2.0)):
        p = MrpDirectParametricParams.from_case(case)
        np.testing.assert_allclose(np.array(p.f0), scale * e, atol=EXACT_TOL)
        np.testing.assert_allclose(np.array(p.z), np.hstack((np.eye(3), np.eye(3))))


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"f0": -seed001_e(), "z": np.hstack((np.eye(3), np.eye(3)))}, "f0"),
        ({"f0": seed001_e(), "z": np.hstack((np.eye(3), np.zeros((3, 3))))}, "z"),
        ({"f0": seed001_e()[:5], "z": np.hstack((np.eye(3), np.eye(3)))}, "f0"),
        ({"f0": seed001_e(), "z": np.eye(3)}, "z"),
    ],
)
def test_bad_design_is_rejected(kwargs: dict[str, np.ndarray], key: str) -> None:
    """Non-Hurwitz F0, singular V = [Z; Z F0] and wrong shapes raise ConfigError naming the key."""
    with pytest.raises(ConfigError, match=key):
        MrpDirectParametricParams(**kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize("case", [0, 4, True, 1.5])
def test_unknown_case_is_rejected(case: object) -> None:
    """Only cases 1, 2, 3 exist."""
    with pytest.raises(ConfigError, match="case"):
        MrpDirectParametricParams.from_case(case)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    "inertia",
    [
        np.array([[25.0, 1.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 15.0]]),
        np.diag([25.0, -20.0, 15.0]),
        np.diag([25.0, math.nan, 15.0]),
    ],
)
def test_bad_inertia_is_rejected(inertia: np.ndarray) -> None:
    """Asymmetric, indefinite or non-finite inertia raises ValueError."""
    ctrl = MrpDirectParametric(MrpDirectParametricParams.from_case(1), SEED001_INERTIA_KGM2)
    with pytest.raises(ValueError, match="inertia"):
        ctrl.set_inertia_B_kgm2(inertia)
