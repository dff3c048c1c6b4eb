"""Scenario keys with element indices: parse, expand, read, write, and TOML round trips."""

from __future__ import annotations

import math

import pytest

from bench.campaign.paths import (
    expand,
    get_value,
    leaf_key,
    parse_key,
    path_text,
    set_value,
    toml_value,
)
from dbc.datafile import parse_toml
from dbc.errors import ConfigError

DATA = {"vehicle": {"inertia_B_kgm2": [[1.0, 0.0], [0.0, 2.0]]},
        "faults": [{"t_s": 1.0}, {"t_s": 2.0}]}


def test_star_expands_to_every_element_in_order() -> None:
    """[*][*] over a 2x2 matrix: four paths, row-major; faults[*].t_s: one per fault."""
    ps = expand(DATA, parse_key("c", "k", "vehicle.inertia_B_kgm2[*][*]"))
    assert [path_text(p) for p in ps] == [f"vehicle.inertia_B_kgm2[{i}][{j}]"
                                         for i in range(2) for j in range(2)]
    assert [get_value(DATA, p) for p in expand(DATA, parse_key("c", "k", "faults[*].t_s"))] \
        == [1.0, 2.0]


def test_set_then_get_round_trips_and_leaf_key_keeps_table_indices() -> None:
    """A written element reads back; the --set key of faults[1].t_s keeps [1]."""
    import copy

    d = copy.deepcopy(DATA)
    (p,) = expand(d, parse_key("c", "k", "faults[1].t_s"))
    set_value(d, p, 9.5)
    assert get_value(d, p) == 9.5 and DATA["faults"][1]["t_s"] == 2.0  # type: ignore[index]
    (q,) = expand(d, parse_key("c", "k", "vehicle.inertia_B_kgm2[1][1]"))
    assert leaf_key(p) == "faults[1].t_s" and leaf_key(q) == "vehicle.inertia_B_kgm2"


@pytest.mark.parametrize("key", ["", "a..b", "a[x]", "a[0][1].b"])
def test_bad_keys_are_refused(key: str) -> None:
    """Empty, a blank part, a non-numeric index, two indices on a table: refused."""
    with pytest.raises(ConfigError):
        parse_key("c.toml", "dispersions[0].key", key)


def test_missing_element_is_a_key_error_naming_it() -> None:
    """An index beyond the array names the element and the array's length."""
    with pytest.raises(KeyError, match=r"no element \[5\] \(it has 2\)"):
        expand(DATA, parse_key("c", "k", "faults[5].t_s"))


@pytest.mark.parametrize("value", [0.1, 1e-05, -2.5e300, 3, True, "x\"y", [1.0, [2, 3]],
                                   {"t_s": 0.30000000000000004, "kind": "drop"}])
def test_toml_value_reads_back_exactly(value: object) -> None:
    """Every value written as TOML parses back equal (floats bit for bit)."""
    assert parse_toml(f"v = {toml_value(value)}", "t")["v"] == value


def test_toml_value_refuses_a_non_finite_float() -> None:
    """NaN has no place in a scenario: refused, not written."""
    with pytest.raises(ValueError):
        toml_value(math.nan)
