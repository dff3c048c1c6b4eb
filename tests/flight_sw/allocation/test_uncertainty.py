"""Tests of the uncertainty sets and their exact worst-case residuals (seed 001, sec. 4)."""

from __future__ import annotations

import numpy as np

from flight_sw.allocation.uncertainty import (
    SEED001_BASIS_WEIGHTS,
    SEED001_LFT_E_SHAPE,
    SEED001_LFT_H,
    SEED001_RHO,
    lft_worst_case_perturbation,
    lft_worst_case_residual,
    polyhedral_vertices,
    polytopic_vertices,
    relative_basis,
    vertex_worst_case_residual,
)

N_SAMPLES = 200
WC_TOL = 1e-7


def test_vertex_counts(b001: np.ndarray, rng: np.random.Generator) -> None:
    """2^q corners (merged when equal) for Δ_I, q vertices for Δ_P."""
    basis = rng.normal(size=(3, 3, 8))
    assert polyhedral_vertices(b001, basis).shape == (8, 3, 8)
    assert polytopic_vertices(b001, basis).shape == (3, 3, 8)
    paper = relative_basis(b001, SEED001_RHO, SEED001_BASIS_WEIGHTS)
    # δ·(0.1, 0.1, 0.2, 0.2) sums to 7 distinct multiples −0.6 … 0.6 of B.
    assert polyhedral_vertices(b001, paper).shape[0] == 7


def test_polyhedral_worst_case_dominates_interior(
    b001: np.ndarray, rng: np.random.Generator
) -> None:
    """No δ inside the box gives a larger residual than the corner maximum."""
    basis = 0.1 * rng.normal(size=(3, 3, 8))
    verts = polyhedral_vertices(b001, basis)
    t, v = rng.normal(size=8), rng.normal(size=3)
    wc = vertex_worst_case_residual(verts, t, v)
    for delta in rng.uniform(-1.0, 1.0, (N_SAMPLES, 3)):
        b = b001 + np.einsum("q,qmn->mn", delta, basis)
        assert np.linalg.norm(b @ t - v) <= wc + WC_TOL


def test_lft_worst_case_is_exact(b001: np.ndarray, rng: np.random.Generator) -> None:
    """Random ‖F‖ ≤ 1 never exceed the S-lemma value, and the maximising F attains it."""
    e = SEED001_RHO * np.array(SEED001_LFT_E_SHAPE)
    h = np.array(SEED001_LFT_H)
    for _ in range(20):
        t, v = rng.uniform(-2.3, 2.35, 8), rng.normal(size=3)
        wc = lft_worst_case_residual(b001, e, h, t, v)
        for _ in range(20):
            f = rng.normal(size=(3, 3))
            f /= np.linalg.norm(f, 2)
            assert np.linalg.norm((b001 + e @ f @ h) @ t - v) <= wc + WC_TOL
        f_star = lft_worst_case_perturbation(b001, e, h, t, v)
        assert np.linalg.norm(f_star, 2) <= 1.0 + WC_TOL
        assert abs(np.linalg.norm((b001 + e @ f_star @ h) @ t - v) - wc) <= 1e-6


def test_lft_scalar_e_matches_el_ghaoui_lebret(b001: np.ndarray, rng: np.random.Generator) -> None:
    """For E = σI the worst case is ‖BT − v‖ + σ‖HT‖ exactly."""
    sigma = 0.3
    h = rng.normal(size=(4, 8))
    t, v = rng.normal(size=8), rng.normal(size=3)
    expected = np.linalg.norm(b001 @ t - v) + sigma * np.linalg.norm(h @ t)
    assert abs(lft_worst_case_residual(b001, sigma * np.eye(3), h, t, v) - expected) <= 1e-6
