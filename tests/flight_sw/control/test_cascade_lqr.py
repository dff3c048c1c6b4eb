"""Known answers, LQR design and closed-loop convergence of the seed-003 cascade law."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw import quaternion as qt
from flight_sw.control.cascade_lqr import (
    CascadeLqr,
    CascadeLqrDesign,
    CascadeLqrParams,
    lqr_gains,
    outer_loop_model,
)

EXACT_TOL = 1e-12
RICCATI_TOL = 1e-9
GAIN_RTOL = 1e-9
T_NS = 0
ZERO = np.zeros(3)
# Seed 003 Table 1 and Table 2.
SEED003_INERTIA_KGM2 = (15.95, 72.19, 72.19)
SEED003_CONVERGENCE_TIME_S = 10.0
SEED003_STEADY_ERROR_DEG = 3.0
INITIAL_ERROR_DEG = 30.0
SIM_STEP_S = 1e-3  # well below the 5.3 ms inner time constant about x

KP = (1.0, 2.0, 3.0)
KD = (10.0, 20.0, 30.0)
KI = (5.0, 6.0, 7.0)
DESIGN = CascadeLqrDesign(inner_kp_Nms=(15.0, 15.0, 15.0), q_angle=4.0, q_rate=9.0, r=1.0)


def test_known_torque_for_known_error() -> None:
    """τ = k_i (−k_p 2 sin(θ/2) e − k_d ω_e − ω_e) for a 10° error about e and a rate error."""
    ctrl = CascadeLqr(CascadeLqrParams(outer_kp_1_s=KP, outer_kd=KD, inner_kp_Nms=KI))
    axis = np.array([2.0, -1.0, 2.0]) / 3.0
    angle = math.radians(10.0)
    q_RN = qt.normalise(np.array([0.5, -0.5, 0.5, 0.5]))
    q_BN = qt.multiply(q_RN, qt.from_rotation_vector(axis * angle))
    omega_BN_B = np.array([0.01, -0.02, 0.03])
    omega_RN_B = np.array([0.005, 0.0, -0.01])
    rate_err = omega_BN_B - omega_RN_B
    e = 2.0 * math.sin(angle / 2) * axis
    expected = np.array(KI) * (-np.array(KP) * e - np.array(KD) * rate_err - rate_err)
    torque = ctrl.torque_B_Nm(T_NS, q_BN, omega_BN_B, q_RN, omega_RN_B)
    np.testing.assert_allclose(torque, expected, atol=EXACT_TOL)


def test_zero_error_gives_zero_torque() -> None:
    """On the reference at the reference rate the torque is zero and the command is ω_ref."""
    ctrl = CascadeLqr(CascadeLqrParams.from_table1())
    q = qt.normalise(np.array([0.3, 0.1, -0.9, 0.2]))
    w = np.array([0.01, 0.02, 0.03])
    np.testing.assert_allclose(ctrl.torque_B_Nm(T_NS, q, w, q, w), 0.0, atol=EXACT_TOL)
    np.testing.assert_allclose(ctrl.rate_command_B_rad_s(q, w, q, w), w, atol=EXACT_TOL)


def test_sign_of_quaternion_and_short_way() -> None:
    """q and −q give the same torque; a +270° error about x is corrected as −90° (τ_x > 0)."""
    ctrl = CascadeLqr(CascadeLqrParams.from_table1())
    q_BN = qt.from_rotation_vector(np.array([0.3, -0.2, 0.1]))
    t_pos = ctrl.torque_B_Nm(T_NS, q_BN, ZERO, qt.identity(), ZERO)
    np.testing.assert_allclose(
        ctrl.torque_B_Nm(T_NS, -q_BN, ZERO, qt.identity(), ZERO), t_pos, atol=EXACT_TOL
    )
    np.testing.assert_allclose(
        ctrl.torque_B_Nm(T_NS, q_BN, ZERO, -qt.identity(), ZERO), t_pos, atol=EXACT_TOL
    )
    q_270 = qt.from_rotation_vector(np.array([math.radians(270.0), 0.0, 0.0]))
    assert ctrl.torque_B_Nm(T_NS, q_270, ZERO, qt.identity(), ZERO)[0] > 0.0


def test_rate_limit_sets_the_slew_rate() -> None:
    """Far from the target, slewing at max_rate towards it needs no torque (the limit holds)."""
    max_rate = math.radians(2.0)
    ctrl = CascadeLqr(CascadeLqrParams.from_table1(max_rate_rad_s=max_rate))
    q_BN = qt.from_rotation_vector(np.radians([60.0, -40.0, 0.001]))
    w_ref = np.array([0.01, 0.0, 0.0])
    slewing = w_ref + np.array([-max_rate, max_rate, 0.0])  # towards the target on x and y
    tau = ctrl.torque_B_Nm(T_NS, q_BN, slewing, qt.identity(), w_ref)
    np.testing.assert_allclose(tau[:2], 0.0, atol=EXACT_TOL)
    faster = ctrl.torque_B_Nm(T_NS, q_BN, w_ref + 2.0 * (slewing - w_ref), qt.identity(), w_ref)
    assert faster[0] > 0.0 and faster[1] < 0.0  # beyond the limit: braked


def test_lqr_double_integrator_closed_form() -> None:
    """J θ̈ = u: k_p = √(q1/r), k_d = √(q2/r + 2 J k_p); ARE residual ≈ 0; A − BK Hurwitz."""
    inertia, q1, q2, r = 72.19, 5.0, 3.0, 0.5
    a = np.array([[0.0, 1.0], [0.0, 0.0]])
    b = np.array([[0.0], [1.0 / inertia]])
    q, rm = np.diag([q1, q2]), np.array([[r]])
    k, p = lqr_gains(a, b, q, rm)
    kp = math.sqrt(q1 / r)
    np.testing.assert_allclose(k[0], [kp, math.sqrt(q2 / r + 2 * inertia * kp)], rtol=GAIN_RTOL)
    residual = a.T @ p + p @ a - p @ b @ np.linalg.solve(rm, b.T) @ p + q
    assert float(np.max(np.abs(residual))) < RICCATI_TOL
    assert float(np.max(np.linalg.eigvals(a - b @ k).real)) < 0.0


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_lqr_reproduces_table1_with_matching_weights(axis: int) -> None:
    """Cascade model, q_angle/r = k_p², q_rate/r = k_d² + 2k_d − 2k_p J/k_i: Table 1 exactly."""
    kp, kd, ki, inertia = 72.0, 200.0, 15.0, SEED003_INERTIA_KGM2[axis]
    q = np.diag([kp**2, kd**2 + 2 * kd - 2 * kp * inertia / ki])
    a, b = outer_loop_model(inertia, ki)
    k, _ = lqr_gains(a, b, q, np.array([[1.0]]))
    np.testing.assert_allclose(k[0], [kp, kd], rtol=GAIN_RTOL)


def test_design_gains_and_inertia_update() -> None:
    """from_design gives the closed-form cascade gains; set_inertia redesigns; fixed gains stay."""
    ctrl = CascadeLqr.from_design(DESIGN, np.diag(SEED003_INERTIA_KGM2))

    def closed_form(inertia: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
        j = np.array(inertia)
        kp = math.sqrt(DESIGN.q_angle / DESIGN.r) * np.ones(3)
        ki = np.array(DESIGN.inner_kp_Nms)
        return kp, np.sqrt(1 + DESIGN.q_rate / DESIGN.r + 2 * kp * j / ki) - 1

    for inertia in (SEED003_INERTIA_KGM2, (30.0, 40.0, 50.0)):
        ctrl.set_inertia_B_kgm2(np.diag(inertia))
        kp, kd = closed_form(inertia)
        np.testing.assert_allclose(ctrl.params.outer_kp_1_s, kp, rtol=GAIN_RTOL)
        np.testing.assert_allclose(ctrl.params.outer_kd, kd, rtol=GAIN_RTOL)
    fixed = CascadeLqr(CascadeLqrParams.from_table1())
    fixed.set_inertia_B_kgm2(np.diag((30.0, 40.0, 50.0)))
    assert fixed.params == CascadeLqrParams.from_table1()


def test_table1_converges_from_30_deg_within_10_s() -> None:
    """Euler equations with Table 1 inertia and gains: 30° → under 3° (Table 2) within 10 s."""
    ctrl = CascadeLqr(CascadeLqrParams.from_table1())
    inertia = np.diag(SEED003_INERTIA_KGM2)
    j_inv = np.linalg.inv(inertia)
    axis = np.array([1.0, -2.0, 2.0]) / 3.0
    q_RN = qt.normalise(np.array([0.9, 0.1, -0.3, 0.2]))
    q = qt.multiply(q_RN, qt.from_rotation_vector(math.radians(INITIAL_ERROR_DEG) * axis))
    w = np.zeros(3)
    for _ in range(round(SEED003_CONVERGENCE_TIME_S / SIM_STEP_S)):
        tau = ctrl.torque_B_Nm(T_NS, q, w, q_RN, ZERO)
        w = w + SIM_STEP_S * (j_inv @ (tau - np.cross(w, inertia @ w)))
        q = qt.multiply(q, qt.from_rotation_vector(w * SIM_STEP_S))
    error_deg = math.degrees(qt.rotation_angle_rad(qt.error_quaternion(q_RN, q)))
    assert error_deg < SEED003_STEADY_ERROR_DEG


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"outer_kp_1_s": (-1.0, 1.0, 1.0)}, "outer_kp_1_s"),
        ({"outer_kd": (1.0, 1.0)}, "outer_kd"),
        ({"inner_kp_Nms": (0.0, 1.0, 1.0)}, "inner_kp_Nms"),
        ({"inner_kp_Nms": (math.nan, 1.0, 1.0)}, "inner_kp_Nms"),
        ({"max_rate_rad_s": 0.0}, "max_rate_rad_s"),
    ],
)
def test_bad_gains_are_rejected(kwargs: dict[str, object], key: str) -> None:
    """Negative, zero inner, non-finite or wrong-length gains raise ConfigError naming the key."""
    args: dict[str, object] = {"outer_kp_1_s": KP, "outer_kd": KD, "inner_kp_Nms": KI}
    args.update(kwargs)
    with pytest.raises(ConfigError, match=key):
        CascadeLqrParams(**args)  # type: ignore[arg-type]


@pytest.mark.parametrize(("key", "value"), [("q_angle", 0.0), ("q_rate", -1.0), ("r", True)])
def test_bad_design_is_rejected(key: str, value: object) -> None:
    """Zero angle weight, negative rate weight or non-number command weight raise ConfigError."""
    args: dict[str, object] = {"inner_kp_Nms": KI, "q_angle": 1.0, "q_rate": 1.0, "r": 1.0}
    args[key] = value
    with pytest.raises(ConfigError, match=key):
        CascadeLqrDesign(**args)  # type: ignore[arg-type]
