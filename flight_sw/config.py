"""Flight-software configuration: a JSON file -> the wired :class:`FlightComputer`.

The file (written by the bench's orchestrator from the scenario, or by hand for a real
vehicle) holds the nominal vehicle (mass, inertia), the thruster geometry, the manoeuvre
and the ``flight_sw`` table of the scenario: which estimator, controller, allocator and
modulator to use, with their parameters. Each strategy is chosen by ``kind`` from a
registry: a new algorithm is a new file plus one registry line. Every bad value raises
ConfigError naming the scenario file and the dotted key (``flight_sw.modulator.km``).
Angles are converted to radians here.

Optional tables of ``flight_sw`` (issue 4):
- ``translation`` (``kind`` from :data:`TRANSLATION_CONTROLLERS`): makes the vehicle 6-DoF;
  the allocator then gets the 6 wrench rows (force, torque) instead of the 3 torque rows.
  ``r_target_N_m`` (optional) is the position to hold, else the first navigation fix.
- ``thruster_fdir``: one sub-table per strategy of :data:`THRUSTER_FDIR`
  (``[flight_sw.thruster_fdir.valve_status]``, ``[flight_sw.thruster_fdir.rate_residual]``)
  with its parameters, and ``precompute_masks`` (default true: the allocators for every
  single-thruster mask are built at start-up, so a reconfiguration costs nothing in the
  cycle; ≈ 0.2 s each for 16 thrusters and 6 rows).
- ``sensor_fdir`` (``kind`` from :data:`SENSOR_FDIR`): frozen-sensor counts; defaults
  apply when absent.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from dbc.errors import ConfigError
from dbc.schema import Table
from flight_sw.allocation.base import Allocator
from flight_sw.allocation.effectiveness import effectiveness_matrix
from flight_sw.allocation.pseudo_inverse import PseudoInverseAllocator, PseudoInverseParams
from flight_sw.allocation.qp_osqp import BoundedQpAllocator, BoundedQpParams
from flight_sw.allocation.robust_lft import RobustLftAllocator, RobustLftParams
from flight_sw.allocation.robust_polyhedral import RobustPolyhedralAllocator
from flight_sw.allocation.robust_polytopic import RobustParams, RobustPolytopicAllocator
from flight_sw.computer import (
    DEFAULT_CYCLE_PHASE_NS,
    DEFAULT_NAV_TIMEOUT_NS,
    FlightComputer,
    Timeline,
)
from flight_sw.control.base import AttitudeController, PoseController, TranslationController
from flight_sw.control.cascade_lqr import CascadeLqr, CascadeLqrDesign, CascadeLqrParams
from flight_sw.control.mrp_direct_parametric import MrpDirectParametric, MrpDirectParametricParams
from flight_sw.control.nftsm_dq import NftsmDq, NftsmDqParams
from flight_sw.control.position_pd import PositionPd, PositionPdParams
from flight_sw.control.quaternion_pd import QuaternionPd, QuaternionPdParams
from flight_sw.control.quaternion_pid import QuaternionPid, QuaternionPidParams
from flight_sw.control.tsm_dq import TsmDq, TsmDqParams
from flight_sw.estimation.base import AttitudeEstimator, InertiaIdentifier
from flight_sw.estimation.mekf import Mekf, MekfParams
from flight_sw.estimation.rls_inertia import RlsInertiaIdentifier, RlsInertiaParams
from flight_sw.fdir.base import ThrusterFdirStrategy
from flight_sw.fdir.frozen_sensor import FrozenSensorMonitor, FrozenSensorParams
from flight_sw.fdir.rate_residual import RateResidualFdir, RateResidualParams
from flight_sw.fdir.sensor_watchdog import LOST_AFTER_PERIODS, SensorWatchdog
from flight_sw.fdir.thruster_fdir import ThrusterFdir
from flight_sw.fdir.valve_status import ValveStatusFdir, ValveStatusParams
from flight_sw.fdir.valve_timing import DEFAULT_TIMING, ValveTiming
from flight_sw.guidance.base import AttitudeGuidance
from flight_sw.guidance.mrp_polynomial import MrpPolynomialGuidance
from flight_sw.modulation.base import Modulator
from flight_sw.modulation.proportional import ProportionalModulator
from flight_sw.modulation.pwpf import PwpfModulator, PwpfParams
from flight_sw.modulation.remainder import RemainderModulator, RemainderParams
from flight_sw.modulation.schmitt import SchmittModulator, SchmittParams

DEG_RAD = math.pi / 180.0
ARCSEC_RAD = DEG_RAD / 3600.0
SQRT_HOUR_S = 60.0
NS_PER_S = 1_000_000_000
TORQUE_ROWS = slice(3, 6)
WRENCH_ROWS = slice(0, 6)


class _NoAttitudeLaw:
    """Stands in for the attitude law when a coupled 6-DoF law commands the torque."""

    def torque_B_Nm(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
        domega_RN_B: np.ndarray | None = None,
    ) -> np.ndarray:
        """Never called while the pose law is set (see FlightComputer.cycle)."""
        raise RuntimeError("the coupled 6-DoF law commands the torque")


class Vehicle:
    """Nominal vehicle data the strategies are built from."""

    def __init__(self, t: Table, root: Table) -> None:
        self.mass_kg = t.number("mass_kg", lo=0.0, lo_open=True)
        self.inertia_B_kgm2 = np.array(t.matrix3("inertia_B_kgm2"))
        t.done()
        thr = root.tables("thrusters")
        if not thr:
            raise root.error("thrusters", [], "at least one thruster")
        self.r_thr_B_m = np.array([x.vector("r_thr_B_m", 3) for x in thr])
        self.d_thr_B = np.array([x.vector("d_thr_B", 3) for x in thr])
        # one maximum for all, or each thruster its own (e.g. seed 001's opposing valves of
        # unequal bounds); every consumer gets the per-thruster vector (n,) [N]
        default_N = root.number("max_thrust_N", lo=0.0, lo_open=True)
        self.max_thrust_each_N = np.array(
            [x.number("max_thrust_N", default_N, lo=0.0, lo_open=True) for x in thr]
        )
        for x in thr:
            x.done()
        self.min_on_s = root.number("min_on_s", lo=0.0)
        self.valve_timing = _valve_timing(root)
        self.effectiveness = effectiveness_matrix(self.r_thr_B_m, self.d_thr_B)
        self.demand_rows = TORQUE_ROWS  # WRENCH_ROWS once a translation controller is set
        self.control_period_ns = 0
        self.imu_period_ns = 0


def _valve_timing(root: Table) -> ValveTiming:
    """The vehicle's valve timing from the optional ``valve_timing`` table (each key
    optional; defaults: :mod:`flight_sw.fdir.valve_timing`)."""
    if not root.has("valve_timing"):
        return DEFAULT_TIMING
    t = root.table("valve_timing")
    d = DEFAULT_TIMING
    timing = ValveTiming(
        command_delay_s=t.number("command_delay_s", d.command_delay_s, lo=0.0),
        open_delay_s=t.number("open_delay_s", d.open_delay_s, lo=0.0),
        close_delay_s=t.number("close_delay_s", d.close_delay_s, lo=0.0),
        rise_tau_s=t.number("rise_tau_s", d.rise_tau_s, lo=0.0),
        tail_tau_s=t.number("tail_tau_s", d.tail_tau_s, lo=0.0),
    )
    t.done()
    return timing


def _mekf(t: Table, v: Vehicle) -> AttitudeEstimator:
    return Mekf(
        MekfParams(
            gyro_arw_rad_sqrt_s=t.number("gyro_arw_deg_sqrt_h", lo=0.0) * DEG_RAD / SQRT_HOUR_S,
            gyro_bias_rw_rad_s_sqrt_s=t.number("gyro_bias_rw_deg_h_sqrt_h", lo=0.0)
            * DEG_RAD
            / 3600.0
            / SQRT_HOUR_S,
            star_tracker_sigma_rad=t.number("star_tracker_noise_arcsec", lo=0.0, lo_open=True)
            * ARCSEC_RAD,
            initial_attitude_sigma_rad=t.number(
                "initial_attitude_sigma_deg", 0.1, lo=0.0, lo_open=True
            )
            * DEG_RAD,
            initial_bias_sigma_rad_s=t.number("initial_bias_sigma_deg_h", lo=0.0, lo_open=True)
            * DEG_RAD
            / 3600.0,
        )
    )


def _quaternion_pd_params(t: Table, v: Vehicle) -> QuaternionPdParams:
    max_rate = (
        t.number("max_rate_deg_s", lo=0.0, lo_open=True) * DEG_RAD
        if t.has("max_rate_deg_s")
        else math.inf
    )
    if t.has("kp_Nm"):
        return QuaternionPdParams(
            kp_Nm=t.vector3("kp_Nm"),
            kd_Nms=t.vector3("kd_Nms"),
            max_rate_rad_s=max_rate,
        )
    return QuaternionPdParams.from_bandwidth(
        np.diag(v.inertia_B_kgm2).tolist(),
        t.number("natural_frequency_rad_s", lo=0.0, lo_open=True),
        t.number("damping_ratio", lo=0.0),
        max_rate,
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


def _max_rate(t: Table) -> float:
    """Optional ``max_rate_deg_s`` in rad/s (inf when absent)."""
    if not t.has("max_rate_deg_s"):
        return math.inf
    return t.number("max_rate_deg_s", lo=0.0, lo_open=True) * DEG_RAD


def _cascade_lqr(t: Table, v: Vehicle) -> AttitudeController:
    """Seed 003: Table 1 gains (``table1 = true``), explicit gains, or an LQR design."""
    max_rate = _max_rate(t)
    table1 = t.raw("table1", False)
    if not isinstance(table1, bool):
        raise t.error("table1", table1, "true or false")
    if table1:
        return CascadeLqr(CascadeLqrParams.from_table1(max_rate))
    if t.has("outer_kp_1_s"):
        return CascadeLqr(
            CascadeLqrParams(
                outer_kp_1_s=t.vector3("outer_kp_1_s"),
                outer_kd=t.vector3("outer_kd"),
                inner_kp_Nms=t.vector3("inner_kp_Nms"),
                max_rate_rad_s=max_rate,
            )
        )
    design = CascadeLqrDesign(
        inner_kp_Nms=t.vector3("inner_kp_Nms"),
        q_angle=t.number("q_angle", lo=0.0, lo_open=True),
        q_rate=t.number("q_rate", 0.0, lo=0.0),
        r=t.number("r", 1.0, lo=0.0, lo_open=True),
        max_rate_rad_s=max_rate,
    )
    return CascadeLqr.from_design(design, v.inertia_B_kgm2)


def _matrix(t: Table, key: str, rows: int, cols: int) -> np.ndarray:
    value = t.raw(key)
    try:
        m = np.array(value, dtype=float)
    except (TypeError, ValueError):
        m = np.zeros(0)
    if m.shape != (rows, cols) or not np.all(np.isfinite(m)):
        raise t.error(key, value, f"a {rows}x{cols} matrix of finite numbers")
    return m


def _mrp_direct_parametric(t: Table, v: Vehicle) -> AttitudeController:
    """Seed 001 §3: cases 1-3 of §5, or an explicit F0 (6×6) and Z (3×6)."""
    if t.has("f0"):
        params = MrpDirectParametricParams(
            f0=tuple(tuple(float(x) for x in r) for r in _matrix(t, "f0", 6, 6)),
            z=tuple(tuple(float(x) for x in r) for r in _matrix(t, "z", 3, 6)),
        )
    else:
        case = t.integer("case", 1, lo=1)
        if case > 3:
            raise t.error("case", case, "1, 2 or 3 (seed 001 §5)")
        params = MrpDirectParametricParams.from_case(case)
    return MrpDirectParametric(params, v.inertia_B_kgm2)


def _dataclass_params(t: Table, cls: Any, defaults: dict[str, Any]) -> Any:
    """``cls`` built from the table: every field optional, read by its default's type."""
    kwargs: dict[str, Any] = {}
    for f in dataclasses.fields(cls):
        default = defaults.get(f.name, f.default)
        if not t.has(f.name):
            kwargs[f.name] = default
        elif isinstance(default, bool):
            value = t.raw(f.name)
            if not isinstance(value, bool):
                raise t.error(f.name, value, "true or false")
            kwargs[f.name] = value
        elif isinstance(default, tuple):
            kwargs[f.name] = t.vector3(f.name)
        else:
            kwargs[f.name] = t.number(f.name)
    return cls(**kwargs)


