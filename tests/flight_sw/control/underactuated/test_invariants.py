"""The invariants of single spin (seed 004 eqs. 21–22, 28–35) on the reference plant."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flight_sw.control.underactuated.invariants import (
    TWO_PI,
    planned_stop_turn,
    remainder_error_m,
    spin_angle_rad,
    stopping_position_error_m,
    stopping_position_m,
    stopping_velocity_m_s,
    unwrap,
)
from tests.flight_sw.control.underactuated import ffrb_reference as ref

INVARIANT_TOL = 1e-9


def _spinning(psi: float, w3: float, z: float, vz: float) -> ref.Plant:
    return ref.Plant(ref.spin_dcm(psi), np.array([0.0, 0.0, w3]), np.array([0.1, -0.2, z]),
                     np.array([0.01, 0.0, vz]), substeps=2)


def _track(plant: ref.Plant, law, steps: int):
    thr = ref.vehicle()
    kappa = thr.kappa_m_s_per_rad_s
    psi = spin_angle_rad(plant.q_BR())
    out = []
    for k in range(steps):
        plant.step(thr.thrust_N(law(k)))
        psi = unwrap(psi, spin_angle_rad(plant.q_BR()))
        out.append((stopping_velocity_m_s(plant.v[2], plant.w[2], kappa),
                    stopping_position_m(plant.r[2], psi, 0.0, kappa)))
    return np.array(out)


def test_stopping_velocity_and_position_hold_in_single_spin() -> None:
    """Any axis-III torque profile in single spin leaves V_s and Z unchanged (with V_s = 0)."""
    thr = ref.vehicle()
    kappa = thr.kappa_m_s_per_rad_s
    plant = _spinning(0.4, -0.5, 0.3, kappa * -0.5)  # V_s = 0
    rng = np.random.default_rng(21)
    profile = rng.uniform(0.0, 0.05, size=400)
    track = _track(plant, lambda k: np.array([0.0, 0.0, profile[k]]), 400)
    np.testing.assert_allclose(track[:, 0], 0.0, atol=INVARIANT_TOL)
    np.testing.assert_allclose(track[:, 1], track[0, 1], atol=INVARIANT_TOL)
    assert plant.w[2] > -0.5 + 0.05  # the profile really slowed the spin


def test_stopping_velocity_moves_off_the_manifold() -> None:
    """A transverse torque changes V_s (eq. 22): the invariant is not trivially constant."""
    thr = ref.vehicle()
    plant = _spinning(0.0, -0.5, 0.0, 0.0)
    t1 = 0.02
    track = _track(plant, lambda _k: np.array([t1, 0.0, thr.min_torque_III_Nm(t1, 0.0)]), 100)
    assert abs(track[-1, 0] - track[0, 0]) > 1e-4


def test_stop_on_the_planned_turn_lands_at_z_plus_two_pi_kappa_n() -> None:
    """Stopping on turn n ends at z = Z + 2πκn: de-spin with the final-turn law and compare."""
    thr = ref.vehicle()
    kappa = thr.kappa_m_s_per_rad_s
    psi0, w0 = 2.0, -2.0
    plant = _spinning(psi0, w0, 0.05, kappa * w0)
    n = planned_stop_turn(psi0, 0.0, TWO_PI)
    psi_f = TWO_PI * n
    assert psi0 - TWO_PI > psi_f >= psi0 - 2 * TWO_PI
    z_stop = stopping_position_m(0.05, psi0, 0.0, kappa)
    psi = psi0
    while psi - psi_f > 1e-4 and plant.w[2] < 0.0:
        left = psi - psi_f
        t3 = thr.inertia_diag_kgm2[2] * plant.w[2] ** 2 / left  # −ηJω with η = −ω/left
        plant.step(thr.thrust_N(np.array([0.0, 0.0, t3])))
        psi = unwrap(psi, spin_angle_rad(plant.q_BR()))
    assert abs(plant.w[2]) < 1e-4 * abs(w0) * 2
    assert plant.r[2] == pytest.approx(stopping_position_error_m(z_stop, n, kappa), abs=2e-4)


def test_spin_angle_and_unwrap() -> None:
    """ψ read from q_BR is the spin angle; unwrap keeps it continuous over many turns."""
    psi = 0.0
    for true in np.linspace(0.0, -5 * TWO_PI, 400):
        psi = unwrap(psi, spin_angle_rad(ref.q_BR_of(ref.spin_dcm(true))))
        assert psi == pytest.approx(true, abs=1e-12)


def test_remainder_form_is_periodic_in_whole_turns() -> None:
    """The remainder of Z (eq. 35) does not see whole turns: Z and Z + 2πκk agree."""
    kappa = 0.031
    for z in (-0.3, 0.01, 0.45):
        for k in (-3, 1, 7):
            assert remainder_error_m(z + TWO_PI * kappa * k, kappa) == pytest.approx(
                remainder_error_m(z, kappa), abs=1e-12)
        assert abs(remainder_error_m(z, kappa)) <= math.pi * kappa + 1e-15
