"""What crosses between bench and flight software besides frames: typed, versioned records.

The bench starts the flight software by command (``--fsw-cmd``) with file placeholders;
these records are the files' content (JSON), each tagged with ``schema`` and ``version``:

* :class:`FswConfig` (``{config}``, written by the bench, read by the flight software):
  the nominal vehicle (mass [kg], inertia about the reference point, body axes [kg m^2]),
  the thrusters in command order (thruster k is ``OnTime_Tkk`` of the DBC: position
  ``r_thr_B_m`` [m] about the vehicle's reference point, unit direction of the thrust
  force ``d_thr_B``, maximum thrust [N]), the valve drive electronics' timing (minimum
  on-time, opening and closing delays [s]), the manoeuvre (step: target attitude q_BN,
  scalar first, Hamilton convention, rotating N into B; or an MRP polynomial reference;
  start time [s] on the bench's time axis; optional target position r_N [m]) and the
  scenario's ``[flight_sw]`` table verbatim (our flight software's strategies; another
  flight software may ignore it). It is the only source of the thruster geometry, limits
  and target.
* :class:`FswRefusal` (``{stats}``, written by a flight software that refuses its
  configuration, which then exits with :data:`EXIT_REFUSED`): where the bad value came
  from, the key, the value and what was expected.
* The statistics (``{stats}``, written by the flight software at the end of a run, and
  whenever it likes before): a JSON object with ``schema`` = :data:`STATS_SCHEMA`; every
  field is optional (:data:`STATS_FIELDS` names those the bench reads). A flight software
  may write none: the bench then reports only what it saw on the bus.

A record of another major version is refused with a :class:`~dbc.errors.ConfigError`
naming the file, so neither side misreads a newer one. docs/icd.md has the field tables.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from dbc.errors import ConfigError
from dbc.schema import Table

CONFIG_SCHEMA = "thruster-hil/fsw-config"
REFUSAL_SCHEMA = "thruster-hil/fsw-refusal"
STATS_SCHEMA = "thruster-hil/fsw-stats"
VERSION = 1
EXIT_REFUSED = 2  # the flight software's exit code when it refuses its configuration
UNIT_NORM_TOL = 1e-6
VALVE_KEYS = ("min_on_s", "open_delay_s", "close_delay_s", "rise_tau_s", "tail_tau_s")
MANOEUVRE_KINDS = ("step", "mrp_polynomial")
# statistics fields the bench reads (all optional): see docs/icd.md
STATS_FIELDS = ("cycles", "overruns", "sent", "received", "second_sender_evidence", "mode",
                "cycle_time_us", "allocation", "inertia_estimate_B_kgm2",
                "inertia_identification", "restarts",
                "restarts_refused", "fdir", "warnings", "bus_overrun_drops",
                "bus_overrun_drops_by_pid")
Vec3 = tuple[float, float, float]


def _header(t: Table, schema: str) -> None:
    """Check a record's ``schema`` and ``version`` (same major version only)."""
    got = t.string("schema")
    if got != schema:
        raise t.error("schema", got, repr(schema))
    version = t.integer("version", lo=1)
    if version != VERSION:
        raise t.error("version", version, f"{VERSION} (this build reads version {VERSION})")


@dataclass(frozen=True)
class ThrusterConfig:
    """One thruster as the flight software sees it (nominal geometry and limit)."""

    r_thr_B_m: Vec3
    d_thr_B: Vec3
    max_thrust_N: float


@dataclass(frozen=True)
class ValveTiming:
    """The valves' nominal timing [s]: pulses shorter than ``min_on_s`` are extended to it
    by the drive electronics; the valve starts opening ``open_delay_s`` after a command's
    receipt and closing ``close_delay_s`` after its end; thrust rises and decays with the
    first-order time constants ``rise_tau_s`` and ``tail_tau_s``."""

    min_on_s: float
    open_delay_s: float
    close_delay_s: float
    rise_tau_s: float
    tail_tau_s: float


@dataclass(frozen=True)
class Manoeuvre:
    """The reference: hold until ``t_start_s``, then ``q_target_BN`` (a step), or follow an
    MRP polynomial (``mrp_coefficients``: one row per axis, highest power first, in the
    time since the start [s]); ``q_target_BN`` is then its attitude at the end of the run."""

    q_target_BN: tuple[float, float, float, float]
    t_start_s: float
    kind: str = "step"
    mrp_coefficients: tuple[tuple[float, ...], ...] = ()
    r_target_N_m: Vec3 | None = None