def _nominal_mass(v: Vehicle) -> dict[str, Any]:
    j = v.inertia_B_kgm2
    return {
        "mass_kg": v.mass_kg,
        "inertia_B_kgm2": (float(j[0, 0]), float(j[1, 1]), float(j[2, 2])),
    }


def _nftsm_dq(t: Table, v: Vehicle) -> PoseController:
    return NftsmDq(_dataclass_params(t, NftsmDqParams, _nominal_mass(v)))


def _tsm_dq(t: Table, v: Vehicle) -> PoseController:
    return TsmDq(_dataclass_params(t, TsmDqParams, _nominal_mass(v)))


def _upper_N(v: Vehicle) -> tuple[float, ...]:
    return tuple(float(x) for x in v.max_thrust_each_N)


def _pseudo_inverse(t: Table, v: Vehicle) -> Allocator:
    """Seeds 003/000 baseline; each thruster bounded by its own maximum thrust."""
    b = v.effectiveness[v.demand_rows]
    return PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_N=_upper_N(v)))


def _qp_osqp(t: Table, v: Vehicle) -> Allocator:
    """Seed 000 eqs. 27-32: bounded least-shift allocation, an OSQP QP."""
    d = BoundedQpParams(upper_N=1.0)
    m = v.demand_rows.stop - v.demand_rows.start
    weights = t.vector("demand_weights", m) if t.has("demand_weights") else None
    params = BoundedQpParams(
        upper_N=_upper_N(v),
        regularization=t.number("regularization", d.regularization, lo=0.0, lo_open=True),
        demand_weights=weights,
    )
    return BoundedQpAllocator(v.effectiveness[v.demand_rows], params)


