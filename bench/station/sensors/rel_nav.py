"""Relative-navigation sensor: position and velocity of the vehicle with white noise.

In: true position r_N [m] and velocity v_N [m/s] in the navigation frame (inertial for
now; the Hill frame once relative orbital motion is modelled). Out: measured position and
velocity, and a validity flag, for the NAV_POS / NAV_VEL frames. Noise is white, Gaussian,
per axis (1 sigma ``noise_pos_m``, ``noise_vel_m_s``), drawn from the given generator so
that the same seed gives the same samples; ``outage`` makes samples invalid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dbc import validation as check

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class RelNavParams:
    """Noise of the relative-navigation solution (1 sigma per axis)."""

    noise_pos_m: float
    noise_vel_m_s: float

    def __post_init__(self) -> None:
        for key in ("noise_pos_m", "noise_vel_m_s"):
            value = check.non_negative("RelNavParams", key, getattr(self, key))
            object.__setattr__(self, key, value)


class RelNav:
    """Relative-navigation sensor."""

    def __init__(self, params: RelNavParams, rng: np.random.Generator) -> None:
        self.params = params
        self._rng = rng
        self.outage = False

    def sample(self, t_ns: int, r_N_m: Vec3, v_N_m_s: Vec3) -> tuple[Vec3, Vec3, bool]:
        """Measured (position, velocity, valid) at ``t_ns``."""
        n = self._rng.standard_normal(6)
        p, v = self.params.noise_pos_m, self.params.noise_vel_m_s
        pos = (r_N_m[0] + p * n[0], r_N_m[1] + p * n[1], r_N_m[2] + p * n[2])
        vel = (v_N_m_s[0] + v * n[3], v_N_m_s[1] + v * n[4], v_N_m_s[2] + v * n[5])
        return (
            (float(pos[0]), float(pos[1]), float(pos[2])),
            (float(vel[0]), float(vel[1]), float(vel[2])),
            not self.outage,
        )
