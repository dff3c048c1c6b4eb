"""Named thruster layouts: pure functions from a few dimensions to thruster geometry.

Output: a tuple of (r_thr_B_m, d_thr_B) pairs, body frame B, metres and unit vectors.

``seed003_cascade_8`` — the 8 on-off thrusters of seed 003 (cascade QPD-LQR + PWPF paper,
Table 1: arm R = 0.45 m, length L = 0.22 m). The paper's configuration matrix E (eq. 6)
did not survive text extraction, so the layout is reconstructed to be consistent with
its symbols and with pure couples: two clusters at x_B = +R and x_B = -R, each with four
thrusters offset by L from the x_B axis and firing tangentially. Pairs give pure torques:
(3,4) +roll 2LT, (1,2) -roll, (4,8) +pitch 2RT, (3,7) -pitch, (1,5) +yaw 2RT, (2,6) -yaw
(1-based), with no net force. Roll arm L suits the small roll inertia (Ix = 15.95 kg m^2).
"""

from __future__ import annotations

Vec3 = tuple[float, float, float]


def seed003_cascade_8(arm_R_m: float, length_L_m: float) -> tuple[tuple[Vec3, Vec3], ...]:
    """Geometry of the seed-003 8-thruster layout (see module docstring)."""
    R, L = arm_R_m, length_L_m
    return (
        ((R, 0.0, L), (0.0, 1.0, 0.0)),
        ((R, 0.0, -L), (0.0, -1.0, 0.0)),
        ((R, L, 0.0), (0.0, 0.0, 1.0)),
        ((R, -L, 0.0), (0.0, 0.0, -1.0)),
        ((-R, 0.0, L), (0.0, -1.0, 0.0)),
        ((-R, 0.0, -L), (0.0, 1.0, 0.0)),
        ((-R, L, 0.0), (0.0, 0.0, -1.0)),
        ((-R, -L, 0.0), (0.0, 0.0, 1.0)),
    )


LAYOUTS = {"seed003_cascade_8": seed003_cascade_8}
