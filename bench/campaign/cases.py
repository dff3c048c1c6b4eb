"""A campaign's cases: each one scenario + ``--set`` overrides + a run seed. Pure.

A *vehicle* is one draw of every dispersion (Monte Carlo: ``cases`` of them; factorial:
every combination of the sweeps' levels, in file order, the last varying fastest). With
``failures``, every vehicle is run once per single-thruster failure of each kind
(thruster-major within a kind), else once. Vehicle ``j``'s draws come from a generator
seeded by ``SeedSequence([campaign seed, j, DRAW_STREAM])`` and its run seed from
``SeedSequence([campaign seed, j, RUN_SEED_STREAM])``, so a case depends on its own index
alone: any case reruns alone, and results do not depend on the order cases run in.

A case's overrides carry whole leaf values (``thrusters.actual_thrust_scale=[1.0, 0.98,
...]``) so ``thruster-hil run SCENARIO --seed S --set ...`` reproduces it outside the
campaign. A dispersed mass or inertia leaves what the flight software is told at the
scenario's values (``vehicle.nominal``), unless the scenario gives its own nominal.
A value is an offset from (``apply = "offset"``) or a factor on (``"scale"``) the
scenario's value; a key the scenario leaves out starts from :data:`ABSENT_DEFAULTS`;
an integer key (``bus.bitrate_bps``) gets the nearest integer.
"""

from __future__ import annotations

import copy
import itertools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from bench.campaign.distributions import Value
from bench.campaign.paths import (
    Part,
    expand,
    get_value,
    leaf_key,
    leaf_path,
    path_text,
    set_value,
    toml_value,
)
from bench.campaign.spec import CampaignSpec, Dispersion
from bench.scenario.limits import SEED_MAX
from dbc.errors import ConfigError

DRAW_STREAM = 1
RUN_SEED_STREAM = 2


@dataclass(frozen=True)
class Case:
    """One run of a campaign."""

    index: int
    name: str
    vehicle: int
    seed: int
    overrides: tuple[str, ...]
    values: tuple[tuple[str, Value], ...]
    """Each dispersed concrete key and its value, in draw order."""
    failure: tuple[str, int] | None = None
    """(kind, thruster) of the injected single-thruster failure, if any."""


def _zeros3(_n: int) -> list[float]:
    return [0.0, 0.0, 0.0]


ABSENT_DEFAULTS: dict[str, Callable[[int], Any]] = {
    "thrusters.actual_thrust_scale": lambda n: [1.0] * n,
    "thrusters.actual_misalignment_deg": lambda n: [[0.0, 0.0, 0.0] for _ in range(n)],
    "vehicle.com_offset_B_m": _zeros3,
    "initial.attitude_offset_deg": _zeros3,
    "initial.omega_BN_B_deg_s": _zeros3,
    "initial.r_N_m": _zeros3,
    "initial.v_N_m_s": _zeros3,
}
"""Scenario keys that may be absent, and their nominal value (n: the number of thrusters)."""

MASS_KEYS = ("vehicle.mass_kg", "vehicle.inertia_B_kgm2")


def with_defaults(keys: list[tuple[Part, ...]], data: dict[str, Any],
                  n_thrusters: int) -> dict[str, Any]:
    """A copy of scenario ``data`` with every dispersed key of ``keys`` (parsed by
    :func:`~bench.campaign.paths.parse_key`) that it leaves out set to its nominal value
    (:data:`ABSENT_DEFAULTS`)."""
    out = copy.deepcopy(data)
    for parts in keys:
        fill = ABSENT_DEFAULTS.get(leaf_key(tuple((n, ()) for n, _ in parts)))
        if fill is None:
            continue
        table: dict[str, Any] = out
        for name, _ in parts[:-1]:
            table = table.setdefault(name, {})
        table.setdefault(parts[-1][0], fill(n_thrusters))
    return out


def _targets(spec: CampaignSpec, base: dict[str, Any]) -> list[list[tuple[Part, ...]]]:
    out = []
    for i, d in enumerate(spec.dispersions):
        try:
            out.append(expand(base, d.parts))
        except KeyError as exc:
            raise ConfigError(spec.source, f"dispersions[{i}].key", d.key,
                              f"a key the scenario has ({exc.args[0]})") from exc
    return out


