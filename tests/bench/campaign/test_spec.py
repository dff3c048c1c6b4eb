"""Campaign files: the example ships valid; every bad entry is named with its file and key."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from bench.campaign.cases import with_defaults
from bench.campaign.paths import expand, parse_key
from bench.campaign.spec import ALIASES, load_campaign, parse_campaign
from bench.scenario.parse import parse_scenario
from dbc.datafile import parse_toml
from dbc.errors import ConfigError

REPO = Path(__file__).resolve().parents[3]
EXAMPLES = sorted((REPO / "scenarios" / "campaigns").glob("*.toml"))


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_shipped_campaigns_load(path: Path) -> None:
    """Each campaign in scenarios/campaigns/ loads and names an existing scenario."""
    spec = load_campaign(path)
    assert spec.scenario.exists() and spec.dispersions


@pytest.mark.parametrize("alias", sorted(ALIASES))
def test_every_alias_names_keys_the_scenario_has_or_fills(alias: str) -> None:
    """On the quickstart with one fault scheduled, each alias's key expands to at least one
    element, filled with its nominal value where the scenario leaves it out."""
    data = parse_toml((REPO / "scenarios" / "quickstart.toml").read_text(), "q")
    data["faults"] = [{"t_s": 1.0, "kind": "stuck_closed", "thruster": 0}]
    n = len(parse_scenario(copy.deepcopy(data), "q").thrusters)
    parts = parse_key("test", "alias", ALIASES[alias])
    assert expand(with_defaults([parts], data, n), parts)


@pytest.mark.parametrize("campaign, dispersions, key", [
    ({}, [], "campaign.scenario"),
    ({"scenario": "q.toml", "study": "latin"}, [], "campaign.study"),
    ({"scenario": "q.toml", "cases": 0}, [], "campaign.cases"),
    ({"scenario": "q.toml", "failures": ["leak"]}, [], "campaign.failures"),
    ({"scenario": "q.toml", "set": ["nokey"]}, [], "campaign.set"),
    ({"scenario": "q.toml", "sed": 1}, [], "campaign.sed"),
    ({"scenario": "q.toml"}, [{"name": "mas", "dist": "sweep", "values": [1]}],
     "dispersions[0].name"),
    ({"scenario": "q.toml"}, [{"dist": "sweep", "values": [1]}], "dispersions[0]"),
    ({"scenario": "q.toml"}, [{"name": "mass", "dist": "sweep", "values": [1], "apply": "add"}],
     "dispersions[0].apply"),
    ({"scenario": "q.toml"}, [{"name": "mass", "dist": "sweep", "values": [1], "sigma": 1}],
     "dispersions[0].sigma"),
    ({"scenario": "q.toml", "study": "factorial", "cases": 5}, [], "campaign.cases"),
    ({"scenario": "q.toml", "fault_time_s": 3.0}, [], "campaign.fault_time_s"),
    ({"scenario": "q.toml", "study": "factorial"},
     [{"name": "mass", "dist": "normal", "mean": 0, "sigma": 1}], "dispersions[0].dist"),
])
def test_bad_campaigns_name_the_key(campaign: dict[str, Any], dispersions: list[Any],
                                    key: str) -> None:
    """Each mistake: a ConfigError whose key is the one to fix."""
    with pytest.raises(ConfigError) as e:
        parse_campaign({"campaign": campaign, "dispersions": dispersions}, "c.toml", REPO)
    assert e.value.key == key and "c.toml" in str(e.value)
