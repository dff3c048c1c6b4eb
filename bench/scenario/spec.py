"""The validated scenario: frozen records of everything one run needs.

A :class:`Scenario` says everything about one run: vehicle (actual and nominal mass
properties), thrusters (geometry, per-thruster maximum thrust, valve dynamics), sensors,
bus, initial state, manoeuvre, the flight-software configuration (handed to the
flight-software process as data), scheduled faults and expectations. Built by
:func:`bench.scenario.parse.parse_scenario` from TOML data (file reading and ``--set``
overrides: :mod:`bench.scenario.load`); read by every room of the bench.

Units are in the field names (``_s``, ``_m``, ``_N`` ...); angles are radians;
quaternions are scalar-first q_BN. Pure data: no file, clock or socket.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from bench.station.dynamics.hcw import SEED000_ORBIT_RADIUS_M
from bench.station.environment.disturbance import DisturbanceParams
from bench.station.faults import FaultSpec
from bench.station.reference import KIND_STEP, ReferenceParams
from dbc.contract import FswConfig, Manoeuvre, ThrusterConfig, ValveTiming
from dbc.errors import BRIEF_CHARS

FSW_TABLE = "flight_sw"  # the table passed through to the flight software
TRANSLATIONS = ("inertial", "hcw")
"""[dynamics] translation: inertial (default) or HCW relative motion (station.dynamics.hcw)."""
VALVE_MODELS = ("on_off", "throttled")
"""[thrusters] valve_model: on_off (station.valves.valve), throttled (station.valves.throttled)."""
EVENT_KINDS = ("capture",)
"""[[events]] kinds: capture (bench.station.dynamics.capture)."""

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]


@dataclass(frozen=True)
class MassSpec:
    mass_kg: float
    inertia_B_kgm2: tuple[Vec3, Vec3, Vec3]
    com_offset_B_m: Vec3 = (0.0, 0.0, 0.0)
    """Where the centre of mass actually is relative to the thruster geometry's reference
    point [m, body axes] (the bench's truth only; the flight software assumes the origin)."""


@dataclass(frozen=True)
class ThrusterSpec:
    r_thr_B_m: Vec3
    d_thr_B: Vec3
    max_thrust_N: float | None = None
    """This thruster's maximum thrust [N]; None = the valve's ``max_thrust_N``."""
    thrust_scale: float = 1.0
    """Actual over nominal thrust (the bench's truth only; the flight software is told the
    nominal): ``[thrusters] actual_thrust_scale``."""
    actual_d_thr_B: Vec3 | None = None
    """Actual unit force direction (the bench's truth only), None = ``d_thr_B``:
    ``[thrusters] actual_misalignment_deg``."""


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
    net_delta_v_m_s_max: float | None = None  # |v_end − v0| the firing may leave [m/s]
    # (expectation row name, requirement ID) pairs: "settling_time_s", ..., "converged"
    requirements: tuple[tuple[str, str], ...] = ()

    def requirement(self, name: str) -> str | None:
        """The requirement ID the scenario gives the expectation row ``name``, if any."""
        return dict(self.requirements).get(name)


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
    def actual_max_thrusts_N(self) -> tuple[float, ...]:
        """What each thruster actually delivers at full thrust [N]: its maximum thrust times
        its ``thrust_scale`` (the bench's truth; :attr:`max_thrusts_N` is what the flight
        software is told)."""
        return tuple(m * t.thrust_scale if t.thrust_scale != 1.0 else m
                     for t, m in zip(self.thrusters, self.max_thrusts_N, strict=True))

    @property
    def has_position_reference(self) -> bool:
        """Whether the run has a position to hold or reach: a ``r_target_N_m``, or a
        position expectation (band, steady-state, final or settling limit). Without one it
        is an attitude-only run: its translation is reported as what the firing caused,
        not as a position error."""
        e = self.expectations
        return self.r_target_N_m is not None or any(
            x is not None for x in (e.position_band_m, e.steady_state_position_error_m_max,
                                    e.final_position_error_m_max,
                                    e.position_settling_time_s_max))

    @property
    def r_reference_N_m(self) -> Vec3:
        """Reference position of the position metrics [m] (target, else the initial one)."""
        return self.r0_N_m if self.r_target_N_m is None else self.r_target_N_m

    def fsw_config(self) -> dict[str, Any]:
        """The flight-software configuration file's content (dbc.contract.FswConfig): the
        nominal vehicle, every thruster with its own maximum thrust, the valves' nominal
        timing (``min_on_s`` 0 for throttled valves, which have no minimum pulse), the
        manoeuvre (an MRP polynomial's ``q_target_BN`` is its attitude at the end of the
        run) and ``[flight_sw]`` as it is."""
        v = self.valve
        ref = self.reference
        config = FswConfig(
            source=override_source(self.path, [
                o for o in self.overrides if o.startswith(FSW_TABLE + ".")]),
            mass_kg=self.nominal.mass_kg,
            inertia_B_kgm2=self.nominal.inertia_B_kgm2,
            thrusters=tuple(ThrusterConfig(t.r_thr_B_m, t.d_thr_B, m)
                            for t, m in zip(self.thrusters, self.max_thrusts_N, strict=True)),
            valves=ValveTiming(0.0 if v.model != "on_off" else v.min_on_s, v.open_delay_s,
                               v.close_delay_s, v.rise_tau_s, v.tail_tau_s),
            manoeuvre=Manoeuvre(self.q_target_BN, self.manoeuvre_start_s, ref.kind,
                                ref.mrp_coefficients if ref.kind != KIND_STEP else (),
                                self.r_target_N_m),
            flight_sw=self.flight_sw,
        )
        return config.to_json()



def override_source(path: str, items: list[str]) -> str:
    """Where a value came from: the file, or the ``--set`` items applied to it."""
    if not items:
        return path
    cut = [i if len(i) <= BRIEF_CHARS else i[:BRIEF_CHARS] + "..." for i in items]
    return "command line " + " ".join(f"--set {i}" for i in cut) + f" (on {path})"
