"""Scenario files (TOML) -> a validated, frozen :class:`Scenario`.

A scenario says everything about one run: vehicle (actual and nominal mass properties),
thrusters (a named layout or an explicit list, valve dynamics), sensors, bus, initial
state, manoeuvre, the flight-software configuration (passed to the flight-software
process as data, validated there), scheduled faults and expectations. Every bad field
raises :class:`dbc.errors.ConfigError` naming the file, the dotted key, the value and what
was expected; unknown keys are errors too. Nothing in a scenario is ever evaluated.

Units are in the key names (``_s``, ``_m``, ``_deg``, ``_N`` ...). Angles are converted to
radians here; quaternions are scalar-first q_BN.
"""

from __future__ import annotations

import dataclasses
import math
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cantools.database.can import Database

from bench.station.dynamics.hcw import SEED000_ORBIT_RADIUS_M
from bench.station.dynamics.rigid_body import MassProperties
from bench.station.environment.disturbance import FORCE_FRAMES, DisturbanceParams, Sinusoid
from bench.station.faults import FaultSpec, parse_faults
from bench.station.reference import KIND_STEP, KINDS, ReferenceParams, reference
from bench.station.valves.layouts import LAYOUT_MAX_THRUST_N, LAYOUTS
from dbc import load_database
from dbc.codec import BITRATE_ATTRIBUTE, bitrate_bps, bitrate_range_bps
from dbc.errors import ConfigError
from dbc.schema import Table

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

DEG_RAD = math.pi / 180.0
# A target Euler angle beyond a full turn is no attitude anyone writes: a unit slip.
EULER_LIMIT_DEG = 360.0
SQRT_HOUR_S = 60.0  # sqrt(3600 s)
UNIT_NORM_TOL = 1e-6
MODES = ("lockstep", "realtime")
TRANSLATIONS = ("inertial", "hcw")
FSW_TABLE = "flight_sw"  # the table passed through to the flight software
"""[dynamics] translation: inertial (default) or HCW relative motion (station.dynamics.hcw)."""
VALVE_MODELS = ("on_off", "throttled")
"""[thrusters] valve_model: on_off (station.valves.valve), throttled (station.valves.throttled)."""
EVENT_KINDS = ("capture",)
"""[[events]] kinds: capture (bench.station.dynamics.capture)."""
MAX_THRUSTERS = 16

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]


@dataclass(frozen=True)
class MassSpec:
    mass_kg: float
    inertia_B_kgm2: tuple[Vec3, Vec3, Vec3]


@dataclass(frozen=True)
class ThrusterSpec:
    r_thr_B_m: Vec3
    d_thr_B: Vec3
    max_thrust_N: float | None = None
    """This thruster's maximum thrust [N]; None = the valve's ``max_thrust_N``."""


@dataclass(frozen=True)
class ValveSpec:
    max_thrust_N: float
    isp_s: float
    open_delay_s: float
    close_delay_s: float
    rise_tau_s: float
    tail_tau_s: float
    min_on_s: float
    model: str = "on_off"


@dataclass(frozen=True)
class DynamicsSpec:
    """[dynamics]: translation model and the leader's circular orbit radius [m]."""

    translation: str = "inertial"
    orbit_radius_m: float = SEED000_ORBIT_RADIUS_M


@dataclass(frozen=True)
class EnvironmentSpec:
    """[environment]: gravity-gradient torque on/off about a circular orbit of radius [m]."""

    gravity_gradient: bool = False
    orbit_radius_m: float = SEED000_ORBIT_RADIUS_M


@dataclass(frozen=True)
class CaptureSpec:
    """A [[events]] capture: new mass [kg], inertia about the new CoM [kg m^2], CoM [m]."""

    t_s: float
    mass: MassSpec
    com_B_m: Vec3

    def record(self) -> dict[str, Any]:
        """The event as logged (events.jsonl, summary.json)."""
        return {
            "kind": "capture",
            "t_s": self.t_s,
            "mass_kg": self.mass.mass_kg,
            "inertia_B_kgm2": [list(r) for r in self.mass.inertia_B_kgm2],
            "com_B_m": list(self.com_B_m),
        }


@dataclass(frozen=True)
class GyroSpec:
    arw_rad_sqrt_s: float
    bias_rad_s: Vec3
    bias_rw_rad_s_sqrt_s: float
    lsb_rad_s: float
    range_rad_s: float


