"""Prescribed disturbance force and torque: a constant plus a sum of sinusoids.

What it does
    d(t) = c + Σ_k a_k sin(ω_k t + φ_k), per component, for the force [N] and the torque
    [N·m] separately; t [s] is simulation time. Seed 000 §V uses exactly this form:
    u_d = [0.06 + 0.03 sin(0.6t), 0.05 + 0.04 sin(0.9t), 0.04 + 0.01 sin(0.5t)] N and
    τ_d = [2e-5 + 5e-4 sin(0.8t), 3e-5 + 3e-4 sin(0.5t), 1e-5 + 7e-4 sin(0.3t)] N·m.

Frames
    The torque is in body axes. The force is in body axes (``force_frame = "body"``) or in
    the navigation frame of the translation state (``"nav"``: the inertial frame, or the
    Hill frame with HCW translation), rotated into body axes with the attitude:
    F_B = C(q_BN) C_IN(t) F_nav (``TranslationModel.nav_to_inertial``).

Assumptions: the disturbance acts through the centre of mass (the torque is given
separately) and does not depend on the state besides the attitude for ``"nav"`` forces.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from mypy_extensions import mypyc_attr

from bench.station.dynamics.rigid_body import (
    ZERO_VEC3,
    MassProperties,
    Quat,
    Vec3,
    Wrench,
    rotate_N_to_B,
)
from bench.station.dynamics.translation import InertialTranslation, TranslationModel
from dbc import validation as check
from dbc.errors import ConfigError

FORCE_FRAMES = ("body", "nav")
"""Frames a disturbance force may be given in (module docstring)."""
VEC3_LEN = 3


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class Sinusoid:
    """a sin(ω t + φ): amplitude 3-vector (unit of the quantity), ω [rad/s], φ [rad]."""

    amplitude: Vec3
    omega_rad_s: float
    phase_rad: float = 0.0
    source: str = field(default="Sinusoid", compare=False, repr=False, kw_only=True)

    def __post_init__(self) -> None:
        # getattr: the fields as given (compiled code would cast a read to its type first)
        src = self.source
        amplitude = getattr(self, "amplitude")  # noqa: B009
        object.__setattr__(self, "amplitude", check.triple(src, "amplitude", amplitude))
        for key in ("omega_rad_s", "phase_rad"):
            object.__setattr__(self, key, check.number(src, key, getattr(self, key)))


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class DisturbanceParams:
    """Constant force [N] / torque [N·m] plus sinusoids, and the force's frame."""

    force_N: Vec3 = ZERO_VEC3
    force_sinusoids: tuple[Sinusoid, ...] = ()
    torque_Nm: Vec3 = ZERO_VEC3
    torque_sinusoids: tuple[Sinusoid, ...] = ()
    force_frame: str = "body"
    source: str = field(default="DisturbanceParams", compare=False, repr=False, kw_only=True)

    def __post_init__(self) -> None:
        src = self.source
        # getattr: the fields as given (compiled code would cast a read to Vec3 first)
        for key in ("force_N", "torque_Nm"):
            object.__setattr__(self, key, check.triple(src, key, getattr(self, key)))
        for key in ("force_sinusoids", "torque_sinusoids"):
            items = tuple(getattr(self, key))
            if not all(isinstance(s, Sinusoid) for s in items):
                raise ConfigError(src, key, getattr(self, key), "a sequence of Sinusoid")
            object.__setattr__(self, key, items)
        if self.force_frame not in FORCE_FRAMES:
            raise ConfigError(src, "force_frame", self.force_frame, f"one of {FORCE_FRAMES}")

    @property
    def is_zero(self) -> bool:
        """True if the disturbance is identically zero."""
        zero = (0.0, 0.0, 0.0)
        return (
            self.force_N == zero
            and self.torque_Nm == zero
            and all(s.amplitude == zero for s in (*self.force_sinusoids, *self.torque_sinusoids))
        )


SinusoidTerm = tuple[float, float, float, float, float]
"""A sinusoid as plain floats: (ω [rad/s], φ [rad], amplitude x, y, z)."""


def sinusoid_terms(sinusoids: Sequence[Sinusoid]) -> list[SinusoidTerm]:
    """The sinusoids as plain float tuples (what the hot path reads)."""
    return [(s.omega_rad_s, s.phase_rad, s.amplitude[0], s.amplitude[1], s.amplitude[2])
            for s in sinusoids]


def sinusoid_sum(t_s: float, constant: Vec3, sinusoids: Sequence[Sinusoid]) -> Vec3:
    """c + Σ a sin(ω t + φ) at ``t_s`` [s]."""
    return terms_sum(t_s, constant, sinusoid_terms(sinusoids))


def terms_sum(t_s: float, constant: Vec3, terms: list[SinusoidTerm]) -> Vec3:
    """:func:`sinusoid_sum` of sinusoids given as :func:`sinusoid_terms`."""
    x, y, z = constant
    for omega, phase, ax, ay, az in terms:
        k = math.sin(omega * t_s + phase)
        x += ax * k
        y += ay * k
        z += az * k
    return (x, y, z)


def sinusoid_sum_integral(
    t0_s: float, t1_s: float, constant: Vec3, sinusoids: Sequence[Sinusoid]
) -> Vec3:
    """∫_{t0}^{t1} (c + Σ a sin(ω t + φ)) dt, analytic (a ω = 0 term integrates as constant)."""
    dt = t1_s - t0_s
    out = [c * dt for c in constant]
    for s in sinusoids:
        w = s.omega_rad_s
        if w == 0.0:
            k = math.sin(s.phase_rad) * dt
        else:
            k = (math.cos(w * t0_s + s.phase_rad) - math.cos(w * t1_s + s.phase_rad)) / w
        for i in range(VEC3_LEN):
            out[i] += s.amplitude[i] * k
    return (out[0], out[1], out[2])


class Disturbance:
    """``EnvironmentModel`` of a prescribed disturbance (module docstring)."""

    def __init__(
        self, params: DisturbanceParams, translation: TranslationModel | None = None
    ) -> None:
        self.params = params
        self.translation: TranslationModel = translation or InertialTranslation()
        self._nav = params.force_frame == "nav"
        self._force0: Vec3 = params.force_N
        self._torque0: Vec3 = params.torque_Nm
        self._force_terms = sinusoid_terms(params.force_sinusoids)
        self._torque_terms = sinusoid_terms(params.torque_sinusoids)

    def force_nav_or_body_N(self, t_s: float) -> Vec3:
        """The force as given, in its own frame (body or navigation) [N]."""
        return terms_sum(t_s, self._force0, self._force_terms)

    def wrench_B(self, t_s: float, q_BN: Quat, mp: MassProperties) -> Wrench:
        """Disturbance force [N] and torque [N·m] in body axes at ``t_s``."""
        f = self.force_nav_or_body_N(t_s)
        if self._nav:
            f = rotate_N_to_B(q_BN, self.translation.nav_to_inertial(t_s, f))
        tq = terms_sum(t_s, self._torque0, self._torque_terms)
        return (f[0], f[1], f[2], tq[0], tq[1], tq[2])
