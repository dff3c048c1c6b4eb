"""A control frame for seed 004's steps: the principal axes renamed so that axis III is any
of them.

What it does: the steps (Step A to Step D and the supervisor) run with axis III = z_B, the
principal axis the body spins about. Three thrusters may qualify only with axis III along
another principal axis: the configuration check tries the six control frames K of
:data:`~flight_sw.control.underactuated.geometry.CONTROL_FRAMES`, and the triples of the
canted seed-000 layout qualify along ±x or ±y only. :class:`ControlFrame` carries the
steps' inputs into K and their torque back:

- attitude: ``C_KR = C_KB C_BR``, i.e. ``q_KR = q_BR ⊗ q_KB`` (``C(p ⊗ q) = C(q) C(p)`` in
  this project's convention, :mod:`flight_sw.quaternion`);
- rate: ``ω_K = C_KB ω_B``; torque: ``T_B = C_KBᵀ T_K``;
- the three-thruster model from the K components of the thrusters' torque and force
  columns and the inertia about K's axes (``|C_KB| J``, a permutation of the diagonal).

The thrusts are the same numbers in either frame (``f = M_K⁻¹ T_K = M_B⁻¹ C_KBᵀ T_K``),
so the three valves are commanded as they are; positions and velocities stay in R.

Inputs: a control frame's name (``"III=+x"``, ...); 6×n effectiveness (rows force [N/N],
then torque [N m/N], body axes), diagonal inertia [kg m²], mass [kg], the triple's thruster
indices; ``q_BR`` scalar first, rates [rad/s], torques [N m]. Each frame's quaternion
``q_KB`` is tabled (:data:`FRAME_QUATERNIONS`; a test checks ``C(q_KB)`` against the
frame's matrix). Source: seed 004 §2 (conditions stated in principal axes); Markley &
Crassidis 2014, "Fundamentals of Spacecraft Attitude Determination and Control", §2.9
(composition of rotations).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dbc.errors import ConfigError
from flight_sw.control.underactuated.geometry import (
    CONTROL_FRAMES,
    ThreeThrusters,
    principal_diag,
)
from flight_sw.quaternion import multiply

_SOURCE = "seed-004 control frame"
HALF = 0.5

FRAME_QUATERNIONS: dict[str, tuple[float, float, float, float]] = {
    "III=+z": (1.0, 0.0, 0.0, 0.0),
    "III=-z": (0.0, 1.0, 0.0, 0.0),
    "III=+x": (HALF, HALF, HALF, HALF),
    "III=-x": (-HALF, HALF, HALF, -HALF),
    "III=+y": (-HALF, HALF, HALF, HALF),
    "III=-y": (HALF, HALF, -HALF, HALF),
}
"""``q_KB`` of each control frame of ``CONTROL_FRAMES`` (scalar first): ``C(q_KB)`` is the
frame's matrix, rows axes I, II, III in body axes."""


@dataclass(frozen=True)
class ControlFrame:
    """One control frame K (module docstring), by its name in ``CONTROL_FRAMES``."""

    name: str
    c_KB: np.ndarray = field(init=False, repr=False)
    q_KB: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        frames = dict(CONTROL_FRAMES)
        if self.name not in frames:
            raise ConfigError(_SOURCE, "frame", self.name, " or ".join(frames))
        object.__setattr__(self, "c_KB", frames[self.name].copy())
        object.__setattr__(self, "q_KB", np.array(FRAME_QUATERNIONS[self.name]))

    def q_KR(self, q_BR: np.ndarray) -> np.ndarray:
        """The attitude of K relative to R: ``q_BR ⊗ q_KB``."""
        return multiply(q_BR, self.q_KB)

    def omega_K(self, omega_B: np.ndarray) -> np.ndarray:
        """A rate (or any vector) from body axes to K's [same unit]."""
        return self.c_KB @ np.asarray(omega_B, dtype=float)

    def torque_B(self, torque_K_Nm: np.ndarray) -> np.ndarray:
        """A torque (or any vector) from K's axes to body axes [N m]."""
        return self.c_KB.T @ np.asarray(torque_K_Nm, dtype=float)

    def three_thrusters(self, effectiveness: np.ndarray, inertia_B_kgm2: np.ndarray,
                        mass_kg: float, thrusters: tuple[int, int, int]) -> ThreeThrusters:
        """The model of ``thrusters`` (indices into the layout's columns) in this frame;
        ConfigError if they do not qualify in it."""
        b = np.asarray(effectiveness, dtype=float)
        if b.ndim != 2 or b.shape[0] != 6 or max(thrusters) >= b.shape[1] or min(thrusters) < 0:
            raise ConfigError(_SOURCE, "thrusters", thrusters,
                              f"three columns of the 6×n effectiveness matrix ({b.shape})")
        cols = list(thrusters)
        return ThreeThrusters(self.c_KB @ b[3:, cols], self.c_KB @ b[:3, cols],
                              np.abs(self.c_KB) @ principal_diag(inertia_B_kgm2), mass_kg,
                              thrusters)
