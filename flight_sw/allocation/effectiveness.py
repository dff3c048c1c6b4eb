"""Thruster effectiveness (control-input) matrix: body wrench per unit thrust of each thruster.

What it does: for n thrusters with positions ``r_i`` and unit thrust directions ``d_i``
(both in body axes B), returns the 6×n matrix whose column i is the wrench a thrust of
1 N on thruster i produces about the centre of mass:
    ``B[:, i] = [d_i ; r_i × d_i]``  (force [N/N] in rows 0–2, torque [N m/N] in rows 3–5).
A torque-only allocator uses rows 3–5 (:data:`TORQUE_ROWS`), a 6-DoF one all six.

Inputs: ``r_thr_B_m`` (n×3) thruster positions relative to the centre of mass [m], body
axes; ``d_thr_B`` (n×3) thrust directions (the direction of the force on the vehicle,
i.e. opposite to the exhaust), body axes, unit vectors (checked to
``UNIT_VECTOR_TOLERANCE``; they are not silently renormalised).
Output: the 6×n float64 matrix.

Assumptions: rigid vehicle, point thrusters, force along ``d_i`` independent of the other
thrusters (no plume impingement), centre of mass known.

Sources: Wie 2008, "Space Vehicle Dynamics and Control", 2nd ed., ch. 7 (thruster torque
``r × F``); Bordignon 1996, "Constrained Control Allocation for Systems with Redundant
Control Effectors", PhD thesis, Virginia Tech, ch. 2 (the control effectiveness matrix
``B`` in ``m = B u``); seed 003 (8-thruster layout, Eq. 6's allocation matrix).
"""

from __future__ import annotations

import numpy as np

from dbc.errors import ConfigError

FORCE_ROWS = slice(0, 3)
TORQUE_ROWS = slice(3, 6)
WRENCH_DIM = 6
# |‖d_i‖ − 1| allowed for a thrust direction (catches unnormalised or garbled input).
UNIT_VECTOR_TOLERANCE = 1e-6

_SOURCE = "effectiveness_matrix"


def effectiveness_matrix(r_thr_B_m: np.ndarray, d_thr_B: np.ndarray) -> np.ndarray:
    """The 6×n matrix ``[d_i ; r_i × d_i]`` per unit thrust (see the module docstring).

    Raises ``ConfigError`` for mismatched shapes, non-finite values or non-unit directions.
    """
    r = np.asarray(r_thr_B_m, dtype=float)
    d = np.asarray(d_thr_B, dtype=float)
    if r.ndim != 2 or r.shape[1] != 3 or r.shape[0] == 0:
        raise ConfigError(_SOURCE, "r_thr_B_m", r.shape, "an n×3 array with n >= 1")
    if d.shape != r.shape:
        raise ConfigError(_SOURCE, "d_thr_B", d.shape, f"shape {r.shape} like r_thr_B_m")
    if not (np.all(np.isfinite(r)) and np.all(np.isfinite(d))):
        raise ConfigError(_SOURCE, "r_thr_B_m/d_thr_B", "non-finite", "finite values")
    norms = np.linalg.norm(d, axis=1)
    bad = np.flatnonzero(np.abs(norms - 1.0) > UNIT_VECTOR_TOLERANCE)
    if bad.size:
        i = int(bad[0])
        raise ConfigError(_SOURCE, f"d_thr_B[{i}]", d[i].tolist(), "a unit vector")
    b = np.empty((WRENCH_DIM, r.shape[0]))
    b[FORCE_ROWS] = d.T
    b[TORQUE_ROWS] = np.cross(r, d).T
    return b