@dataclass(frozen=True)
class AccelSpec:
    vrw_m_s_sqrt_s: float
    bias_m_s2: Vec3
    lsb_m_s2: float
    range_m_s2: float


@dataclass(frozen=True)
class StarTrackerSpec:
    noise_cross_arcsec: float
    noise_about_arcsec: float
    boresight_B: Vec3


@dataclass(frozen=True)
class RelNavSpec:
    noise_pos_m: float
    noise_vel_m_s: float


@dataclass(frozen=True)
class BusSpecCfg:
    bitrate_bps: int
    fsw_response_delay_s: float
    stall_timeout_s: float
    startup_timeout_s: float


@dataclass(frozen=True)
class Expectations:
    settling_band_deg: float
    settling_time_s_max: float | None
    steady_state_attitude_error_deg_max: float | None
    steady_state_rate_error_deg_s_max: float | None
    steady_state_window_s: float
    steady_state_position_error_m_max: float | None = None
    final_position_error_m_max: float | None = None
    position_band_m: float | None = None
    position_settling_time_s_max: float | None = None
    rate_settling_band_deg_s: float | None = None
    rate_settling_time_s_max: float | None = None


@dataclass(frozen=True)
class Scenario:
    """A validated scenario. ``flight_sw`` is handed verbatim to the flight software."""

    path: str
    name: str
    description: str
    duration_s: float
    seed: int
    actual: MassSpec
    nominal: MassSpec
    thrusters: tuple[ThrusterSpec, ...]
    valve: ValveSpec
    gyro: GyroSpec
    accel: AccelSpec
    star_tracker: StarTrackerSpec
    rel_nav: RelNavSpec | None
    bus: BusSpecCfg
    q0_BN: Quat
    omega0_BN_B_rad_s: Vec3
    r0_N_m: Vec3
    v0_N_m_s: Vec3
    q_target_BN: Quat
    manoeuvre_start_s: float
    flight_sw: dict[str, Any]
    faults: tuple[FaultSpec, ...]
    expectations: Expectations
    raw: dict[str, Any] = field(repr=False, compare=False, default_factory=dict)
    overrides: tuple[str, ...] = ()
    dynamics: DynamicsSpec = DynamicsSpec()
    environment: EnvironmentSpec = EnvironmentSpec()
    disturbance: DisturbanceParams | None = None
    events: tuple[CaptureSpec, ...] = ()
    reference: ReferenceParams = field(default_factory=ReferenceParams)
    r_target_N_m: Vec3 | None = None
    """[manoeuvre] r_target_N_m: reference position of the position metrics (None = r0)."""

    @property
    def max_thrusts_N(self) -> tuple[float, ...]:
        """Maximum thrust of every thruster [N] (its own, else the valve's)."""
        v = self.valve.max_thrust_N
        return tuple(v if t.max_thrust_N is None else t.max_thrust_N for t in self.thrusters)

    @property
    def r_reference_N_m(self) -> Vec3:
        """Reference position of the position metrics [m] (target, else the initial one)."""
        return self.r0_N_m if self.r_target_N_m is None else self.r_target_N_m

    def fsw_config(self) -> dict[str, Any]:
        """The flight-software configuration file content (nominal vehicle + [flight_sw]).

        New keys appear only when the scenario uses the feature, so the configuration of
        a scenario without them is unchanged: per-thruster ``max_thrust_N`` (when the
        thrusters' maxima differ from the valve's; the top-level one is their maximum),
        ``valve_model`` (when throttled; ``min_on_s`` is then 0), and in ``manoeuvre``
        ``kind`` + ``mrp_coefficients`` (MRP polynomial; ``q_target_BN`` is then the
        reference at the end of the run) and ``r_target_N_m`` (when given).
        """
        maxima = self.max_thrusts_N
        per_thruster = any(m != self.valve.max_thrust_N for m in maxima)
        thrusters: list[dict[str, Any]] = []
        for t, m in zip(self.thrusters, maxima, strict=True):
            entry: dict[str, Any] = {"r_thr_B_m": list(t.r_thr_B_m), "d_thr_B": list(t.d_thr_B)}
            if per_thruster:
                entry["max_thrust_N"] = m
            thrusters.append(entry)
        throttled = self.valve.model != "on_off"
        manoeuvre: dict[str, Any] = {
            "q_target_BN": list(self.q_target_BN),
            "t_start_s": self.manoeuvre_start_s,
        }
        if self.reference.kind != KIND_STEP:
            manoeuvre["kind"] = self.reference.kind
            manoeuvre["mrp_coefficients"] = [list(c) for c in self.reference.mrp_coefficients]
        if self.r_target_N_m is not None:
            manoeuvre["r_target_N_m"] = list(self.r_target_N_m)
        cfg: dict[str, Any] = {
            "source": override_source(self.path, [
                o for o in self.overrides if o.startswith(FSW_TABLE + ".")]),
            "vehicle": {
                "mass_kg": self.nominal.mass_kg,
                "inertia_B_kgm2": [list(r) for r in self.nominal.inertia_B_kgm2],
            },
            "thrusters": thrusters,
            "max_thrust_N": max(maxima),
            "min_on_s": 0.0 if throttled else self.valve.min_on_s,
            "manoeuvre": manoeuvre,
            "flight_sw": self.flight_sw,
        }
        if throttled:
            cfg["valve_model"] = self.valve.model
        return cfg


