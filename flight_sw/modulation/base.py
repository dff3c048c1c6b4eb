"""The thruster modulator interface: a demanded thrust fraction in, a valve on-time out.

What it does: defines :class:`Modulator`, the one interface every modulation strategy
implements. One instance drives one on-off thruster (instances keep the modulator's
internal state, e.g. a filter and a trigger).

Inputs: ``t_ns`` [integer ns] the start of the coming control period; ``u`` the demanded
mean thrust over that period as a fraction of the thruster's maximum thrust (dimensionless,
in [0, 1]; strategies clip values outside and treat NaN as 0); ``period_s`` the length of
the period [s] (> 0).
Output: the valve on-time for that period [s], ``0 ≤ on ≤ period_s``, emitted as one pulse
starting at the beginning of the period.

Assumptions: the caller calls once per period, in time order, with the period it will
actually use.

Source: interface only; see the strategies.
"""

from __future__ import annotations

from typing import Protocol


class Modulator(Protocol):
    """Turns a thrust fraction into a valve on-time, one period at a time."""

    def on_time_s(self, t_ns: int, u: float, period_s: float) -> float:
        """Valve on-time [s] for the period starting at ``t_ns`` with demanded fraction ``u``."""
        ...
