"""Known-answer and conservation tests of bench.station.dynamics.rigid_body."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bench.station.dynamics.rigid_body import (
    IDX_Q0,
    SL_OMEGA_BN_B,
    SL_Q_BN,
    SL_R_N,
    SL_V_N,
    STATE_SIZE,
    ZERO_WRENCH,
    MassProperties,
    Quat,
    State,
    Vec3,
    Wrench,
    angular_momentum_N,
    derivative,
    inverse3,
    kinetic_energy,
    linear_momentum_N,
    make_state,
    quat_conjugate,
    quat_from_axis_angle,
    quat_multiply,
    quat_normalize,
    rk4_step,
    rotate_B_to_N,
    rotate_N_to_B,
    state_omega_BN_B,
    state_q_BN,
    state_r_N,
    state_v_N,
)
from dbc.errors import ConfigError
from tests.values import same_value

DT_S = 1e-3
TUMBLE_DURATION_S = 100.0
CONSERVATION_REL_TOL = 1e-9
QUAT_UNIT_TOL = 1e-12
KNOWN_ANSWER_REL_TOL = 1e-12
ROUNDOFF_ABS_TOL = 1e-14
RK4_ORDER = 4.0
RK4_ORDER_TOL = 0.2

# A full (non-diagonal) but physical inertia tensor [kg m^2] and a tumbling rate [rad/s].
J_FULL = ((12.0, -0.8, 0.4), (-0.8, 9.0, 0.6), (0.4, 0.6, 7.0))
MASS_KG = 180.0
OMEGA_TUMBLE = (0.4, -0.3, 0.5)
Q_TILTED = quat_normalize((0.8, 0.3, -0.4, 0.2))


def _mp() -> MassProperties:
    return MassProperties(MASS_KG, J_FULL)


def _norm(v: Vec3) -> float:
    return math.sqrt(v[0] ** 2 + v[1] ** 2 + v[2] ** 2)


def _rel_diff(a: Vec3, b: Vec3) -> float:
    return _norm((a[0] - b[0], a[1] - b[1], a[2] - b[2])) / _norm(b)


def _textbook_rk4(
    state: State, dt: float, w0: Wrench, wm: Wrench, w1: Wrench, mp: MassProperties
) -> State:
    """Reference RK4 on ``derivative`` with generic tuple arithmetic."""

    def f(s: State, w: Wrench) -> State:
        return derivative(s, (w[0], w[1], w[2]), (w[3], w[4], w[5]), mp)

    def add(s: State, k: State, c: float) -> State:
        return tuple(a + c * b for a, b in zip(s, k, strict=True))

    k1 = f(state, w0)
    k2 = f(add(state, k1, dt / 2), wm)
    k3 = f(add(state, k2, dt / 2), wm)
    k4 = f(add(state, k3, dt), w1)
    y = tuple(
        s + dt / 6 * (a + 2 * b + 2 * c + d)
        for s, a, b, c, d in zip(state, k1, k2, k3, k4, strict=True)
    )
    q = y[SL_Q_BN]
    return make_state(
        quat_normalize((q[0], q[1], q[2], q[3])), y[SL_OMEGA_BN_B], y[SL_R_N], y[SL_V_N]
    )


# --- configuration ---------------------------------------------------------------------
@pytest.mark.parametrize("mass", [0.0, -1.0, math.nan, math.inf])
def test_mass_must_be_positive_finite(mass: float) -> None:
    """A non-positive or non-finite mass is a ConfigError naming mass_kg and the value."""
    with pytest.raises(ConfigError) as exc:
        MassProperties(mass, J_FULL, source="vehicle.toml")
    assert exc.value.key == "mass_kg"
    assert "mass_kg" in str(exc.value)
    assert "vehicle.toml" in str(exc.value)
    assert same_value(exc.value.value, mass)


@pytest.mark.parametrize(
    "inertia",
    [
        ((1.0, 0.1, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),  # asymmetric
        ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),  # not positive definite
        ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 3.0)),  # violates triangle inequality
        ((1.0, 0.0), (0.0, 1.0)),  # wrong shape
        ((1.0, 0.0, 0.0), (0.0, math.nan, 0.0), (0.0, 0.0, 1.0)),  # not finite
    ],
)
def test_inertia_is_validated(inertia: tuple[tuple[float, ...], ...]) -> None:
    """Bad inertia tensors are rejected with a ConfigError naming inertia_B_kgm2."""
    with pytest.raises(ConfigError) as exc:
        MassProperties(MASS_KG, inertia)  # type: ignore[arg-type]
    assert exc.value.key == "inertia_B_kgm2"
    assert "inertia_B_kgm2" in str(exc.value)
    assert "MassProperties" in str(exc.value)


def test_inverse_inertia_is_precomputed() -> None:
    """The stored flat inverse times the flat tensor is the identity."""
    mp = _mp()
    j = np.array(mp.inertia_flat_B_kgm2).reshape(3, 3)
    ji = np.array(mp.inertia_inv_flat_B_per_kgm2).reshape(3, 3)
    assert np.allclose(j @ ji, np.eye(3), rtol=0.0, atol=ROUNDOFF_ABS_TOL)
    assert mp.inv_mass_per_kg == pytest.approx(1.0 / MASS_KG, rel=KNOWN_ANSWER_REL_TOL)


def test_make_state_layout_and_validation() -> None:
    """make_state packs 13 floats in the documented order and rejects non-unit quaternions."""
    s = make_state(Q_TILTED, (1.0, 2.0, 3.0), (4.0, 5.0, 6.0), (7.0, 8.0, 9.0))
    assert len(s) == STATE_SIZE
    assert state_q_BN(s) == pytest.approx(Q_TILTED, abs=ROUNDOFF_ABS_TOL)
    assert state_omega_BN_B(s) == (1.0, 2.0, 3.0)
    assert state_r_N(s) == (4.0, 5.0, 6.0)
    assert state_v_N(s) == (7.0, 8.0, 9.0)
    with pytest.raises(ValueError):
        make_state((1.0, 1.0, 0.0, 0.0))


# --- frames and kinematics ----------------------------------------------------------------
def test_rotation_helpers_match_quaternion_sandwich() -> None:
    """v_B = q* ⊗ v_N ⊗ q, and rotate_B_to_N inverts rotate_N_to_B."""
    v_N = (0.3, -1.2, 2.5)
    q = Q_TILTED
    sandwich = quat_multiply(quat_multiply(quat_conjugate(q), (0.0, *v_N)), q)
    v_B = rotate_N_to_B(q, v_N)
    assert v_B == pytest.approx(sandwich[1:], abs=ROUNDOFF_ABS_TOL)
    assert rotate_B_to_N(q, v_B) == pytest.approx(v_N, abs=ROUNDOFF_ABS_TOL)


def test_kinematics_rotate_body_axes_the_right_way() -> None:
    """Spinning about +z_B at ω turns x_B towards +y_N: x_B in N = (cos ωt, sin ωt, 0)."""
    mp = MassProperties(MASS_KG, ((2.0, 0.0, 0.0), (0.0, 2.0, 0.0), (0.0, 0.0, 3.0)))
    omega = 0.7
    s = make_state(omega_BN_B=(0.0, 0.0, omega))
    n_steps = 1000
    for _ in range(n_steps):
        s = rk4_step(s, DT_S, ZERO_WRENCH, ZERO_WRENCH, ZERO_WRENCH, mp)
    angle = omega * n_steps * DT_S
    x_N = rotate_B_to_N(state_q_BN(s), (1.0, 0.0, 0.0))
    assert x_N == pytest.approx((math.cos(angle), math.sin(angle), 0.0), abs=ROUNDOFF_ABS_TOL * 100)


def test_derivative_known_values() -> None:
    """At identity attitude q̇ = (0, ω/2); Euler's equations match the diagonal closed form."""
    jx, jy, jz = 2.0, 3.0, 5.0
    mp = MassProperties(MASS_KG, ((jx, 0.0, 0.0), (0.0, jy, 0.0), (0.0, 0.0, jz)))
    w = (0.1, -0.2, 0.3)
    tau = (0.01, 0.02, -0.03)
    force = (1.0, -2.0, 3.0)
    d = derivative(make_state(omega_BN_B=w, v_N=(4.0, 5.0, 6.0)), force, tau, mp)
    assert d[SL_Q_BN] == pytest.approx((0.0, w[0] / 2, w[1] / 2, w[2] / 2), abs=ROUNDOFF_ABS_TOL)
    expected_wdot = (
        (tau[0] - (jz - jy) * w[1] * w[2]) / jx,
        (tau[1] - (jx - jz) * w[2] * w[0]) / jy,
        (tau[2] - (jy - jx) * w[0] * w[1]) / jz,
    )
    assert d[SL_OMEGA_BN_B] == pytest.approx(expected_wdot, rel=KNOWN_ANSWER_REL_TOL)
    assert d[SL_R_N] == (4.0, 5.0, 6.0)
    assert d[SL_V_N] == pytest.approx(tuple(f / MASS_KG for f in force), rel=KNOWN_ANSWER_REL_TOL)