def quat_from_euler_zyx(yaw_rad: float, pitch_rad: float, roll_rad: float) -> Quat:
    """q_BN of a 3-2-1 (yaw, pitch, roll) rotation from N to B, scalar first, q0 >= 0."""
    cy, sy = math.cos(yaw_rad / 2), math.sin(yaw_rad / 2)
    cp, sp = math.cos(pitch_rad / 2), math.sin(pitch_rad / 2)
    cr, sr = math.cos(roll_rad / 2), math.sin(roll_rad / 2)
    q = (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )
    return q if q[0] >= 0 else (-q[0], -q[1], -q[2], -q[3])


def _unit(t: Table, key: str, n: int) -> tuple[float, ...]:
    v = t.vector(key, n)
    norm = math.sqrt(sum(x * x for x in v))
    if abs(norm - 1.0) > UNIT_NORM_TOL:
        raise t.error(
            key, list(v), f"a unit vector (norm 1 +- {UNIT_NORM_TOL}), norm is {norm:.6g}"
        )
    return v


def _quat(t: Table, key: str) -> Quat:
    a, b, c, d = _unit(t, key, 4)
    return (a, b, c, d)


def _mass(t: Table) -> MassSpec:
    """Mass and inertia, checked as the plant will use them (:class:`MassProperties`:
    symmetric, positive definite, principal moments obeying the triangle inequality), so a
    body that cannot exist is refused here, naming the key, before any process starts."""
    m = t.number("mass_kg", lo=0.0, lo_open=True)
    J = t.matrix3("inertia_B_kgm2")
    try:
        MassProperties(m, J)
    except ConfigError as exc:
        raise t.error(exc.key, [list(r) for r in J] if exc.key == "inertia_B_kgm2" else m,
                      exc.expected) from exc
    return MassSpec(m, J)  # type: ignore[arg-type]


def _thrusters(t: Table) -> tuple[tuple[ThrusterSpec, ...], ValveSpec]:
    layout = t.string("layout", "explicit", choices=("explicit", *LAYOUTS))
    if layout == "explicit":
        items = t.tables("list")
        if not items:
            raise t.error("list", [], "at least one [[thrusters.list]] entry (or a layout)")
        geo = []
        for it in items:
            geo.append(
                ThrusterSpec(
                    it.vector("r_thr_B_m", 3),  # type: ignore[arg-type]
                    _unit(it, "d_thr_B", 3),  # type: ignore[arg-type]
                    it.number("max_thrust_N", lo=0.0, lo_open=True)
                    if it.has("max_thrust_N") else None,
                )
            )
            it.done()
    else:
        arm = t.number("arm_R_m", lo=0.0, lo_open=True)
        length = t.number("length_L_m", lo=0.0, lo_open=True)
        geo = [ThrusterSpec(r, d) for r, d in LAYOUTS[layout](arm, length)]
        default_max = LAYOUT_MAX_THRUST_N.get(layout)
        if default_max is not None:
            geo = [
                dataclasses.replace(g, max_thrust_N=m)
                for g, m in zip(geo, default_max, strict=True)
            ]
    if len(geo) > MAX_THRUSTERS:
        raise t.error("list", len(geo), "at most 16 thrusters (THR_CMD_0..3 carry 16)")
    if t.has("max_thrust_per_thruster_N"):
        if layout == "explicit":
            raise t.error("max_thrust_per_thruster_N", t.raw("max_thrust_per_thruster_N"),
                          "absent with an explicit list (give max_thrust_N per entry)")
        maxima = t.vector("max_thrust_per_thruster_N", len(geo))
        if min(maxima) <= 0.0:
            raise t.error("max_thrust_per_thruster_N", list(maxima), "numbers > 0")
        geo = [dataclasses.replace(g, max_thrust_N=m) for g, m in zip(geo, maxima, strict=True)]
    v = ValveSpec(
        max_thrust_N=t.number("max_thrust_N", lo=0.0, lo_open=True),
        isp_s=t.number("isp_s", lo=0.0, lo_open=True),
        open_delay_s=t.number("open_delay_s", lo=0.0, hi=0.1),
        close_delay_s=t.number("close_delay_s", lo=0.0, hi=0.1),
        rise_tau_s=t.number("rise_tau_s", lo=0.0, lo_open=True, hi=1.0),
        tail_tau_s=t.number("tail_tau_s", lo=0.0, lo_open=True, hi=1.0),
        min_on_s=t.number("min_on_s", lo=0.0, hi=0.1),
        model=t.string("valve_model", "on_off", choices=VALVE_MODELS),
    )
    t.done()
    return tuple(geo), v


