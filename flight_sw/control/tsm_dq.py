"""Dual-quaternion terminal sliding-mode (TSM) 6-DoF pose control: seed 000's baseline.

What it does: the conventional TSM law the paper compares its NFTSM law with, on the same
error state, nominal model and reaching law as :mod:`flight_sw.control.nftsm_dq`, but the
dual terminal sliding surface of eq. (12),
    ``Ŝ = ξ̂̇ + b̂ ⊙ sig(ξ̂)^α``,
whose derivative holds the negative power ``α |ξ|^(α−1) ξ̇`` (singular at ``ξ = 0`` with
``ξ̇ ≠ 0``). The law is the NFTSM structure of eq. (17) with ``α̂1 = 0`` and the auxiliary
term replaced by the TSM one (the paper builds it "as the similar structure in [15]"):
    ``û_c = M̂0 ω̂̇* − F̂ − K̂ ⊙ tanh(Ŝ/w)``,
    ``ω̂̇* = −Θ̂⁻¹ [Θ̂̇ ω̂_e + α b̂ ⊙ |ξ̂|^(α−1) ⊙ ξ̂̇ + α̂3 ⊙ sig(Ŝ)^p2]``.
On the sliding surface ``ξ̇ = −b sig(ξ)^α``: finite-time but, without the linear term of
the NFTSM surface, slow far from the target (seed 000: position converges in 78 s, against
22 s for NFTSM).

Singularity guard: ``|ξ_i|`` is floored at ``XI_FLOOR`` in the negative power, so the
output stays finite (large) where the paper's TSM law is undefined.

Inputs/outputs, frames, orbit terms, dual-slot convention, output limits, anti-unwinding
option: as :mod:`flight_sw.control.nftsm_dq` (``PoseController``, ``InertiaAware``); the
error state, kinematics, drift and wrench assembly are
:mod:`flight_sw.control.dq_error_state`'s, on floats (the tests hold the law to the
paper's terms composed as arrays, ``tests/flight_sw/control/dq_reference.py``).

Source: seed 000, eq. (12), Section V (α = 0.67, b̂ = 0.05 + ϵ 0.1, with the NFTSM reaching
gains α̂3, K̂, p2 and the nominal model, as the paper's reference [15] is not given);
Feng, Yu & Man 2002, "Non-singular terminal sliding mode control of rigid manipulators",
Automatica 38(12) 2159–2167 (the singularity of the TSM law).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from flight_sw import vec3
from flight_sw.control import dq_error_state as es
from flight_sw.control.dq_error_state import MU_EARTH_M3_S2
from flight_sw.control.nftsm_dq import sig_vec
from flight_sw.control.nftsm_dq_params import (
    DEFAULT_ANTI_UNWINDING_MU,
    DEFAULT_SWITCHING_WIDTH,
    N_AXES,
    validate_inertia,
    validate_orbit,
)

# Floor of |ξ_i| in the negative power α |ξ|^(α−1) of the TSM surface derivative.
XI_FLOOR = 1e-9

_SOURCE = "TsmDqParams"


@dataclass(frozen=True)
class TsmDqParams:
    """Gains and nominal model of the TSM law; defaults are seed 000, Section V.

    Attributes: ``b_att``, ``b_pos`` the b̂ of eq. (12) [1/s]; ``alpha`` its exponent in
    (0.5, 1) (``ξ̇ α|ξ|^(α−1)`` stays finite on the surface only for α > 0.5); the rest as
    :class:`flight_sw.control.nftsm_dq.NftsmDqParams`.
    """

    mass_kg: float = 100.0
    inertia_B_kgm2: tuple[float, float, float] = (18.0, 18.0, 24.0)
    b_att: tuple[float, float, float] = (0.05, 0.05, 0.05)
    b_pos: tuple[float, float, float] = (0.1, 0.1, 0.1)
    alpha: float = 0.67
    alpha3_att: tuple[float, float, float] = (2.0, 2.0, 2.0)
    alpha3_pos: tuple[float, float, float] = (2.0, 2.0, 2.0)
    k_att_Nm: tuple[float, float, float] = (20.0, 20.0, 20.0)
    k_pos_N: tuple[float, float, float] = (20.0, 20.0, 20.0)
    p2: float = 0.67
    switching_width: float = DEFAULT_SWITCHING_WIDTH
    mean_motion_rad_s: float = 0.0
    mu_m3_s2: float = MU_EARTH_M3_S2
    anti_unwinding: bool = False
    anti_unwinding_mu: float = DEFAULT_ANTI_UNWINDING_MU
    max_force_N: float = math.inf
    max_torque_Nm: float = math.inf

    def __post_init__(self) -> None:
        s = _SOURCE
        check.positive(s, "mass_kg", self.mass_kg, unit="kg")
        for key in (
            "inertia_B_kgm2",
            "b_att",
            "b_pos",
            "alpha3_att",
            "alpha3_pos",
            "k_att_Nm",
            "k_pos_N",
        ):
            object.__setattr__(self, key, check.triple(s, key, getattr(self, key), 0.0,
                                                        lo_open=True))
        check.number(s, "alpha", self.alpha, 0.5, 1.0, lo_open=True, hi_open=True)
        check.number(s, "p2", self.p2, 0.0, 1.0, lo_open=True, hi_open=True)
        for key in ("switching_width", "anti_unwinding_mu"):
            check.positive(s, key, getattr(self, key))
        validate_orbit(s, self.mean_motion_rad_s, self.mu_m3_s2)
        check.flag(s, "anti_unwinding", self.anti_unwinding)
        check.limit(s, "max_force_N", self.max_force_N, unit="N")
        check.limit(s, "max_torque_Nm", self.max_torque_Nm, unit="N m")


class TsmDq:
    """Dual-quaternion TSM pose controller (implements ``PoseController``, ``InertiaAware``)."""

    def __init__(self, params: TsmDqParams) -> None:
        self._params = params
        self._inertia = validate_inertia(params.inertia_B_kgm2)
        p = params
        self._b = [float(x) for x in p.b_att + p.b_pos]
        self._alpha3 = [float(x) for x in p.alpha3_att + p.alpha3_pos]
        self._k_att = [float(x) for x in p.k_att_Nm]
        self._k_pos = [float(x) for x in p.k_pos_N]
        self._inertia_f = vec3.mat3(self._inertia)

    @property
    def params(self) -> TsmDqParams:
        """The gains this controller was built with."""
        return self._params

    @property
    def inertia_B_kgm2(self) -> np.ndarray:
        """The nominal inertia in use (3×3) [kg m²]."""
        return self._inertia.copy()

    def set_inertia_B_kgm2(self, inertia_B_kgm2: np.ndarray) -> None:
        """Use ``inertia_B_kgm2`` (3×3 SPD, or 3 principal moments) [kg m²] from now on."""
        self._inertia = validate_inertia(inertia_B_kgm2)
        self._inertia_f = vec3.mat3(self._inertia)

    def _surface(self, xi: list[float], xi_dot: list[float]) -> list[float]:
        """``Ŝ = ξ̂̇ + b̂ ⊙ sig(ξ̂)^α`` (eq. 12)."""
        sa = sig_vec(xi, self._params.alpha)
        return [xi_dot[i] + self._b[i] * sa[i] for i in range(6)]

    def surface(self, xi: np.ndarray, xi_dot: np.ndarray) -> np.ndarray:
        """``Ŝ = ξ̂̇ + b̂ ⊙ sig(ξ̂)^α`` (eq. 12), (6,)."""
        return np.array(self._surface(np.asarray(xi, dtype=float).tolist(),
                                      np.asarray(xi_dot, dtype=float).tolist()))

    def wrench_B(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        r_N_m: np.ndarray,
        v_N_m_s: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
        r_ref_N_m: np.ndarray,
        v_ref_N_m_s: np.ndarray,
    ) -> np.ndarray:
        """The TSM law: the demanded wrench [force_B_N; torque_B_Nm], shape (6,).

        ``ω̂̇* = −Θ̂⁻¹ [Θ̂̇ ω̂_e + α b̂ ⊙ |ξ̂|^(α−1) ⊙ ξ̂̇ + α̂3 ⊙ sig(Ŝ)^p2]`` (|ξ̂| floored at
        :data:`XI_FLOOR`), then law (17)'s wrench
        (:func:`flight_sw.control.dq_error_state.wrench`).
        """
        p = self._params
        st = es.error_state(q_BN, omega_BN_B, r_N_m, v_N_m_s, q_RN, omega_RN_B, r_ref_N_m,
                            v_ref_N_m_s, p.mean_motion_rad_s, p.mu_m3_s2, p.anti_unwinding,
                            p.anti_unwinding_mu)
        xi, xi_dot = st.xi, st.xi_dot
        s = self._surface(xi, xi_dot)
        sp = sig_vec(s, p.p2)
        tdot_nu = es.theta_dot_nu(st)
        b, a3, alpha = self._b, self._alpha3, p.alpha
        br = [tdot_nu[i] + alpha * b[i] * max(abs(xi[i]), XI_FLOOR) ** (alpha - 1.0) * xi_dot[i]
              + a3[i] * sp[i] for i in range(6)]
        acc_w, acc_v = es.acceleration(st, br)
        return es.wrench(st, p.mass_kg, self._inertia_f, acc_w, acc_v, s, self._k_att,
                         self._k_pos, p.switching_width, p.max_force_N, p.max_torque_Nm)


__all__ = ["N_AXES", "XI_FLOOR", "TsmDq", "TsmDqParams"]
