"""Cascade attitude control of seed 003: outer quaternion PD (LQR-designed), inner P rate loop.

What it does (seed 003, "The QPDLQR and LPC approaches", Fig. 1): the outer loop (QPDLQR)
turns the attitude error into a body-rate command, the inner loop (LPC, "linear
proportional control": the same law without its derivative term) turns the rate error
into a torque, per axis i:
    ``e = 2 sgn(δq0) δq_vec`` with ``δq = q_RN* ⊗ q_BN`` (= q_BR; ``e`` ≈ the rotation
    angles for small errors, the seed's QV2RA block; the sign picks the short way),
    ``ω_e = ω_BN_B − ω_RN_B``,
    ``Δω_cmd,i = sat_ωmax(−k_p,i e_i − k_d,i ω_e,i)``   (QPDLQR, ``u = −k_p(x1 − x0) − k_d x2``),
    ``τ_i = k_i,i (ω_RN_B,i + Δω_cmd,i − ω_BN_B,i)``    (LPC).
With no rate limit this is a PD law with torque gains ``k_i k_p`` and ``k_i (1 + k_d)``.

LQR design (:func:`lqr_gains`, :meth:`CascadeLqrDesign.params`): with the inner loop
closed, axis i obeys ``J_i ω̇_e = k_i (Δω_cmd − ω_e)`` and ``ė ≈ ω_e``, so the outer loop
sees ``x = [e, ė]``, ``ẋ = A x + B Δω_cmd`` with ``A = [[0, 1], [0, −k_i/J_i]]``,
``B = [0, k_i/J_i]ᵀ`` (:func:`outer_loop_model`). The seed's index
``∫ xᵀQx + uᵀRu dt`` with ``Q = diag(q_angle, q_rate)``, ``R = r`` and the Riccati equation
``AᵀP + PA − PBR⁻¹BᵀP + Q = 0`` give ``[k_p, k_d] = R⁻¹BᵀP``; in closed form
``k_p = √(q_angle/r)``, ``k_d = √(1 + q_rate/r + 2 k_p J_i/k_i) − 1``.

Rate limit (optional ``max_rate_rad_s``, Wie & Lu 1995 as in :mod:`.quaternion_pd`): the
proportional term's error is clipped per axis at ``L_i = (1 + k_d,i) ω_max / k_p,i``
(:func:`flight_sw.control.base.error_limit`), so far from the target the inner loop's
equilibrium ``(1 + k_d) ω_e = −k_p L`` is a slew at ``ω_max``. Clipping the whole command
offset instead would cap the braking torque at ``k_i (ω_max + |ω|)``, a few N m with
Table 1's ``k_i`` — too little to stop a 72 kg m² axis in time.

Inputs/outputs: see :class:`flight_sw.control.base.AttitudeController`; torque [N m];
gain and weight units in :class:`CascadeLqrParams` and :class:`CascadeLqrDesign`.

Assumptions: principal body axes for the design (diagonal of J), gyroscopic coupling and
the reference acceleration ignored (``domega_RN_B`` unused, as in the seed); continuous
time. The inner loop's time constant ``J_i/(k_i (1 + k_d))`` must be well above the
control period: with Table 1 and J_x = 15.95 kg m² it is 5.3 ms, so at 50 Hz the ideal
sampled loop is unstable about x (q_angle = 1, q_rate = 4, r = 1, k_i = 15 is fine there).

Sources: seed 003 (cascade QPDLQR + LPC, performance index and Riccati equation of the
QPDLQR section, Table 1: I = (15.95, 72.19, 72.19) kg m², LPC k_p = 15, QPDLQR k_p = 72,
k_d = 200; Table 2: error < 3°, convergence < 10 s). The seed's equations were lost in
text extraction; the structure above follows its prose and Fig. 1.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_continuous_are

from dbc import validation as check
from flight_sw.control.base import error_limit
from flight_sw.quaternion import error_quaternion

N_AXES = 3
# e = ANGLE_PER_QUATERNION_VECTOR · δq_vec: δq_vec = sin(θ/2) e ≈ θ/2.
ANGLE_PER_QUATERNION_VECTOR = 2.0
# Seed 003 Table 1 (identical on the three axes).
SEED003_OUTER_KP_1_S = 72.0
SEED003_OUTER_KD = 200.0
SEED003_INNER_KP_NMS = 15.0

Triple = tuple[float, float, float]


def _principal_moments(inertia_B_kgm2: np.ndarray) -> list[float]:
    j = np.asarray(inertia_B_kgm2, dtype=float)
    if j.shape != (N_AXES, N_AXES):
        raise ValueError(f"inertia_B_kgm2 = {j.tolist()!r}: expected a 3x3 matrix")
    return [float(x) for x in np.diag(j)]


def lqr_gains(
    a: np.ndarray, b: np.ndarray, q: np.ndarray, r: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(K, P)``: ``K = R⁻¹BᵀP`` with P the stabilising solution of the continuous ARE."""
    p = np.asarray(solve_continuous_are(a, b, q, r), dtype=float)
    k = np.linalg.solve(np.atleast_2d(r), b.T @ p)
    return k, p


