"""The nominal vehicle the flight-software strategies are built from, and shared helpers.

What it does: :class:`Vehicle` reads the configuration file's vehicle data
(dbc.contract.FswConfig: nominal mass [kg] and inertia [kg m²], the thrusters' positions
[m], directions in body axes and each one's maximum thrust [N], the ``valves`` table: the
minimum on-time and the valves' delays and time constants [s]),
builds the effectiveness matrix and records which demand rows the allocator gets (torque,
or the full wrench in 6 DoF). The helpers read the table forms several builder families
share (a matrix, an optional rate limit, a dataclass whose every field is optional).

Inputs: :class:`dbc.schema.Table` views of the configuration (errors name the file and
the dotted key). Units: as the field names say; angles in the file are in degrees.

Source: project convention (``flight_sw`` configuration file, ``docs/scenarios.md``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from dbc import validation as check
from dbc.schema import Table
from flight_sw.allocation.effectiveness import effectiveness_matrix
from flight_sw.fdir.valve_timing import DEFAULT_TIMING, ValveTiming

DEG_RAD = math.pi / 180.0
ARCSEC_RAD = DEG_RAD / 3600.0
SQRT_HOUR_S = 60.0
NS_PER_S = 1_000_000_000
TORQUE_ROWS = slice(3, 6)
WRENCH_ROWS = slice(0, 6)


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
        # each thruster its own maximum (e.g. seed 001's opposing valves of unequal
        # bounds); every consumer gets the per-thruster vector (n,) [N]
        self.max_thrust_each_N = np.array(
            [x.number("max_thrust_N", lo=0.0, lo_open=True) for x in thr])
        for x in thr:
            x.done()
        valves = root.table("valves")
        self.min_on_s = valves.number("min_on_s", lo=0.0)
        self.valve_timing = valve_timing(valves)
        self.effectiveness = effectiveness_matrix(self.r_thr_B_m, self.d_thr_B)
        self.demand_rows = TORQUE_ROWS  # WRENCH_ROWS once a translation controller is set
        self.control_period_ns = 0
        self.imu_period_ns = 0


def valve_timing(t: Table) -> ValveTiming:
    """The vehicle's valve timing from the configuration's ``valves`` table
    (dbc.contract.ValveTiming); the command delay is the flight software's own default
    (:mod:`flight_sw.fdir.valve_timing`)."""
    timing = ValveTiming(
        command_delay_s=DEFAULT_TIMING.command_delay_s,
        open_delay_s=t.number("open_delay_s", lo=0.0),
        close_delay_s=t.number("close_delay_s", lo=0.0),
        rise_tau_s=t.number("rise_tau_s", lo=0.0),
        tail_tau_s=t.number("tail_tau_s", lo=0.0),
    )
    t.done()
    return timing


def max_rate(t: Table) -> float:
    """Optional ``max_rate_deg_s`` in rad/s (inf when absent)."""
    if not t.has("max_rate_deg_s"):
        return math.inf
    return t.number("max_rate_deg_s", lo=0.0, lo_open=True) * DEG_RAD


def matrix(t: Table, key: str, rows: int, cols: int) -> np.ndarray:
    """The ``rows``×``cols`` matrix of finite numbers at ``key`` (ConfigError naming it)."""
    return check.matrix(t.source, f"{t.path}.{key}" if t.path else key, t.raw(key), rows, cols)


def dataclass_params(t: Table, cls: Any, defaults: dict[str, Any]) -> Any:
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


def nominal_mass(v: Vehicle) -> dict[str, Any]:
    j = v.inertia_B_kgm2
    return {
        "mass_kg": v.mass_kg,
        "inertia_B_kgm2": (float(j[0, 0]), float(j[1, 1]), float(j[2, 2])),
    }


def upper_N(v: Vehicle) -> tuple[float, ...]:
    return tuple(float(x) for x in v.max_thrust_each_N)