def _robust_params(t: Table, v: Vehicle) -> RobustParams:
    d = RobustParams(upper_N=1.0)
    weights = t.raw("basis_weights", list(d.basis_weights))
    if not (
        isinstance(weights, list)
        and weights
        and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in weights)
    ):
        raise t.error("basis_weights", weights, "a non-empty list of numbers")
    return RobustParams(
        upper_N=_upper_N(v),
        rho=t.number("rho", d.rho, lo=0.0),
        basis_weights=tuple(float(x) for x in weights),
    )


def _robust_polyhedral(t: Table, v: Vehicle) -> Allocator:
    """Seed 001 Theorem 1: ΔB = Σ δ_i ρ w_i B, |δ_i| ≤ 1 (the §5 example by default)."""
    return RobustPolyhedralAllocator(v.effectiveness[v.demand_rows], _robust_params(t, v))


def _robust_polytopic(t: Table, v: Vehicle) -> Allocator:
    """Seed 001 Theorem 2: ΔB in the convex hull of ±ρ w_i B."""
    return RobustPolytopicAllocator(v.effectiveness[v.demand_rows], _robust_params(t, v))


def _robust_lft(t: Table, v: Vehicle) -> Allocator:
    """Seed 001 Theorem 3: ΔB = E F H, ‖F‖ ≤ 1 (E = ρ e_shape; H from the table or B)."""
    d = RobustLftParams(upper_N=1.0)
    m = v.demand_rows.stop - v.demand_rows.start
    e_shape = _matrix(t, "e_shape", m, m) if t.has("e_shape") else None
    h = t.raw("h_matrix", None)
    h_matrix = None
    if h is not None:
        rows = len(h) if isinstance(h, list) else 0
        h_matrix = _matrix(t, "h_matrix", rows, len(v.r_thr_B_m))
    return RobustLftAllocator(
        v.effectiveness[v.demand_rows],
        RobustLftParams(
            upper_N=_upper_N(v),
            rho=t.number("rho", d.rho, lo=0.0),
            e_shape=None if e_shape is None else tuple(tuple(map(float, r)) for r in e_shape),
            h_matrix=None if h_matrix is None else tuple(tuple(map(float, r)) for r in h_matrix),
        ),
    )


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


