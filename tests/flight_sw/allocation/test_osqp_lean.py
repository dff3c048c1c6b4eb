"""The lean OSQP call path: bit-identical to osqp's public update/solve, and in use."""

from __future__ import annotations

import numpy as np
import osqp
import scipy.sparse as sp

from flight_sw.allocation.osqp_lean import LeanOsqp, osqp_settings

N_VARS = 8
N_ROWS = 3
N_CALLS = 40
T_MAX = 2.0


def _problem(rng: np.random.Generator) -> tuple[osqp.OSQP, np.ndarray, sp.csc_matrix]:
    """A warm-started bounded least-squares QP in OSQP's form (as the allocators set up)."""
    b = rng.normal(size=(N_ROWS, N_VARS))
    p = sp.csc_matrix(b.T @ b + 1e-3 * np.eye(N_VARS))
    a = sp.csc_matrix(np.vstack([b, np.eye(N_VARS)]))
    lo = np.concatenate([np.full(N_ROWS, -np.inf), np.zeros(N_VARS)])
    hi = np.concatenate([np.zeros(N_ROWS), np.full(N_VARS, T_MAX)])
    problem = osqp.OSQP()
    problem.setup(p, np.zeros(N_VARS), a, lo, hi, **osqp_settings(True))
    return problem, b, a


def test_the_binding_path_is_what_runs() -> None:
    """With the installed osqp the allocators' calls go straight to the C binding."""
    problem, _, _ = _problem(np.random.default_rng(0))
    assert LeanOsqp(problem).uses_binding
    assert not LeanOsqp(problem, use_binding=False).uses_binding


def test_binding_and_public_api_agree_bit_for_bit() -> None:
    """The same updates (vectors, matrix values, infinite bounds) give identical x, y, status."""
    seq = np.random.default_rng(1)
    paths = []
    for use_binding in (True, False):
        problem, b, a = _problem(np.random.default_rng(7))
        paths.append((LeanOsqp(problem, use_binding=use_binding), b, a))
    got: list[list[tuple[bytes, bytes, bool]]] = [[], []]
    for _ in range(N_CALLS):
        q = seq.normal(size=N_VARS)
        d = seq.normal(size=N_ROWS) * T_MAX
        scale = float(seq.uniform(0.5, 2.0))
        for i, (lean, b, a) in enumerate(paths):
            px = sp.triu(sp.csc_matrix(scale * (b.T @ b) + 1e-3 * np.eye(N_VARS))).tocsc().data
            lo = np.concatenate([d - 1.0, np.zeros(N_VARS)])
            lo[0] = -np.inf
            hi = np.concatenate([d + 1.0, np.full(N_VARS, T_MAX)])
            lean.update(q=q, l=lo, u=hi, Px=px, Ax=a.data)
            res = lean.solve()
            got[i].append((res.x.tobytes(), res.y.tobytes(), res.solved))
    assert got[0] == got[1]
    assert any(solved for _, _, solved in got[0])
