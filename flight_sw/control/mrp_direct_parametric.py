"""MRP attitude tracking by Duan's direct parametric PD design (seed 001, section 3).

What it does: a PD law on the MRP attitude error with gains chosen so that the closed-loop
error dynamics are linear, constant and similar to a chosen Hurwitz matrix ``F0`` (6×6).

Error variables: ``ε = σ_BR`` the MRP of the error quaternion ``q_BR = q_RN* ⊗ q_BN``
(shadow set, ``|ε| ≤ 1``: the short way) and ``ε̇ = F(ε) ω_e`` with the rate error
``ω_e = ω_BN_B − ω_RN_B`` (:mod:`flight_sw.mrp`). With ``G = F⁻¹``, Euler's equation
``J ω̇ = τ − ω × Jω`` and ``d/dt(ω_RN_B) = ω̇_RN_B − ω_e × ω_RN_B`` (``ω̇_RN_B`` =
``domega_RN_B``) become the Lagrange form of seed 001 eq. (3)/(7),
    ``H(ε) ε̈ + C(ε, ε̇) ε̇ = Gᵀ (τ − n)``,  ``H = GᵀJG``,  ``C = −GᵀJG Ḟ G``,
    ``n = ω × Jω + J ω̇_RN_B − J (ω_e × ω_RN_B)`` (gyroscopic and reference feed-forward).
Control (seed 001 section 3, ``T = u_c + u_f``, external signal ``v_c = 0``):
    ``τ_B = n + Fᵀ(ε) (K0 ε + K1 ε̇)``,  ``[K0 K1] = W V⁻¹`` (eq. (10)),
    ``V = [Z; Z F0]`` (eq. (9)),  ``W = H Z F0² + C Z F0`` (eq. (11)),
with ``Z`` (3×6) a free parameter, ``det V ≠ 0`` (eq. (12)). The closed loop is then
``Ẋ = V F0 V⁻¹ X`` for ``X = [ε; ε̇]`` (Proposition 1), so ``V⁻¹X(t) = e^{F0 t} V⁻¹X(0)``
exactly for the modelled rigid body, at any error size (until a shadow switch at 180°).

Inputs/outputs: see :class:`flight_sw.control.base.AttitudeController`; torque [N m];
inertia ``J`` [kg m²] (3×3, body axes, about the centre of mass); ``F0`` [1/s] and ``Z``
dimensionless. ``domega_RN_B = None`` is taken as zero.

Cases of seed 001 section 5 (:meth:`MrpDirectParametricParams.from_case`):
``E = blockdiag([[−1, 1], [−1, −1]], −3, −4, −5, −6)``, ``Z = [I3 I3]`` and ``F0 = E``
(case 1), ``0.5 E`` (case 2), ``2 E`` (case 3).

Deviation from the seed (stated): the seed writes the error as the difference
``ε = σ − σ_d`` of the body and reference MRPs (eq. (4)) and moves the reference into
``u_f``. Here the error is the relative MRP ``σ_BR`` (identical when R = N, i.e. for
regulation), which needs no reference MRP near the shadow boundary and keeps ``q`` and
``−q`` equivalent; the reference motion enters through ``n``. The gravity-gradient term
``g`` of eq. (3) is omitted (a disturbance here: no orbit model in this law).

Assumptions: rigid body, exact ``J`` for the exact closed loop (``set_inertia_B_kgm2``
takes an identified one); unit quaternions; rates measured; no actuator limits.

Sources: seed 001 (Attitude control and structure robust control allocation for combined
spacecraft), eq. (1)–(12), Proposition 1, section 5 cases 1–3; Duan 2014, "Satellite
attitude control — a direct parametric approach" (the method of seed 001's ref. [13]).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import block_diag

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw import mrp
from flight_sw.quaternion import error_quaternion
from flight_sw.vec3 import Vec3, cross, mat3, mat_t_vec, mat_vec, vec3

N_AXES = 3
N_STATES = 2 * N_AXES
# Seed 001 section 5: E = blockdiag([[−1, 1], [−1, −1]], −3, −4, −5, −6) [1/s].
SEED001_E_OSCILLATORY_BLOCK = ((-1.0, 1.0), (-1.0, -1.0))
SEED001_E_REAL_EIGENVALUES = (-3.0, -4.0, -5.0, -6.0)
# F0 = scale · E for cases 1, 2, 3.
SEED001_CASE_F0_SCALE = {1: 1.0, 2: 0.5, 3: 2.0}
# V = [Z; Z F0] is rejected as singular above this condition number.
MAX_V_CONDITION = 1e10

_SOURCE = "MrpDirectParametricParams"

Matrix = tuple[tuple[float, ...], ...]


def _as_tuple(arr: np.ndarray) -> Matrix:
    return tuple(tuple(float(x) for x in row) for row in arr)


def seed001_e() -> np.ndarray:
    """The matrix E of seed 001 section 5 (6×6, eigenvalues −1 ± i, −3, −4, −5, −6)."""
    return np.asarray(
        block_diag(np.array(SEED001_E_OSCILLATORY_BLOCK), *SEED001_E_REAL_EIGENVALUES),
        dtype=float,
    )


@dataclass(frozen=True)
class MrpDirectParametricParams:
    """The design of the direct parametric law.

    Attributes:
        f0: the desired closed-loop matrix F0 (6×6) [1/s], Hurwitz.
        z: the free parameter Z (3×6), with ``V = [Z; Z F0]`` nonsingular (eq. (12)).
    """

    f0: Matrix
    z: Matrix

    def __post_init__(self) -> None:
        f0 = check.matrix(_SOURCE, "f0", self.f0, N_STATES, N_STATES)
        z = check.matrix(_SOURCE, "z", self.z, N_AXES, N_STATES)
        if not float(np.max(np.linalg.eigvals(f0).real)) < 0.0:
            raise ConfigError(_SOURCE, "f0", self.f0, "a Hurwitz matrix (eigenvalues Re < 0)")
        v = np.vstack((z, z @ f0))
        if not float(np.linalg.cond(v)) < MAX_V_CONDITION:
            raise ConfigError(_SOURCE, "z", self.z, "Z with [Z; Z F0] nonsingular (eq. (12))")
        object.__setattr__(self, "f0", _as_tuple(f0))
        object.__setattr__(self, "z", _as_tuple(z))

    @classmethod
    def from_case(cls, case: int) -> MrpDirectParametricParams:
        """Case 1, 2 or 3 of seed 001 section 5: ``F0 = E, 0.5 E, 2 E``, ``Z = [I3 I3]``."""
        if isinstance(case, bool) or case not in SEED001_CASE_F0_SCALE:
            raise ConfigError(_SOURCE, "case", case, "1, 2 or 3 (seed 001 section 5)")
        f0 = SEED001_CASE_F0_SCALE[case] * seed001_e()
        z = np.hstack((np.eye(N_AXES), np.eye(N_AXES)))
        return cls(f0=_as_tuple(f0), z=_as_tuple(z))

    def v_matrix(self) -> np.ndarray:
        """``V = [Z; Z F0]`` (eq. (9)), 6×6."""
        z = np.array(self.z)
        return np.vstack((z, z @ np.array(self.f0)))

    def closed_loop_matrix(self) -> np.ndarray:
        """``V F0 V⁻¹``: the constant closed-loop matrix of ``X = [ε; ε̇]`` (Proposition 1)."""
        v = self.v_matrix()
        return np.asarray(v @ np.array(self.f0) @ np.linalg.inv(v))


class MrpDirectParametric:
    """Direct parametric MRP tracking law (implements ``AttitudeController``, ``InertiaAware``)."""

    def __init__(self, params: MrpDirectParametricParams, inertia_B_kgm2: np.ndarray) -> None:
        self._params = params
        f0 = np.array(params.f0)
        z = np.array(params.z)
        v_inv = np.linalg.inv(params.v_matrix())
        # K0 ε + K1 ε̇ = H (Z F0² V⁻¹ X) + C (Z F0 V⁻¹ X), from eq. (10)–(11).
        self._zf0sq_vinv_t = tuple((z @ f0 @ f0 @ v_inv).reshape(-1).tolist())
        self._zf0_vinv_t = tuple((z @ f0 @ v_inv).reshape(-1).tolist())
        self._inertia = check.inertia("MrpDirectParametric", "inertia_B_kgm2", inertia_B_kgm2)
        self._j = mat3(self._inertia)

    @property
    def params(self) -> MrpDirectParametricParams:
        """The design this controller was built with."""
        return self._params

    @property
    def inertia_B_kgm2(self) -> np.ndarray:
        """The inertia model in use [kg m²] (a copy)."""
        return self._inertia.copy()

    def set_inertia_B_kgm2(self, inertia_B_kgm2: np.ndarray) -> None:
        """Use ``inertia_B_kgm2`` (3×3, symmetric positive definite) from now on."""
        self._inertia = check.inertia("MrpDirectParametric", "inertia_B_kgm2", inertia_B_kgm2)
        self._j = mat3(self._inertia)

    def torque_B_Nm(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
        domega_RN_B: np.ndarray | None = None,
    ) -> np.ndarray:
        """``τ_B = n + Fᵀ(ε)(K0 ε + K1 ε̇)`` [N m] (module docstring), on floats: with
        ``H = GᵀJG`` and ``C = −H Ḟ G``, ``K0 ε + K1 ε̇ = H (a − Ḟ G b)`` for
        ``a = Z F0² V⁻¹ X`` and ``b = Z F0 V⁻¹ X``."""
        j = self._j
        w = vec3(omega_BN_B)
        wr = vec3(omega_RN_B)
        we = (w[0] - wr[0], w[1] - wr[1], w[2] - wr[2])
        q0, q1, q2, q3 = error_quaternion(q_RN, q_BN).tolist()
        e0, e1, e2 = mrp.from_quaternion_f(q0, q1, q2, q3)
        f = mrp.kinematics(e0, e1, e2)
        ed = mat_vec(f, we[0], we[1], we[2])
        g_scale = mrp.inverse_factor(e0 * e0 + e1 * e1 + e2 * e2)
        x = (e0, e1, e2, ed[0], ed[1], ed[2])
        a = _times6(self._zf0sq_vinv_t, x)
        b = _times6(self._zf0_vinv_t, x)
        gb = mat_t_vec(f, g_scale * b[0], g_scale * b[1], g_scale * b[2])  # G = s Fᵀ
        fdot_gb = mat_vec(mrp.kinematics_rate((e0, e1, e2), ed), gb[0], gb[1], gb[2])
        u = (a[0] - fdot_gb[0], a[1] - fdot_gb[1], a[2] - fdot_gb[2])
        gu = mat_t_vec(f, g_scale * u[0], g_scale * u[1], g_scale * u[2])
        jgu = mat_vec(j, gu[0], gu[1], gu[2])
        hu = mat_vec(f, g_scale * jgu[0], g_scale * jgu[1], g_scale * jgu[2])  # Gᵀ = s F
        jw = mat_vec(j, w[0], w[1], w[2])
        gyro = cross(w, jw)
        jx = mat_vec(j, *cross(we, wr))
        n = [gyro[0] - jx[0], gyro[1] - jx[1], gyro[2] - jx[2]]
        if domega_RN_B is not None:
            jd = mat_vec(j, *vec3(domega_RN_B))
            n = [n[0] + jd[0], n[1] + jd[1], n[2] + jd[2]]
        ft = mat_t_vec(f, hu[0], hu[1], hu[2])
        return np.array((n[0] + ft[0], n[1] + ft[1], n[2] + ft[2]))


def _times6(m: tuple[float, ...], x: tuple[float, ...]) -> Vec3:
    """A 3×6 row-major matrix times a 6-vector."""
    out = [0.0, 0.0, 0.0]
    for i in range(N_AXES):
        row = m[N_STATES * i:N_STATES * (i + 1)]
        acc = 0.0  # left to right (sum() of floats is compensated from Python 3.12)
        for r, v in zip(row, x, strict=True):
            acc += r * v
        out[i] = acc
    return (out[0], out[1], out[2])
