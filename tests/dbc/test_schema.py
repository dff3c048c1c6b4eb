"""Strict table reading: hints for missing and unknown keys point at real mistakes only."""

from __future__ import annotations

import pytest

from dbc.errors import ConfigError
from dbc.schema import Table


def test_missing_key_suggests_only_an_unread_near_miss() -> None:
    """A required key that is absent: a typo among the unread keys is suggested, a read one not."""
    t = Table({"gyro_arw_deg_sqrt_h": 1.0}, "f.json", "estimator")
    t.number("gyro_arw_deg_sqrt_h")
    with pytest.raises(ConfigError) as err:
        t.number("gyro_bias_rw_deg_h_sqrt_h")
    assert "misspelt" not in str(err.value) and "key is required" in str(err.value)
    typo = Table({"gyro_arw_deg_sqrt_hr": 1.0}, "f.json", "estimator")
    with pytest.raises(ConfigError, match="found 'gyro_arw_deg_sqrt_hr': misspelt"):
        typo.number("gyro_arw_deg_sqrt_h")


def test_unknown_key_lists_the_keys_the_table_takes() -> None:
    """done(): the stray key is named with the keys read, and a near miss among them."""
    t = Table({"kind": "pd", "kp": 1.0, "integral_band_deg": 2.0}, "f.json", "controller")
    t.string("kind")
    t.number("kp")
    t.number("kd", 0.5)
    with pytest.raises(ConfigError) as err:
        t.done()
    assert err.value.key == "controller.integral_band_deg"
    assert "this table takes: kd, kind, kp" in str(err.value)
    near = Table({"kpp": 1.0}, "f.json", "controller")
    near.number("kp", 1.0)
    with pytest.raises(ConfigError, match="did you mean 'kp'"):
        near.done()


def test_unknown_key_lists_an_optional_table_asked_for_by_has() -> None:
    """An absent optional key the reader asked for with has() is one the table takes (the
    scenario's [disturbance]); a present one left unread is still refused, not listed."""
    t = Table({"vehicle": {}, "nosuch": 1, "unread": 2}, "s.toml")
    t.table("vehicle")
    assert not t.has("disturbance")
    assert t.has("unread")
    with pytest.raises(ConfigError) as err:
        t.done()
    assert err.value.key == "nosuch"
    assert "this table takes: disturbance, vehicle)" in str(err.value)


FILE = "f.toml"
TABLE = "vehicle"
BOUND = 360.0  # a symmetric bound of a vector's elements


@pytest.mark.parametrize("bad", [True, float("nan"), float("inf"), "1.0"])
def test_number_refuses_like_the_validators_naming_file_and_dotted_key(bad: object) -> None:
    """A bool, NaN, inf or a string is refused with the file, the dotted key and the value."""
    with pytest.raises(ConfigError) as err:
        Table({"mass_kg": bad}, FILE, TABLE).number("mass_kg", lo=0.0, lo_open=True)
    assert (err.value.source, err.value.key) == (FILE, "vehicle.mass_kg")
    assert err.value.value is bad
    assert err.value.expected == "a finite number > 0"


def test_vector_length_and_range() -> None:
    """A vector of the wrong length or with an element out of [lo, hi] names its key."""
    t = Table({"short": [1.0, 2.0], "wide": [0.0, 2 * BOUND, 0.0], "ok": [1, 2, 3]}, FILE, TABLE)
    assert t.vector("ok", 3, lo=-BOUND, hi=BOUND) == (1.0, 2.0, 3.0)
    with pytest.raises(ConfigError, match=r"vehicle\.short = \[1\.0, 2\.0\]: expected 3 finite"):
        t.vector("short", 3)
    with pytest.raises(ConfigError, match=r"expected 3 finite numbers in \[-360, 360\]"):
        t.vector("wide", 3, lo=-BOUND, hi=BOUND)


def test_matrix3_names_the_bad_row() -> None:
    """A row that is not 3 finite numbers is named by its index in the dotted key."""
    bad_row = [0.0, float("nan"), 0.0]
    t = Table({"inertia_B_kgm2": [[1.0, 0.0, 0.0], bad_row, [0.0, 0.0, 1.0]]}, FILE, TABLE)
    with pytest.raises(ConfigError) as err:
        t.matrix3("inertia_B_kgm2")
    assert err.value.key == "vehicle.inertia_B_kgm2[1]" and err.value.value is bad_row


def test_unit_vector_and_flag() -> None:
    """A unit vector's norm is checked (and reported); a flag is a bool, not 0 or 1."""
    t = Table({"d": [0.0, 0.0, 1.0], "far": [0.0, 0.0, 2.0], "on": 1}, FILE, TABLE)
    assert t.unit_vector("d", 3) == (0.0, 0.0, 1.0)
    with pytest.raises(ConfigError, match="its norm is 2"):
        t.unit_vector("far", 3)
    with pytest.raises(ConfigError, match=r"vehicle\.on = 1: expected true or false"):
        t.flag("on")
    assert t.flag("absent", False) is False