def _icd_range(db: Database, message: str, signals: tuple[str, ...]) -> float:
    """The largest symmetric range the DBC's ``signals`` of ``message`` can carry."""
    msg = db.get_message_by_name(message)
    spans = [msg.get_signal_by_name(n) for n in signals]
    return min(min(-float(x.minimum), float(x.maximum)) for x in spans)  # type: ignore[arg-type]


def _sensor_range(t: Table, key: str, db: Database, message: str, axes: str) -> float:
    """A sensor's measurement range, no wider than its frame's signals in the DBC (the ICD)."""
    limit = _icd_range(db, message, tuple(f"{axes}{c}" for c in "XYZ"))
    value = t.number(key, lo=0.0, lo_open=True)
    if value > limit:
        raise t.error(key, value, f"at most {limit:g} ({message}.{axes}X/Y/Z carry "
                      f"[-{limit:g}, {limit:g}] in the DBC, the interface control document)")
    return value


def _sensors(
    t: Table, db: Database
) -> tuple[GyroSpec, AccelSpec, StarTrackerSpec, RelNavSpec | None]:
    g = t.table("gyro")
    gyro = GyroSpec(
        arw_rad_sqrt_s=g.number("arw_deg_sqrt_h", lo=0.0) * DEG_RAD / SQRT_HOUR_S,
        bias_rad_s=tuple(x * DEG_RAD / 3600.0 for x in g.vector("bias_deg_h", 3)),  # type: ignore[arg-type]
        bias_rw_rad_s_sqrt_s=g.number("bias_rw_deg_h_sqrt_h", lo=0.0)
        * DEG_RAD
        / 3600.0
        / SQRT_HOUR_S,
        lsb_rad_s=g.number("lsb_rad_s", lo=0.0),
        range_rad_s=_sensor_range(g, "range_rad_s", db, "IMU_RATE", "Rate"),
    )
    g.done()
    a = t.table("accelerometer")
    accel = AccelSpec(
        vrw_m_s_sqrt_s=a.number("vrw_m_s_sqrt_h", lo=0.0) / SQRT_HOUR_S,
        bias_m_s2=tuple(x * 1e-6 * 9.80665 for x in a.vector("bias_ug", 3)),  # type: ignore[arg-type]
        lsb_m_s2=a.number("lsb_m_s2", lo=0.0),
        range_m_s2=_sensor_range(a, "range_m_s2", db, "IMU_ACCEL", "Accel"),
    )
    a.done()
    s = t.table("star_tracker")
    st = StarTrackerSpec(
        noise_cross_arcsec=s.number("noise_cross_arcsec", lo=0.0),
        noise_about_arcsec=s.number("noise_about_arcsec", lo=0.0),
        boresight_B=_unit(s, "boresight_B", 3),  # type: ignore[arg-type]
    )
    s.done()
    nav = None
    if t.has("rel_nav"):
        n = t.table("rel_nav")
        nav = RelNavSpec(n.number("noise_pos_m", lo=0.0), n.number("noise_vel_m_s", lo=0.0))
        n.done()
    t.done()
    return gyro, accel, st, nav


