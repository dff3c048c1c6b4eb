"""Control authority of a thruster set: which body directions no non-negative thrust reaches.

What it does: from the effectiveness matrix ``B`` (columns ``[d; r × d]``: force [N] and
torque [N m] per newton of each thruster, flight_sw.allocation.effectiveness), for each
signed body axis ±x, ±y, ±z of the torque (and of the force, when this flight software
controls translation too) whether some thrusts ``T ≥ 0`` produce it, and, for
attitude-only control, whether they produce each torque with zero net force
(:func:`force_free_torque_unreached`). The test: the least absolute residual of
``B T = ±e_i`` over ``T ≥ 0`` (a linear programme with slacks
``B T + s⁺ − s⁻ = ±e_i``, minimising ``Σ s``; HiGHS, flight_sw.allocation.linear_program)
is zero to round-off exactly when the axis lies in the cone of the columns (Lawson &
Hanson 1974, ch. 23, for the same test by non-negative least squares, which tests/ use as
the reference). An axis outside
it is a demand the allocator can never meet: the configuration is accepted (seed 004
controls a vehicle with three thrusters) but warned about, in the statistics file
(``warnings``, which the bench shows on its console) and by ``--check``.

Thrusters are on-off valves (thrust ≥ 0); a bidirectional actuator is an opposing pair.
Pure functions; no units beyond the inputs'.
"""

from __future__ import annotations

import numpy as np

from flight_sw.allocation.linear_program import solve_lp

# An axis counts as reached when the residual ‖B T − e‖ is below this (unit target).
REACH_TOL = 1e-9
# Smallest component (of a unit-sum null vector) accepted as "strictly positive".
NULL_VECTOR_MIN_COMPONENT = 1e-9
AXES = ("x", "y", "z")
def _cone_residual(rows: np.ndarray, target: np.ndarray) -> float:
    """``‖rows T − target‖`` at the ``T ≥ 0`` of least absolute residual (an LP)."""
    m, n = rows.shape
    eye = np.eye(m)
    x = solve_lp(np.r_[np.zeros(n), np.ones(2 * m)], np.zeros(n + 2 * m),
                 np.full(n + 2 * m, np.inf), np.hstack([rows, eye, -eye]), target)
    if x is None:  # always feasible (the slacks): only a solver failure gets here
        return float("inf")
    return float(np.linalg.norm(rows @ np.maximum(x[:n], 0.0) - target))


def unreached_axes(rows: np.ndarray, first: int = 0) -> list[str]:
    """The signed axes (``+x`` ... ``-z``) no thrusts ``T ≥ 0`` give: ``rows`` (m × n) times
    ``T`` must equal the unit vector along rows ``first``…``first + 2``, the other rows 0."""
    out = []
    for i, axis in enumerate(AXES):
        for sign in (1.0, -1.0):
            target = np.zeros(rows.shape[0])
            target[first + i] = sign
            if _cone_residual(rows, target) > REACH_TOL:
                out.append(f"{'+' if sign > 0 else '-'}{axis}")
    return out


def force_free_torque_unreached(b: np.ndarray) -> list[str]:
    """The signed torque axes the thrusters of the 6 × n ``b`` cannot give with zero net
    force (no ``T ≥ 0`` with ``B_F T = 0`` and ``B_τ T = ±e``): where attitude-only firing
    must translate the vehicle."""
    return unreached_axes(b, first=3)


def authority_warnings(b: np.ndarray, controls_force: bool) -> list[str]:
    """Warnings for torque (and, if ``controls_force``, force) axes the thrusters of the
    6 × n effectiveness matrix ``b`` cannot give."""
    warnings = []
    for what, rows, needed in (("torque", b[3:6], True), ("force", b[0:3], controls_force)):
        missing = unreached_axes(rows) if needed else []
        if missing:
            warnings.append(
                f"the {b.shape[1]} thrusters cannot produce {what} about/along "
                f"{', '.join(missing)} (no non-negative thrust combination does): demands "
                "there go unmet whatever the controller asks, and show only as an "
                "allocation residual (fsw.allocation in summary.json)")
    return warnings


def positive_null_vector(b: np.ndarray, pinv: np.ndarray) -> np.ndarray | None:
    """A unit-sum v > 0 with B v = 0 maximising min v, or None if there is none: the
    columns of B then positively span its range (``pinv``: B's pseudo-inverse, which
    takes the LP's round-off back into the null space)."""
    m, n = b.shape
    cost = np.zeros(n + 1)
    cost[-1] = -1.0  # maximise t
    a_eq = np.zeros((m + 1, n + 1))
    a_eq[:m, :n] = b
    a_eq[m, :n] = 1.0
    b_eq = np.zeros(m + 1)
    b_eq[m] = 1.0
    a_ub = np.hstack([-np.eye(n), np.ones((n, 1))])  # t − v_i ≤ 0
    lo = np.r_[np.zeros(n), -np.inf]
    x = solve_lp(cost, lo, np.full(n + 1, np.inf), a_eq, b_eq, a_ub, np.zeros(n))
    if x is None:
        return None
    v = x[:n]
    v = v - pinv @ (b @ v)  # remove the LP's round-off component outside the null space
    v = v / v.sum()
    if v.min() <= NULL_VECTOR_MIN_COMPONENT:
        return None
    return v
