"""A campaign's cases: reproducible per index, applied as the run will read them."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from bench.campaign.cases import build_cases
from bench.campaign.spec import parse_campaign
from bench.scenario.load import apply_overrides
from bench.scenario.parse import parse_scenario
from dbc.datafile import parse_toml
from dbc.errors import ConfigError

REPO = Path(__file__).resolve().parents[3]
QUICKSTART = REPO / "scenarios" / "quickstart.toml"
N_THRUSTERS = 8


def _data() -> dict[str, Any]:
    return parse_toml(QUICKSTART.read_text(encoding="utf-8"), str(QUICKSTART))


def _spec(dispersions: list[dict[str, Any]], **campaign: Any) -> Any:
    c = {"scenario": str(QUICKSTART), "seed": 5, **campaign}
    return parse_campaign({"campaign": c, "dispersions": dispersions}, "c.toml", REPO)


MASS = {"name": "mass", "dist": "normal", "mean": 0.0, "sigma": 2.0, "apply": "offset"}
SCALE = {"name": "thrust_scale", "dist": "uniform", "low": 0.9, "high": 1.1}


def test_a_case_depends_on_its_index_alone() -> None:
    """The first 3 of 10 cases equal the 3 of a 3-case campaign; another seed differs."""
    ten = build_cases(_spec([MASS, SCALE], cases=10), _data(), N_THRUSTERS, 3)
    three = build_cases(_spec([MASS, SCALE], cases=3), _data(), N_THRUSTERS, 3)
    other = build_cases(_spec([MASS, SCALE], cases=3, seed=6), _data(), N_THRUSTERS, 3)
    assert ten[:3] == three and other[0].overrides != three[0].overrides
    assert len({c.seed for c in ten}) == 10


def test_overrides_rebuild_the_drawn_vehicle_and_keep_the_nominal() -> None:
    """Applied as --set, the overrides give the drawn mass and thrust scales to the bench
    and leave the flight software's mass at the scenario's 100 kg."""
    (case,) = build_cases(_spec([MASS, SCALE], cases=1), _data(), N_THRUSTERS, 3)
    d = _data()
    apply_overrides(d, list(case.overrides), "t")
    sc = parse_scenario(d, "t")
    values = dict(case.values)
    assert sc.actual.mass_kg == pytest.approx(100.0 + 0.0, abs=6.0 + 1e-9)
    assert sc.actual.mass_kg == values["vehicle.mass_kg"] and sc.nominal.mass_kg == 100.0
    assert [t.thrust_scale for t in sc.thrusters] == [
        values[f"thrusters.actual_thrust_scale[{k}]"] for k in range(N_THRUSTERS)]
    assert sc.fsw_config()["thrusters"] == parse_scenario(_data(), "t").fsw_config()["thrusters"]


def test_factorial_is_every_combination_last_fastest() -> None:
    """2 x 3 levels: 6 cases, the second sweep varying fastest; [*] sets every element."""
    sweeps = [{"key": "bus.bitrate_bps", "dist": "sweep", "values": [500_000, 1_000_000]},
              {"name": "thrust_scale", "dist": "sweep", "values": [0.9, 1.0, 1.1]}]
    cases = build_cases(_spec(sweeps, study="factorial"), _data(), N_THRUSTERS, 3)
    got = [(dict(c.values)["bus.bitrate_bps"], dict(c.values)["thrusters.actual_thrust_scale[7]"])
           for c in cases]
    assert got == [(b, s) for b in (500_000, 1_000_000) for s in (0.9, 1.0, 1.1)]


def test_failures_cross_every_vehicle() -> None:
    """2 kinds x 8 thrusters x 3 vehicles = 48 cases, each with its one fault appended."""
    cases = build_cases(_spec([MASS], cases=3, failures=["stuck_closed", "stuck_open"]),
                        _data(), N_THRUSTERS, 3)
    assert len(cases) == 48 and cases[5].failure == ("stuck_closed", 1)
    assert cases[5].overrides[-1] == 'faults=[{t_s = 10.0, kind = "stuck_closed", thruster = 1}]'
    assert cases[5].seed == cases[2].seed  # the same vehicle, another failure


def test_scale_and_integer_keys() -> None:
    """apply = scale multiplies the scenario's value; an integer key gets an integer."""
    disp = [{"name": "inertia_xx", "dist": "sweep", "values": [2.0], "apply": "scale"},
            {"name": "bitrate", "dist": "sweep", "values": [0.5], "apply": "scale"}]
    (case,) = build_cases(_spec(disp, study="factorial"), _data(), N_THRUSTERS, 3)
    values = dict(case.values)
    assert values["vehicle.inertia_B_kgm2[0][0]"] == 2 * 15.95
    assert values["bus.bitrate_bps"] == 500_000 and isinstance(values["bus.bitrate_bps"], int)


def test_a_key_the_scenario_lacks_is_refused_naming_the_dispersion() -> None:
    """A misspelt key: ConfigError naming dispersions[0].key and the missing piece."""
    spec = _spec([{"key": "vehicle.mas_kg", "dist": "sweep", "values": [1.0]}])
    with pytest.raises(ConfigError) as e:
        build_cases(spec, copy.deepcopy(_data()), N_THRUSTERS, 3)
    assert e.value.key == "dispersions[0].key" and "mas_kg" in str(e.value)


def test_factorial_refuses_a_continuous_distribution() -> None:
    """A full-factorial study needs levels: a normal is refused, naming it."""
    with pytest.raises(ConfigError, match="sweep or a choice"):
        _spec([MASS], study="factorial")
