"""Intentional disturbances of Steps B and C, planned as a least-spin linear program.

What it does: in single spin (axis III along the target z, spin rate ``Ω = ω_III``),
plans the three thrusts over one spin turn, held over blocks of control periods, that
change the stopping velocity ``V_s = v_z − κ ω_III`` (eq. 21) by a requested ``ΔV_s`` and
leave the body, to first order, back in single spin:
- transverse body rates zero at the end (Euler's equations linearised about the spin:
  ``J_I ṗ = (J_II − J_III) Ω q + T_I``, ``J_II q̇ = (J_III − J_I) Ω p + T_II``; the
  nutation's transition matrix, exact for a torque held over each block);
- the inertial transverse angular momentum unchanged (``Ḣ_N = C_NB T``, the body turned by
  ``ψ = ψ_0 + Ω t``), so axis III ends along z again;
- the inertial x–y velocity unchanged (what seed 004's supplemental sequence, eq. 54,
  minimises);
- ``ΔV_s = Σ (D_III − κ m / J_III · M_III) f h / m``: the z force that comes with the
  transverse torques (eq. 9), which is what moves V_s off the manifold (eq. 22);
minimising what it does to the spin, ``Δω_III = Σ M_III f h / J_III`` (condition (ii):
every firing raises ω_III, so it slows the negative spin Step A gives), with
``0 ≤ f ≤ f_max`` (push-only; ``f_max`` = None for ideal thrusters). scipy's HiGHS
(``linprog``: a well-kept LP solver) solves it in milliseconds.

Seed 004 shapes its disturbances (eqs. 24–26, 36–38: a transverse-rate excursion in the
second or fourth quadrant, scaled by 1/ω_III, constants set by simulation for its body);
this plans the same kind of excursion on line, for any body that passes the
configuration check. Second-order effects (the gyroscopic ``(J_I − J_II) p q`` term,
tilt × thrust) are left to Step A's return and to the next sequence, as the paper
repeats its sequences.

In: Ω [rad/s], the spin angle ψ_0 in the target frame [rad], ΔV_s [m/s]. Out: a
:class:`Kick` (thrusts per block [N], block length [s], predicted ΔV_s and spin change).
Source: seed 004 §3.3 (eqs. 21–27), §3.4 (eqs. 36–38), §3.6 (eq. 54).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm
from scipy.optimize import linprog

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw.control.underactuated.geometry import ThreeThrusters

_SOURCE = "[flight_sw.pose] disturbance"
TWO_PI = 2.0 * math.pi
N_END_ROWS = 7  # body rates (2), inertial transverse momentum (2), ΔV_s (1), x–y velocity (2)
ROW_DV_STOP = 4


@dataclass(frozen=True)
class DisturbanceParams:
    """Block length [control periods], horizon [spin turns], largest ΔV_s per kick [m/s],
    thrust limit [N] (None: ideal thrusters, unbounded)."""

    block_periods: int = 5
    horizon_turns: float = 1.0
    max_dv_stop_m_s: float = 0.04
    max_thrust_N: float | None = None

    def __post_init__(self) -> None:
        check.integer(_SOURCE, "block_periods", self.block_periods, lo=1)
        check.positive(_SOURCE, "horizon_turns", self.horizon_turns)
        check.positive(_SOURCE, "max_dv_stop_m_s", self.max_dv_stop_m_s)
        if self.max_thrust_N is not None:
            check.positive(_SOURCE, "max_thrust_N", self.max_thrust_N)


@dataclass(frozen=True)
class Kick:
    """A planned disturbance: ``thrusts_N[k]`` held over block k of ``block_s``."""

    thrusts_N: np.ndarray
    block_s: float
    dv_stop_m_s: float
    domega_III_rad_s: float
    dv_stop_blocks_m_s: np.ndarray  # each block's share of dv_stop_m_s (first order)

    @property
    def duration_s(self) -> float:
        """The whole kick [s]."""
        return float(len(self.thrusts_N)) * self.block_s

    def z_stop_shift_m(self, v_stop_m_s: float) -> float:
        """How far the stopping position Z moves over the kick, from a stopping velocity
        ``v_stop_m_s`` before it (first order: Ż = V_s, each block's change held to the
        end) [m]."""
        n = len(self.dv_stop_blocks_m_s)
        left_s = (n - np.arange(n) - 0.5) * self.block_s
        return v_stop_m_s * self.duration_s + float(self.dv_stop_blocks_m_s @ left_s)

    def thrusts_at(self, t_s: float) -> np.ndarray:
        """The thrusts ``t_s`` after the kick started (zero after its end) [N]."""
        k = int(t_s / self.block_s)
        if t_s < 0.0 or k >= len(self.thrusts_N):
            return np.zeros(3)
        return self.thrusts_N[k]


def end_rows(thr: ThreeThrusters, omega_III_rad_s: float, psi0_rad: float, block_s: float,
             n_blocks: int) -> np.ndarray:
    """The linear map from the thrusts of each block (3·n, block-major) to the end state
    (:data:`N_END_ROWS` rows, module docstring): the first-order model the plan uses."""
    j = np.asarray(thr.inertia_diag_kgm2, dtype=float)
    w = omega_III_rad_s
    a = np.array([[0.0, (j[1] - j[2]) * w / j[0]], [(j[2] - j[0]) * w / j[1], 0.0]])
    aug = np.zeros((4, 4))
    aug[:2, :2] = a * block_s
    aug[:2, 2:] = np.diag(1.0 / j[:2]) * block_s
    e = expm(aug)  # [[Φ, Γ], [0, I]]: one block of the nutation with a held torque
    phi, gam = e[:2, :2], e[:2, 2:]
    m_t, d_f = np.asarray(thr.torque_B, dtype=float), np.asarray(thr.force_B, dtype=float)
    mass = thr.mass_kg
    dv_row = (d_f[2] - thr.kappa_m_s_per_rad_s * mass / j[2] * m_t[2]) * block_s / mass
    out = np.zeros((N_END_ROWS, 3 * n_blocks))
    to_end = np.eye(2)  # Φ^(n-1-k), built from the last block backwards
    for k in range(n_blocks - 1, -1, -1):
        psi = psi0_rad + w * (k + 0.5) * block_s
        c, s = math.cos(psi), math.sin(psi)
        rot = np.array([[c, -s], [s, c]])
        cols = slice(3 * k, 3 * k + 3)
        out[0:2, cols] = to_end @ gam @ m_t[:2]
        out[2:4, cols] = rot @ m_t[:2] * block_s
        out[ROW_DV_STOP, cols] = dv_row
        out[5:7, cols] = rot @ d_f[:2] * block_s / mass
        to_end = to_end @ phi
    return out


def plan_kick(thr: ThreeThrusters, params: DisturbanceParams, period_s: float,
              omega_III_rad_s: float, psi0_rad: float, dv_stop_m_s: float) -> Kick:
    """The least-spin kick that changes V_s by ``dv_stop_m_s`` (clipped to the params'
    largest), from single spin at ``omega_III_rad_s`` and spin angle ``psi0_rad``."""
    if omega_III_rad_s == 0.0:
        raise ConfigError(_SOURCE, "omega_III_rad_s", omega_III_rad_s, "a spin (≠ 0)")
    p = params
    block_s = p.block_periods * period_s
    n = max(1, round(p.horizon_turns * TWO_PI / abs(omega_III_rad_s) / block_s))
    target = max(-p.max_dv_stop_m_s, min(p.max_dv_stop_m_s, dv_stop_m_s))
    a_eq = end_rows(thr, omega_III_rad_s, psi0_rad, block_s, n)
    b_eq = np.zeros(N_END_ROWS)
    b_eq[ROW_DV_STOP] = target
    m3 = np.asarray(thr.torque_B, dtype=float)[2]
    j3 = float(thr.inertia_diag_kgm2[2])
    cost = np.tile(m3, n) * block_s / j3  # Δω_III per N of each block (> 0: condition ii)
    res = linprog(cost, A_eq=a_eq, b_eq=b_eq, bounds=(0.0, p.max_thrust_N), method="highs")
    if res.status != 0:
        raise ConfigError(_SOURCE, "dv_stop_m_s", target,
                          f"a change the thrusters can make in one turn ({res.message})")
    f = np.asarray(res.x, dtype=float).reshape(n, 3)
    return Kick(f, block_s, target, float(res.fun), f @ a_eq[ROW_DV_STOP, :3])
