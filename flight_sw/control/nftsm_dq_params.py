"""Gains and nominal model of the dual-quaternion NFTSM pose law (seed 000, Section V).

What it does: :class:`NftsmDqParams`, the frozen, self-validating parameters of
:class:`flight_sw.control.nftsm_dq.NftsmDq` (defaults: seed 000's Section V), and the two
validators the TSM baseline (:mod:`flight_sw.control.tsm_dq`) shares: the leader's orbit
(mean motion [rad/s] ≥ 0, µ [m³/s²] > 0) and the nominal inertia (3×3 symmetric positive
definite, or 3 principal moments [kg m²]).

Units are in the field names; gains per body axis (``_att``: attitude, the real part of
the dual surfaces; ``_pos``: position, the dual part). Errors: ConfigError naming the
dataclass, field and value (:mod:`dbc.validation`).

Source: seed 000, eqs. (13)–(17), (25)–(26), Section V (p1 = 0.6, p2 = 0.67,
δ̂ = 0.05 + ϵ 0.001, K̂ = 20 + ϵ 20, α̂1 = α̂2 = 0.05 + ϵ 0.1, α̂3 = 2 + ϵ 2, m0 = 100 kg,
J0 = diag(18, 18, 24) kg m²).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from flight_sw.control.dq_error_state import MU_EARTH_M3_S2

N_AXES = 3
# Default width w of tanh(S/w) replacing sgn(S) (the paper gives no value).
DEFAULT_SWITCHING_WIDTH = 0.05
# Default µ of the anti-unwinding error vector (the paper gives no value); with it Θ_r is
# singular at 103.1° (0.1: 99.1°, beyond the paper's initial 102.7°, which then diverges).
DEFAULT_ANTI_UNWINDING_MU = 0.01

_SOURCE = "NftsmDqParams"


def validate_orbit(source: str, mean_motion_rad_s: object, mu_m3_s2: object) -> None:
    """Validate the mean motion (finite, ≥ 0) [rad/s] and µ (finite, > 0) [m³/s²]."""
    check.non_negative(source, "mean_motion_rad_s", mean_motion_rad_s, unit="rad/s")
    check.positive(source, "mu_m3_s2", mu_m3_s2, unit="m^3/s^2")


def validate_inertia(inertia: object) -> np.ndarray:
    """A 3×3 symmetric positive-definite inertia [kg m²] (or 3 principal moments)."""
    return check.inertia("PoseController", "inertia_B_kgm2", inertia)


@dataclass(frozen=True)
class NftsmDqParams:
    """Gains and nominal model of the NFTSM law; defaults are seed 000, Section V.

    Attributes (``_att``: real part, attitude, 3 body axes; ``_pos``: dual part, position):
        mass_kg: nominal mass m0 [kg] (> 0).
        inertia_B_kgm2: nominal principal moments J0 [kg m²] (3 numbers > 0).
        alpha1_att, alpha1_pos: α̂1 of eq. (13) [1/s].
        alpha2_att, alpha2_pos: α̂2 of eq. (13) [1/s].
        alpha3_att, alpha3_pos: α̂3 of eq. (17) (reaching gain).
        k_att_Nm: K, torque gain of the attitude surface [N m]; k_pos_N: K′ [N].
        p1: exponent of the auxiliary surface, in (0.5, 1); p2: reaching exponent, (0, 1).
        delta_att, delta_pos: δ, δ′ switching thresholds of eqs. (14)–(15) (> 0).
        switching_width: w of tanh(S/w) replacing sgn(S) (> 0).
        mean_motion_rad_s: n of the leader's circular orbit (0: N inertial, no gravity).
        mu_m3_s2: gravitational parameter [m³/s²].
        anti_unwinding: use e_r of eq. (26) as the attitude state.
        anti_unwinding_mu: µ of eqs. (25)–(26) (> 0).
        max_force_N, max_torque_Nm: optional output norm limits (inf: unbounded).
    """

    mass_kg: float = 100.0
    inertia_B_kgm2: tuple[float, float, float] = (18.0, 18.0, 24.0)
    alpha1_att: tuple[float, float, float] = (0.05, 0.05, 0.05)
    alpha1_pos: tuple[float, float, float] = (0.1, 0.1, 0.1)
    alpha2_att: tuple[float, float, float] = (0.05, 0.05, 0.05)
    alpha2_pos: tuple[float, float, float] = (0.1, 0.1, 0.1)
    alpha3_att: tuple[float, float, float] = (2.0, 2.0, 2.0)
    alpha3_pos: tuple[float, float, float] = (2.0, 2.0, 2.0)
    k_att_Nm: tuple[float, float, float] = (20.0, 20.0, 20.0)
    k_pos_N: tuple[float, float, float] = (20.0, 20.0, 20.0)
    p1: float = 0.6
    p2: float = 0.67
    delta_att: float = 0.05
    delta_pos: float = 0.001
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
            "alpha1_att",
            "alpha1_pos",
            "alpha2_att",
            "alpha2_pos",
            "alpha3_att",
            "alpha3_pos",
            "k_att_Nm",
            "k_pos_N",
        ):
            object.__setattr__(self, key, check.triple(s, key, getattr(self, key), 0.0,
                                                        lo_open=True))
        check.number(s, "p1", self.p1, 0.5, 1.0, lo_open=True, hi_open=True)
        check.number(s, "p2", self.p2, 0.0, 1.0, lo_open=True, hi_open=True)
        for key in ("delta_att", "delta_pos", "switching_width", "anti_unwinding_mu"):
            check.positive(s, key, getattr(self, key))
        validate_orbit(s, self.mean_motion_rad_s, self.mu_m3_s2)
        check.flag(s, "anti_unwinding", self.anti_unwinding)
        check.limit(s, "max_force_N", self.max_force_N, unit="N")
        check.limit(s, "max_torque_Nm", self.max_torque_Nm, unit="N m")
