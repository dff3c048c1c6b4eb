"""Step D's closed forms (seed 004 eqs. 40–53) against numerical integration."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from flight_sw.control.underactuated.despin import (
    Despin,
    cin,
    final_turn,
    final_turn_offset_m,
    half_turn_for,
    max_half_turn_dv,
)

LAM_M, ALPHA_RAD = 0.354, -1.63
RTOL = 1e-8


def integrate(seq: Despin, v_a: np.ndarray, t_end_s: float) -> np.ndarray:
    """ψ, ω, v, r after ``t_end_s`` of T = −ηJω (per unit J) from the sequence's start."""
    eta = seq.eta_per_s

    def f(_t: float, x: np.ndarray) -> list[float]:
        psi, w = x[0], x[1]
        dw = -eta * w
        return [w, dw, LAM_M * dw * math.cos(psi + ALPHA_RAD),
                LAM_M * dw * math.sin(psi + ALPHA_RAD), x[2], x[3]]

    x0 = [seq.psi_a_rad, seq.omega_a_rad_s, *v_a, 0.0, 0.0]
    return solve_ivp(f, (0.0, t_end_s), x0, rtol=1e-12, atol=1e-14).y[:, -1]


@pytest.mark.parametrize("psi_a, w_a, w_b, eta, v_a", [
    (1.0, -0.5, -0.2, 0.1, (0.01, -0.02)),
    (-2.0, -0.3, -0.29, 0.05, (0.0, 0.0)),
    (4.0, -1.2, -0.1, 0.4, (-0.003, 0.004)),
])
def test_sequence_closed_forms_match_integration(psi_a, w_a, w_b, eta, v_a) -> None:
    """End angle, duration (eq. 42), Δv (eq. 40) and Δr with Si/Ci (eqs. 41, 43–45)."""
    seq = Despin(psi_a, w_a, w_b, eta)
    va = np.array(v_a)
    x = integrate(seq, va, seq.duration_s)
    assert x[1] == pytest.approx(w_b, rel=RTOL)
    assert x[0] == pytest.approx(seq.psi_b_rad, rel=RTOL, abs=1e-9)
    np.testing.assert_allclose(x[2:4], va + seq.delta_v(LAM_M, ALPHA_RAD), atol=1e-10)
    np.testing.assert_allclose(x[4:6], seq.delta_r(va, LAM_M, ALPHA_RAD), atol=1e-8)


def test_final_turn_stops_on_target_at_the_predicted_offset() -> None:
    """A whole-turn de-spin from rest in x–y stops on ψ_f, back at zero velocity, moved
    by Δr_f (Cin and Si form)."""
    seq = final_turn(0.3, -0.8)
    x = integrate(seq, np.zeros(2), 40.0 / seq.eta_per_s)
    assert x[0] == pytest.approx(0.3, abs=1e-9)
    np.testing.assert_allclose(x[2:4], 0.0, atol=1e-9)
    np.testing.assert_allclose(x[4:6], seq.delta_r(np.zeros(2), LAM_M, ALPHA_RAD), atol=1e-7)


def test_final_offset_is_a_constant_of_the_vehicle() -> None:
    """Δr_f depends on ψ_f but not on the spin rate it starts from (§3.5)."""
    ref = final_turn_offset_m(0.7, LAM_M, ALPHA_RAD)
    for w in (-0.05, -0.3, -2.0):
        np.testing.assert_allclose(final_turn(0.7, w).delta_r(np.zeros(2), LAM_M, ALPHA_RAD),
                                   ref, rtol=1e-12)
    assert np.linalg.norm(ref) == pytest.approx(
        LAM_M * math.hypot(cin(2 * math.pi), quad(lambda t: math.sin(t) / t, 0, 2 * math.pi)[0]),
        rel=1e-9)


def test_final_sequence_with_velocity_left_diverges() -> None:
    """A spin that stops with x–y velocity left drifts forever: Δr is infinite."""
    assert not np.all(np.isfinite(final_turn(0.0, -0.5).delta_r(np.array([1e-3, 0.0]),
                                                                 LAM_M, ALPHA_RAD)))


def test_half_turn_gives_the_asked_velocity_change() -> None:
    """half_turn_for: Δv as asked, ψ_b = ψ_a − π, |Δv| = 2λη."""
    for dv in (np.array([0.01, 0.0]), np.array([-0.003, 0.004]), np.array([0.0, -0.02])):
        seq = half_turn_for(dv, -0.5, LAM_M, ALPHA_RAD)
        np.testing.assert_allclose(seq.delta_v(LAM_M, ALPHA_RAD), dv, atol=1e-15)
        assert seq.psi_a_rad - seq.psi_b_rad == pytest.approx(math.pi)
        assert np.linalg.norm(dv) == pytest.approx(2 * LAM_M * seq.eta_per_s)


def test_half_turn_limit_keeps_the_spin() -> None:
    """At the limit with half the spin kept, the sequence ends at half the rate."""
    dv_max = max_half_turn_dv(-0.4, LAM_M, 0.5)
    seq = half_turn_for(np.array([dv_max, 0.0]), -0.4, LAM_M, ALPHA_RAD)
    assert seq.omega_b_rad_s == pytest.approx(-0.2)


def test_cin_matches_its_integral() -> None:
    """Cin(x) = ∫₀ˣ (1 − cos t)/t dt, small and large x."""
    for x in (1e-6, 5e-5, 0.3, 2 * math.pi, 40.0):
        want = quad(lambda t: (1 - math.cos(t)) / t, 0.0, x, limit=200)[0]
        assert cin(x) == pytest.approx(want, rel=1e-9, abs=1e-15)
