"""Test reference for seed 004: the chosen three-thruster body and a textbook plant.

The vehicle (seed 004 §4.1 lost its inertias and placements; these are ours, documented
in docs/reproductions.md): mass 20 kg (the paper's), principal inertias (1.6, 1.0, 2.0)
kg m², three thrusters whose torques point 120° apart in the I–II plane with a small
positive III component (conditions (i)–(ii)) and whose directions have III components of
both signs (iii). The plant integrates the direction cosine matrix C_RB (not a
quaternion: a second form beside the flight software's model) with RK4 and the torque
held over each control period, re-orthonormalised by SVD.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.spatial.transform import Rotation

from flight_sw.control.underactuated.geometry import ThreeThrusters

MASS_KG = 20.0
INERTIA_DIAG_KGM2 = np.array([1.6, 1.0, 2.0])
R_THR_B_M = np.array([[-0.1034, 0.0094, -0.2816],
                      [0.1023, -0.1911, -0.2077],
                      [-0.1455, -0.2559, -0.0589]])
_D = np.array([[-0.9388, -0.0115, 0.3442],
               [0.3669, -0.5875, 0.7213],
               [0.1264, 0.1536, -0.9800]])
D_THR_B = _D / np.linalg.norm(_D, axis=1)[:, None]
PERIOD_S = 0.02


def vehicle() -> ThreeThrusters:
    """The seed-004 test body as the flight software models it."""
    return ThreeThrusters(np.cross(R_THR_B_M, D_THR_B).T, D_THR_B.T, INERTIA_DIAG_KGM2,
                          MASS_KG)


def effectiveness() -> np.ndarray:
    """Its 6×3 effectiveness matrix (force rows, then torque rows)."""
    return np.vstack((D_THR_B.T, np.cross(R_THR_B_M, D_THR_B).T))


def q_BR_of(c_RB: np.ndarray) -> np.ndarray:
    """The flight software's scalar-first q_BR for the body-to-R matrix C_RB."""
    x, y, z, w = Rotation.from_matrix(c_RB).as_quat()
    return np.array([w, x, y, z])


def spin_dcm(psi_rad: float) -> np.ndarray:
    """C_RB of a single spin at angle ψ about z."""
    c, s = np.cos(psi_rad), np.sin(psi_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class Plant:
    """Free rigid body and translation under three thrusters (module docstring)."""

    def __init__(self, c_RB: np.ndarray, omega_B: np.ndarray, r_R: np.ndarray,
                 v_R: np.ndarray, substeps: int = 4) -> None:
        self.c = np.array(c_RB, dtype=float)
        self.w = np.array(omega_B, dtype=float)
        self.r = np.array(r_R, dtype=float)
        self.v = np.array(v_R, dtype=float)
        self.t = 0.0
        self.substeps = substeps

    def _f(self, c: np.ndarray, w: np.ndarray, v: np.ndarray, thrust_N: np.ndarray):
        j = INERTIA_DIAG_KGM2
        torque = np.cross(R_THR_B_M, D_THR_B).T @ thrust_N
        force_B = D_THR_B.T @ thrust_N
        wx = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
        dw = (torque - np.cross(w, j * w)) / j
        return c @ wx, dw, v, c @ force_B / MASS_KG

    def step(self, thrust_N: np.ndarray, dt_s: float = PERIOD_S) -> None:
        """Advance ``dt_s`` with the three thrusts held [N]."""
        h = dt_s / self.substeps
        for _ in range(self.substeps):
            c, w, r, v = self.c, self.w, self.r, self.v
            k1 = self._f(c, w, v, thrust_N)
            k2 = self._f(c + h / 2 * k1[0], w + h / 2 * k1[1], v + h / 2 * k1[3], thrust_N)
            k3 = self._f(c + h / 2 * k2[0], w + h / 2 * k2[1], v + h / 2 * k2[3], thrust_N)
            k4 = self._f(c + h * k3[0], w + h * k3[1], v + h * k3[3], thrust_N)
            inc = [h / 6 * (a + 2 * b + 2 * cc + d) for a, b, cc, d in zip(k1, k2, k3, k4,
                                                                          strict=True)]
            u, _, vt = np.linalg.svd(c + inc[0])
            self.c, self.w = u @ vt, w + inc[1]
            self.r, self.v = r + inc[2], v + inc[3]
        self.t += dt_s

    def q_BR(self) -> np.ndarray:
        """The attitude as the flight software reads it."""
        return q_BR_of(self.c)

    def run(self, law: Callable[[Plant], np.ndarray], duration_s: float,
            until: Callable[[Plant], bool] | None = None) -> list[np.ndarray]:
        """Close the loop: ``law`` gives body torque; returns every period's thrusts."""
        m_inv = np.linalg.inv(np.cross(R_THR_B_M, D_THR_B).T)
        out = []
        end = self.t + duration_s
        while self.t < end - 1e-9:
            if until is not None and until(self):
                break
            thrust = m_inv @ law(self)
            out.append(thrust)
            self.step(thrust)
        return out
