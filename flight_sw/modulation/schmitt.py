"""Schmitt-trigger thruster firing: duty-cycle on-times with a hysteresis for short pulses.

What it does: one modulator per thruster, mirroring Basilisk's ``thrFiringSchmitt`` module
(no filter: the trigger acts on the demanded on-time itself). Each period:
    ``t_i = u · P``  (the demanded on-time, ``u`` clipped to [0, 1], NaN → 0);
- if ``t_i ≥ P``: fire for the whole period, state := on (Basilisk requests 1.1 P to
  over-saturate; a pulse is capped at the period here, as the interface requires);
- else if ``t_i ≥ t_min``: fire for ``t_i`` (proportional), state := on;
- else (a request shorter than the minimum fire time) the Schmitt trigger decides on the
  level ``l = t_i / t_min`` (the duty relative to the minimum fire time):
  ``l ≥ level_on`` → fire ``t_min``, state := on; ``l ≤ level_off`` → fire nothing,
  state := off; ``level_off < l < level_on`` → keep the previous state (fire ``t_min`` if it
  was on, nothing if off).
The order of the tests follows Basilisk (the ``t_i < t_min`` branch comes first); with
``t_min ≥ P`` a short pulse is capped at the period, so the whole period is fired.

Unlike :mod:`flight_sw.modulation.remainder`, the impulse rounded away (or added) by the
trigger is not remembered: the mean thrust deviates from the demand below ``t_min``. The
static characteristic for constant ``u`` started from rest (off) is therefore: 0 for
``u P < level_on t_min``, ``t_min`` for ``level_on t_min ≤ u P < t_min``, ``u P`` above
(monotone non-decreasing); started from on, the lower threshold is ``level_off t_min``.

Inputs/outputs: ``u`` thrust fraction (dimensionless), ``period_s`` [s], on-time [s];
parameters ``min_on_s`` [s] (Basilisk ``thrMinFireTime``), ``level_on`` and ``level_off``
(dimensionless fractions of ``min_on_s``, 0 ≤ level_off < level_on ≤ 1).

Assumptions: on-pulsing only (Basilisk's off-pulsing ``baseThrustState = 1`` is not
provided: a one-sided thruster demand in [0, 1] is what the allocator produces); the
on-time resolution of the valve command is the node's business (no quantisation here).

Sources: Basilisk ``fswAlgorithms/effectorInterfaces/thrFiringSchmitt`` (AVS Lab, CU
Boulder), ``Update_thrFiringSchmitt`` and its documentation (which cites Alcorn 2016 for
the logic); "Steady-State Attitude and Control Effort Sensitivity Analysis of Discretized
Thruster Implementations", J. Spacecraft and Rockets, doi:10.2514/1.A33709 (compares this
Schmitt logic with the remainder logic).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dbc import validation as check

_SOURCE = "SchmittParams"
# Default trigger levels (fractions of the minimum fire time), chosen here: fire a
# minimum pulse once three quarters of it is demanded, stop below one quarter.
DEFAULT_LEVEL_ON = 0.75
DEFAULT_LEVEL_OFF = 0.25


@dataclass(frozen=True)
class SchmittParams:
    """Schmitt firing-logic parameters.

    Attributes:
        min_on_s: minimum valve on-time t_min [s] (≥ 0; 0 makes the logic proportional).
        level_on: on-level as a fraction of t_min (level_off < level_on ≤ 1).
        level_off: off-level as a fraction of t_min (0 ≤ level_off < level_on).
    """

    min_on_s: float = 0.0
    level_on: float = DEFAULT_LEVEL_ON
    level_off: float = DEFAULT_LEVEL_OFF

    def __post_init__(self) -> None:
        s = _SOURCE
        check.non_negative(s, "min_on_s", self.min_on_s, unit="s")
        level_on = check.number(s, "level_on", self.level_on, 0.0, 1.0, lo_open=True)
        check.number(s, "level_off", self.level_off, 0.0, level_on, hi_open=True)


class SchmittModulator:
    """One thruster's Schmitt firing logic (implements ``Modulator``)."""

    def __init__(self, params: SchmittParams) -> None:
        self._params = params
        self._on = False

    @property
    def params(self) -> SchmittParams:
        """The parameters this modulator was built with."""
        return self._params

    @property
    def trigger_on(self) -> bool:
        """The trigger state after the last period (Basilisk ``lastThrustState``)."""
        return self._on

    def reset(self, trigger_on: bool = False) -> None:
        """Set the trigger state (default: off)."""
        self._on = bool(trigger_on)

    def on_time_s(self, t_ns: int, u: float, period_s: float) -> float:
        """Valve on-time [s] for the coming period (``t_ns`` unused)."""
        if not (period_s > 0.0 and math.isfinite(period_s)):
            raise ValueError(f"period_s = {period_s!r}: expected a finite number > 0")
        p = self._params
        uc = 0.0 if not u > 0.0 else min(float(u), 1.0)  # NaN -> 0
        demanded = uc * period_s
        min_on = p.min_on_s
        if demanded < min_on:
            level = demanded / min_on
            if level >= p.level_on:
                self._on = True
            elif level <= p.level_off:
                self._on = False
            return min(min_on, period_s) if self._on else 0.0
        self._on = demanded > 0.0  # min_on = 0: a zero demand leaves the trigger off
        return min(demanded, period_s)