def outer_loop_model(inertia_kgm2: float, inner_kp_Nms: float) -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)`` of one axis seen by the outer loop: ``x = [e, ė]``, input Δω_cmd [rad/s]."""
    bandwidth = inner_kp_Nms / inertia_kgm2
    return np.array([[0.0, 1.0], [0.0, -bandwidth]]), np.array([[0.0], [bandwidth]])


@dataclass(frozen=True)
class CascadeLqrParams:
    """Per-axis gains of the cascade.

    Attributes:
        outer_kp_1_s: QPDLQR proportional gains (x, y, z) [1/s], each ≥ 0.
        outer_kd: QPDLQR derivative gains (x, y, z) [–], each ≥ 0.
        inner_kp_Nms: LPC rate gains (x, y, z) [N m s/rad], each > 0.
        max_rate_rad_s: slew rate the clipped proportional term settles at [rad/s] (inf: none).
    """

    outer_kp_1_s: Triple
    outer_kd: Triple
    inner_kp_Nms: Triple
    max_rate_rad_s: float = math.inf

    def __post_init__(self) -> None:
        src = "CascadeLqrParams"
        for key, strict in (("outer_kp_1_s", False), ("outer_kd", False), ("inner_kp_Nms", True)):
            value = check.triple(src, key, getattr(self, key), 0.0, lo_open=strict)
            object.__setattr__(self, key, value)
        check.limit(src, "max_rate_rad_s", self.max_rate_rad_s, unit="rad/s")

    @classmethod
    def from_table1(cls, max_rate_rad_s: float = math.inf) -> CascadeLqrParams:
        """The gains of seed 003 Table 1, as printed: k_p = 72, k_d = 200, LPC k_p = 15."""
        return cls(
            outer_kp_1_s=(SEED003_OUTER_KP_1_S, SEED003_OUTER_KP_1_S, SEED003_OUTER_KP_1_S),
            outer_kd=(SEED003_OUTER_KD, SEED003_OUTER_KD, SEED003_OUTER_KD),
            inner_kp_Nms=(SEED003_INNER_KP_NMS, SEED003_INNER_KP_NMS, SEED003_INNER_KP_NMS),
            max_rate_rad_s=max_rate_rad_s,
        )


@dataclass(frozen=True)
class CascadeLqrDesign:
    """LQR weights and inner gains from which the outer gains are computed for an inertia.

    Attributes:
        inner_kp_Nms: LPC rate gains (x, y, z) [N m s/rad], each > 0.
        q_angle: weight on the angle error [1/rad²], > 0.
        q_rate: weight on the rate error [s²/rad²], ≥ 0.
        r: weight on the rate command [s²/rad²], > 0.
        max_rate_rad_s: slew rate the clipped proportional term settles at [rad/s] (inf: none).
    """

    inner_kp_Nms: Triple
    q_angle: float
    q_rate: float
    r: float
    max_rate_rad_s: float = math.inf

    def __post_init__(self) -> None:
        src = "CascadeLqrDesign"
        inner = check.triple(src, "inner_kp_Nms", self.inner_kp_Nms, 0.0, lo_open=True)
        object.__setattr__(self, "inner_kp_Nms", inner)
        for key, strict in (("q_angle", True), ("q_rate", False), ("r", True)):
            value = check.number(src, key, getattr(self, key), 0.0, lo_open=strict)
            object.__setattr__(self, key, value)
        check.limit(src, "max_rate_rad_s", self.max_rate_rad_s, unit="rad/s")

    def params(self, inertia_diag_kgm2: Sequence[float]) -> CascadeLqrParams:
        """The LQR gains of each axis for principal moments ``inertia_diag_kgm2`` [kg m²]."""
        inertia = check.triple("CascadeLqrDesign", "inertia_diag_kgm2", inertia_diag_kgm2, 0.0,
                               lo_open=True)
        q = np.diag([self.q_angle, self.q_rate])
        r = np.array([[self.r]])
        gains = [
            lqr_gains(*outer_loop_model(j, ki), q, r)[0][0]
            for j, ki in zip(inertia, self.inner_kp_Nms, strict=True)
        ]
        return CascadeLqrParams(
            outer_kp_1_s=(float(gains[0][0]), float(gains[1][0]), float(gains[2][0])),
            outer_kd=(float(gains[0][1]), float(gains[1][1]), float(gains[2][1])),
            inner_kp_Nms=self.inner_kp_Nms,
            max_rate_rad_s=self.max_rate_rad_s,
        )


class CascadeLqr:
    """Cascade QPDLQR + LPC controller (``AttitudeController``, ``InertiaAware``); stateless.

    Built from fixed gains (e.g. Table 1) the law does not depend on the inertia and
    :meth:`set_inertia_B_kgm2` keeps them; built with :meth:`from_design` it re-solves the
    LQR for the new principal moments (the diagonal of J).
    """

    def __init__(self, params: CascadeLqrParams, design: CascadeLqrDesign | None = None) -> None:
        self._design = design
        self._set_params(params)

    @classmethod
    def from_design(cls, design: CascadeLqrDesign, inertia_B_kgm2: np.ndarray) -> CascadeLqr:
        """Gains from the LQR design for the principal moments of ``inertia_B_kgm2``."""
        return cls(design.params(_principal_moments(inertia_B_kgm2)), design)

    def _set_params(self, params: CascadeLqrParams) -> None:
        self._params = params
        self._kp = np.array(params.outer_kp_1_s)
        self._kd = np.array(params.outer_kd)
        self._ki = np.array(params.inner_kp_Nms)
        self._error_limit = error_limit(self._kp, 1.0 + self._kd, params.max_rate_rad_s)

    @property
    def params(self) -> CascadeLqrParams:
        """The gains in use."""
        return self._params

    def set_inertia_B_kgm2(self, inertia_B_kgm2: np.ndarray) -> None:
        """Redesign for ``inertia_B_kgm2`` (3×3) if built from a design; fixed gains stay."""
        if self._design is not None:
            self._set_params(self._design.params(_principal_moments(inertia_B_kgm2)))

    def rate_command_B_rad_s(
        self, q_BN: np.ndarray, omega_BN_B: np.ndarray, q_RN: np.ndarray, omega_RN_B: np.ndarray
    ) -> np.ndarray:
        """The outer loop's body-rate command ``ω_RN_B + Δω_cmd`` [rad/s]."""
        dq = error_quaternion(q_RN, q_BN)
        sign = -1.0 if dq[0] < 0.0 else 1.0
        angle_error = ANGLE_PER_QUATERNION_VECTOR * sign * dq[1:]
        omega_ref = np.asarray(omega_RN_B, dtype=float)
        rate_error = np.asarray(omega_BN_B, dtype=float) - omega_ref
        limited = np.clip(angle_error, -self._error_limit, self._error_limit)
        return omega_ref - self._kp * limited - self._kd * rate_error

    def torque_B_Nm(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
        domega_RN_B: np.ndarray | None = None,
    ) -> np.ndarray:
        """``τ_B = k_i ∘ (ω_cmd − ω_BN_B)`` [N m] (module docstring)."""
        command = self.rate_command_B_rad_s(q_BN, omega_BN_B, q_RN, omega_RN_B)
        return np.asarray(self._ki * (command - np.asarray(omega_BN_B, dtype=float)))
