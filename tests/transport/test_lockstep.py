"""Tests of :mod:`transport.lockstep`'s polling time (its waits and bursts are tested on
every bus kind in ``test_bus_contract.py``)."""

from __future__ import annotations

import pytest

from dbc.errors import ConfigError
from transport.lockstep import (
    LOCKSTEP_SPIN_ENV,
    LOCKSTEP_SPIN_MIN_CPUS,
    LOCKSTEP_SPIN_S,
    lockstep_spin_s,
)


def test_lockstep_spin_default_and_environment() -> None:
    """Polling by default on enough CPUs, none on fewer; the environment variable wins."""
    assert lockstep_spin_s(LOCKSTEP_SPIN_MIN_CPUS, {}) == LOCKSTEP_SPIN_S
    assert lockstep_spin_s(LOCKSTEP_SPIN_MIN_CPUS - 1, {}) == 0.0
    assert lockstep_spin_s(1, {LOCKSTEP_SPIN_ENV: "0.002"}) == 0.002
    assert lockstep_spin_s(64, {LOCKSTEP_SPIN_ENV: "0"}) == 0.0


@pytest.mark.parametrize("bad", ["fast", "-1", "nan", "inf", ""])
def test_lockstep_spin_bad_environment_value_names_it(bad: str) -> None:
    """A bad THRUSTER_HIL_LOCKSTEP_SPIN_S raises ConfigError naming the variable and value."""
    with pytest.raises(ConfigError, match=rf"{LOCKSTEP_SPIN_ENV} = '{bad}'"):
        lockstep_spin_s(2, {LOCKSTEP_SPIN_ENV: bad})
