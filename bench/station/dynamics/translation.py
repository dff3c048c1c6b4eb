"""Translation models: the frame the position/velocity state lives in and its accelerations.

What it does
    A ``TranslationModel`` says how the translational part of the rigid-body state
    (``r``, ``v``: state indices 7..12, see ``bench.station.dynamics.rigid_body``) evolves, given
    the non-gravitational acceleration the wrench produces, expressed in the inertial
    frame I (= the frame N of ``rigid_body``): ṙ = v, v̇ = ``acceleration(t, r, v, a_I)``.
    It also rotates vectors between I and its own "navigation" frame (the frame of r and
    v), so that environment models can express a force given in the navigation frame.

Strategies
    - ``InertialTranslation`` (this file): r, v are inertial (frame I = N); v̇ = a_I.
      The bench's historical behaviour (free space, no gravity).
    - ``HcwTranslation`` (``bench.station.dynamics.hcw``): r, v relative to a leader on a
      circular orbit, in the leader's rotating Hill frame.

Inputs/outputs: t_s [s] since the start of the run, r [m], v [m/s], accelerations [m/s²].
Assumptions: the attitude state is always relative to the inertial frame I.
"""

from __future__ import annotations

from typing import Protocol

from bench.station.dynamics.rigid_body import Vec3


class TranslationModel(Protocol):
    """Translational equations of motion in a navigation frame (see module docstring)."""

    def acceleration(self, t_s: float, r_m: Vec3, v_m_s: Vec3, a_force_I_m_s2: Vec3) -> Vec3:
        """v̇ in the navigation frame [m/s²] given the wrench's acceleration in I."""
        ...

    def inertial_to_nav(self, t_s: float, v_I: Vec3) -> Vec3:
        """Components of the inertial vector ``v_I`` in the navigation frame at ``t_s``."""
        ...

    def nav_to_inertial(self, t_s: float, v_nav: Vec3) -> Vec3:
        """Components of the navigation-frame vector ``v_nav`` in I at ``t_s``."""
        ...


class InertialTranslation:
    """r, v inertial: v̇ = a_I (Newton's second law; no gravity, no frame rotation)."""

    def acceleration(self, t_s: float, r_m: Vec3, v_m_s: Vec3, a_force_I_m_s2: Vec3) -> Vec3:
        """v̇ = a_I [m/s²]."""
        return a_force_I_m_s2

    def inertial_to_nav(self, t_s: float, v_I: Vec3) -> Vec3:
        """Identity: the navigation frame is I."""
        return v_I

    def nav_to_inertial(self, t_s: float, v_nav: Vec3) -> Vec3:
        """Identity: the navigation frame is I."""
        return v_nav
