"""Step A: to single spin about body axis III, with axis III along the target z.

What it does: the torques about axes I and II (the two the three thrusters make in both
directions, condition (i)) steer the body onto the manifold ω_I = ω_II = 0, axis III ∥ z_R,
with a negative spin ω_III, so that the always-positive axis-III torque (condition (ii))
can later stop it (Step D). Two parts, as seed 004's Step A asks of the law of its ref.
[11] (eqs. 12–17, which did not survive in the seed text; this is a substitute with the
same job, inputs and outputs):
- spin-up: while the spin is slower than ``spin_min_rad_s`` the transverse rates are held
  on the diagonal ``ω_I = −sgn(J_I − J_II) ω_II`` (the second/fourth quadrant of §3.3
  when J_I > J_II), so the gyroscopic term ``(J_I − J_II) ω_I ω_II`` of Euler's third
  equation spins the body negative faster than the positive T_III that comes with the
  transverse torques slows it; until the spin reaches ``spin_target_rad_s``.
- pointing: the transverse rate demand ``ω_d = k_p θ (e_3 × ẑ)/|e_3 × ẑ|`` (ẑ the target z
  in body axes, θ its angle from axis III) turns axis III onto z_R (``dẑ/dt = ẑ × ω``), at
  most ``max_rate_rad_s``.
Both are tracked by a rate loop with the gyroscopic terms cancelled:
``T_I = J_I k_ω (ω_d,I − ω_I) − (J_II − J_III) ω_II ω_III`` (and II likewise); the axis-III
torque is the least the thrusters allow (:meth:`ThreeThrusters.min_torque_III_Nm`),
so the spin is spent as little as possible. The singularity of the paper's law at
ω_III → 0 does not arise; the rate demand is saturated instead.

Inputs: ``q_BR`` (body relative to the target frame), ``omega_BN_B`` [rad/s]. Output: the
torque demand in body axes [N m] (thrusts ≥ 0 by construction).
Source: seed 004 §3.2 (the manifold and the role of Step A), §3.3 (quadrants); Euler's
equations (eq. 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw.control.underactuated.geometry import ThreeThrusters
from flight_sw.control.underactuated.invariants import target_z_in_B

_SOURCE = "[flight_sw.pose] step A"


@dataclass(frozen=True)
class StepAParams:
    """Gains [1/s], rates [rad/s] (spin rates are magnitudes of the negative spin).

    The defaults are gentle: every N s of thrust here leaves x–y velocity that Step D
    pays for in spin (docs/reproductions.md, seed 004)."""

    pointing_gain_per_s: float = 0.3
    rate_gain_per_s: float = 4.0
    max_rate_rad_s: float = 0.05
    spin_up_rate_rad_s: float = 0.3
    spin_min_rad_s: float = 0.15
    spin_target_rad_s: float = 0.25

    def __post_init__(self) -> None:
        for key in ("pointing_gain_per_s", "rate_gain_per_s", "max_rate_rad_s",
                    "spin_up_rate_rad_s", "spin_min_rad_s", "spin_target_rad_s"):
            check.positive(_SOURCE, key, getattr(self, key))
        if self.spin_target_rad_s <= self.spin_min_rad_s:
            raise ConfigError(_SOURCE, "spin_target_rad_s", self.spin_target_rad_s,
                              f"> spin_min_rad_s = {self.spin_min_rad_s}")


def tilt_rad(q_BR: np.ndarray) -> float:
    """Angle between body axis III and the target z [rad]."""
    return math.acos(max(-1.0, min(1.0, float(target_z_in_B(q_BR)[2]))))


def in_single_spin(q_BR: np.ndarray, omega_BN_B: np.ndarray, tilt_max_rad: float,
                   rate_max_rad_s: float) -> bool:
    """Step A's exit condition: axis III within ``tilt_max_rad`` of the target z and the
    transverse rates below ``rate_max_rad_s`` (the manifold of seed 004 §3.2)."""
    return (tilt_rad(q_BR) <= tilt_max_rad
            and math.hypot(float(omega_BN_B[0]), float(omega_BN_B[1])) <= rate_max_rad_s)


class StepA:
    """Step A's law (module docstring); ``spinning_up`` is its one piece of state."""

    def __init__(self, thrusters: ThreeThrusters, params: StepAParams) -> None:
        self.thr = thrusters
        self.p = params
        j = thrusters.inertia_diag_kgm2
        self._j = np.asarray(j, dtype=float)
        # ω_I ω_II < 0 spins negative when J_I > J_II (and the reverse)
        self._spin_dir = np.array([1.0, -math.copysign(1.0, j[0] - j[1])]) / math.sqrt(2.0)
        self.spinning_up = True

    def rate_demand(self, q_BR: np.ndarray, omega_BN_B: np.ndarray) -> np.ndarray:
        """The transverse rate demand (ω_I, ω_II) [rad/s]; updates the spin-up latch."""
        w3 = float(omega_BN_B[2])
        if w3 > -self.p.spin_min_rad_s:
            self.spinning_up = True
        elif w3 < -self.p.spin_target_rad_s:
            self.spinning_up = False
        if self.spinning_up:
            return self.p.spin_up_rate_rad_s * self._spin_dir
        return self.pointing_rate(q_BR)

    def pointing_rate(self, q_BR: np.ndarray) -> np.ndarray:
        """ω_d = k_p θ (e₃ × ẑ)/|e₃ × ẑ|, saturated [rad/s]."""
        z = target_z_in_B(q_BR)
        s = math.hypot(float(z[0]), float(z[1]))
        if s < 1e-12:
            return np.zeros(2)
        theta = math.atan2(s, float(z[2]))
        w = self.p.pointing_gain_per_s * theta * np.array([-z[1], z[0]]) / s
        n = float(np.linalg.norm(w))
        return w * (self.p.max_rate_rad_s / n) if n > self.p.max_rate_rad_s else w

    def track(self, omega_BN_B: np.ndarray, w_d: np.ndarray, extra_III_Nm: float = 0.0
              ) -> np.ndarray:
        """The torque that tracks transverse rate demand ``w_d`` (gyroscopic terms
        cancelled), with the least axis-III torque plus ``extra_III_Nm`` [N m]."""
        w = np.asarray(omega_BN_B, dtype=float)
        j = self._j
        k = self.p.rate_gain_per_s
        t1 = j[0] * k * (w_d[0] - w[0]) - (j[1] - j[2]) * w[1] * w[2]
        t2 = j[1] * k * (w_d[1] - w[1]) - (j[2] - j[0]) * w[2] * w[0]
        return self.thr.torque_B_Nm(t1, t2, extra_III_Nm)

    def torque_B_Nm(self, q_BR: np.ndarray, omega_BN_B: np.ndarray) -> np.ndarray:
        """Step A's torque demand [N m]."""
        return self.track(omega_BN_B, self.rate_demand(q_BR, omega_BN_B))
