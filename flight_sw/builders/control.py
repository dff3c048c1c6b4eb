"""Builders of the control laws: ``[flight_sw.controller]`` and ``[flight_sw.translation]``.

What it does: one builder per ``kind`` in three registries: attitude laws
(:data:`CONTROLLERS`: quaternion PD/PID from gains or a bandwidth, seed 003's cascade
from Table 1, gains or an LQR design, seed 001's direct-parametric MRP law), coupled 6-DoF
laws (:data:`POSE_CONTROLLERS`: seed 000's NFTSM and TSM, every field optional, nominal
mass and inertia from the vehicle) and translation laws
(:data:`TRANSLATION_CONTROLLERS`: position PD, with its optional hold position). Angles
and rates in the file are in degrees, converted here. The two laws designed with
scipy.linalg (the cascade's Riccati solution, the MRP law's block matrices) are imported
when chosen, so a flight software that uses neither starts without scipy.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from types import MappingProxyType

import numpy as np

from dbc.schema import Table
from flight_sw.builders.vehicle import (
    DEG_RAD,
    Vehicle,
    dataclass_params,
    matrix,
    max_rate,
    nominal_mass,
)
from flight_sw.control.base import AttitudeController, PoseController, TranslationController
from flight_sw.control.nftsm_dq import NftsmDq, NftsmDqParams
from flight_sw.control.position_pd import PositionPd, PositionPdParams
from flight_sw.control.quaternion_pd import QuaternionPd, QuaternionPdParams
from flight_sw.control.quaternion_pid import QuaternionPid, QuaternionPidParams
from flight_sw.control.tsm_dq import TsmDq, TsmDqParams


def _quaternion_pd_params(t: Table, v: Vehicle) -> QuaternionPdParams:
    rate_limit = max_rate(t)
    if t.has("kp_Nm"):
        return QuaternionPdParams(
            kp_Nm=t.vector3("kp_Nm"),
            kd_Nms=t.vector3("kd_Nms"),
            max_rate_rad_s=rate_limit,
        )
    return QuaternionPdParams.from_bandwidth(
        np.diag(v.inertia_B_kgm2).tolist(),
        t.number("natural_frequency_rad_s", lo=0.0, lo_open=True),
        t.number("damping_ratio", lo=0.0),
        rate_limit,
    )


def _quaternion_pd(t: Table, v: Vehicle) -> AttitudeController:
    return QuaternionPd(_quaternion_pd_params(t, v))


def _quaternion_pid(t: Table, v: Vehicle) -> AttitudeController:
    return QuaternionPid(
        QuaternionPidParams(
            pd=_quaternion_pd_params(t, v),
            integral_time_s=t.number("integral_time_s", lo=0.0, lo_open=True),
            integral_band_rad=t.number("integral_band_deg", 2.0, lo=0.0, lo_open=True) * DEG_RAD,
            max_integral_torque_Nm=t.number(
                "max_integral_torque_Nm", math.inf, lo=0.0, lo_open=True
            )
            if t.has("max_integral_torque_Nm")
            else math.inf,
        )
    )


def _cascade_lqr(t: Table, v: Vehicle) -> AttitudeController:
    """Seed 003: Table 1 gains (``table1 = true``), explicit gains, or an LQR design."""
    from flight_sw.control.cascade_lqr import CascadeLqr, CascadeLqrDesign, CascadeLqrParams

    rate_limit = max_rate(t)
    table1 = t.raw("table1", False)
    if not isinstance(table1, bool):
        raise t.error("table1", table1, "true or false")
    if table1:
        return CascadeLqr(CascadeLqrParams.from_table1(rate_limit))
    if t.has("outer_kp_1_s"):
        return CascadeLqr(
            CascadeLqrParams(
                outer_kp_1_s=t.vector3("outer_kp_1_s"),
                outer_kd=t.vector3("outer_kd"),
                inner_kp_Nms=t.vector3("inner_kp_Nms"),
                max_rate_rad_s=rate_limit,
            )
        )
    design = CascadeLqrDesign(
        inner_kp_Nms=t.vector3("inner_kp_Nms"),
        q_angle=t.number("q_angle", lo=0.0, lo_open=True),
        q_rate=t.number("q_rate", 0.0, lo=0.0),
        r=t.number("r", 1.0, lo=0.0, lo_open=True),
        max_rate_rad_s=rate_limit,
    )
    return CascadeLqr.from_design(design, v.inertia_B_kgm2)


def _mrp_direct_parametric(t: Table, v: Vehicle) -> AttitudeController:
    """Seed 001 §3: cases 1-3 of §5, or an explicit F0 (6×6) and Z (3×6)."""
    from flight_sw.control.mrp_direct_parametric import (
        MrpDirectParametric,
        MrpDirectParametricParams,
    )

    if t.has("f0"):
        params = MrpDirectParametricParams(
            f0=tuple(tuple(float(x) for x in r) for r in matrix(t, "f0", 6, 6)),
            z=tuple(tuple(float(x) for x in r) for r in matrix(t, "z", 3, 6)),
        )
    else:
        case = t.integer("case", 1, lo=1)
        if case > 3:
            raise t.error("case", case, "1, 2 or 3 (seed 001 §5)")
        params = MrpDirectParametricParams.from_case(case)
    return MrpDirectParametric(params, v.inertia_B_kgm2)


def _nftsm_dq(t: Table, v: Vehicle) -> PoseController:
    return NftsmDq(dataclass_params(t, NftsmDqParams, nominal_mass(v)))


def _tsm_dq(t: Table, v: Vehicle) -> PoseController:
    return TsmDq(dataclass_params(t, TsmDqParams, nominal_mass(v)))


def _position_pd(t: Table, v: Vehicle) -> tuple[TranslationController, np.ndarray | None]:
    max_force = t.number("max_force_N", lo=0.0, lo_open=True) if t.has("max_force_N") else math.inf
    max_speed = (
        t.number("max_speed_m_s", lo=0.0, lo_open=True) if t.has("max_speed_m_s") else math.inf
    )
    if t.has("kp_N_m"):
        params = PositionPdParams(t.vector3("kp_N_m"), t.vector3("kd_N_s_m"), max_force, max_speed)
    else:
        params = PositionPdParams.from_bandwidth(
            v.mass_kg,
            t.number("natural_frequency_rad_s", lo=0.0, lo_open=True),
            t.number("damping_ratio", lo=0.0),
            max_force,
            max_speed,
        )
    r_target = np.array(t.vector3("r_target_N_m")) if t.has("r_target_N_m") else None
    return PositionPd(params), r_target


# Attitude laws (``[flight_sw.controller] kind``).
CONTROLLERS: Mapping[str, Callable[[Table, Vehicle], AttitudeController]] = MappingProxyType({
    "quaternion_pd": _quaternion_pd,
    "quaternion_pid": _quaternion_pid,
    "cascade_lqr": _cascade_lqr,
    "mrp_direct_parametric": _mrp_direct_parametric,
})

# Coupled 6-DoF laws (force and torque together), chosen by [flight_sw.controller] kind too.
POSE_CONTROLLERS: Mapping[str, Callable[[Table, Vehicle], PoseController]] = MappingProxyType({
    "nftsm_dq": _nftsm_dq,
    "tsm_dq": _tsm_dq,
})

# Translation laws (``[flight_sw.translation] kind``): the force of an attitude-only law.
TRANSLATION_CONTROLLERS: Mapping[
    str, Callable[[Table, Vehicle], tuple[TranslationController, np.ndarray | None]]
] = MappingProxyType({"position_pd": _position_pd})