def _pwpf(t: Table, v: Vehicle) -> Callable[[], Modulator]:
    params = PwpfParams(
        km=t.number("km", lo=0.0, lo_open=True),
        tm_s=t.number("tm_s", lo=0.0, lo_open=True),
        u_on=t.number("u_on", lo=0.0, lo_open=True),
        u_off=t.number("u_off", lo=0.0),
        min_on_s=v.min_on_s,
    )
    return lambda: PwpfModulator(params)


def _schmitt(t: Table, v: Vehicle) -> Callable[[], Modulator]:
    d = SchmittParams()
    params = SchmittParams(
        min_on_s=v.min_on_s,
        level_on=t.number("level_on", d.level_on, lo=0.0, hi=1.0),
        level_off=t.number("level_off", d.level_off, lo=0.0, hi=1.0),
    )
    return lambda: SchmittModulator(params)


def _remainder(t: Table, v: Vehicle) -> Callable[[], Modulator]:
    params = RemainderParams(min_on_s=v.min_on_s)
    return lambda: RemainderModulator(params)


def _proportional(t: Table, v: Vehicle) -> Callable[[], Modulator]:
    return ProportionalModulator


def _rls(t: Table, v: Vehicle) -> InertiaIdentifier:
    d = RlsInertiaParams(inertia_guess_B_kgm2=v.inertia_B_kgm2)
    guess = np.array(t.matrix3("inertia_guess_B_kgm2")) if t.has("inertia_guess_B_kgm2") else None
    return RlsInertiaIdentifier(
        RlsInertiaParams(
            inertia_guess_B_kgm2=v.inertia_B_kgm2 if guess is None else guess,
            forgetting_factor=t.number(
                "forgetting_factor", d.forgetting_factor, lo=0.0, lo_open=True, hi=1.0
            ),
            initial_covariance=t.number(
                "initial_covariance", d.initial_covariance, lo=0.0, lo_open=True
            ),
            min_information=t.number("min_information", d.min_information, lo=0.0),
            min_regressor_norm=t.number("min_regressor_norm", d.min_regressor_norm, lo=0.0),
            max_gap_s=t.number("max_gap_s", d.max_gap_s, lo=0.0, lo_open=True),
            window_cycles=t.integer("window_cycles", d.window_cycles, lo=1),
        )
    )