def _applied(d: Dispersion, nominal: Any, x: Value, source: str) -> Value:
    if d.apply == "value":
        v: Any = x
    else:
        if isinstance(nominal, bool) or not isinstance(nominal, int | float) or \
                isinstance(x, bool) or not isinstance(x, int | float):
            raise ConfigError(source, f"dispersions.{d.key}.apply", d.apply,
                              "value, for a key or draw that is not a number")
        v = nominal + x if d.apply == "offset" else nominal * x
    if isinstance(nominal, int) and not isinstance(nominal, bool) and isinstance(v, float):
        v = round(v)
    return v


def _vehicle_draws(spec: CampaignSpec, targets: list[list[tuple[Part, ...]]]) -> list[list[Any]]:
    """Per vehicle, per dispersion, per concrete target: the drawn (or swept) value."""
    if spec.study == "factorial":
        grids = [d.dist.levels() for d in spec.dispersions]
        return [[[lvl] * len(t) for lvl, t in zip(combo, targets, strict=True)]
                for combo in itertools.product(*grids)]
    draws = []
    for j in range(spec.cases):
        rng = np.random.default_rng(np.random.SeedSequence([spec.seed, j, DRAW_STREAM]))
        draws.append([[d.dist.draw(rng) for _ in t]
                      for d, t in zip(spec.dispersions, targets, strict=True)])
    return draws


def run_seed(spec: CampaignSpec, vehicle: int, scenario_seed: int) -> int:
    """The run seed of vehicle ``vehicle`` (module docstring)."""
    if not spec.vary_seed:
        return scenario_seed
    ss = np.random.SeedSequence([spec.seed, vehicle, RUN_SEED_STREAM])
    return int(ss.generate_state(1, np.uint64)[0] % (SEED_MAX + 1))


def build_cases(spec: CampaignSpec, data: dict[str, Any], n_thrusters: int,
                scenario_seed: int) -> list[Case]:
    """Every case of the campaign on scenario ``data`` (module docstring; ``data`` with the
    campaign's own overrides already applied)."""
    base = with_defaults([d.parts for d in spec.dispersions], data, n_thrusters)
    targets = _targets(spec, base)
    pin_nominal = "nominal" not in base.get("vehicle", {}) and any(
        leaf_key(p).startswith(MASS_KEYS) for t in targets for p in t)
    vehicles = []
    for j, draws in enumerate(_vehicle_draws(spec, targets)):
        applied = copy.deepcopy(base)
        values: list[tuple[str, Value]] = []
        leaves: dict[str, tuple[Part, ...]] = {}
        for d, paths, xs in zip(spec.dispersions, targets, draws, strict=True):
            for p, x in zip(paths, xs, strict=True):
                v = _applied(d, get_value(base, p), x, spec.source)
                set_value(applied, p, v)
                values.append((path_text(p), v))
                leaves.setdefault(leaf_key(p), p)
        overrides = [*spec.overrides] + [
            f"{k}={toml_value(get_value(applied, leaf_path(p)))}" for k, p in leaves.items()]
        if pin_nominal:
            v = base["vehicle"]
            overrides.append("vehicle.nominal=" + toml_value(
                {"mass_kg": v["mass_kg"], "inertia_B_kgm2": v["inertia_B_kgm2"]}))
        vehicles.append((applied, tuple(overrides), tuple(values),
                         run_seed(spec, j, scenario_seed)))
    if not spec.failures:
        return [Case(j, f"{j:04d}", j, seed, ov, vals)
                for j, (_, ov, vals, seed) in enumerate(vehicles)]
    cases: list[Case] = []
    for kind in spec.failures:
        for k in range(n_thrusters):
            for j, (applied, ov, vals, seed) in enumerate(vehicles):
                fault = {"t_s": spec.fault_time_s, "kind": kind, "thruster": k}
                faults = [*applied.get("faults", []), fault]
                name = f"{kind}_T{k:02d}" + (f"_v{j:04d}" if len(vehicles) > 1 else "")
                cases.append(Case(len(cases), name, j, seed,
                                  (*ov, f"faults={toml_value(faults)}"), vals, (kind, k)))
    return cases