def test_rk4_step_matches_textbook_rk4() -> None:
    """The hot-path RK4 equals a textbook RK4 built on derivative() to round-off."""
    mp = _mp()
    s = make_state(Q_TILTED, OMEGA_TUMBLE, (1.0, 2.0, 3.0), (0.1, -0.2, 0.3))
    w0 = (1.0, 2.0, -3.0, 0.1, -0.2, 0.3)
    wm = (1.5, 2.5, -3.5, 0.15, -0.25, 0.35)
    w1 = (2.0, 3.0, -4.0, 0.2, -0.3, 0.4)
    for dt in (DT_S, 0.05):
        fast = rk4_step(s, dt, w0, wm, w1, mp)
        ref = _textbook_rk4(s, dt, w0, wm, w1, mp)
        assert fast == pytest.approx(ref, abs=ROUNDOFF_ABS_TOL)


# --- conservation and known answers ---------------------------------------------------------
def test_torque_free_tumble_conserves_momentum_and_energy() -> None:
    """Full-inertia torque-free tumble: H_N and T conserved to 1e-9 over 100 s at 1 kHz."""
    mp = _mp()
    s = make_state(Q_TILTED, OMEGA_TUMBLE)
    h0 = angular_momentum_N(s, mp)
    t0 = kinetic_energy(s, mp)
    max_norm_err = 0.0
    for _ in range(round(TUMBLE_DURATION_S / DT_S)):
        s = rk4_step(s, DT_S, ZERO_WRENCH, ZERO_WRENCH, ZERO_WRENCH, mp)
        q = s[SL_Q_BN]
        max_norm_err = max(max_norm_err, abs(math.sqrt(sum(x * x for x in q)) - 1.0))
    assert _rel_diff(angular_momentum_N(s, mp), h0) <= CONSERVATION_REL_TOL
    assert abs(kinetic_energy(s, mp) - t0) / t0 <= CONSERVATION_REL_TOL
    assert max_norm_err <= QUAT_UNIT_TOL
    # the body really tumbles: the rate vector has moved in body axes
    assert _rel_diff(state_omega_BN_B(s), OMEGA_TUMBLE) > CONSERVATION_REL_TOL