def _mrp_polynomial(t: Table, v: Vehicle) -> AttitudeGuidance:
    """Seed 001 §5: ``mrp_coefficients`` per axis, highest power first, τ = t − t_start_s."""
    coeffs = t.raw("mrp_coefficients")
    ok = (
        isinstance(coeffs, list)
        and len(coeffs) == 3
        and all(
            isinstance(c, list)
            and c
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in c)
            for c in coeffs
        )
    )
    if not ok:
        raise t.error("mrp_coefficients", coeffs, "3 lists of numbers (highest power first)")
    try:
        return MrpPolynomialGuidance(
            sigma_coeffs=tuple(tuple(float(x) for x in reversed(c)) for c in coeffs),
            t0_ns=round(t.number("t_start_s", 0.0, lo=0.0) * NS_PER_S),
            duration_s=math.inf,  # the bench's reference does not stop either
        )
    except ValueError as exc:
        raise t.error("mrp_coefficients", coeffs, str(exc)) from exc


ESTIMATORS: dict[str, Callable[[Table, Vehicle], AttitudeEstimator]] = {"mekf": _mekf}
CONTROLLERS: dict[str, Callable[[Table, Vehicle], AttitudeController]] = {
    "quaternion_pd": _quaternion_pd,
    "quaternion_pid": _quaternion_pid,
    "cascade_lqr": _cascade_lqr,
    "mrp_direct_parametric": _mrp_direct_parametric,
}
# Coupled 6-DoF laws (force and torque together), chosen by [flight_sw.controller] kind too.
POSE_CONTROLLERS: dict[str, Callable[[Table, Vehicle], PoseController]] = {
    "nftsm_dq": _nftsm_dq,
    "tsm_dq": _tsm_dq,
}
ALLOCATORS: dict[str, Callable[[Table, Vehicle], Allocator]] = {
    "pseudo_inverse": _pseudo_inverse,
    "qp_osqp": _qp_osqp,
    "robust_polyhedral": _robust_polyhedral,
    "robust_polytopic": _robust_polytopic,
    "robust_lft": _robust_lft,
}
MODULATORS: dict[str, Callable[[Table, Vehicle], Callable[[], Modulator]]] = {
    "pwpf": _pwpf,
    "schmitt": _schmitt,
    "remainder": _remainder,
    "proportional": _proportional,
}
INERTIA_IDENTIFIERS: dict[str, Callable[[Table, Vehicle], InertiaIdentifier]] = {"rls": _rls}
# Moving references (``[manoeuvre] kind``); "step" is the Timeline (hold, then the target).
GUIDANCE: dict[str, Callable[[Table, Vehicle], AttitudeGuidance]] = {
    "mrp_polynomial": _mrp_polynomial
}
TRANSLATION_CONTROLLERS: dict[
    str, Callable[[Table, Vehicle], tuple[TranslationController, np.ndarray | None]]
] = {"position_pd": _position_pd}
# Strategies run in this order (the first to isolate in a cycle wins).
THRUSTER_FDIR: dict[str, Callable[[Table, Vehicle], ThrusterFdirStrategy]] = {
    "valve_status": _valve_status,
    "rate_residual": _rate_residual,
}
SENSOR_FDIR: dict[str, Callable[[Table, Vehicle], FrozenSensorMonitor]] = {
    "frozen_value": _frozen_value
}


