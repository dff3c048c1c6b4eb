"""The controller interfaces: attitude (torque out) and translation (force out), body axes.

What it does: defines :class:`AttitudeController`, the one interface every attitude
control strategy implements, and :class:`TranslationController`, the one every
translation (position) control strategy of a 6-DoF configuration implements (its
inputs and output are in its own docstring). Below: the attitude interface.

Inputs: ``t_ns`` [integer ns, the caller's time base; strategies without memory ignore
it]; ``q_BN`` the (estimated) attitude, scalar-first, maps inertial N to body B;
``omega_BN_B`` the (estimated) body rate of B relative to N in body axes [rad/s];
``q_RN`` the reference attitude (maps N to the reference frame R); ``omega_RN_B`` the
reference rate of R relative to N expressed in body axes [rad/s] (zero for regulation or
a slew to a fixed attitude); ``domega_RN_B`` the reference angular acceleration (derivative
taken in R, expressed in body axes) [rad/s²], None for a fixed reference (laws without
feed-forward ignore it).
Output: the demanded control torque about the centre of mass in body axes [N m], shape (3,).

Assumptions: unit quaternions; the caller expresses the reference rate in body axes
(``omega_RN_B = C(q_BR) omega_RN_R``); actuator limits are the allocator's business.

Source: interface only; conventions as in :mod:`flight_sw.quaternion`.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np


class AttitudeController(Protocol):
    """An attitude control law producing a body torque demand."""

    def torque_B_Nm(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
        domega_RN_B: np.ndarray | None = None,
    ) -> np.ndarray:
        """The demanded torque in body axes [N m], shape (3,)."""
        ...


class InertiaAware(Protocol):
    """A law built on a model of the mass properties that an identifier can update.

    The flight computer calls :meth:`set_inertia_B_kgm2` when an inertia estimator (e.g.
    :mod:`flight_sw.estimation.rls_inertia`) has a new estimate; laws that do not use the
    inertia simply do not implement it.
    """

    def set_inertia_B_kgm2(self, inertia_B_kgm2: np.ndarray) -> None:
        """Use ``inertia_B_kgm2`` (3×3, body axes, about the centre of mass) from now on."""
        ...


class PoseController(Protocol):
    """A coupled 6-DoF law producing force and torque together (e.g. dual-quaternion laws).

    Inputs: ``t_ns`` [integer ns]; ``q_BN``/``omega_BN_B`` the estimated attitude and body
    rate [rad/s]; ``r_N_m``/``v_N_m_s`` position [m] and velocity [m/s] in the navigation
    frame N (inertial, or the Hill frame of a relative-navigation sensor); ``q_RN``,
    ``omega_RN_B`` the reference attitude and rate (body axes); ``r_ref_N_m``,
    ``v_ref_N_m_s`` the reference position and velocity in N.
    Output: shape (6,): the demanded force on the vehicle in body axes [N] (first three)
    and torque about the centre of mass in body axes [N m] (last three), the row order of
    the 6-row effectiveness matrix.
    """

    def wrench_B(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        r_N_m: np.ndarray,
        v_N_m_s: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
        r_ref_N_m: np.ndarray,
        v_ref_N_m_s: np.ndarray,
    ) -> np.ndarray:
        """The demanded wrench [force_B_N; torque_B_Nm], shape (6,)."""
        ...


class TranslationController(Protocol):
    """A translation control law producing a body-axes force demand (6-DoF runs).

    Inputs: ``t_ns`` [integer ns]; ``q_BN`` the estimated attitude (scalar-first, maps the
    navigation frame N to body B), used to express the force in body axes;
    ``r_N_m``/``v_N_m_s`` the measured position [m] and velocity [m/s] of the vehicle in
    the navigation frame N (inertial, or the Hill frame of a relative-navigation sensor);
    ``r_ref_N_m``/``v_ref_N_m_s`` the reference position and velocity in N.
    Output: the demanded control force on the vehicle in body axes [N], shape (3,).
    """

    def force_B_N(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        r_N_m: np.ndarray,
        v_N_m_s: np.ndarray,
        r_ref_N_m: np.ndarray,
        v_ref_N_m_s: np.ndarray,
    ) -> np.ndarray:
        """The demanded force in body axes [N], shape (3,)."""
        ...


def error_limit(kp: np.ndarray, kd: np.ndarray, max_rate: float) -> np.ndarray:
    """Per-axis clip of the proportional error so a saturated PD law settles at ``max_rate``.

    Far from the target the law ``−K_p sat_L(e) − K_d ė`` drives ``ė`` towards
    ``K_p L / K_d``; ``L = K_d max_rate / K_p`` makes that the rate limit (Wie & Lu 1995).
    Axes with ``K_p = 0`` or no limit (``max_rate = inf``) get ``inf``.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        lim = kd * max_rate / kp
    return np.where(np.isfinite(lim), lim, np.inf)
