"""3-vectors and 3×3 matrices on Python floats (compiled with mypyc): the one implementation.

What it does: the small fixed-size algebra of the flight software's per-cycle laws, on
tuples of floats (no array per 3-vector): cross product, matrix–vector products, the
solution of a 3×3 system by the adjugate, and the norm clip of a 3-vector. The array
functions of :mod:`flight_sw.quaternion` (``cross``) and the pose laws
(:mod:`flight_sw.control.dq_error_state`, :mod:`flight_sw.control.nftsm_dq`,
:mod:`flight_sw.control.tsm_dq`) are built on these.

Conventions: ``Vec3`` is ``(x, y, z)``; ``Mat3`` is a 3×3 matrix in row-major order
``(m00, m01, m02, m10, ..., m22)``. Units: the caller's.

Assumptions: finite inputs; :func:`solve3` needs a non-singular matrix (its caller
guarantees it: Θ of eq. 10 of seed 000 with its scalar part floored).

Source: elementary linear algebra (cross product; Cramer's rule: Golub & Van Loan 2013,
"Matrix Computations", 4th ed., sec. 2.1).
"""

from __future__ import annotations

import math

import numpy as np

Vec3 = tuple[float, float, float]
Mat3 = tuple[float, float, float, float, float, float, float, float, float]  # row-major


def cross(a: Vec3, b: Vec3) -> Vec3:
    """``a × b``."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def mat_vec(m: Mat3, x: float, y: float, z: float) -> Vec3:
    """``M v``."""
    return (m[0] * x + m[1] * y + m[2] * z, m[3] * x + m[4] * y + m[5] * z,
            m[6] * x + m[7] * y + m[8] * z)


def mat_t_vec(m: Mat3, x: float, y: float, z: float) -> Vec3:
    """``Mᵀ v``."""
    return (m[0] * x + m[3] * y + m[6] * z, m[1] * x + m[4] * y + m[7] * z,
            m[2] * x + m[5] * y + m[8] * z)


def solve3(m: Mat3, b: Vec3) -> Vec3:
    """``M⁻¹ b`` by the adjugate (Cramer's rule); M non-singular."""
    c0 = m[4] * m[8] - m[5] * m[7]
    c1 = m[5] * m[6] - m[3] * m[8]
    c2 = m[3] * m[7] - m[4] * m[6]
    inv_det = 1.0 / (m[0] * c0 + m[1] * c1 + m[2] * c2)
    return (
        (c0 * b[0] + (m[2] * m[7] - m[1] * m[8]) * b[1] + (m[1] * m[5] - m[2] * m[4]) * b[2])
        * inv_det,
        (c1 * b[0] + (m[0] * m[8] - m[2] * m[6]) * b[1] + (m[2] * m[3] - m[0] * m[5]) * b[2])
        * inv_det,
        (c2 * b[0] + (m[1] * m[6] - m[0] * m[7]) * b[1] + (m[0] * m[4] - m[1] * m[3]) * b[2])
        * inv_det,
    )


def clip(x: float, y: float, z: float, limit: float) -> Vec3:
    """``(x, y, z)`` scaled down to norm ``limit`` if longer (direction preserved)."""
    norm = math.sqrt(x * x + y * y + z * z)
    if norm > limit:
        k = limit / norm
        return (x * k, y * k, z * k)
    return (x, y, z)


def mat3(m: np.ndarray) -> Mat3:
    """A 3×3 array as a row-major tuple."""
    a = m.reshape(-1).tolist()
    return (a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8])


def vec3(v: np.ndarray) -> Vec3:
    """A 3-vector (array or sequence) as a tuple of floats."""
    a = np.asarray(v, dtype=float).tolist()
    return (a[0], a[1], a[2])