def _build(t: Table, builder: Callable[[Table, Vehicle], Any], v: Vehicle) -> Any:
    try:
        built = builder(t, v)
    except ConfigError as exc:
        if exc.source == t.source:
            raise
        # a parameter class rejected a derived value: re-anchor the error in the file
        raise ConfigError(t.source, f"{t.path}.{exc.key}", exc.value, exc.expected) from exc
    t.done()
    return built


def _strategy(parent: Table, key: str, registry: dict[str, Any], v: Vehicle) -> Any:
    t = parent.table(key)
    kind = t.string("kind", choices=tuple(registry))
    return _build(t, registry[kind], v)


def _thruster_fdir(parent: Table, v: Vehicle) -> tuple[ThrusterFdir | None, bool]:
    """The thruster FDIR of ``[flight_sw.thruster_fdir]`` (None if absent), precompute flag."""
    if not parent.has("thruster_fdir"):
        return None, False
    t = parent.table("thruster_fdir")
    precompute = t.raw("precompute_masks", True)
    if not isinstance(precompute, bool):
        raise t.error("precompute_masks", precompute, "true or false")
    names = [name for name in THRUSTER_FDIR if t.has(name)]
    strategies = [_build(t.table(name), THRUSTER_FDIR[name], v) for name in names]
    t.done()
    if not strategies:
        raise parent.error(
            "thruster_fdir", {}, "a table naming at least one of " + ", ".join(THRUSTER_FDIR)
        )
    return ThrusterFdir(len(v.r_thr_B_m), strategies), precompute


def _single_failure_allocators(alloc: Allocator, n: int) -> dict[tuple[bool, ...], Allocator]:
    """Allocators for every mask with one thruster removed."""
    out: dict[tuple[bool, ...], Allocator] = {}
    for k in range(n):
        mask = np.ones(n, dtype=bool)
        mask[k] = False
        out[tuple(bool(x) for x in mask)] = alloc.with_mask(mask)
    return out


