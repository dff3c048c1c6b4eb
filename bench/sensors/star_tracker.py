"""Star tracker: attitude quaternion with cross- and about-boresight noise, and outages.

What it does
    ``StarTracker.sample(t_ns, q_BN)`` returns the measured attitude quaternion and a
    validity flag, as reported in ``STR_QUAT``. Quantisation is left to the CAN encoding;
    the output rate and latency are the scheduler's business (this model is sampled
    when a measurement is due). Deterministic: 3 normals per sample from the
    ``numpy.random.Generator`` given to the constructor, drawn during outages too so the
    noise sequence after an outage does not depend on its length.

Inputs / outputs, frames and units
    q_BN: true attitude (scalar first, maps N to B; see ``bench.dynamics.rigid_body``).
    Output q̃_BN = q_BN ⊗ δq, normalised, sign chosen so that q̃0 ≥ 0, where δq is the
    rotation by the small body-axes error vector
        θ_B = σ⊥ (n₁ ê₁ + n₂ ê₂) + σ∥ n₃ b̂          [rad], n_i ~ N(0, 1)
    b̂ = the boresight (default +z_B), ê₁, ê₂ completing an orthonormal triad. So the
    measured body frame is the true one rotated by θ about body axes; its components
    across and about the boresight have 1σ ``noise_cross_arcsec`` and
    ``noise_about_arcsec`` (typical trackers are 5–10× worse about the boresight;
    Markley & Crassidis, "Fundamentals of Spacecraft Attitude Determination and
    Control", 2014, §5.4). δq = (cos(|θ|/2), sin(|θ|/2) θ/|θ|) (exact rotation vector map).

Outage
    ``set_outage(True)`` makes samples invalid: the output is frozen at the last valid
    measurement (identity before any), with ``valid = False``.

Assumptions
    Tracker frame aligned with B apart from the boresight convention; noise white and
    independent between samples; no bias, no aberration, no rate-induced smearing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bench.dynamics.rigid_body import QUAT_IDENTITY, Quat, Vec3, quat_multiply
from bench.sensors.gyro import check_number, check_vec3
from dbc.errors import ConfigError

RAD_PER_ARCSEC = math.pi / (180.0 * 3600.0)
UNIT_NORM_TOL = 1e-6
"""Allowed |‖boresight_B‖ − 1|."""
NORMALS_PER_SAMPLE = 3
SMALL_ANGLE_RAD = 1e-12
"""Below this rotation angle δq is taken as identity plus θ/2 (avoids 0/0)."""


@dataclass(frozen=True)
class StarTrackerParams:
    """Star tracker noise (1σ, arcsec) and boresight (unit vector in B)."""

    noise_cross_arcsec: float = 0.0
    noise_about_arcsec: float = 0.0
    boresight_B: Vec3 = (0.0, 0.0, 1.0)
    source: str = field(default="StarTrackerParams", compare=False, repr=False, kw_only=True)

    def __post_init__(self) -> None:
        src = self.source
        put = object.__setattr__
        for key in ("noise_cross_arcsec", "noise_about_arcsec"):
            put(self, key, check_number(getattr(self, key), src, key, positive=False))
        b = check_vec3(self.boresight_B, src, "boresight_B")
        if not abs(math.sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]) - 1.0) <= UNIT_NORM_TOL:
            raise ConfigError(
                src,
                "boresight_B",
                self.boresight_B,
                f"a unit vector (|norm - 1| <= {UNIT_NORM_TOL:g})",
            )
        put(self, "boresight_B", b)


def _cross_axes(b: Vec3) -> tuple[Vec3, Vec3]:
    """Unit vectors ê₁, ê₂ with (ê₁, ê₂, b̂) right-handed and orthonormal."""
    # Start from the body axis least aligned with b for a well-conditioned cross product.
    k = min(range(len(b)), key=lambda i: abs(b[i]))
    a = [0.0, 0.0, 0.0]
    a[k] = 1.0
    e1 = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    n = math.sqrt(e1[0] ** 2 + e1[1] ** 2 + e1[2] ** 2)
    e1 = (e1[0] / n, e1[1] / n, e1[2] / n)
    e2 = (b[1] * e1[2] - b[2] * e1[1], b[2] * e1[0] - b[0] * e1[2], b[0] * e1[1] - b[1] * e1[0])
    return e1, e2


class StarTracker:
    """A star tracker drawing its noise from ``rng`` (see the module docstring)."""

    __slots__ = (
        "_axes",
        "_last",
        "_rng",
        "_sigma_about_rad",
        "_sigma_cross_rad",
        "outage",
        "params",
    )

    def __init__(self, params: StarTrackerParams, rng: np.random.Generator) -> None:
        self.params = params
        self._rng = rng
        b = params.boresight_B
        e1, e2 = _cross_axes(b)
        self._axes = (e1, e2, b)
        self._sigma_cross_rad = params.noise_cross_arcsec * RAD_PER_ARCSEC
        self._sigma_about_rad = params.noise_about_arcsec * RAD_PER_ARCSEC
        self._last: Quat = QUAT_IDENTITY
        self.outage = False

    def set_outage(self, outage: bool) -> None:
        """Start (True) or end (False) an outage: samples are invalid while it lasts."""
        self.outage = bool(outage)

    def sample(self, t_ns: int, q_BN: Quat) -> tuple[Quat, bool]:
        """(measured q_BN with q0 ≥ 0, valid) at ``t_ns`` for the true attitude ``q_BN``.

        The noise is white, so ``t_ns`` only documents when the measurement is taken.
        """
        n1, n2, n3 = self._rng.standard_normal(NORMALS_PER_SAMPLE).tolist()
        if self.outage:
            return self._last, False
        (e1x, e1y, e1z), (e2x, e2y, e2z), (bx, by, bz) = self._axes
        a1 = self._sigma_cross_rad * n1
        a2 = self._sigma_cross_rad * n2
        a3 = self._sigma_about_rad * n3
        tx = a1 * e1x + a2 * e2x + a3 * bx
        ty = a1 * e1y + a2 * e2y + a3 * by
        tz = a1 * e1z + a2 * e2z + a3 * bz
        angle = math.sqrt(tx * tx + ty * ty + tz * tz)
        if angle < SMALL_ANGLE_RAD:
            dq: Quat = (1.0, 0.5 * tx, 0.5 * ty, 0.5 * tz)
        else:
            s = math.sin(0.5 * angle) / angle
            dq = (math.cos(0.5 * angle), s * tx, s * ty, s * tz)
        q0, q1, q2, q3 = quat_multiply(q_BN, dq)
        inv = 1.0 / math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
        if q0 < 0.0:
            inv = -inv
        self._last = (q0 * inv, q1 * inv, q2 * inv, q3 * inv)
        return self._last, True
