"""Builders of the modulators: ``[flight_sw.modulator]``.

What it does: one builder per ``kind`` (:data:`MODULATORS`: PWPF, Schmitt trigger,
remainder, proportional); each returns a factory, since every thruster gets its own
modulator (and a restarted one after a reconfiguration). The minimum on-time [s] is the
vehicle's.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType

from dbc.schema import Table
from flight_sw.builders.vehicle import Vehicle
from flight_sw.modulation.base import Modulator
from flight_sw.modulation.proportional import ProportionalModulator
from flight_sw.modulation.pwpf import PwpfModulator, PwpfParams
from flight_sw.modulation.remainder import RemainderModulator, RemainderParams
from flight_sw.modulation.schmitt import SchmittModulator, SchmittParams


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


MODULATORS: Mapping[str, Callable[[Table, Vehicle], Callable[[], Modulator]]] = MappingProxyType({
    "pwpf": _pwpf,
    "schmitt": _schmitt,
    "remainder": _remainder,
    "proportional": _proportional,
})
