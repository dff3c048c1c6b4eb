"""Proportional (ideal continuous-thrust) modulation: on-time = demanded fraction × period.

What it does: the reference "modulator" for comparisons: ``on = clip(u, 0, 1) · P``, no
minimum on-time, no memory. Driving an on-off valve it is plain pulse-width modulation
at the control rate; with a throttled valve model on the bench side the on-time is spread
over the period as a constant thrust ``u · F_max``, i.e. the ideal continuous actuator the control
laws of the seeds assume (seed 001, §2 assumption 2: "thrusters ... assumed to be
continuously controllable").

Inputs/outputs: ``u`` thrust fraction (dimensionless; clipped to [0, 1], NaN → 0),
``period_s`` [s], on-time [s] in [0, ``period_s``]. No parameters.

Assumptions: the on-time is not quantised here; the on-time resolution of the valve
command (the ICD) is applied by the node, so very small demands may round to 0 there.

Source: seed 001 (continuously controllable thrusters); interface of
:mod:`flight_sw.modulation.base`.
"""

from __future__ import annotations

import math


class ProportionalModulator:
    """Stateless proportional modulator (implements ``Modulator``)."""

    def on_time_s(self, t_ns: int, u: float, period_s: float) -> float:
        """Valve on-time ``clip(u, 0, 1) · period_s`` [s] (``t_ns`` unused)."""
        if not (period_s > 0.0 and math.isfinite(period_s)):
            raise ValueError(f"period_s = {period_s!r}: expected a finite number > 0")
        uc = 0.0 if not u > 0.0 else min(float(u), 1.0)  # NaN -> 0
        return uc * period_s
