"""Tests of the proportional (ideal continuous-thrust) modulator."""

from __future__ import annotations

import math

import pytest

from flight_sw.modulation.proportional import ProportionalModulator

PERIOD_S = 0.02
T_NS = 0


@pytest.mark.parametrize(
    ("u", "expected_s"),
    [
        (0.0, 0.0),
        (1e-6, 1e-6 * PERIOD_S),
        (0.37, 0.37 * PERIOD_S),
        (1.0, PERIOD_S),
        (2.0, PERIOD_S),
        (-0.5, 0.0),
        (math.nan, 0.0),
        (math.inf, PERIOD_S),
    ],
)
def test_on_time_is_clipped_fraction_of_period(u: float, expected_s: float) -> None:
    """on = clip(u, 0, 1) · P, NaN → 0, with no minimum on-time."""
    assert ProportionalModulator().on_time_s(T_NS, u, PERIOD_S) == pytest.approx(
        expected_s, rel=1e-15, abs=0.0
    )


def test_invalid_period_is_rejected() -> None:
    """A non-finite period raises ValueError."""
    with pytest.raises(ValueError, match="period_s"):
        ProportionalModulator().on_time_s(T_NS, 0.5, math.inf)