def _opt(t: Table, key: str) -> float | None:
    return t.number(key, lo=0.0) if t.has(key) else None


def _bool(t: Table, key: str, default: bool) -> bool:
    v = t.raw(key, default)
    if not isinstance(v, bool):
        raise t.error(key, v, "true or false")
    return v


def _dynamics_environment(root: Table) -> tuple[DynamicsSpec, EnvironmentSpec]:
    dt = root.table("dynamics", {})
    dyn = DynamicsSpec(
        translation=dt.string("translation", "inertial", choices=TRANSLATIONS),
        orbit_radius_m=dt.number("orbit_radius_m", SEED000_ORBIT_RADIUS_M, lo=0.0, lo_open=True),
    )
    dt.done()
    et = root.table("environment", {})
    env = EnvironmentSpec(
        gravity_gradient=_bool(et, "gravity_gradient", False),
        orbit_radius_m=et.number("orbit_radius_m", dyn.orbit_radius_m, lo=0.0, lo_open=True),
    )
    if dyn.translation == "hcw" and env.orbit_radius_m != dyn.orbit_radius_m:
        raise et.error("orbit_radius_m", env.orbit_radius_m,
                       f"the HCW orbit's radius dynamics.orbit_radius_m = {dyn.orbit_radius_m}"
                       " (one orbit)")
    et.done()
    return dyn, env


def _sinusoid(t: Table, amplitude_key: str) -> Sinusoid:
    s = Sinusoid(
        t.vector3(amplitude_key),
        t.number("omega_rad_s"),
        t.number("phase_rad", 0.0),
        source=f"{t.source}: {t.path}",
    )
    t.done()
    return s


def _disturbance(root: Table) -> DisturbanceParams | None:
    if not root.has("disturbance"):
        return None
    t = root.table("disturbance")
    p = DisturbanceParams(
        force_N=t.vector3("force_N", [0.0, 0.0, 0.0]),
        force_sinusoids=tuple(_sinusoid(x, "amplitude_N") for x in t.tables("force_sinusoids")),
        torque_Nm=t.vector3("torque_Nm", [0.0, 0.0, 0.0]),
        torque_sinusoids=tuple(
            _sinusoid(x, "amplitude_Nm") for x in t.tables("torque_sinusoids")
        ),
        force_frame=t.string("force_frame", "body", choices=FORCE_FRAMES),
        source=f"{t.source}: {t.path}",
    )
    t.done()
    return p


def _events(root: Table, duration_s: float) -> tuple[CaptureSpec, ...]:
    out = []
    for t in root.tables("events"):
        t.string("kind", choices=EVENT_KINDS)
        out.append(
            CaptureSpec(
                t_s=t.number("t_s", lo=0.0, hi=duration_s),
                mass=_mass(t),
                com_B_m=t.vector3("com_B_m", [0.0, 0.0, 0.0]),
            )
        )
        t.done()
    return tuple(sorted(out, key=lambda e: e.t_s))


def _mrp_coefficients(t: Table) -> tuple[tuple[float, ...], ...]:
    v = t.raw("mrp_coefficients")
    expected = "3 lists (x, y, z) of polynomial coefficients, highest power first"
    if not isinstance(v, list) or len(v) != 3:
        raise t.error("mrp_coefficients", v, expected)
    for i, c in enumerate(v):
        if (
            not isinstance(c, list)
            or not c
            or not all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                for x in c
            )
        ):
            raise t.error(f"mrp_coefficients[{i}]", c, "a non-empty list of finite numbers")
    return tuple(tuple(float(x) for x in c) for c in v)