@dataclass(frozen=True)
class FswConfig:
    """The flight software's configuration file (module docstring)."""

    source: str
    mass_kg: float
    inertia_B_kgm2: tuple[Vec3, Vec3, Vec3]
    thrusters: tuple[ThrusterConfig, ...]
    valves: ValveTiming
    manoeuvre: Manoeuvre
    flight_sw: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.thrusters:
            raise ConfigError(self.source, "thrusters", [], "at least one thruster")
        q = self.manoeuvre.q_target_BN
        if abs(math.sqrt(sum(x * x for x in q)) - 1.0) > UNIT_NORM_TOL:
            raise ConfigError(self.source, "manoeuvre.q_target_BN", list(q), "a unit quaternion")

    def to_json(self) -> dict[str, Any]:
        """The file's content."""
        m = self.manoeuvre
        man: dict[str, Any] = {"kind": m.kind, "q_target_BN": list(m.q_target_BN),
                               "t_start_s": m.t_start_s}
        if m.mrp_coefficients:
            man["mrp_coefficients"] = [list(c) for c in m.mrp_coefficients]
        if m.r_target_N_m is not None:
            man["r_target_N_m"] = list(m.r_target_N_m)
        return {
            "schema": CONFIG_SCHEMA, "version": VERSION, "source": self.source,
            "vehicle": {"mass_kg": self.mass_kg,
                        "inertia_B_kgm2": [list(r) for r in self.inertia_B_kgm2]},
            "thrusters": [{"r_thr_B_m": list(t.r_thr_B_m), "d_thr_B": list(t.d_thr_B),
                           "max_thrust_N": t.max_thrust_N} for t in self.thrusters],
            "valves": {"min_on_s": self.valves.min_on_s,
                       "open_delay_s": self.valves.open_delay_s,
                       "close_delay_s": self.valves.close_delay_s,
                       "rise_tau_s": self.valves.rise_tau_s,
                       "tail_tau_s": self.valves.tail_tau_s},
            "manoeuvre": man,
            "flight_sw": self.flight_sw,
        }

    @classmethod
    def from_json(cls, data: Any, source: str) -> FswConfig:
        """Validate a configuration file's content; ConfigError names file, key and value."""
        root = Table(data, source)
        _header(root, CONFIG_SCHEMA)
        origin = root.string("source", source)
        vt = root.table("vehicle")
        mass = vt.number("mass_kg", lo=0.0, lo_open=True)
        inertia = vt.matrix3("inertia_B_kgm2")
        vt.done()
        thrusters = []
        for t in root.tables("thrusters"):
            thrusters.append(ThrusterConfig(t.vector3("r_thr_B_m"), t.vector3("d_thr_B"),
                                            t.number("max_thrust_N", lo=0.0, lo_open=True)))
            t.done()
        vl = root.table("valves")
        valves = ValveTiming(*(vl.number(k, lo=0.0) for k in VALVE_KEYS))
        vl.done()
        mt = root.table("manoeuvre")
        kind = mt.string("kind", "step", choices=MANOEUVRE_KINDS)
        coeffs = mt.raw("mrp_coefficients", [])
        if not isinstance(coeffs, list):
            raise mt.error("mrp_coefficients", coeffs, "a list of rows of numbers")
        man = Manoeuvre(mt.vector4("q_target_BN"), mt.number("t_start_s", lo=0.0), kind,
                        tuple(tuple(float(x) for x in row) for row in coeffs),
                        mt.vector3("r_target_N_m") if mt.has("r_target_N_m") else None)
        mt.done()
        fsw = root.raw("flight_sw", {})
        if not isinstance(fsw, dict):
            raise root.error("flight_sw", fsw, "a table")
        root.done()
        return cls(origin, mass, inertia, tuple(thrusters), valves, man, fsw)  # type: ignore[arg-type]


def _json_safe(x: Any) -> bool:
    """``x`` is made of JSON's types only (finite numbers)."""
    if x is None or isinstance(x, (bool, int, str)):
        return True
    if isinstance(x, float):
        return math.isfinite(x)
    if isinstance(x, (list, tuple)):
        return all(_json_safe(v) for v in x)
    if isinstance(x, dict):
        return all(isinstance(k, str) and _json_safe(v) for k, v in x.items())
    return False


@dataclass(frozen=True)
class FswRefusal:
    """A flight software's refusal of its configuration: where, which key, what value."""

    source: str
    key: str
    value: Any
    expected: str

    @property
    def message(self) -> str:
        """The refusal as one line (as :class:`~dbc.errors.ConfigError` words it)."""
        return str(ConfigError(self.source, self.key, self.value, self.expected))

    @classmethod
    def of(cls, exc: ConfigError) -> FswRefusal:
        """The refusal for a ConfigError."""
        return cls(exc.source, exc.key, exc.value, exc.expected)

    def to_json(self) -> dict[str, Any]:
        """The record (the value as JSON allows, else its text)."""
        value = self.value if _json_safe(self.value) else repr(self.value)
        return {"schema": REFUSAL_SCHEMA, "version": VERSION, "source": self.source,
                "key": self.key, "value": value, "expected": self.expected,
                "message": self.message}

    @classmethod
    def from_json(cls, data: Any, source: str) -> FswRefusal:
        """Read a refusal record; ConfigError if it is not one."""
        t = Table(data, source)
        _header(t, REFUSAL_SCHEMA)
        out = cls(t.string("source"), t.string("key"), t.raw("value", None), t.string("expected"))
        t.raw("message", "")
        t.done()
        return out
