"""Step D's closed forms: velocity and position changes of an exponential de-spin.

What it does: in single spin (ω_I = ω_II = 0, axis III along z_R) the axis-III torque
``T_III = −η J_III ω_III`` (η > 0 [1/s], eq. 39) slows the (negative) spin as
``ω_III = ω_a e^{−η t}``, i.e. linearly in the spin angle: ``ω_III = ω_a − η (ψ − ψ_a)``.
The body force ``P e_3 T_III`` turns with the body (eq. 9), so the x–y velocity changes by
    ``Δv = −λ η [S(ψ_b) − S(ψ_a)]``,  ``S(ψ) = (sin(ψ+α), −cos(ψ+α))`` (eq. 40),
with ``λ = ρ J_III / m`` and α the direction of that force in body axes. With
``y = −ω_III/η`` (the angle left before the spin would stop) the duration is
``Δt = ln(y_a/y_b)/η`` (eq. 42) and the position change (eqs. 41, 43–45)
    ``Δr = (v_a + λη S(ψ_a)) Δt − λ ∫_{y_b}^{y_a} S(y + c)/y dy``,  ``c = ψ_a + α − y_a``,
whose integrals are sine and cosine integrals, Si and Ci (scipy.special.sici). The final
sequence runs to y = 0 (the spin stops on ψ_f); its position change is finite only if the
velocity also ends at zero, and is then (with ``Cin(x) = γ + ln x − Ci(x)``)
    ``Δr_f = λ (sin c Cin(y_a) − cos c Si(y_a), −cos c Cin(y_a) − sin c Si(y_a))``, ``c = ψ_f + α``:
over a whole turn (``y_a = 2π``, velocity 0 at both ends) a constant of the vehicle, not
of the spin rate (§3.5's third sequence).

Units: rad, rad/s, 1/s, m, m/s, s; x–y in the target frame R. Assumptions: ideal
continuous thrust, exactly single spin, V_stop = 0 (z is the invariants' business).
Source: seed 004 §3.5, eqs. (39)–(53); Si/Ci: Abramowitz & Stegun 5.2.1–5.2.2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import sici

TWO_PI = 2.0 * math.pi
HALF_TURN_RAD = math.pi


def _s(angle: float) -> np.ndarray:
    return np.array([math.sin(angle), -math.cos(angle)])


def cin(x: float) -> float:
    """Cin(x) = ∫₀ˣ (1 − cos t)/t dt = γ + ln x − Ci(x) (entire; Cin(0) = 0)."""
    if x <= 0.0:
        return 0.0
    if x < 1e-4:
        return x * x / 4.0
    return float(np.euler_gamma) + math.log(x) - float(sici(x)[1])


@dataclass(frozen=True)
class Despin:
    """One exponential de-spin sequence from (ψ_a, ω_a) to ω_b (same sign, |ω_b| < |ω_a|)."""

    psi_a_rad: float
    omega_a_rad_s: float
    omega_b_rad_s: float
    eta_per_s: float

    @property
    def psi_b_rad(self) -> float:
        """The spin angle at the end [rad]."""
        return self.psi_a_rad + (self.omega_a_rad_s - self.omega_b_rad_s) / self.eta_per_s

    @property
    def duration_s(self) -> float:
        """Δt = ln(ω_a/ω_b)/η (eq. 42) [s] (inf for a sequence that stops the spin)."""
        if self.omega_b_rad_s == 0.0:
            return math.inf
        return math.log(self.omega_a_rad_s / self.omega_b_rad_s) / self.eta_per_s

    def delta_v(self, lam_m: float, alpha_rad: float) -> np.ndarray:
        """Eq. (40): the x–y velocity change [m/s]."""
        return -lam_m * self.eta_per_s * (_s(self.psi_b_rad + alpha_rad)
                                          - _s(self.psi_a_rad + alpha_rad))

    def delta_r(self, v_a: np.ndarray, lam_m: float, alpha_rad: float) -> np.ndarray:
        """Eqs. (41), (43)–(45): the x–y position change from velocity ``v_a`` [m]."""
        eta = self.eta_per_s
        y_a = -self.omega_a_rad_s / eta
        y_b = -self.omega_b_rad_s / eta
        c = self.psi_a_rad + alpha_rad - y_a
        if y_b == 0.0:  # the final sequence: finite only if it ends at rest
            v_end = np.asarray(v_a, dtype=float) + self.delta_v(lam_m, alpha_rad)
            if float(np.linalg.norm(v_end)) > 1e-12 * max(1.0, lam_m * eta):
                return np.array([math.inf, math.inf])
            cf = self.psi_b_rad + alpha_rad
            ci_, si_ = cin(y_a), float(sici(y_a)[0])
            return lam_m * np.array([math.sin(cf) * ci_ - math.cos(cf) * si_,
                                     -math.cos(cf) * ci_ - math.sin(cf) * si_])
        si_a, ci_a = (float(v) for v in sici(y_a))
        si_b, ci_b = (float(v) for v in sici(y_b))
        d_si, d_ci = si_a - si_b, ci_a - ci_b
        integral = np.array([math.cos(c) * d_si + math.sin(c) * d_ci,
                             -math.cos(c) * d_ci + math.sin(c) * d_si])
        start = np.asarray(v_a, dtype=float) + lam_m * eta * _s(self.psi_a_rad + alpha_rad)
        return start * self.duration_s - lam_m * integral


def final_turn(psi_f_rad: float, omega_a_rad_s: float) -> Despin:
    """The last sequence: one whole turn from ψ_f + 2π, stopping exactly on ψ_f."""
    return Despin(psi_f_rad + TWO_PI, omega_a_rad_s, 0.0, -omega_a_rad_s / TWO_PI)


def final_turn_offset_m(psi_f_rad: float, lam_m: float, alpha_rad: float) -> np.ndarray:
    """Δr of the last turn (velocity 0 before it): a constant of the vehicle and ψ_f [m]."""
    return final_turn(psi_f_rad, -1.0).delta_r(np.zeros(2), lam_m, alpha_rad)


def half_turn_for(delta_v: np.ndarray, omega_a_rad_s: float, lam_m: float,
                  alpha_rad: float) -> Despin:
    """The half-turn sequence giving the x–y velocity change ``delta_v``: its start angle
    (mod 2π) sets the direction, η the size: ``|Δv| = 2λη`` (eq. 40 with ψ_b = ψ_a − π).

    ω_b = ω_a + πη may not reach 0: the caller limits |Δv| below ``2λ|ω_a|/π``.
    """
    dv = np.asarray(delta_v, dtype=float)
    size = float(np.linalg.norm(dv))
    eta = size / (2.0 * lam_m)
    phi = math.atan2(float(dv[0]), -float(dv[1]))  # (sin φ, −cos φ) ∥ Δv, φ = ψ_a + α
    return Despin(phi - alpha_rad, omega_a_rad_s, omega_a_rad_s + HALF_TURN_RAD * eta, eta)


def max_half_turn_dv(omega_a_rad_s: float, lam_m: float, keep_fraction: float) -> float:
    """The largest |Δv| of a half turn that keeps ``keep_fraction`` of the spin [m/s]."""
    return 2.0 * lam_m * abs(omega_a_rad_s) * (1.0 - keep_fraction) / HALF_TURN_RAD
