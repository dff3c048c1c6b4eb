"""Star tracker: attitude quaternion with cross- and about-boresight noise, and outages.

What it does
    ``StarTracker.sample(t_ns, q_BN)`` returns the measured attitude quaternion and a
    validity flag, as reported in ``STR_QUAT``. Quantisation is left to the CAN encoding;
    the output rate and latency are the scheduler's business (this model is sampled
    when a measurement is due). Deterministic: 3 normals per sample from the
    ``numpy.random.Generator`` given to the constructor, drawn during outages too so the
    noise sequence after an outage does not depend on its length.

Inputs / outputs, frames and units
    q_BN: true attitude (scalar first, maps N to B; see ``bench.station.dynamics.rigid_body``).
    Output q̃_BN = q_BN ⊗ δq, normalised, sign chosen so that q̃0 ≥ 0, where δq is the
    rotation by the small body-axes error vector
        θ_B = σ⊥ (n₁ ê₁ + n₂ ê₂) + σ∥ n₃ b̂          [rad], n_i ~ N(0, 1)
    b̂ = the boresight (default +z_B), ê₁, ê₂ completing an orthonormal triad. So the
    measured body frame is the true one rotated by θ about body axes; its components
    across and about the boresight have 1σ ``noise_cross_arcsec`` and
    ``noise_about_arcsec`` (typical trackers are 5–10× worse about the boresight;
    Markley & Crassidis, "Fundamentals of Spacecraft Attitude Determination and
    Control", 2014, §5.4). δq = (cos(|θ|/2), sin(|θ|/2) θ/|θ|) (exact rotation vector map).

Faults (``set_fault(kind, t_ns, **params)`` / ``clear_fault(kind, t_ns)``; DESIGN.md §7)
    Each applies from the next sample (the tracker keeps no clock: ``t_ns`` is the event
    time, for the caller's records); several may be active; setting an active kind
    again replaces its parameters; ``set_fault(None)`` clears all; ``faults_active``
    lists them (kind → parameters). The 3 normals are drawn whatever is active.
    - ``"outage"`` (no parameter; also ``set_outage(True/False)`` and the ``outage``
      attribute): samples are invalid: the output is the last valid measurement
      (identity before any), with ``valid = False``.
    - ``"frozen"`` (no parameter): the output repeats the last measurement exactly
      (the first one if there was none), reported valid: a stuck tracker.
    - ``"noise"``, ``factor`` [-] ≥ 0: both noise σ (across and about the boresight)
      are multiplied by ``factor``.
    - ``"bias_jump"``, ``misalignment_arcsec`` (3 numbers [arcsec], body axes): a fixed
      rotation vector β of the tracker mounting, applied to every output:
      q̃_BN = q_BN ⊗ δq(β) ⊗ δq(θ) (δq the exact rotation-vector map above), so the
      measured frame is rotated by |β| about β/|β| (plus the noise).
    Precedence: outage, then frozen, then the live measurement. An inactive fault costs
    one truth test per sample.

Assumptions
    Tracker frame aligned with B apart from the boresight convention; noise white and
    independent between samples; no aberration, no rate-induced smearing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from mypy_extensions import mypyc_attr

from bench.station.dynamics.rigid_body import QUAT_IDENTITY, Quat, Vec3, quat_multiply
from bench.station.sensors.gyro import (
    FAULT_BIAS_JUMP,
    FAULT_FROZEN,
    FAULT_NOISE,
    FAULT_OUTAGE,
    SensorFaultParams,
    check_fault_kind,
)
from dbc import validation as check
from dbc.errors import ConfigError

RAD_PER_ARCSEC = math.pi / (180.0 * 3600.0)
NORMALS_PER_SAMPLE = 3
SMALL_ANGLE_RAD = 1e-12
"""Below this rotation angle δq is taken as identity plus θ/2 (avoids 0/0)."""
STAR_TRACKER_FAULT_PARAMS: dict[str, tuple[str, ...]] = {
    FAULT_OUTAGE: (),
    FAULT_FROZEN: (),
    FAULT_NOISE: ("factor",),
    FAULT_BIAS_JUMP: ("misalignment_arcsec",),
}
"""Star-tracker fault kinds and their parameter names (see the module docstring)."""
SOURCE = "star tracker"
NOMINAL_NOISE_FACTOR = 1.0


def rotation_vector_quat(theta: Vec3) -> Quat:
    """δq = (cos(|θ|/2), sin(|θ|/2) θ/|θ|) of the rotation vector ``theta`` [rad]."""
    tx, ty, tz = theta
    angle = math.sqrt(tx * tx + ty * ty + tz * tz)
    if angle < SMALL_ANGLE_RAD:
        return (1.0, 0.5 * tx, 0.5 * ty, 0.5 * tz)
    s = math.sin(0.5 * angle) / angle
    return (math.cos(0.5 * angle), s * tx, s * ty, s * tz)


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
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
            put(self, key, check.non_negative(src, key, getattr(self, key)))
        given = getattr(self, "boresight_B")  # noqa: B009 - uncast (see setup.py)
        put(self, "boresight_B", check.unit_triple(src, "boresight_B", given))


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
        "_bias_q",
        "_faults",
        "_last",
        "_rng",
        "_sigma_about_rad",
        "_sigma_cross_rad",
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
        self._last: Quat | None = None  # last valid output
        self._faults: dict[str, SensorFaultParams] = {}
        self._bias_q: Quat = QUAT_IDENTITY  # δq(β) of an active bias_jump

    # --- faults ------------------------------------------------------------------------
    @property
    def outage(self) -> bool:
        """True while an ``outage`` fault is active (assignable, like ``set_outage``)."""
        return FAULT_OUTAGE in self._faults

    @outage.setter
    def outage(self, outage: bool) -> None:
        self.set_outage(outage)

    def set_outage(self, outage: bool) -> None:
        """Start (True) or end (False) an outage: samples are invalid while it lasts."""
        if outage:
            self.set_fault(FAULT_OUTAGE)
        else:
            self.clear_fault(FAULT_OUTAGE)

    @property
    def faults_active(self) -> dict[str, SensorFaultParams]:
        """Active faults: kind → parameters (a copy; empty when healthy)."""
        return {k: dict(v) for k, v in self._faults.items()}

    def set_fault(self, kind: str | None, t_ns: int | None = None, **params: object) -> None:
        """Inject fault ``kind`` (module docstring) from the next sample, or clear all (None).

        ``t_ns`` is the event time, for the caller's records. Bad kinds or parameters
        raise ``ConfigError``.
        """
        source = f"{SOURCE}.set_fault({kind!r})"
        if kind is None:
            if params:
                key = next(iter(params))
                raise ConfigError(source, key, params[key], "no parameter when clearing (None)")
            for k in list(self._faults):
                self.clear_fault(k, t_ns)
            return
        check_fault_kind(kind, params, source, STAR_TRACKER_FAULT_PARAMS)
        recorded: SensorFaultParams = {}
        if kind == FAULT_NOISE:
            factor = check.non_negative(source, "factor", params["factor"])
            recorded["factor"] = factor
            self._set_noise_factor(factor)
        elif kind == FAULT_BIAS_JUMP:
            beta = check.triple(source, "misalignment_arcsec", params["misalignment_arcsec"])
            recorded["misalignment_arcsec"] = beta
            self._bias_q = rotation_vector_quat(
                (beta[0] * RAD_PER_ARCSEC, beta[1] * RAD_PER_ARCSEC, beta[2] * RAD_PER_ARCSEC)
            )
        self._faults[kind] = recorded

    def clear_fault(self, kind: str, t_ns: int | None = None) -> None:
        """Clear fault ``kind`` from the next sample; a no-op if it is not active."""
        if kind not in STAR_TRACKER_FAULT_PARAMS:
            raise ConfigError(
                f"{SOURCE}.clear_fault({kind!r})",
                "kind",
                kind,
                f"one of {sorted(STAR_TRACKER_FAULT_PARAMS)}",
            )
        if self._faults.pop(kind, None) is None:
            return
        if kind == FAULT_NOISE:
            self._set_noise_factor(NOMINAL_NOISE_FACTOR)
        elif kind == FAULT_BIAS_JUMP:
            self._bias_q = QUAT_IDENTITY

    def _set_noise_factor(self, factor: float) -> None:
        p = self.params
        self._sigma_cross_rad = p.noise_cross_arcsec * RAD_PER_ARCSEC * factor
        self._sigma_about_rad = p.noise_about_arcsec * RAD_PER_ARCSEC * factor

    # --- sampling ----------------------------------------------------------------------
    def sample(self, t_ns: int, q_BN: Quat) -> tuple[Quat, bool]:
        """(measured q_BN with q0 ≥ 0, valid) at ``t_ns`` for the true attitude ``q_BN``.

        The noise is white, so ``t_ns`` only documents when the measurement is taken.
        """
        n1, n2, n3 = self._rng.standard_normal(NORMALS_PER_SAMPLE).tolist()
        if self._faults:
            faults = self._faults
            last = self._last
            if FAULT_OUTAGE in faults:
                return (QUAT_IDENTITY if last is None else last), False
            if FAULT_FROZEN in faults and last is not None:
                return last, True
            q_BN = quat_multiply(q_BN, self._bias_q)
        (e1x, e1y, e1z), (e2x, e2y, e2z), (bx, by, bz) = self._axes
        a1 = self._sigma_cross_rad * n1
        a2 = self._sigma_cross_rad * n2
        a3 = self._sigma_about_rad * n3
        tx = a1 * e1x + a2 * e2x + a3 * bx
        ty = a1 * e1y + a2 * e2y + a3 * by
        tz = a1 * e1z + a2 * e2z + a3 * bz
        angle = math.sqrt(tx * tx + ty * ty + tz * tz)
        if angle < SMALL_ANGLE_RAD:  # δq inline (see rotation_vector_quat): hot path
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