def parse_scenario(data: dict[str, Any], source: str) -> Scenario:
    """Validate parsed TOML ``data`` from file ``source`` into a :class:`Scenario`."""
    root = Table(data, source)
    sc = root.table("scenario")
    name = sc.string("name")
    description = sc.string("description", "")
    duration_s = sc.number("duration_s", lo=0.0, lo_open=True, hi=1e6)
    seed = sc.integer("seed", 0, lo=0)
    sc.done()

    vt = root.table("vehicle")
    actual = _mass(vt)
    nominal = _mass(vt.table("nominal")) if vt.has("nominal") else actual
    vt.done()

    thrusters, valve = _thrusters(root.table("thrusters"))
    db = load_database()
    gyro, accel, st, nav = _sensors(root.table("sensors"), db)

    bt = root.table("bus", {})
    rate_default, (rate_lo, rate_hi) = bitrate_bps(db), bitrate_range_bps(db)
    bus = BusSpecCfg(
        bitrate_bps=bt.integer("bitrate_bps", rate_default, lo=rate_lo),
        fsw_response_delay_s=bt.number("fsw_response_delay_s", 0.001, lo=0.0, hi=0.1),
        stall_timeout_s=bt.number("stall_timeout_s", 2.0, lo=0.0, lo_open=True),
        startup_timeout_s=bt.number("startup_timeout_s", 60.0, lo=0.0, lo_open=True),
    )
    if bus.bitrate_bps > rate_hi:
        raise bt.error("bitrate_bps", bus.bitrate_bps,
                       f"at most {rate_hi} (the DBC's {BITRATE_ATTRIBUTE} range)")
    bt.done()

    it = root.table("initial", {})
    q0 = _quat(it, "q_BN") if it.has("q_BN") else (1.0, 0.0, 0.0, 0.0)
    w0 = tuple(x * DEG_RAD for x in it.vector("omega_BN_B_deg_s", 3, [0.0, 0.0, 0.0]))
    r0 = it.vector3("r_N_m", [0.0, 0.0, 0.0])
    v0 = it.vector3("v_N_m_s", [0.0, 0.0, 0.0])
    it.done()

    mt = root.table("manoeuvre")
    kind = mt.string("kind", KIND_STEP, choices=KINDS)
    t_start = mt.number("t_start_s", 0.0, lo=0.0, hi=duration_s)
    if kind != KIND_STEP:
        ref = ReferenceParams(kind, mrp_coefficients=_mrp_coefficients(mt), t_start_s=t_start,
                              source=f"{source}: manoeuvre")
        q_target = reference(ref, duration_s)[0]
    else:
        if mt.has("target_q_BN"):
            q_target = _quat(mt, "target_q_BN")
        else:
            euler = mt.vector("target_euler_zyx_deg", 3, lo=-EULER_LIMIT_DEG, hi=EULER_LIMIT_DEG)
            yaw, pitch, roll = (x * DEG_RAD for x in euler)
            q_target = quat_from_euler_zyx(yaw, pitch, roll)
        ref = ReferenceParams(kind, q_target, t_start_s=t_start, source=f"{source}: manoeuvre")
    r_target = mt.vector3("r_target_N_m") if mt.has("r_target_N_m") else None
    mt.done()
    dynamics, environment = _dynamics_environment(root)
    disturbance = _disturbance(root)
    events = _events(root, duration_s)

    fsw = root.raw("flight_sw", {})
    if not isinstance(fsw, dict):
        raise root.error("flight_sw", fsw, "a table")

    db = load_database()
    faults = parse_faults(
        root.tables("faults"), duration_s, len(thrusters),
        frozenset(m.name for m in db.messages), frozenset(n.name for n in db.nodes),
    )

    et = root.table("expectations", {})
    exp = Expectations(
        settling_band_deg=et.number("settling_band_deg", 0.5, lo=0.0, lo_open=True),
        settling_time_s_max=_opt(et, "settling_time_s_max"),
        steady_state_attitude_error_deg_max=_opt(et, "steady_state_attitude_error_deg_max"),
        steady_state_rate_error_deg_s_max=_opt(et, "steady_state_rate_error_deg_s_max"),
        steady_state_position_error_m_max=_opt(et, "steady_state_position_error_m_max"),
        final_position_error_m_max=_opt(et, "final_position_error_m_max"),
        position_band_m=et.number("position_band_m", lo=0.0, lo_open=True)
        if et.has("position_band_m") else None,
        position_settling_time_s_max=_opt(et, "position_settling_time_s_max"),
        rate_settling_band_deg_s=et.number("rate_settling_band_deg_s", lo=0.0, lo_open=True)
        if et.has("rate_settling_band_deg_s") else None,
        rate_settling_time_s_max=_opt(et, "rate_settling_time_s_max"),
        steady_state_window_s=et.number(
            "steady_state_window_s", 10.0, lo=0.0, lo_open=True, hi=duration_s
        ),
    )
    for key, band in (("position_settling_time_s_max", "position_band_m"),
                      ("rate_settling_time_s_max", "rate_settling_band_deg_s")):
        if et.has(key) and not et.has(band):
            raise et.error(key, et.raw(key, None), f"set together with {band} (the band it "
                           "settles into)")
    et.done()
    root.done()
    return Scenario(
        path=source,
        name=name,
        description=description,
        duration_s=duration_s,
        seed=seed,
        actual=actual,
        nominal=nominal,
        thrusters=thrusters,
        valve=valve,
        gyro=gyro,
        accel=accel,
        star_tracker=st,
        rel_nav=nav,
        bus=bus,
        q0_BN=q0,
        omega0_BN_B_rad_s=w0,  # type: ignore[arg-type]
        r0_N_m=r0,
        v0_N_m_s=v0,
        q_target_BN=q_target,
        manoeuvre_start_s=t_start,
        flight_sw=fsw,
        faults=faults,
        expectations=exp,
        raw=data,
        dynamics=dynamics,
        environment=environment,
        disturbance=disturbance,
        events=events,
        reference=ref,
        r_target_N_m=r_target,
    )