def test_rk4_is_fourth_order() -> None:
    """Halving dt divides the error of a fast tumble by ~2^4."""
    mp = _mp()
    s0 = make_state(Q_TILTED, (3.0, -2.0, 4.0))
    duration = 1.0

    def run(dt: float) -> State:
        s = s0
        for _ in range(round(duration / dt)):
            s = rk4_step(s, dt, ZERO_WRENCH, ZERO_WRENCH, ZERO_WRENCH, mp)
        return s

    ref = run(1e-4)

    def err(s: State) -> float:
        return max(abs(a - b) for a, b in zip(s, ref, strict=True))

    order = math.log2(err(run(1e-2)) / err(run(5e-3)))
    assert order == pytest.approx(RK4_ORDER, abs=RK4_ORDER_TOL)


def test_constant_torque_about_principal_axis() -> None:
    """Constant torque τ along a principal axis e of a full tensor: ω = τt/λ e, angle ½τt²/λ."""
    mp = _mp()
    eigval, eigvec = np.linalg.eigh(np.array(J_FULL))
    lam = float(eigval[1])
    e = (float(eigvec[0, 1]), float(eigvec[1, 1]), float(eigvec[2, 1]))
    tau_Nm = 0.05
    w = (0.0, 0.0, 0.0, tau_Nm * e[0], tau_Nm * e[1], tau_Nm * e[2])
    s = make_state()
    n_steps = 2000
    for _ in range(n_steps):
        s = rk4_step(s, DT_S, w, w, w, mp)
    t = n_steps * DT_S
    expected_w = tuple(tau_Nm * t / lam * c for c in e)
    assert state_omega_BN_B(s) == pytest.approx(expected_w, rel=1e-9, abs=ROUNDOFF_ABS_TOL)
    q_expected: Quat = quat_from_axis_angle(e, 0.5 * tau_Nm * t * t / lam)
    assert state_q_BN(s) == pytest.approx(q_expected, abs=1e-12)


