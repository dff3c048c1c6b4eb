"""Builders of the FDIR strategies: ``[flight_sw.thruster_fdir]`` and ``[flight_sw.sensor_fdir]``.

What it does: one builder per strategy (:data:`THRUSTER_FDIR`, run in this order: the
valve-status FDIR, the acceleration-residual FDIR; :data:`SENSOR_FDIR`: frozen values).
The residual FDIR gets the nominal vehicle (inertia, mass, each thruster's own maximum
thrust, minimum on-time, the control and IMU periods) and takes the valve timing keys it
does not set from the vehicle's valve data (:mod:`flight_sw.fdir.valve_timing`'s defaults
when the file has none).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType

from dbc.schema import Table
from flight_sw.builders.vehicle import Vehicle
from flight_sw.fdir.base import ThrusterFdirStrategy
from flight_sw.fdir.frozen_sensor import FrozenSensorMonitor, FrozenSensorParams
from flight_sw.fdir.rate_residual import RateResidualFdir, RateResidualParams
from flight_sw.fdir.valve_status import ValveStatusFdir, ValveStatusParams


def _valve_status(t: Table, v: Vehicle) -> ThrusterFdirStrategy:
    d = ValveStatusParams()
    params = ValveStatusParams(
        stuck_closed_samples=t.integer("stuck_closed_samples", d.stuck_closed_samples, lo=1),
        window_samples=t.integer("window_samples", d.window_samples, lo=1),
        stuck_open_samples=t.integer("stuck_open_samples", d.stuck_open_samples, lo=1),
        quiet_cycles=t.integer("quiet_cycles", d.quiet_cycles, lo=1),
    )
    return ValveStatusFdir(len(v.r_thr_B_m), params)


def _rate_residual(t: Table, v: Vehicle) -> ThrusterFdirStrategy:
    d = RateResidualParams()
    vt = v.valve_timing  # the vehicle's valve data (defaults: flight_sw.fdir.valve_timing)
    use_accel = t.raw("use_accel", d.use_accel)
    if not isinstance(use_accel, bool):
        raise t.error("use_accel", use_accel, "true or false")
    params = RateResidualParams(
        window_s=t.number("window_s", d.window_s, lo=0.0, lo_open=True),
        threshold=t.number("threshold", d.threshold, lo=0.0, lo_open=True),
        glr_threshold=t.number("glr_threshold", d.glr_threshold, lo=0.0, lo_open=True),
        persistence_cycles=t.integer("persistence_cycles", d.persistence_cycles, lo=1),
        isolation_cycles=t.integer("isolation_cycles", d.isolation_cycles, lo=1),
        explained_fraction=t.number(
            "explained_fraction", d.explained_fraction, lo=0.0, lo_open=True, hi=1.0
        ),
        isolation_margin=t.number("isolation_margin", d.isolation_margin, lo=0.0),
        command_delay_s=t.number("command_delay_s", vt.command_delay_s, lo=0.0),
        valve_open_delay_s=t.number("valve_open_delay_s", vt.open_delay_s, lo=0.0),
        valve_close_delay_s=t.number("valve_close_delay_s", vt.close_delay_s, lo=0.0),
        valve_rise_tau_s=t.number("valve_rise_tau_s", vt.rise_tau_s, lo=0.0),
        valve_tail_tau_s=t.number("valve_tail_tau_s", vt.tail_tau_s, lo=0.0),
        edge_uncertainty_s=t.number("edge_uncertainty_s", d.edge_uncertainty_s, lo=0.0),
        gyro_noise_rad_s=t.number("gyro_noise_rad_s", d.gyro_noise_rad_s, lo=0.0, lo_open=True),
        accel_noise_m_s2=t.number("accel_noise_m_s2", d.accel_noise_m_s2, lo=0.0, lo_open=True),
        accel_bias_m_s2=t.number("accel_bias_m_s2", d.accel_bias_m_s2, lo=0.0),
        model_rel_error=t.number("model_rel_error", d.model_rel_error, lo=0.0),
        thrust_rel_error=t.number("thrust_rel_error", d.thrust_rel_error, lo=0.0),
        bias_time_constant_s=t.number(
            "bias_time_constant_s", d.bias_time_constant_s, lo=0.0, lo_open=True
        ),
        use_accel=use_accel,
    )
    return RateResidualFdir(
        v.effectiveness,
        v.inertia_B_kgm2,
        v.mass_kg,
        v.max_thrust_each_N,
        v.min_on_s,
        v.control_period_ns,
        v.imu_period_ns,
        params,
    )


def _frozen_value(t: Table, v: Vehicle) -> FrozenSensorMonitor:
    d = FrozenSensorParams()
    params = FrozenSensorParams(
        imu_rate_samples=t.integer("imu_rate_samples", d.imu_rate_samples, lo=2),
        str_quat_samples=t.integer("str_quat_samples", d.str_quat_samples, lo=2),
    )
    return FrozenSensorMonitor(params.by_message())


# Strategies run in this order (the first to isolate in a cycle wins).
THRUSTER_FDIR: Mapping[str, Callable[[Table, Vehicle], ThrusterFdirStrategy]] = MappingProxyType({
    "valve_status": _valve_status,
    "rate_residual": _rate_residual,
})

SENSOR_FDIR: Mapping[str, Callable[[Table, Vehicle], FrozenSensorMonitor]] = MappingProxyType({
    "frozen_value": _frozen_value
})
