"""Flight-software configuration: a JSON file -> the wired :class:`FlightComputer`.

The file (written by the bench's orchestrator from the scenario, or by hand for a real
vehicle) holds the nominal vehicle (mass, inertia), the thruster geometry, the manoeuvre
and the ``flight_sw`` table of the scenario: which estimator, controller, allocator and
modulator to use, with their parameters. Each strategy is chosen by ``kind`` from a
registry, one builder module per strategy family (:mod:`flight_sw.builders.estimation`,
``.control``, ``.allocation``, ``.modulation``, ``.fdir``, ``.guidance``; the nominal
vehicle in :mod:`flight_sw.builders.vehicle`): a new algorithm is a new file plus one
registry line. Every bad value raises
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
- ``fine_hold`` (with a 6-DoF ``controller`` only): the thresholds of
  :class:`flight_sw.control.fine_hold.FineHoldParams` and the fine laws ``attitude`` (a
  ``kind`` of :data:`CONTROLLERS`) and ``translation`` (``position_pd``) that take over
  near the target (:mod:`flight_sw.control.fine_hold`).
- ``pure_torque`` (default true): attitude-only control allocates the torque with zero
  force on the 6 wrench rows (:func:`_pure_torque`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from dbc.contract import FswConfig
from dbc.datafile import parse_json, read_text
from dbc.errors import ConfigError
from dbc.schema import Table
from flight_sw.allocation.authority import authority_warnings, force_free_torque_unreached
from flight_sw.allocation.base import Allocator
from flight_sw.builders.allocation import ALLOCATORS
from flight_sw.builders.control import CONTROLLERS, POSE_CONTROLLERS, TRANSLATION_CONTROLLERS
from flight_sw.builders.estimation import ESTIMATORS, INERTIA_IDENTIFIERS
from flight_sw.builders.fdir import SENSOR_FDIR, THRUSTER_FDIR
from flight_sw.builders.guidance import GUIDANCE
from flight_sw.builders.modulation import MODULATORS
from flight_sw.builders.vehicle import NS_PER_S, WRENCH_ROWS, Vehicle, dataclass_params
from flight_sw.computer import (
    DEFAULT_CYCLE_PHASE_NS,
    DEFAULT_NAV_TIMEOUT_NS,
    FlightComputer,
    Timeline,
)
from flight_sw.control.base import AttitudeController, PoseController
from flight_sw.estimation.base import AttitudeEstimator
from flight_sw.fdir.frozen_sensor import FrozenSensorMonitor, FrozenSensorParams
from flight_sw.fdir.layout_check import LayoutCheck, check_layout
from flight_sw.fdir.sensor_watchdog import LOST_AFTER_PERIODS, SensorWatchdog
from flight_sw.fdir.thruster_fdir import ThrusterFdir

__all__ = [
    "ALLOCATORS",
    "CONTROLLERS",
    "ESTIMATORS",
    "GUIDANCE",
    "INERTIA_IDENTIFIERS",
    "MODULATORS",
    "POSE_CONTROLLERS",
    "SENSOR_FDIR",
    "THRUSTER_FDIR",
    "TRANSLATION_CONTROLLERS",
    "Vehicle",
    "build_computer",
    "load_config",
]


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


def _strategy(parent: Table, key: str, registry: Mapping[str, Any], v: Vehicle) -> Any:
    t = parent.table(key)
    kind = t.string("kind", choices=tuple(registry))
    return _build(t, registry[kind], v)


def _fine_hold(t: Table, coarse: PoseController, v: Vehicle) -> PoseController:
    """``[flight_sw.fine_hold]``: the thresholds of :class:`FineHoldParams` and the fine
    laws, ``attitude`` (an attitude ``kind``) and ``translation`` (``position_pd``)."""
    from flight_sw.control.fine_hold import FineHold, FineHoldParams

    attitude = _strategy(t, "attitude", CONTROLLERS, v)
    translation, r_target = _strategy(t, "translation", TRANSLATION_CONTROLLERS, v)
    if r_target is not None:
        raise t.error("translation.r_target_N_m", r_target.tolist(), "absent: the fine hold "
                      "holds the manoeuvre's target")
    params = dataclass_params(t, FineHoldParams, {})
    t.done()
    return FineHold(coarse, attitude, translation, params)


def _pure_torque(fsw: Table, v: Vehicle, attitude_only: bool) -> tuple[bool, tuple[str, ...]]:
    """Whether attitude-only control allocates the wrench with zero force, and a warning.

    ``[flight_sw] pure_torque`` (default true): an attitude-only controller's torque is
    allocated on the 6 wrench rows with a zero force demand, so the thrusters fire in
    force-free sets (couples) and an attitude manoeuvre leaves no net ΔV; with torque rows
    only, the allocator may meet a torque with thrusters whose forces add (on seed 003's
    layout, diagonal pairs: 0.12 m/s over 60 s). When the layout cannot give some torque
    axis without force, the torque rows are used and the statistics say which axes.
    Ignored (must be absent or true) with a 6-DoF or translation controller, which
    allocate the wrench already.
    """
    if not fsw.has("pure_torque"):
        wanted = True
    else:
        wanted = fsw.flag("pure_torque")
        if wanted is False and not attitude_only:
            raise fsw.error("pure_torque", False, "absent or true: the 6-DoF controller "
                            "allocates force and torque together")
    if not (wanted and attitude_only):
        return False, ()
    missing = force_free_torque_unreached(v.effectiveness)
    if missing:
        return False, (
            f"pure_torque: the {v.effectiveness.shape[1]} thrusters cannot produce torque "
            f"about {', '.join(missing)} without a net force, so attitude-only firing is "
            "allocated on the torque rows alone and will translate the vehicle "
            "(net_translation in summary.json)",
        )
    return True, ()


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
    FswConfig.from_json(cfg, source)  # the contract's schema, version and vehicle data
    root = Table(cfg, source)
    root.raw("schema")
    root.raw("version")
    root.raw("source", "")
    vehicle = Vehicle(root.table("vehicle"), root)
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
        if fsw.has("fine_hold"):
            pose = _fine_hold(fsw.table("fine_hold"), pose, vehicle)
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
        if fsw.has("fine_hold"):
            raise fsw.error("fine_hold", fsw.raw("fine_hold"), "no fine_hold table: it hands "
                            "a 6-DoF controller (nftsm_dq, tsm_dq) over to PD laws near the "
                            "target")
    translation, r_target = None, None
    if fsw.has("translation"):
        translation, r_target = _strategy(fsw, "translation", TRANSLATION_CONTROLLERS, vehicle)
        vehicle.demand_rows = WRENCH_ROWS
    pure_torque, pure_torque_note = _pure_torque(fsw, vehicle, pose is None and translation is None)
    if pure_torque:
        vehicle.demand_rows = WRENCH_ROWS  # the torque demand with zero force
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
    for alloc in (allocator, *by_mask.values()):
        alloc.warm_up()  # first-call costs paid here, not in the first control cycle

    def make_estimator() -> AttitudeEstimator:
        # the table was validated above; rebuilding it cannot fail
        built: AttitudeEstimator = _strategy(
            Table({"estimator": est_table}, source), "estimator", ESTIMATORS, vehicle
        )
        return built

    nav_period = watch_periods_ns.get("NAV_POS")
    controls_force = vehicle.demand_rows == WRENCH_ROWS and not pure_torque
    b_full, j_nominal = vehicle.effectiveness.copy(), vehicle.inertia_B_kgm2.copy()

    def layout_check(mask: np.ndarray) -> LayoutCheck:
        return check_layout(b_full, j_nominal, mask, controls_force)

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
        pure_torque=pure_torque,
        layout_check=layout_check,
        warnings=(
            *authority_warnings(vehicle.effectiveness, controls_force=controls_force),
            *pure_torque_note,
        ),
    )


def load_config(path: str | Path) -> dict[str, Any]:
    """Read the configuration JSON at ``path`` (size, encoding, nesting: :mod:`dbc.datafile`)."""
    p = Path(path)
    data = parse_json(read_text(p, "configuration file"), str(p))
    if not isinstance(data, dict):
        raise ConfigError(str(p), "<root>", type(data).__name__, "a JSON object")
    return data
