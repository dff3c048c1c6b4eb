"""Control authority: the signed axes a thruster set cannot reach with thrusts T >= 0."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bench.scenario.load import load_scenario
from flight_sw.allocation.authority import (
    REACH_TOL,
    authority_warnings,
    force_free_torque_unreached,
    unreached_axes,
)
from flight_sw.allocation.effectiveness import effectiveness_matrix

QUICKSTART = Path(__file__).resolve().parents[3] / "scenarios" / "quickstart.toml"


def test_one_thruster_reaches_one_signed_axis() -> None:
    """r = +y, d = +x: torque r × d = −z only; force +x only."""
    b = effectiveness_matrix(np.array([(0.0, 1.0, 0.0)]), np.array([(1.0, 0.0, 0.0)]))
    assert unreached_axes(b[3:]) == ["+x", "-x", "+y", "-y", "+z"]
    assert unreached_axes(b[:3]) == ["-x", "+y", "-y", "+z", "-z"]


def test_seed003_set_has_full_torque_authority_and_losing_yaw_is_warned() -> None:
    """Quickstart's 8 thrusters reach every torque axis; without those giving z torque, ±z."""
    sc = load_scenario(QUICKSTART)
    b = effectiveness_matrix(np.array([t.r_thr_B_m for t in sc.thrusters]),
                             np.array([t.d_thr_B for t in sc.thrusters]))
    assert authority_warnings(b, controls_force=False) == []
    keep = [k for k in range(b.shape[1]) if abs(b[5, k]) < 1e-12]  # no z torque
    assert keep and len(keep) < b.shape[1]
    (w,) = authority_warnings(b[:, keep], controls_force=False)
    assert "cannot produce torque about/along +z, -z" in w


def test_a_torque_only_layout_is_warned_only_when_force_is_controlled() -> None:
    """The quickstart's couples give no net force: a warning only for a 6-DoF flight
    software, which would need it."""
    sc = load_scenario(QUICKSTART)
    b = effectiveness_matrix(np.array([t.r_thr_B_m for t in sc.thrusters]),
                             np.array([t.d_thr_B for t in sc.thrusters]))
    assert authority_warnings(b, controls_force=False) == []
    (w,) = authority_warnings(b, controls_force=True)
    assert "cannot produce force" in w


def _nnls_unreached(rows: np.ndarray, first: int) -> list[str]:
    """The reference: signed axes along rows ``first``… (others 0) whose NNLS residual of
    ``rows T = target`` is not zero (scipy's nnls, Lawson & Hanson)."""
    from scipy.optimize import nnls

    out = []
    for i, axis in enumerate("xyz"):
        for sign in (1.0, -1.0):
            target = np.zeros(rows.shape[0])
            target[first + i] = sign
            if nnls(rows, target)[1] > REACH_TOL:
                out.append(f"{'+' if sign > 0 else '-'}{axis}")
    return out


def test_cone_test_agrees_with_nonnegative_least_squares() -> None:
    """Random 3 × n sets: the unreached axes are those with a non-zero NNLS residual."""
    rng = np.random.default_rng(11)
    for _ in range(60):
        rows = rng.normal(size=(3, int(rng.integers(1, 7))))
        assert unreached_axes(rows) == _nnls_unreached(rows, 0)


def _quickstart_b() -> np.ndarray:
    sc = load_scenario(QUICKSTART)
    return effectiveness_matrix(np.array([t.r_thr_B_m for t in sc.thrusters]),
                                np.array([t.d_thr_B for t in sc.thrusters]))


def test_seed003_set_gives_every_torque_without_force() -> None:
    """The quickstart's 8 thrusters make each signed torque from force-free sets."""
    assert force_free_torque_unreached(_quickstart_b()) == []


def test_losing_one_thruster_leaves_a_torque_only_with_force() -> None:
    """Without thruster 0 (+y at +x): +z torque still reachable, but only with a net force
    (its force-free partner sets all need it), so only the force-free test names +z."""
    b = np.delete(_quickstart_b(), 0, axis=1)
    assert unreached_axes(b[3:]) == []
    assert force_free_torque_unreached(b) == ["+z"]


def test_force_free_test_agrees_with_nonnegative_least_squares() -> None:
    """Random 6 × n sets: a torque axis is unreached without force exactly when NNLS of
    B T = (0, ±e) leaves a residual."""
    rng = np.random.default_rng(13)
    for _ in range(40):
        b = rng.normal(size=(6, int(rng.integers(4, 12))))
        assert force_free_torque_unreached(b) == _nnls_unreached(b, 3)
