"""Remainder-tracking thruster firing: duty-cycle on-times, short pulses saved for later.

What it does: one modulator per thruster, mirroring Basilisk's ``thrFiringRemainder``
module. Each period:
    ``t_i = u · P + r``  (demanded on-time plus the remainder ``r`` [s] carried over;
    ``u`` clipped to [0, 1], NaN → 0), then ``r := 0`` and
- if ``t_i < t_min``: fire nothing and keep the whole request, ``r := t_i``;
- else if ``t_i ≥ P``: fire the whole period (Basilisk requests 1.1 P to over-saturate;
  capped at the period here, as the interface requires); the excess ``t_i − P`` is
  dropped, as in Basilisk (saturation is not owed later);
- else: fire ``t_i``.
Basilisk stores the remainder as a fraction of ``t_min``; it is kept in seconds here (the
same quantity, and defined for ``t_min = 0``).

Invariant: as long as the demand does not saturate (``t_i < P``), the impulse fired so far
equals the impulse demanded so far minus ``r``, with ``0 ≤ r < t_min``: the long-run
mean on-time equals the demand exactly, and every pulse is 0 or ≥ ``t_min``.

Inputs/outputs: ``u`` thrust fraction (dimensionless), ``period_s`` [s], on-time [s];
parameter ``min_on_s`` [s] (Basilisk ``thrMinFireTime``, ≥ 0; 0 makes it proportional).

Assumptions: on-pulsing only (Basilisk's off-pulsing ``baseThrustState = 1`` is not
provided); ``t_min < P`` for the minimum-pulse guarantee (with ``t_min ≥ P`` a request
reaching ``t_min`` fires the whole period); the on-time resolution of the valve command
is the node's business (no quantisation here).

Sources: Basilisk ``fswAlgorithms/effectorInterfaces/thrFiringRemainder`` (AVS Lab, CU
Boulder), ``Update_thrFiringRemainder`` and its documentation; "Steady-State Attitude and
Control Effort Sensitivity Analysis of Discretized Thruster Implementations", J. Spacecraft
and Rockets, doi:10.2514/1.A33709 (compares the remainder and Schmitt logics).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dbc import validation as check

_SOURCE = "RemainderParams"


@dataclass(frozen=True)
class RemainderParams:
    """Remainder firing-logic parameters.

    Attributes:
        min_on_s: minimum valve on-time t_min [s] (≥ 0; 0 makes the logic proportional).
    """

    min_on_s: float = 0.0

    def __post_init__(self) -> None:
        check.non_negative(_SOURCE, "min_on_s", self.min_on_s, unit="s")


class RemainderModulator:
    """One thruster's remainder firing logic (implements ``Modulator``)."""

    def __init__(self, params: RemainderParams) -> None:
        self._params = params
        self._remainder_s = 0.0

    @property
    def params(self) -> RemainderParams:
        """The parameters this modulator was built with."""
        return self._params

    @property
    def remainder_s(self) -> float:
        """On-time demanded but not yet fired [s] (0 ≤ r < min_on_s)."""
        return self._remainder_s

    def reset(self) -> None:
        """Forget the remainder."""
        self._remainder_s = 0.0

    def on_time_s(self, t_ns: int, u: float, period_s: float) -> float:
        """Valve on-time [s] for the coming period (``t_ns`` unused)."""
        if not (period_s > 0.0 and math.isfinite(period_s)):
            raise ValueError(f"period_s = {period_s!r}: expected a finite number > 0")
        uc = 0.0 if not u > 0.0 else min(float(u), 1.0)  # NaN -> 0
        wanted = uc * period_s + self._remainder_s
        self._remainder_s = 0.0
        if wanted < self._params.min_on_s:
            self._remainder_s = wanted
            return 0.0
        return min(wanted, period_s)
