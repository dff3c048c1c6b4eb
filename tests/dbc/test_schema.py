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
