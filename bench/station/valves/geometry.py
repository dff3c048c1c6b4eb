"""Mounting geometry of a thruster, and its ``misaligned`` fault.

What it does
    ``ThrusterGeometry`` validates one thruster's mounting and precomputes its torque arm;
    ``misaligned_geometry`` validates the parameters of a ``misaligned`` fault and rotates
    a geometry's thrust direction by it. The thruster set
    (:mod:`bench.station.valves.thruster_set`) builds its wrench rows from these.

Inputs / outputs and units
    - ``ThrusterGeometry``: ``r_thr_B_m`` the thrust application point relative to the
      centre of mass, body axes [m]; ``d_thr_B`` the unit direction of the force the
      thruster exerts *on the vehicle* (opposite to the plume), body axes [-];
      ``torque_arm_B_m`` = r × d [m], the torque per newton of thrust.
    - ``misaligned_geometry(nominal, params, source)`` → (recorded parameters, rotated
      geometry); bad parameters raise ``ConfigError(source, key, value, expected)``.

The ``misaligned`` fault
    ``angle_deg`` [deg] in [−180, 180] and ``axis_B`` (unit vector, body axes [-]): the
    thrust direction is rotated by the angle about the axis (right hand),
    d' = R(axis, angle) d (Rodrigues' rotation formula, applied through the quaternion
    ``quat_from_axis_angle``), so both the force row d' and the torque row r × d' of that
    thruster change; models a bent nozzle or a shifted mount. The rotated direction is
    renormalised (round-off) so that it stays a unit vector.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from mypy_extensions import mypyc_attr

from bench.station.dynamics.rigid_body import Vec3, quat_from_axis_angle, rotate_B_to_N
from bench.station.valves.params import FaultParams
from dbc import validation as check
from dbc.errors import ConfigError
from dbc.faults import MISALIGNED

FAULT_MISALIGNED = MISALIGNED
MISALIGNED_PARAMS = ("angle_deg", "axis_B")
MAX_MISALIGNMENT_DEG = 180.0
"""|angle_deg| of a ``misaligned`` fault is at most this (any rotation is reachable)."""


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class ThrusterGeometry:
    """Mounting of one thruster: application point [m] and unit force direction, body axes."""

    r_thr_B_m: Vec3
    d_thr_B: Vec3
    source: str = field(default="ThrusterGeometry", compare=False, repr=False, kw_only=True)
    torque_arm_B_m: Vec3 = field(init=False, repr=False, compare=False)
    """r × d [m]: torque per newton of thrust."""

    def __post_init__(self) -> None:
        # getattr: the fields as given (compiled code would cast a read to Vec3 first)
        r = check.triple(self.source, "r_thr_B_m", getattr(self, "r_thr_B_m"))  # noqa: B009
        d = check.unit_triple(self.source, "d_thr_B", getattr(self, "d_thr_B"))  # noqa: B009
        object.__setattr__(self, "r_thr_B_m", r)
        object.__setattr__(self, "d_thr_B", d)
        object.__setattr__(
            self,
            "torque_arm_B_m",
            (r[1] * d[2] - r[2] * d[1], r[2] * d[0] - r[0] * d[2], r[0] * d[1] - r[1] * d[0]),
        )


def misaligned_geometry(
    nominal: ThrusterGeometry, params: dict[str, object], source: str
) -> tuple[FaultParams, ThrusterGeometry]:
    """Validated ``misaligned`` parameters and ``nominal`` with its direction rotated."""
    for key, value in params.items():
        if key not in MISALIGNED_PARAMS:
            raise ConfigError(
                source, key, value, f"no such parameter (expected {list(MISALIGNED_PARAMS)})"
            )
    for key in MISALIGNED_PARAMS:
        if key not in params:
            raise ConfigError(source, key, None, f"a value (required by {FAULT_MISALIGNED!r})")
    angle = check.number(
        source, "angle_deg", params["angle_deg"], -MAX_MISALIGNMENT_DEG, MAX_MISALIGNMENT_DEG,
        unit="deg",
    )
    axis = check.unit_triple(source, "axis_B", params["axis_B"])
    d = rotate_B_to_N(quat_from_axis_angle(axis, math.radians(angle)), nominal.d_thr_B)
    # Renormalise away round-off so the geometry stays a unit direction.
    n = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    rotated = ThrusterGeometry(
        nominal.r_thr_B_m, (d[0] / n, d[1] / n, d[2] / n), source=nominal.source
    )
    return {"angle_deg": angle, "axis_B": axis}, rotated
