"""Instantaneous change of mass properties ("capture"): the momentum-conserving state jump.

What it does
    When the vehicle captures an object (seed 001 §2: the combined spacecraft after a
    manipulator grasps a target), its mass, inertia and centre of mass change at once.
    Given the old mass properties (m⁻, J⁻ about the old CoM), the new ones (m⁺, J⁺ about
    the new CoM) and the CoM shift Δc_B = c⁺ − c⁻ [m, body axes], the state jumps as

        v⁺ = (m⁻/m⁺) v⁻                                   linear momentum conserved
        H⁺ = J⁻ω⁻ − Δc_B × (m⁻ C(q) v⁻)                    angular momentum about the
        ω⁺ = (J⁺)⁻¹ H⁺                                      new CoM, body axes
        r⁺ = r⁻ + C(q)ᵀ Δc_B                               the state tracks the CoM
        q⁺ = q⁻                                            body axes keep their directions

    (Newton–Euler impulse balance of the union of two bodies; Goldstein, "Classical
    Mechanics", §1.2, transport of angular momentum H_O' = H_O + (r_O − r_O') × p.)

Assumptions
    The captured object carries no momentum of its own in the frame of the translation
    state (it is at rest there: inertial frame, or relative to the leader in the Hill
    frame, where the frame's rotation over the instant is neglected); its mass and
    inertia are part of m⁺, J⁺. With HCW translation the rotations C(q) of v and Δc use
    the Hill-to-inertial rotation of the translation model. Thruster positions are
    re-referred to the new CoM by the caller (``ThrusterSet.set_com_offset``).
"""

from __future__ import annotations

from bench.station.dynamics.rigid_body import (
    MassProperties,
    State,
    Vec3,
    angular_momentum_B,
    rotate_B_to_N,
    rotate_N_to_B,
)
from bench.station.dynamics.translation import TranslationModel


def _cross(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def capture_state(
    state: State,
    t_s: float,
    mp_before: MassProperties,
    mp_after: MassProperties,
    delta_com_B_m: Vec3,
    translation: TranslationModel,
) -> State:
    """The state just after the mass-property change (module docstring; pure)."""
    q = (state[0], state[1], state[2], state[3])
    r_nav = (state[7], state[8], state[9])
    v_nav = (state[10], state[11], state[12])
    m0, m1 = mp_before.mass_kg, mp_after.mass_kg
    v_B = rotate_N_to_B(q, translation.nav_to_inertial(t_s, v_nav))
    p_B = (m0 * v_B[0], m0 * v_B[1], m0 * v_B[2])
    h0 = angular_momentum_B(state, mp_before)
    t = _cross(delta_com_B_m, p_B)
    h1 = (h0[0] - t[0], h0[1] - t[1], h0[2] - t[2])
    ji = mp_after.inertia_inv_flat_B_per_kgm2
    w1 = (
        ji[0] * h1[0] + ji[1] * h1[1] + ji[2] * h1[2],
        ji[3] * h1[0] + ji[4] * h1[1] + ji[5] * h1[2],
        ji[6] * h1[0] + ji[7] * h1[1] + ji[8] * h1[2],
    )
    k = m0 / m1
    dc_nav = translation.inertial_to_nav(t_s, rotate_B_to_N(q, delta_com_B_m))
    return (
        *q,
        *w1,
        r_nav[0] + dc_nav[0],
        r_nav[1] + dc_nav[1],
        r_nav[2] + dc_nav[2],
        k * v_nav[0],
        k * v_nav[1],
        k * v_nav[2],
    )
