"""Scenario TOML data -> a validated :class:`~bench.scenario.spec.Scenario`.

Every bad field raises :class:`dbc.errors.ConfigError` naming the file, the dotted key,
the value and what was expected; unknown keys are errors too (:class:`dbc.schema.Table`).
Nothing in a scenario is ever evaluated. Angles in degrees in the file become radians
here; rates per hour become per second; sensor ranges default to, and may not exceed,
the DBC's signal ranges; the number of thrusters to what the command frames address.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from cantools.database.can import Database

from bench.scenario.expectations import parse_expectations
from bench.scenario.limits import MAX_DURATION_S, NS_PER_S, PERIOD_MESSAGE, SEED_MAX
from bench.scenario.spec import (
    EVENT_KINDS,
    TRANSLATIONS,
    VALVE_MODELS,
    AccelSpec,
    BusSpecCfg,
    CaptureSpec,
    DynamicsSpec,
    EnvironmentSpec,
    GyroSpec,
    MassSpec,
    Quat,
    RelNavSpec,
    Scenario,
    StarTrackerSpec,
    ThrusterSpec,
    ValveSpec,
)
from bench.station.dynamics.hcw import SEED000_ORBIT_RADIUS_M
from bench.station.dynamics.rigid_body import (
    MassProperties,
    quat_from_axis_angle,
    quat_multiply,
    quat_normalize,
)
from bench.station.environment.disturbance import FORCE_FRAMES, DisturbanceParams, Sinusoid
from bench.station.faults import parse_faults
from bench.station.reference import KIND_STEP, KINDS, ReferenceParams, reference
from bench.station.valves.geometry import (
    MAX_MISALIGNMENT_DEG,
    ThrusterGeometry,
    misaligned_geometry,
)
from bench.station.valves.layouts import LAYOUT_MAX_THRUST_N, LAYOUTS
from dbc import validation as check
from dbc.codec import bitrate_bps, bitrate_range_bps, cycle_time_ns
from dbc.database import load_database
from dbc.errors import ConfigError
from dbc.icd import Icd
from dbc.schema import Table

MAX_THRUST_SCALE = 2.0
"""``[thrusters] actual_thrust_scale`` at most this: a thruster twice its rating is no
longer a tolerance."""
MAX_COM_OFFSET_M = 10.0
"""``[vehicle] com_offset_B_m``: each component at most this [m] (the vehicles a bench hosts
are metres across)."""

DEG_RAD = math.pi / 180.0
# A target Euler angle beyond a full turn is no attitude anyone writes: a unit slip.
EULER_LIMIT_DEG = 360.0
SQRT_HOUR_S = 60.0  # sqrt(3600 s)
S_PER_H = 3600.0
QUAT_SIZE = 4
VEC3_SIZE = 3


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


def _quat(t: Table, key: str) -> Quat:
    a, b, c, d = t.unit_vector(key, QUAT_SIZE)
    return (a, b, c, d)


def _turned(q_BN: Quat, rotation_deg: tuple[float, ...]) -> Quat:
    """``q_BN`` followed by a body-axis rotation given as a rotation vector [deg]
    (``[initial] attitude_offset_deg``: a dispersed initial attitude)."""
    sq = 0.0  # left to right (sum() of floats is compensated from Python 3.12)
    for x in rotation_deg:
        sq += x * x
    angle = math.radians(math.sqrt(sq))
    if angle == 0.0:
        return q_BN
    axis = tuple(math.radians(x) / angle for x in rotation_deg)
    return quat_normalize(quat_multiply(q_BN, quat_from_axis_angle(axis, angle)))  # type: ignore[arg-type]


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
                    it.unit_vector("d_thr_B", VEC3_SIZE),  # type: ignore[arg-type]
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
    max_thrusters = Icd.from_database(load_database()).max_thrusters
    if len(geo) > max_thrusters:
        raise t.error("list", len(geo), "at most 16 thrusters (THR_CMD_0..3 carry 16)")
    if t.has("max_thrust_per_thruster_N"):
        if layout == "explicit":
            raise t.error("max_thrust_per_thruster_N", t.raw("max_thrust_per_thruster_N"),
                          "absent with an explicit list (give max_thrust_N per entry)")
        maxima = t.vector("max_thrust_per_thruster_N", len(geo), lo=0.0, lo_open=True)
        geo = [dataclasses.replace(g, max_thrust_N=m) for g, m in zip(geo, maxima, strict=True)]
    geo = _actual_thrusters(t, geo)
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


def _actual_thrusters(t: Table, geo: list[ThrusterSpec]) -> list[ThrusterSpec]:
    """The bench's truth where it differs from what the flight software is told (a
    campaign's dispersions): ``actual_thrust_scale`` (one factor per thruster, in
    (0, MAX_THRUST_SCALE]) and ``actual_misalignment_deg`` (one rotation vector per
    thruster [deg]: the force direction turned by its norm about its direction)."""
    n = len(geo)
    if t.has("actual_thrust_scale"):
        scales = t.vector("actual_thrust_scale", n, lo=0.0, lo_open=True, hi=MAX_THRUST_SCALE)
        geo = [dataclasses.replace(g, thrust_scale=k) for g, k in zip(geo, scales, strict=True)]
    if t.has("actual_misalignment_deg"):
        rows = t.raw("actual_misalignment_deg")
        if not isinstance(rows, list) or len(rows) != n:
            raise t.error("actual_misalignment_deg", rows,
                          f"{n} rotation vectors [deg], one per thruster")
        key = t.dotted("actual_misalignment_deg")
        out = []
        for i, (g, row) in enumerate(zip(geo, rows, strict=True)):
            rv = check.triple(t.source, f"{key}[{i}]", row, unit="deg")
            angle = math.sqrt(rv[0] * rv[0] + rv[1] * rv[1] + rv[2] * rv[2])
            if angle > MAX_MISALIGNMENT_DEG:
                raise ConfigError(t.source, f"{key}[{i}]", list(rv),
                                  f"a rotation of at most {MAX_MISALIGNMENT_DEG:g} deg")
            if angle > 0.0:
                axis = (rv[0] / angle, rv[1] / angle, rv[2] / angle)
                _, turned = misaligned_geometry(ThrusterGeometry(g.r_thr_B_m, g.d_thr_B),
                                                {"angle_deg": angle, "axis_B": axis}, t.source)
                g = dataclasses.replace(g, actual_d_thr_B=turned.d_thr_B)
            out.append(g)
        geo = out
    return geo


def _response_delay(t: Table, period_s: float) -> float:
    """``[bus] fsw_response_delay_s``: shorter than one control period, the lockstep
    protocol's assumption (a cycle's commands are applied before the next SYNC)."""
    delay = t.number("fsw_response_delay_s", 0.001, lo=0.0)
    if not delay < period_s:
        raise t.error("fsw_response_delay_s", delay, f"a delay shorter than the control "
                      f"period ({period_s:g} s: lockstep applies each cycle's commands before "
                      "the next SYNC)")
    return delay


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
        bias_rad_s=tuple(x * DEG_RAD / S_PER_H for x in g.vector("bias_deg_h", 3)),  # type: ignore[arg-type]
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
        boresight_B=s.unit_vector("boresight_B", VEC3_SIZE),  # type: ignore[arg-type]
    )
    s.done()
    nav = None
    if t.has("rel_nav"):
        n = t.table("rel_nav")
        nav = RelNavSpec(n.number("noise_pos_m", lo=0.0), n.number("noise_vel_m_s", lo=0.0))
        n.done()
    t.done()
    return gyro, accel, st, nav






def _dynamics_environment(root: Table) -> tuple[DynamicsSpec, EnvironmentSpec]:
    dt = root.table("dynamics", {})
    dyn = DynamicsSpec(
        translation=dt.string("translation", "inertial", choices=TRANSLATIONS),
        orbit_radius_m=dt.number("orbit_radius_m", SEED000_ORBIT_RADIUS_M, lo=0.0, lo_open=True),
    )
    dt.done()
    et = root.table("environment", {})
    env = EnvironmentSpec(
        gravity_gradient=et.flag("gravity_gradient", False),
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
    if not isinstance(v, list) or len(v) != VEC3_SIZE:
        raise t.error("mrp_coefficients", v, expected)
    key = t.dotted("mrp_coefficients")
    return tuple(check.vector(t.source, f"{key}[{i}]", c, None) for i, c in enumerate(v))


def parse_scenario(data: dict[str, Any], source: str) -> Scenario:
    """Validate parsed TOML ``data`` from file ``source`` into a :class:`Scenario`."""
    root = Table(data, source)
    db = load_database()
    sc = root.table("scenario")
    name = sc.string("name")
    description = sc.string("description", "")
    period_s = cycle_time_ns(db, PERIOD_MESSAGE) / NS_PER_S
    duration_s = sc.number("duration_s", lo=period_s, hi=MAX_DURATION_S)
    seed = sc.integer("seed", 0, lo=0, hi=SEED_MAX)
    sc.done()

    vt = root.table("vehicle")
    actual = _mass(vt)
    if vt.has("com_offset_B_m"):
        c = vt.vector("com_offset_B_m", VEC3_SIZE, lo=-MAX_COM_OFFSET_M, hi=MAX_COM_OFFSET_M)
        actual = dataclasses.replace(actual, com_offset_B_m=(c[0], c[1], c[2]))
    nominal = _mass(vt.table("nominal")) if vt.has("nominal") else actual
    vt.done()

    thrusters, valve = _thrusters(root.table("thrusters"))
    gyro, accel, st, nav = _sensors(root.table("sensors"), db)

    bt = root.table("bus", {})
    rate_default, (rate_lo, rate_hi) = bitrate_bps(db), bitrate_range_bps(db)
    bus = BusSpecCfg(
        bitrate_bps=bt.integer("bitrate_bps", rate_default, lo=rate_lo, hi=rate_hi),
        fsw_response_delay_s=_response_delay(bt, period_s),
        stall_timeout_s=bt.number("stall_timeout_s", 2.0, lo=0.0, lo_open=True),
        startup_timeout_s=bt.number("startup_timeout_s", 60.0, lo=0.0, lo_open=True),
    )
    bt.done()

    it = root.table("initial", {})
    q0 = _quat(it, "q_BN") if it.has("q_BN") else (1.0, 0.0, 0.0, 0.0)
    if it.has("attitude_offset_deg"):
        q0 = _turned(q0, it.vector("attitude_offset_deg", VEC3_SIZE,
                                   lo=-MAX_MISALIGNMENT_DEG, hi=MAX_MISALIGNMENT_DEG))
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

    faults = parse_faults(
        root.tables("faults"), duration_s, len(thrusters),
        frozenset(m.name for m in db.messages), frozenset(n.name for n in db.nodes),
    )

    exp = parse_expectations(root.table("expectations", {}), duration_s)
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


