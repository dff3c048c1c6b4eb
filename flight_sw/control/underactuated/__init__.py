"""Seed 004: attitude and position control with three body-fixed, push-only thrusters.

What it does: the parts of seed 004's hierarchical controller (§3), one file per concern:
:mod:`.geometry` (the three-thruster model ``F_B = P T`` and conditions (i)–(iii), and the
configuration check over any layout and failure mask), :mod:`.invariants` (the spin
angle and the stopping velocity/position of single spin, eqs. 21 and 28–35),
:mod:`.step_a` (to single spin about axis III along the target z), :mod:`.despin`
(Step D's closed forms with sine and cosine integrals, eqs. 40–53) and :mod:`.step_d`
(the de-spin planner). Steps B and C (the intentional disturbances that set the stopping
velocity and position) and the supervisor that switches between the steps are not here
yet (docs/reproductions.md, seed 004, says what stands in their way), so no scenario
selects this controller.

Frames: body B = principal axes (I, II, III = x, y, z of B); the target frame R (the
reference attitude and position) plays the paper's inertial frame: at the target,
axis III lies along z_R and the body is at the origin of R.
"""