def test_constant_body_force_gives_parabola() -> None:
    """Constant body force, no rotation: r = r0 + v0 t + ½ (Cᵀ F/m) t², v = v0 + (Cᵀ F/m) t."""
    mp = _mp()
    f_B = (3.0, -1.0, 2.0)
    r0, v0 = (10.0, -5.0, 2.0), (0.1, 0.2, -0.3)
    s = make_state(Q_TILTED, (0.0, 0.0, 0.0), r0, v0)
    w = (*f_B, 0.0, 0.0, 0.0)
    n_steps = 5000
    for _ in range(n_steps):
        s = rk4_step(s, DT_S, w, w, w, mp)
    t = n_steps * DT_S
    a_N = tuple(c / MASS_KG for c in rotate_B_to_N(Q_TILTED, f_B))
    r_exp = tuple(r0[i] + v0[i] * t + 0.5 * a_N[i] * t * t for i in range(3))
    v_exp = tuple(v0[i] + a_N[i] * t for i in range(3))
    assert state_r_N(s) == pytest.approx(r_exp, rel=KNOWN_ANSWER_REL_TOL * 100)
    assert state_v_N(s) == pytest.approx(v_exp, rel=KNOWN_ANSWER_REL_TOL * 100)
    assert state_q_BN(s) == pytest.approx(Q_TILTED, abs=ROUNDOFF_ABS_TOL)
    p = linear_momentum_N(s, mp)
    assert p == pytest.approx(tuple(MASS_KG * x for x in v_exp), rel=KNOWN_ANSWER_REL_TOL * 100)


def test_rk4_step_is_pure() -> None:
    """Same inputs give the same output and the input state is untouched (tuples)."""
    mp = _mp()
    s = make_state(Q_TILTED, OMEGA_TUMBLE)
    w = (1.0, 0.0, 0.0, 0.0, 0.01, 0.0)
    a = rk4_step(s, DT_S, w, w, w, mp)
    b = rk4_step(s, DT_S, w, w, w, mp)
    assert a == b
    assert s[IDX_Q0] == make_state(Q_TILTED, OMEGA_TUMBLE)[IDX_Q0]


def test_inverse3_matches_numpy_and_is_exact_on_a_diagonal() -> None:
    """The float Gauss-Jordan inverse equals numpy's to round-off on a full inertia and on
    random pivoting cases, and is exactly 1/J_ii on a diagonal one."""
    got = np.array(inverse3([list(r) for r in J_FULL]))
    np.testing.assert_allclose(got @ np.array(J_FULL), np.eye(3), atol=ROUNDOFF_ABS_TOL)
    rng = np.random.default_rng(7)
    for _ in range(100):
        a = rng.normal(size=(3, 3))
        np.testing.assert_allclose(np.array(inverse3(a.tolist())), np.linalg.inv(a),
                                   rtol=1e-9, atol=1e-9)
    diag = [[17.0, 0.0, 0.0], [0.0, 19.0, 0.0], [0.0, 0.0, 22.0]]
    assert inverse3(diag) == [[1 / 17.0, 0.0, 0.0], [0.0, 1 / 19.0, 0.0], [0.0, 0.0, 1 / 22.0]]
