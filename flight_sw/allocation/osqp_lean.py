"""A lean per-cycle call path into an OSQP problem that is set up once.

What it does: updates the data of a set-up :class:`osqp.OSQP` problem (vectors ``q``,
``l``, ``u``; values ``Px``, ``Ax`` of its sparse matrices, same pattern) and solves it,
returning the primal ``x``, the dual ``y`` and whether OSQP reports it solved. The
allocators (:mod:`flight_sw.allocation.qp_osqp`, :mod:`flight_sw.allocation.robust_polytopic`)
call it every control cycle.

Why: osqp's Python ``OSQP.update``/``OSQP.solve`` (1.x) wrap every call with constant
look-ups, a copy of every info field into a namespace and a cache kept for derivatives.
On this project's machine that costs about 40 µs a call, as much as solving the
allocators' small QPs. This calls the extension's solver object (``OSQP._solver``, the C
binding that ``update``/``solve`` call themselves) directly, after the same clamping of the
bounds to ±``OSQP_INFTY``: the numbers are the same, bit for bit (tests/flight_sw/
test_osqp_lean.py runs the allocators both ways). When the binding is not there (another
osqp release), the public API is used.

:func:`osqp_settings` gives the allocators' OSQP settings (silent, deterministic: bounded
iterations, no time limit), in two flavours: tight (the robust SQP's subproblems) and the
loose stage-one guess of an active set that an exact dense solve then finishes.

Units: whatever the problem's are. Assumptions: the problem was set up with
:meth:`osqp.OSQP.setup`; matrix updates keep its sparsity pattern (OSQP's own rule).
Source: OSQP 1.x Python interface (``osqp/interface.py``: ``update``, ``solve``).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import osqp

_BINDING_METHODS = ("update_data_vec", "update_data_mat", "solve", "info", "solution")
# OSQP settings: tight tolerances, bounded iterations, iteration-counted rho adaptation,
# no time limit (OSQP 1.x has no "off" value; 1e10 s is its default, i.e. never reached).
OSQP_EPS_ABS = 1e-9
OSQP_EPS_REL = 1e-9
OSQP_MAX_ITER = 4000
OSQP_CHECK_TERMINATION = 10
OSQP_ADAPTIVE_RHO_ITERATIONS = 1  # OSQP 1.x: adapt rho every `interval` iterations
OSQP_ADAPTIVE_RHO_INTERVAL = 25
OSQP_TIME_LIMIT_OFF_S = 1e10
# BoundedQpAllocator only needs OSQP's active set (box_qp then solves exactly): loose
# tolerances, no polishing, and a low iteration bound keep its worst case short.
OSQP_STAGE_ONE_EPS = 1e-4
OSQP_STAGE_ONE_MAX_ITER = 60


def osqp_settings(warm_start: bool, stage_one: bool = False) -> dict[str, Any]:
    """OSQP settings (silent, deterministic); ``stage_one``: the loose active-set guess."""
    return {
        "verbose": False,
        "polishing": not stage_one,
        "warm_starting": warm_start,
        "eps_abs": OSQP_STAGE_ONE_EPS if stage_one else OSQP_EPS_ABS,
        "eps_rel": OSQP_STAGE_ONE_EPS if stage_one else OSQP_EPS_REL,
        "max_iter": OSQP_STAGE_ONE_MAX_ITER if stage_one else OSQP_MAX_ITER,
        "check_termination": OSQP_CHECK_TERMINATION,
        "adaptive_rho": OSQP_ADAPTIVE_RHO_ITERATIONS,
        "adaptive_rho_interval": OSQP_ADAPTIVE_RHO_INTERVAL,
        "time_limit": OSQP_TIME_LIMIT_OFF_S,
    }


class OsqpResult(NamedTuple):
    """One solve: primal ``x``, dual ``y`` (copies) and whether OSQP solved it."""

    x: np.ndarray
    y: np.ndarray
    solved: bool


class LeanOsqp:
    """``update`` + ``solve`` of one set-up OSQP problem, without the wrapper's per-call work."""

    def __init__(self, problem: osqp.OSQP, use_binding: bool = True) -> None:
        self._problem = problem
        binding = getattr(problem, "_solver", None)
        ok = use_binding and all(hasattr(binding, a) for a in _BINDING_METHODS)
        self._binding: Any = binding if ok else None
        self._infty = float(problem.constant("OSQP_INFTY"))
        self._solved = int(osqp.SolverStatus.OSQP_SOLVED)

    @property
    def uses_binding(self) -> bool:
        """True when calls go straight to the extension's solver object."""
        return self._binding is not None

    def update(
        self,
        *,
        q: np.ndarray | None = None,
        l: np.ndarray | None = None,  # noqa: E741 - OSQP's name
        u: np.ndarray | None = None,
        Px: np.ndarray | None = None,
        Ax: np.ndarray | None = None,
    ) -> None:
        """New data; bounds beyond ±OSQP_INFTY are clamped to it, as osqp's ``update`` does."""
        b = self._binding
        if b is None:
            kwargs = {k: v for k, v in (("q", q), ("l", l), ("u", u), ("Px", Px), ("Ax", Ax))
                      if v is not None}
            self._problem.update(**kwargs)
            return
        if l is not None:
            l = np.maximum(l, -self._infty)  # noqa: E741
        if u is not None:
            u = np.minimum(u, self._infty)
        if q is not None or l is not None or u is not None:
            b.update_data_vec(q=q, l=l, u=u)
        if Px is not None or Ax is not None:
            b.update_data_mat(P_x=Px, P_i=None, A_x=Ax, A_i=None)

    def solve(self) -> OsqpResult:
        """Solve with the current data (warm-started as the problem's settings say)."""
        b = self._binding
        if b is None:
            res = self._problem.solve(raise_error=False)
            return OsqpResult(np.array(res.x, dtype=float), np.array(res.y, dtype=float),
                              int(res.info.status_val) == self._solved)
        b.solve()
        sol = b.solution
        return OsqpResult(np.array(sol.x, dtype=float), np.array(sol.y, dtype=float),
                          int(b.info.status_val) == self._solved)