def apply_overrides(data: dict[str, Any], overrides: list[str], source: str) -> None:
    """Apply ``KEY=VALUE`` overrides (dotted keys, TOML values) to parsed scenario data in place.

    ``bus.bitrate_bps=125000``, ``flight_sw.modulator.km=10.0``, ``manoeuvre.t_start_s=2``;
    an element of an array of tables by its index: ``thrusters.list[0].max_thrust_N=5.0``,
    ``faults[1].t_s=30``. A value that is not valid TOML is taken as a string. Errors name
    the override.
    """
    for item in overrides:
        key, sep, text = item.partition("=")
        if not sep or not key:
            raise ConfigError(source, "--set", item, "KEY=VALUE with a dotted KEY")
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
            value = text
        table = data
        parts = [_override_part(source, key, p) for p in key.split(".")]
        for name, index in parts[:-1]:
            nxt = table.setdefault(name, {} if index is None else [])
            if index is not None:
                if not isinstance(nxt, list) or not 0 <= index < len(nxt):
                    size = len(nxt) if isinstance(nxt, list) else 0
                    raise ConfigError(source, key, item, f"{name!r} to be an array of tables "
                                      f"with an element {index} (it has {size})")
                nxt = nxt[index]
            if not isinstance(nxt, dict):
                raise ConfigError(source, key, item, f"{name!r} to be a table")
            table = nxt
        name, index = parts[-1]
        if index is not None:
            raise ConfigError(source, key, item, "a key inside the element (e.g. "
                              f"{name}[{index}].t_s), or the whole array: {name}=[...]")
        table[name] = value


_OVERRIDE_PART = re.compile(r"([A-Za-z0-9_-]+)(?:\[(\d+)\])?")


def _override_part(source: str, key: str, part: str) -> tuple[str, int | None]:
    """``name`` or ``name[i]`` of a dotted override key."""
    m = _OVERRIDE_PART.fullmatch(part)
    if m is None:
        raise ConfigError(source, "--set", key, "a dotted KEY of names, each optionally "
                          "indexed as name[i]")
    return m.group(1), None if m.group(2) is None else int(m.group(2))


def load_scenario(path: str | Path, overrides: list[str] | None = None) -> Scenario:
    """Read and validate the scenario file at ``path``, after ``KEY=VALUE`` overrides."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(
            str(p), "<file>", str(p), f"a readable scenario file ({exc.strerror})"
        ) from exc
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(str(p), "<syntax>", str(exc), "valid TOML") from exc
    apply_overrides(data, overrides or [], str(p))
    try:
        sc = parse_scenario(data, str(p))
    except ConfigError as exc:
        item = _override_of(exc.key, overrides or [])
        if item is None:
            raise
        raise ConfigError(override_source(str(p), [item]), exc.key, exc.value,
                          exc.expected) from exc
    return dataclasses.replace(sc, overrides=tuple(overrides or ()))


def override_source(path: str, items: list[str]) -> str:
    """Where a value came from: the file, or the ``--set`` items applied to it."""
    if not items:
        return path
    return "command line " + " ".join(f"--set {i}" for i in items) + f" (on {path})"


def _override_of(key: str, overrides: list[str]) -> str | None:
    """The ``--set`` item that wrote ``key`` (or a table above or below it), if any."""
    for item in reversed(overrides):  # the last one wins, as applied
        k = item.partition("=")[0]
        if key == k or key.startswith(k + ".") or k.startswith(key + "."):
            return item
    return None
