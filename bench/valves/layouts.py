"""Named thruster layouts: pure functions from a few dimensions to thruster geometry.

Output: a tuple of (r_thr_B_m, d_thr_B) pairs, body frame B, metres and unit vectors.

``seed003_cascade_8`` — the 8 on-off thrusters of seed 003 (cascade QPD-LQR + PWPF paper,
Table 1: arm R = 0.45 m, length L = 0.22 m). The paper's configuration matrix E (eq. 6)
did not survive text extraction, so the layout is reconstructed to be consistent with
its symbols and with pure couples: two clusters at x_B = +R and x_B = -R, each with four
thrusters offset by L from the x_B axis and firing tangentially. Pairs give pure torques:
(3,4) +roll 2LT, (1,2) -roll, (4,8) +pitch 2RT, (3,7) -pitch, (1,5) +yaw 2RT, (2,6) -yaw
(1-based), with no net force. Roll arm L suits the small roll inertia (Ix = 15.95 kg m^2).

``seed000_conventional_16`` — the 16-thruster "conventional thruster configuration (CTC)"
of seed 000 (dual-quaternion 6-DoF control with null-space pseudo-inverse allocation;
5 N thrust limit; 100 kg nominal, J = diag(18, 18, 24) kg m^2). The paper's Fig. 5 (the
geometry) did not survive text extraction; the text only says that #01-#16 are grouped
in fours (Figs. 6-9 plot #01-#04, ... #13-#16), that "pair-mounted actuators can provide
symmetrical thrusts" and that "negative values can also be offered by the thruster from
the other direction". Reconstruction (the classic four-quad reaction-control system,
e.g. the Apollo service module's): four clusters ("quads") of four thrusters at radius
R from the x_B axis, at azimuths +y_B, +z_B, -y_B, -z_B, in the plane x_B = L (the quad
plane sits L ahead of the centre of mass). In quad q with radial unit vector e_q the four
thrusters fire along +x_B, -x_B, +t_q and -t_q with t_q = x_B × e_q (tangential):
index 4q + 0: +x_B, 4q + 1: -x_B, 4q + 2: +t_q (+roll), 4q + 3: -t_q (-roll).
Every direction has its opposite in the same quad (pair-mounted, symmetrical thrusts).
Authority with thrust T: force ±x 4T, ±y 2T (quads ±z), ±z 2T (quads ±y); torque roll
±4RT (tangentials), pitch ±2RT (axials of quads ±z) and yaw ±2RT (axials of quads ±y);
the offset L couples the tangential forces into pitch/yaw by L·T, which the axials
trim. The 16 wrench columns positively span all six degrees of freedom (a strictly
positive null vector of the 6×16 effectiveness matrix exists), and still do with any
single thruster removed (checked in tests/flight_sw/test_fsw_layouts.py), which is what
single-failure reconfiguration needs.
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


def seed000_conventional_16(arm_R_m: float, length_L_m: float) -> tuple[tuple[Vec3, Vec3], ...]:
    """Geometry of the reconstructed seed-000 16-thruster CTC (see module docstring)."""
    R, L = arm_R_m, length_L_m
    out: list[tuple[Vec3, Vec3]] = []
    # (radial e_q, tangential t_q = x_B × e_q) of the quads at +y, +z, -y, -z
    quads: tuple[tuple[Vec3, Vec3], ...] = (
        ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
        ((0.0, 0.0, 1.0), (0.0, -1.0, 0.0)),
        ((0.0, -1.0, 0.0), (0.0, 0.0, -1.0)),
        ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
    )
    for (ey, ez), (ty, tz) in ((e[1:], t[1:]) for e, t in quads):
        r: Vec3 = (L, R * ey, R * ez)
        out += [
            (r, (1.0, 0.0, 0.0)),
            (r, (-1.0, 0.0, 0.0)),
            (r, (0.0, ty, tz)),
            (r, (0.0, -ty or 0.0, -tz or 0.0)),  # `or 0.0`: no negative zeros
        ]
    return tuple(out)


LAYOUTS = {
    "seed003_cascade_8": seed003_cascade_8,
    "seed000_conventional_16": seed000_conventional_16,
}
