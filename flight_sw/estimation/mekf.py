"""Multiplicative extended Kalman filter (MEKF): attitude and gyro bias from gyro + star tracker.

What it does: a 6-state error-state Kalman filter, state ``x = (a, Δb)``: ``a`` the attitude
error rotation vector [rad] in body axes, ``Δb`` the gyro bias error [rad/s]. The attitude
itself is kept as the unit quaternion ``q̂_BN``; the filter estimates the small error about
it and folds it back after every update (the multiplicative "reset"), so the quaternion
never leaves the unit sphere and the covariance stays 6×6.

Inputs: gyro samples ``propagate(t_ns, omega_meas_B)`` [rad/s, body axes, raw: bias
included]; star-tracker samples ``update_star_tracker(t_ns, q_meas_BN)`` (scalar-first,
maps N to B). Output: ``estimate()`` -> :class:`AttitudeEstimate` (q_BN, bias-corrected
ω_BN_B [rad/s], gyro bias [rad/s], covariance diagonal: a [rad²] ×3, Δb [(rad/s)²] ×3).

Models and equations (Hamilton, scalar-first; see :mod:`flight_sw.quaternion`):
- Error definition: ``q_BN = q̂_BN ⊗ exp(a)`` (body-frame, right-multiplied error).
- Gyro (Farrenkopf model): ``ω_meas = ω_BN_B + b + η_v``, ``ḃ = η_u``, white noises with
  spectral densities ``σ_v² I`` (angle random walk, rad²/s) and ``σ_u² I`` (bias random
  walk, rad²/s³).
- Propagation from ``t_k`` to ``t_{k+1}`` (``Δt`` from the integer-ns timestamps), with the
  bias-corrected rate held constant over the interval, ``ω̂ = ½(ω_meas,k + ω_meas,k+1) − b̂``
  (trapezoidal hold: second-order for point-sampled gyros, exact for a constant rate):
  ``q̂ ← q̂ ⊗ exp(ω̂ Δt)`` (exact for constant ω̂), ``b̂`` constant,
  ``P ← Φ P Φᵀ + Q_k`` with the closed-form transition of ``ȧ = −[ω̂×] a − Δb − η_v``:
  ``Φ11 = exp(−[ω̂×] Δt) = C(exp(ω̂ Δt))``,
  ``Φ12 = −(I Δt − [ω̂×] (1 − cos x)/|ω̂|² + [ω̂×]² (x − sin x)/|ω̂|³)``, ``x = |ω̂| Δt``,
  ``Φ21 = 0``, ``Φ22 = I``; and the discrete noise
  ``Q11 = (σ_v² Δt + σ_u² Δt³/3) I``, ``Q12 = −(σ_u² Δt²/2) I``, ``Q22 = σ_u² Δt I``.
- Star-tracker update: measurement ``q_meas = q_BN ⊗ exp(v)``, ``v ~ N(0, σ_st² I)``;
  residual ``y = Log(q̂* ⊗ q_meas)`` (short way, ≈ ``a + v``), ``H = [I 0]``,
  ``K = P Hᵀ (H P Hᵀ + R)⁻¹``, ``x̂ = K y``; reset ``q̂ ← q̂ ⊗ exp(â)`` (renormalised),
  ``b̂ ← b̂ + Δb̂``; Joseph-form covariance ``P ← (I − KH) P (I − KH)ᵀ + K R Kᵀ``.

The covariance arithmetic (``Φ P Φᵀ + Q_k``, the gain and the Joseph form) is
:mod:`flight_sw.estimation.mekf_kernel`'s, on floats in one fixed summation order: numpy's
6×6 products went through the CPU's BLAS kernel and gave different traces on two machines.

Timing rules (all times are arguments; no clock is read):
- The first gyro sample only sets the held rate and the filter time.
- The first star-tracker sample initialises the attitude (``initialised`` becomes True) and
  the covariance to ``diag(σ_att0² I, σ_b0² I)``; before it, gyro samples track time and
  rate only, and ``estimate().q_BN`` is the identity.
- A star-tracker sample stamped before the filter time is carried forward to it with the
  current bias-corrected rate (``q_meas ⊗ exp(ω̂ age)``); one stamped after it makes the
  filter propagate to the sample time with the held rate first.
- A gyro sample older than the previous one is ignored and counted in
  :attr:`Mekf.rejected_samples`; one with the same timestamp replaces the held rate; a
  star-tracker quaternion that is zero or non-finite is ignored and counted likewise.

Assumptions: star-tracker noise isotropic in body axes and white; no misalignment or
scale-factor states; the age compensation of late star-tracker samples neglects the
gyro noise over that age (a few ms).

Sources: Markley & Crassidis 2014, "Fundamentals of Spacecraft Attitude Determination
and Control", ch. 6 (§6.2: the MEKF, its multiplicative reset, the gyro model, the
closed-form Φ and the discrete Q_k); Lefferts, Markley & Shuster 1982, "Kalman filtering
for spacecraft attitude estimation", JGCD 5(5) 417–429; Farrenkopf 1978, "Analytic
steady-state accuracy solutions for two common spacecraft attitude estimators", JGC 1(4)
282–284 (the gyro noise model and Q_k). Those texts write the error as ``δq ⊗ q̂`` with the
Shuster product, which is our Hamilton ``q̂ ⊗ δq``: Φ, Q, H are therefore unchanged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from flight_sw.estimation.base import AttitudeEstimate
from flight_sw.estimation.mekf_kernel import propagate_covariance, star_tracker_update
from flight_sw.quaternion import (
    error_quaternion,
    from_rotation_vector,
    identity,
    multiply,
    to_rotation_vector,
    with_positive_scalar,
)
from flight_sw.quaternion import (
    norm as qt_norm,
)

NS_PER_S = 1_000_000_000
N_STATES = 6
N_AXES = 3
# Below this rotation angle x = |ω̂|Δt [rad] the increment quaternion and the Φ12
# coefficients use their Taylor series (largest truncation error x⁴/720 relative, ≈ 1.4e-15
# at the switch).
SERIES_ANGLE_RAD = 1e-3

_SOURCE = "MekfParams"


@dataclass(frozen=True)
class MekfParams:
    """MEKF tuning: sensor noise model and initial uncertainty.

    Attributes:
        gyro_arw_rad_sqrt_s: σ_v, gyro angle random walk [rad/√s] (≥ 0).
        gyro_bias_rw_rad_s_sqrt_s: σ_u, gyro bias random walk [rad/s/√s] (≥ 0).
        star_tracker_sigma_rad: σ_st, star-tracker noise per body axis [rad] (> 0).
        initial_attitude_sigma_rad: σ_att0, attitude σ per axis at initialisation [rad] (> 0).
        initial_bias_sigma_rad_s: σ_b0, gyro bias σ per axis at initialisation [rad/s] (> 0).
        initial_bias_B_rad_s: initial gyro bias estimate, body axes [rad/s].
    """

    gyro_arw_rad_sqrt_s: float
    gyro_bias_rw_rad_s_sqrt_s: float
    star_tracker_sigma_rad: float
    initial_attitude_sigma_rad: float
    initial_bias_sigma_rad_s: float
    initial_bias_B_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        s = _SOURCE
        check.non_negative(s, "gyro_arw_rad_sqrt_s", self.gyro_arw_rad_sqrt_s)
        check.non_negative(s, "gyro_bias_rw_rad_s_sqrt_s", self.gyro_bias_rw_rad_s_sqrt_s)
        check.positive(s, "star_tracker_sigma_rad", self.star_tracker_sigma_rad, unit="rad")
        check.positive(s, "initial_attitude_sigma_rad", self.initial_attitude_sigma_rad,
                       unit="rad")
        check.positive(s, "initial_bias_sigma_rad_s", self.initial_bias_sigma_rad_s,
                       unit="rad/s")
        bias = check.triple(s, "initial_bias_B_rad_s", self.initial_bias_B_rad_s, unit="rad/s")
        object.__setattr__(self, "initial_bias_B_rad_s", bias)


def _frozen(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


class Mekf:
    """Multiplicative EKF for attitude and gyro bias (implements ``AttitudeEstimator``)."""

    def __init__(self, params: MekfParams) -> None:
        self._params = params
        self._r_st = params.star_tracker_sigma_rad**2
        p0_diag = ([params.initial_attitude_sigma_rad**2] * N_AXES
                   + [params.initial_bias_sigma_rad_s**2] * N_AXES)
        self._p0 = [p0_diag[i] if i == j else 0.0
                    for i in range(N_STATES) for j in range(N_STATES)]
        self._q_BN = identity()
        self._bias_B = np.array(params.initial_bias_B_rad_s, dtype=float)
        self._cov = list(self._p0)  # 6×6, flat row-major (see mekf_kernel)
        self._t_ns: int | None = None  # time the attitude estimate refers to
        self._t_gyro_ns: int | None = None  # time of the newest gyro sample
        self._omega_meas_B: np.ndarray | None = None  # newest raw gyro sample
        self._initialised = False
        self._qd_dt_ns = -1  # one-entry cache of the discrete process noise
        self._qd = (0.0, 0.0, 0.0)  # Q_k's q11 [rad²], q12 [rad²/s], q22 [(rad/s)²]
        self.rejected_samples = 0

    @property
    def params(self) -> MekfParams:
        """The tuning this filter was built with."""
        return self._params

    @property
    def covariance(self) -> np.ndarray:
        """A copy of the 6×6 error covariance (a [rad], Δb [rad/s])."""
        return np.array(self._cov).reshape(N_STATES, N_STATES)

    # --- propagation -------------------------------------------------------------------

    def propagate(self, t_ns: int, omega_meas_B: np.ndarray) -> None:
        """Take one raw gyro sample [rad/s, body axes] at ``t_ns`` and propagate to it."""
        w_new = np.array(omega_meas_B, dtype=float)
        if w_new.shape != (N_AXES,):
            self.rejected_samples += 1
            return
        w1, w2, w3 = w_new.tolist()
        if not (math.isfinite(w1) and math.isfinite(w2) and math.isfinite(w3)):
            self.rejected_samples += 1
            return
        w_prev = self._omega_meas_B
        if w_prev is None or self._t_ns is None or self._t_gyro_ns is None:
            self._omega_meas_B = w_new
            self._t_gyro_ns = t_ns
            if self._t_ns is None:
                self._t_ns = t_ns
            return
        if t_ns < self._t_gyro_ns:
            self.rejected_samples += 1
            return
        self._omega_meas_B = w_new
        self._t_gyro_ns = t_ns
        dt_ns = t_ns - self._t_ns
        if dt_ns <= 0:
            return
        if self._initialised:
            p1, p2, p3 = w_prev.tolist()
            b1, b2, b3 = self._bias_B.tolist()
            omega_hat = (0.5 * (p1 + w1) - b1, 0.5 * (p2 + w2) - b2, 0.5 * (p3 + w3) - b3)
            self._propagate_state(omega_hat, dt_ns)
        self._t_ns = t_ns

    def _propagate_state(self, omega_hat_B: tuple[float, float, float], dt_ns: int) -> None:
        """q̂ ← q̂ ⊗ exp(ω̂ Δt), P ← Φ P Φᵀ + Q_k (scalar arithmetic: this runs at the gyro rate)."""
        dt_s = dt_ns / NS_PER_S
        w1, w2, w3 = omega_hat_B
        w_sq = w1 * w1 + w2 * w2 + w3 * w3
        w = math.sqrt(w_sq)
        x = w * dt_s
        x_sq = x * x
        if x < SERIES_ANGLE_RAD:
            # cos(x/2), sin(x/2)/|ω|, (1 − cos x)/|ω|², (x − sin x)/|ω|³ by their Taylor series
            c_half = 1.0 - x_sq / 8.0 + x_sq * x_sq / 384.0
            s_half = dt_s * (0.5 - x_sq / 48.0 + x_sq * x_sq / 3840.0)
            c1 = dt_s * dt_s * (0.5 - x_sq / 24.0)
            c2 = dt_s * dt_s * dt_s * (1.0 / 6.0 - x_sq / 120.0)
        else:
            c_half = math.cos(0.5 * x)
            s_half = math.sin(0.5 * x) / w
            c1 = (1.0 - math.cos(x)) / w_sq
            c2 = (x - math.sin(x)) / (w_sq * w)
        d0, d1, d2, d3 = c_half, s_half * w1, s_half * w2, s_half * w3  # exp(ω̂ Δt)
        q0, q1, q2, q3 = self._q_BN.tolist()
        n0 = q0 * d0 - q1 * d1 - q2 * d2 - q3 * d3
        n1 = q0 * d1 + q1 * d0 + q2 * d3 - q3 * d2
        n2 = q0 * d2 - q1 * d3 + q2 * d0 + q3 * d1
        n3 = q0 * d3 + q1 * d2 - q2 * d1 + q3 * d0
        inv_norm = 1.0 / math.sqrt(n0 * n0 + n1 * n1 + n2 * n2 + n3 * n3)
        self._q_BN = np.array([n0 * inv_norm, n1 * inv_norm, n2 * inv_norm, n3 * inv_norm])
        # Φ11 = C(exp(ω̂ Δt)) (see flight_sw.quaternion.to_dcm)
        e00, e11, e22, e33 = d0 * d0, d1 * d1, d2 * d2, d3 * d3
        e01, e02, e03 = d0 * d1, d0 * d2, d0 * d3
        e12, e13, e23 = d1 * d2, d1 * d3, d2 * d3
        # Φ12 = −(I Δt − c1 [ω̂×] + c2 [ω̂×]²), with [ω̂×]² = ω̂ ω̂ᵀ − |ω̂|² I
        diag = -dt_s + c2 * w_sq
        phi11 = [e00 + e11 - e22 - e33, 2.0 * (e12 + e03), 2.0 * (e13 - e02),
                 2.0 * (e12 - e03), e00 - e11 + e22 - e33, 2.0 * (e23 + e01),
                 2.0 * (e13 + e02), 2.0 * (e23 - e01), e00 - e11 - e22 + e33]
        phi12 = [diag - c2 * w1 * w1, -c1 * w3 - c2 * w1 * w2, c1 * w2 - c2 * w1 * w3,
                 c1 * w3 - c2 * w1 * w2, diag - c2 * w2 * w2, -c1 * w1 - c2 * w2 * w3,
                 -c1 * w2 - c2 * w1 * w3, c1 * w1 - c2 * w2 * w3, diag - c2 * w3 * w3]
        q11, q12, q22 = self._process_noise(dt_ns)
        self._cov = propagate_covariance(self._cov, phi11, phi12, q11, q12, q22)

    def _process_noise(self, dt_ns: int) -> tuple[float, float, float]:
        """Q_k's blocks (q11 I, q12 I, q22 I) for a step of ``dt_ns``, cached per step."""
        if dt_ns != self._qd_dt_ns:
            dt_s = dt_ns / NS_PER_S
            sv2 = self._params.gyro_arw_rad_sqrt_s**2
            su2 = self._params.gyro_bias_rw_rad_s_sqrt_s**2
            self._qd = (sv2 * dt_s + su2 * dt_s**3 / 3.0, -(su2 * dt_s**2 / 2.0), su2 * dt_s)
            self._qd_dt_ns = dt_ns
        return self._qd

    def _omega_hat_B(self) -> np.ndarray:
        if self._omega_meas_B is None:
            return np.zeros(N_AXES)
        return self._omega_meas_B - self._bias_B

    # --- measurement update ------------------------------------------------------------

    def update_star_tracker(self, t_ns: int, q_meas_BN: np.ndarray) -> None:
        """Take one star-tracker quaternion (maps N to B) measured at ``t_ns``."""
        qm = np.array(q_meas_BN, dtype=float)
        norm = qt_norm(qm) if qm.shape == (4,) else 0.0
        if not (norm > 0.0 and math.isfinite(norm)):
            self.rejected_samples += 1
            return
        qm /= norm
        if self._t_ns is None:
            self._t_ns = t_ns
        elif t_ns > self._t_ns:
            if self._initialised:
                w1, w2, w3 = self._omega_hat_B().tolist()
                self._propagate_state((w1, w2, w3), t_ns - self._t_ns)
            self._t_ns = t_ns
        elif t_ns < self._t_ns:
            age_s = (self._t_ns - t_ns) / NS_PER_S
            qm = multiply(qm, from_rotation_vector(self._omega_hat_B() * age_s))
        if not self._initialised:
            self._q_BN = with_positive_scalar(qm)
            self._cov = list(self._p0)
            self._initialised = True
            return
        y1, y2, y3 = to_rotation_vector(error_quaternion(self._q_BN, qm)).tolist()
        updated = star_tracker_update(self._cov, self._r_st, [y1, y2, y3])
        if updated is None:  # a non-finite covariance: refuse the sample, keep the state
            self.rejected_samples += 1
            return
        dx, self._cov = updated
        q = multiply(self._q_BN, from_rotation_vector(np.array(dx[:3])))
        self._q_BN = with_positive_scalar(q / qt_norm(q))
        self._bias_B = self._bias_B + np.array(dx[3:])

    # --- output ------------------------------------------------------------------------

    def estimate(self) -> AttitudeEstimate:
        """The current estimate (read-only array copies)."""
        return AttitudeEstimate(
            t_ns=self._t_ns,
            q_BN=_frozen(self._q_BN.copy()),
            omega_BN_B=_frozen(self._omega_hat_B()),
            gyro_bias_B_rad_s=_frozen(self._bias_B.copy()),
            covariance_diag=_frozen(np.array(self._cov[::N_STATES + 1])),
            initialised=self._initialised,
        )
