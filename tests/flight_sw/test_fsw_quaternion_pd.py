"""Known-answer tests of the quaternion PD controller and its bandwidth design."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw import quaternion as qt
from flight_sw.control.quaternion_pd import QuaternionPd, QuaternionPdParams

EXACT_TOL = 1e-12
LINEARISATION_STEP = 1e-7  # rad and rad/s, central differences
LINEARISATION_RTOL = 1e-6
T_NS = 0
ZERO_RATE = np.zeros(3)

KP = (1.0, 2.0, 3.0)
KD = (10.0, 20.0, 30.0)


def test_known_torque_for_known_error() -> None:
    """τ = −Kp sin(θ/2) e − Kd (ω − ω_ref) for a 60° error about e and a rate error."""
    ctrl = QuaternionPd(QuaternionPdParams(kp_Nm=KP, kd_Nms=KD))
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    angle = math.radians(60.0)
    q_RN = qt.normalise(np.array([0.5, -0.5, 0.5, 0.5]))
    q_BN = qt.multiply(q_RN, qt.from_rotation_vector(axis * angle))  # q_BR = exp(θ e)
    omega_BN_B = np.array([0.1, -0.2, 0.3])
    omega_RN_B = np.array([0.05, 0.0, -0.1])
    expected = -np.array(KP) * math.sin(angle / 2) * axis - np.array(KD) * (omega_BN_B - omega_RN_B)
    torque = ctrl.torque_B_Nm(T_NS, q_BN, omega_BN_B, q_RN, omega_RN_B)
    np.testing.assert_allclose(torque, expected, atol=EXACT_TOL)


def test_zero_error_gives_zero_torque() -> None:
    """On the reference at the reference rate the torque is zero."""
    ctrl = QuaternionPd(QuaternionPdParams(kp_Nm=KP, kd_Nms=KD))
    q = qt.normalise(np.array([0.3, 0.1, -0.9, 0.2]))
    omega = np.array([0.01, 0.02, 0.03])
    np.testing.assert_allclose(ctrl.torque_B_Nm(T_NS, q, omega, q, omega), 0.0, atol=EXACT_TOL)


def test_sign_of_quaternion_does_not_matter() -> None:
    """q_BN and −q_BN (same attitude) give the same torque: δq0 < 0 is flipped."""
    ctrl = QuaternionPd(QuaternionPdParams(kp_Nm=KP, kd_Nms=KD))
    q_BN = qt.from_rotation_vector(np.array([0.3, -0.2, 0.1]))
    t_pos = ctrl.torque_B_Nm(T_NS, q_BN, ZERO_RATE, qt.identity(), ZERO_RATE)
    t_neg = ctrl.torque_B_Nm(T_NS, -q_BN, ZERO_RATE, qt.identity(), ZERO_RATE)
    t_ref_neg = ctrl.torque_B_Nm(T_NS, q_BN, ZERO_RATE, -qt.identity(), ZERO_RATE)
    np.testing.assert_allclose(t_neg, t_pos, atol=EXACT_TOL)
    np.testing.assert_allclose(t_ref_neg, t_pos, atol=EXACT_TOL)


def test_error_beyond_180_deg_is_corrected_the_short_way() -> None:
    """An error of +270° about x (δq0 < 0) is a −90° error: the torque is about +x."""
    ctrl = QuaternionPd(QuaternionPdParams(kp_Nm=KP, kd_Nms=KD))
    q_BN = qt.from_rotation_vector(np.array([math.radians(270.0), 0.0, 0.0]))
    assert q_BN[0] < 0.0
    torque = ctrl.torque_B_Nm(T_NS, q_BN, ZERO_RATE, qt.identity(), ZERO_RATE)
    np.testing.assert_allclose(torque, [KP[0] * math.sin(math.radians(45.0)), 0, 0], atol=EXACT_TOL)


def test_from_bandwidth_gains(inertia_kgm2: tuple[float, float, float]) -> None:
    """Kp_i = 2 J_i ωn², Kd_i = 2 ζ ωn J_i."""
    wn, zeta = 0.8, 0.7
    p = QuaternionPdParams.from_bandwidth(inertia_kgm2, wn, zeta)
    for j, kp, kd in zip(inertia_kgm2, p.kp_Nm, p.kd_Nms, strict=True):
        assert math.isclose(kp, 2.0 * j * wn**2)
        assert math.isclose(kd, 2.0 * zeta * wn * j)


@pytest.mark.parametrize(("wn", "zeta"), [(0.5, 0.7), (1.2, 1.0), (0.2, 0.3)])
def test_linearised_closed_loop_has_requested_frequency_and_damping(
    wn: float, zeta: float, inertia_kgm2: tuple[float, float, float]
) -> None:
    """Linearising J ω̇ = τ(θ, ω), θ̇ = ω about the reference gives ωn and ζ on every axis."""
    inertia = np.array(inertia_kgm2)
    ctrl = QuaternionPd(QuaternionPdParams.from_bandwidth(tuple(inertia), wn, zeta))
    q_RN = qt.normalise(np.array([0.9, -0.1, 0.3, 0.2]))

    def torque(theta: np.ndarray, omega: np.ndarray) -> np.ndarray:
        q_BN = qt.multiply(q_RN, qt.from_rotation_vector(theta))
        return ctrl.torque_B_Nm(T_NS, q_BN, omega, q_RN, ZERO_RATE)

    h = LINEARISATION_STEP
    d_theta = np.zeros((3, 3))
    d_omega = np.zeros((3, 3))
    for i in range(3):
        e = np.eye(3)[i] * h
        d_theta[:, i] = (torque(e, ZERO_RATE) - torque(-e, ZERO_RATE)) / (2 * h)
        d_omega[:, i] = (torque(np.zeros(3), e) - torque(np.zeros(3), -e)) / (2 * h)
    for i in range(3):
        # axis i: J θ̈ = d_theta θ + d_omega θ̇  ->  ωn² = −d_theta/J, 2ζωn = −d_omega/J
        wn_i = math.sqrt(-d_theta[i, i] / inertia[i])
        zeta_i = -d_omega[i, i] / inertia[i] / (2.0 * wn_i)
        assert math.isclose(wn_i, wn, rel_tol=LINEARISATION_RTOL)
        assert math.isclose(zeta_i, zeta, rel_tol=LINEARISATION_RTOL)
    off_diagonal = d_theta - np.diag(np.diag(d_theta))
    assert np.max(np.abs(off_diagonal)) < LINEARISATION_RTOL * np.max(np.abs(d_theta))


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"kp_Nm": (1.0, 2.0), "kd_Nms": KD}, "kp_Nm"),
        ({"kp_Nm": KP, "kd_Nms": (1.0, -2.0, 3.0)}, "kd_Nms"),
        ({"kp_Nm": (1.0, float("inf"), 3.0), "kd_Nms": KD}, "kp_Nm"),
    ],
)
def test_params_validate(kwargs: dict[str, object], key: str) -> None:
    """Invalid gains raise ConfigError naming the key."""
    with pytest.raises(ConfigError) as info:
        QuaternionPdParams(**kwargs)  # type: ignore[arg-type]
    assert info.value.key == key


def test_from_bandwidth_validates() -> None:
    """Non-positive inertia or frequency raises ConfigError."""
    with pytest.raises(ConfigError):
        QuaternionPdParams.from_bandwidth((1.0, 0.0, 1.0), 1.0, 0.7)
    with pytest.raises(ConfigError):
        QuaternionPdParams.from_bandwidth((1.0, 1.0, 1.0), 0.0, 0.7)
