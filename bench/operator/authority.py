"""Control authority of a thruster set: which body directions no non-negative thrust reaches.

What it does: from the scenario's thruster geometry (position ``r_thr_B_m`` about the
vehicle's reference point, unit direction ``d_thr_B``), the effectiveness columns
``[d; r × d]`` (force [N] and torque [N m] per newton of thrust), and for each signed body
axis ±x, ±y, ±z of the torque (and of the force, when the flight software controls
translation too) whether some thrusts ``T ≥ 0`` produce it: the non-negative least-squares
residual of ``B T = ±e_i`` (Lawson & Hanson 1974, ch. 23; scipy's ``nnls``) is zero to
round-off exactly when the axis lies in the cone of the columns. An axis outside it is a
demand the allocator can never meet: the run is allowed (seed 004 controls a vehicle with
three thrusters) but warned about before anyone reads its results.

Thrusters are on-off valves (thrust ≥ 0); a bidirectional actuator is an opposing pair.
Pure functions; no units beyond the inputs'.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.optimize import nnls

# An axis counts as reached when the NNLS residual is below this (unit target vector).
REACH_TOL = 1e-9
AXES = ("x", "y", "z")
# Controllers that command force as well as torque (6 DoF): they need both cones.
WRENCH_CONTROLLERS = ("nftsm_dq", "tsm_dq")


def effectiveness(r_thr_B_m: Sequence[Sequence[float]], d_thr_B: Sequence[Sequence[float]]
                  ) -> np.ndarray:
    """6 × n: rows force (x, y, z) then torque (x, y, z) per newton of each thruster."""
    r = np.asarray(r_thr_B_m, dtype=float).reshape(-1, 3)
    d = np.asarray(d_thr_B, dtype=float).reshape(-1, 3)
    return np.vstack([d.T, np.cross(r, d).T])


def unreached_axes(rows: np.ndarray) -> list[str]:
    """The signed axes (``+x`` ... ``-z``) of ``rows`` (3 × n) no thrusts ``T ≥ 0`` give."""
    out = []
    for i, axis in enumerate(AXES):
        for sign in (1.0, -1.0):
            target = np.zeros(3)
            target[i] = sign
            _, residual = nnls(rows, target)
            if residual > REACH_TOL:
                out.append(f"{'+' if sign > 0 else '-'}{axis}")
    return out


def authority_warnings(r_thr_B_m: Sequence[Sequence[float]], d_thr_B: Sequence[Sequence[float]],
                       needs_force: bool) -> list[str]:
    """Warnings for torque (and, if ``needs_force``, force) axes the thrusters cannot give."""
    b = effectiveness(r_thr_B_m, d_thr_B)
    warnings = []
    for what, rows, needed in (("torque", b[3:], True), ("force", b[:3], needs_force)):
        missing = unreached_axes(rows) if needed else []
        if missing:
            warnings.append(
                f"the {len(r_thr_B_m)} thrusters cannot produce {what} about/along "
                f"{', '.join(missing)} (no non-negative thrust combination does): demands "
                "there go unmet whatever the controller asks, and show only as an "
                "allocation residual (fsw.allocation in summary.json)")
    return warnings
