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

``seed000_canted_16`` — the same four quads with every thruster canted by
:data:`SEED000_CANT_DEG` about its quad's radial axis e_q: the axial thrusters lean
towards the tangential direction and the tangential ones towards the axis, so each
thruster's torque has components about all three body axes. That is what seed 004's
underactuated control asks of three surviving thrusters (conditions (i)–(iii), in
particular a torque about the spin axis of one sign from all three): no three thrusters of
the conventional layout qualify, in any choice of spin axis (every torque there has a zero
component), while this one has triples that do (flight_sw.control.underactuated.geometry;
docs/reproductions.md, seed 004). The cant costs 1 − cos 10° = 1.5 % of each thruster's
authority along its old direction; the pairs of a quad still fire in opposite directions.

``seed001_table1_16`` — the 8 thrusters of seed 001 (MRP direct-parametric control with
robust least-squares control allocation of a combined spacecraft), §5 Table 1, as 16
unidirectional valves. Table 1 gives positions (arm R = 0.75 m, offset L = 0.75 m:
thrusters 1-4 at (0, -L, R), (-R, -L, 0), (0, -L, -R), (R, -L, 0); 5-8 at
(±R/√2, -L, ±R/√2), i.e. 0.375√2 = R/√2) and orientations as direction angles
(α, β, γ) to x, y, z, so d = (cos α, cos β, cos γ): 1 -z, 2 +x, 3 +z, 4 -x, 5 -x, 6 +x,
7 +x, 8 -x. The paper's actuators are bidirectional with signed bounds
-2.3 N ≤ u_i ≤ 2.35 N (§5 item 4). Mapping: a negative bound is an opposing thruster,
so actuator i (0-based) is the pair of valves i (along d_i, max 2.35 N) and i + 8 (along
-d_i, same position, max 2.3 N); u_i = F_i - F_{i+8}. A bidirectional actuator (e.g. a
cold-gas valve pair) is exactly that pair. ``seed001_table1_max_thrust_N`` gives the
per-valve maxima in that order (the scenario's default for this layout).
"""

from __future__ import annotations

import math

Vec3 = tuple[float, float, float]

SEED000_CANT_DEG = 10.0
"""``seed000_canted_16``: cant of each thruster about its quad's radial axis [deg]."""
SEED001_UPPER_BOUND_N = 2.35
"""Seed 001 §5: upper bound ū of each actuator's force [N] (valve i)."""
SEED001_LOWER_BOUND_N = 2.3
"""Seed 001 §5: magnitude of the lower bound -2.3 N [N] (the opposing valve i + 8)."""
SEED001_ACTUATORS = 8


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


def seed000_canted_16(arm_R_m: float, length_L_m: float) -> tuple[tuple[Vec3, Vec3], ...]:
    """``seed000_conventional_16`` with every direction turned by :data:`SEED000_CANT_DEG`
    about its quad's radial axis (Rodrigues' rotation; see the module docstring)."""
    c, s = math.cos(math.radians(SEED000_CANT_DEG)), math.sin(math.radians(SEED000_CANT_DEG))
    out: list[tuple[Vec3, Vec3]] = []
    for r, d in seed000_conventional_16(arm_R_m, length_L_m):
        rho = math.hypot(r[1], r[2])
        e = (0.0, r[1] / rho, r[2] / rho)  # the quad's radial unit vector
        exd = (e[1] * d[2] - e[2] * d[1], e[2] * d[0] - e[0] * d[2], e[0] * d[1] - e[1] * d[0])
        ed = e[0] * d[0] + e[1] * d[1] + e[2] * d[2]
        turned = tuple(d[i] * c + exd[i] * s + e[i] * ed * (1.0 - c) for i in range(3))
        out.append((r, (turned[0] or 0.0, turned[1] or 0.0, turned[2] or 0.0)))
    return tuple(out)


def seed001_table1_16(arm_R_m: float, length_L_m: float) -> tuple[tuple[Vec3, Vec3], ...]:
    """Geometry of seed 001's Table 1 as 16 valves (see module docstring; R = L = 0.75 m)."""
    R, L = arm_R_m, length_L_m
    a = R / math.sqrt(2.0)
    table1: tuple[tuple[Vec3, Vec3], ...] = (
        ((0.0, -L, R), (0.0, 0.0, -1.0)),
        ((-R, -L, 0.0), (1.0, 0.0, 0.0)),
        ((0.0, -L, -R), (0.0, 0.0, 1.0)),
        ((R, -L, 0.0), (-1.0, 0.0, 0.0)),
        ((a, -L, a), (-1.0, 0.0, 0.0)),
        ((-a, -L, a), (1.0, 0.0, 0.0)),
        ((-a, -L, -a), (1.0, 0.0, 0.0)),
        ((a, -L, -a), (-1.0, 0.0, 0.0)),
    )
    opposing = tuple(
        (r, (-d[0] or 0.0, -d[1] or 0.0, -d[2] or 0.0)) for r, d in table1
    )  # `or 0.0`: no negative zeros
    return table1 + opposing


def seed001_table1_max_thrust_N(
    upper_N: float = SEED001_UPPER_BOUND_N, lower_N: float = SEED001_LOWER_BOUND_N
) -> tuple[float, ...]:
    """Per-valve maximum thrust of ``seed001_table1_16``: 8 × ``upper_N``, 8 × ``lower_N``."""
    return (upper_N,) * SEED001_ACTUATORS + (lower_N,) * SEED001_ACTUATORS


LAYOUTS = {
    "seed003_cascade_8": seed003_cascade_8,
    "seed000_conventional_16": seed000_conventional_16,
    "seed000_canted_16": seed000_canted_16,
    "seed001_table1_16": seed001_table1_16,
}

LAYOUT_MAX_THRUST_N = {
    "seed001_table1_16": seed001_table1_max_thrust_N(),
}
"""Per-thruster maximum thrust [N] of layouts whose source gives one (scenario default)."""