def build_computer(
    cfg: dict[str, Any],
    control_period_ns: int,
    imu_period_ns: int,
    watch_periods_ns: dict[str, int],
) -> FlightComputer:
    """Build the flight computer described by the configuration ``cfg``."""
    source = str(cfg.get("source", "<flight-software config>"))
    root = Table(cfg, source)
    root.raw("source", "")
    vehicle = Vehicle(root.table("vehicle"), root)
    root.string("valve_model", "on_off", choices=("on_off", "throttled"))  # the bench's
    man = root.table("manoeuvre")
    kind = man.string("kind", "step", choices=("step", *GUIDANCE))
    q_target = np.array(man.vector("q_target_BN", 4))
    if abs(float(np.linalg.norm(q_target)) - 1.0) > 1e-6:
        raise man.error("q_target_BN", q_target.tolist(), "a unit quaternion")
    t_start_ns = round(man.number("t_start_s", lo=0.0) * NS_PER_S)
    r_target_man = np.array(man.vector3("r_target_N_m")) if man.has("r_target_N_m") else None
    # a moving reference (else the Timeline's step: hold, then q_target)
    guidance = None if kind == "step" else _build(man, GUIDANCE[kind], vehicle)
    man.done()
    vehicle.control_period_ns = control_period_ns
    vehicle.imu_period_ns = imu_period_ns
    fsw = root.table("flight_sw", {})
    est_table = fsw.raw("estimator", None)
    estimator = _strategy(fsw, "estimator", ESTIMATORS, vehicle)
    ctl = fsw.table("controller")
    pose: PoseController | None = None
    if ctl.string("kind", choices=(*CONTROLLERS, *POSE_CONTROLLERS)) in POSE_CONTROLLERS:
        pose = _strategy(fsw, "controller", POSE_CONTROLLERS, vehicle)
        controller: AttitudeController = _NoAttitudeLaw()
        vehicle.demand_rows = WRENCH_ROWS
        if fsw.has("translation"):
            raise fsw.error(
                "translation",
                fsw.raw("translation"),
                "no translation table: the 6-DoF "
                f"controller {ctl.raw('kind')!r} commands force and torque together",
            )
    else:
        controller = _strategy(fsw, "controller", CONTROLLERS, vehicle)
    translation, r_target = None, None
    if fsw.has("translation"):
        translation, r_target = _strategy(fsw, "translation", TRANSLATION_CONTROLLERS, vehicle)
        vehicle.demand_rows = WRENCH_ROWS
    allocator = _strategy(fsw, "allocator", ALLOCATORS, vehicle)
    make_modulator = _strategy(fsw, "modulator", MODULATORS, vehicle)
    inertia_id = (
        _strategy(fsw, "inertia_identification", INERTIA_IDENTIFIERS, vehicle)
        if fsw.has("inertia_identification")
        else None
    )
    thruster_fdir, precompute = _thruster_fdir(fsw, vehicle)
    phase_s = fsw.number("realtime_cycle_phase_s", DEFAULT_CYCLE_PHASE_NS / NS_PER_S, lo=0.0,
                         hi=(control_period_ns - 1) / NS_PER_S)
    if fsw.has("sensor_fdir"):
        monitor = _strategy(fsw, "sensor_fdir", SENSOR_FDIR, vehicle)
    else:
        monitor = FrozenSensorMonitor(FrozenSensorParams().by_message())
    fsw.done()
    root.done()
    n = len(vehicle.r_thr_B_m)
    by_mask = _single_failure_allocators(allocator, n) if precompute else {}

    def make_estimator() -> AttitudeEstimator:
        # the table was validated above; rebuilding it cannot fail
        built: AttitudeEstimator = _strategy(
            Table({"estimator": est_table}, source), "estimator", ESTIMATORS, vehicle
        )
        return built

    nav_period = watch_periods_ns.get("NAV_POS")
    return FlightComputer(
        estimator=estimator,
        controller=controller,
        allocator=allocator,
        modulators=[make_modulator() for _ in range(n)],
        max_thrust_N=vehicle.max_thrust_each_N,
        control_period_ns=control_period_ns,
        imu_period_ns=imu_period_ns,
        timeline=Timeline(q_target, t_start_ns, r_target if r_target is not None else r_target_man),
        watchdog=SensorWatchdog(
            {k: p for k, p in watch_periods_ns.items() if k in ("IMU_RATE", "STR_QUAT")}
        ),
        translation=translation,
        effectiveness=vehicle.effectiveness[vehicle.demand_rows].copy(),
        thruster_fdir=thruster_fdir,
        sensor_monitor=monitor,
        make_estimator=make_estimator,
        make_modulator=make_modulator,
        allocators_by_mask=by_mask,
        nav_timeout_ns=(LOST_AFTER_PERIODS * nav_period if nav_period else DEFAULT_NAV_TIMEOUT_NS),
        guidance=guidance,
        inertia_id=inertia_id,
        pose=pose,
        cycle_phase_ns=round(phase_s * NS_PER_S),
    )


def load_config(path: str | Path) -> dict[str, Any]:
    """Read the configuration JSON at ``path``."""
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConfigError(
            str(p), "<file>", str(p), f"a readable configuration file ({exc.strerror})"
        ) from exc
    except json.JSONDecodeError as exc:
        raise ConfigError(str(p), "<syntax>", str(exc), "valid JSON") from exc
    if not isinstance(data, dict):
        raise ConfigError(str(p), "<root>", type(data).__name__, "a JSON object")
    return data
