"""Seed 004: attitude and position control with three body-fixed, push-only thrusters.

What it does: the parts of seed 004's hierarchical controller (§3), one file per concern:
:mod:`.geometry` (the three-thruster model ``F_B = P T`` and conditions (i)–(iii), and the
configuration check over any layout and failure mask), :mod:`.invariants` (the spin
angle and the stopping velocity/position of single spin, eqs. 21 and 28–35),
:mod:`.step_a` (to single spin about axis III along the target z), :mod:`.disturbance`,
:mod:`.step_b` and :mod:`.step_c` (the intentional disturbances that set the stopping
velocity and position), :mod:`.despin` (Step D's closed forms with sine and cosine
integrals, eqs. 40–53) and :mod:`.step_d` (the de-spin planner), :mod:`.supervisor` (the
steps in turn; its last leg does not converge yet: docs/reproductions.md, seed 004) and
:mod:`.frame` (a control frame with axis III along another principal axis). No scenario
selects this controller yet.

Frames: body B = principal axes (I, II, III = x, y, z of B); the target frame R (the
reference attitude and position) plays the paper's inertial frame: at the target,
axis III lies along z_R and the body is at the origin of R.
"""
