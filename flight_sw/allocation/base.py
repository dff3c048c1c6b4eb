"""The control-allocation interface: a body torque (or wrench) demand in, thrusts out.

What it does: defines :class:`Allocator`, the one interface every allocation strategy
implements, and :class:`AllocationResult`, its immutable output.

Inputs: ``demand``: the demanded body torque [N m] (m = 3) or wrench [N; N m] (m = 6),
body axes, in the row order of the strategy's effectiveness matrix
(see :mod:`flight_sw.allocation.effectiveness`). Availability: a boolean mask (True =
thruster usable) fixed per instance; ``with_mask(mask)`` returns a new instance, so a
reconfiguration (FDIR isolating a thruster) never mutates an allocator in use.
Output: :class:`AllocationResult`: thrusts [N] within ``[0, max thrust]``, masked thrusters
exactly 0, the achieved demand ``B T``, the residual norm and a saturation flag.

Assumptions: on-off thrusters whose mean thrust over a control period is commanded as a
fraction of their maximum by the modulators downstream.

Source: interface only; see the strategies for their methods and sources.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass(frozen=True, slots=True)
class AllocationResult:
    """The outcome of one allocation (arrays are read-only).

    Attributes:
        thrust_N: thrust per thruster [N], shape (n,), each in [0, max thrust].
        achieved: ``B @ thrust_N``, same shape and units as the demand.
        residual_norm: ``‖demand − achieved‖`` (Euclidean, demand units).
        saturated: True when the thrust bounds prevented reproducing the attainable part
            of the demand (the demand was scaled down or bounded); a residual caused only
            by a direction no thruster can produce is not saturation.
    """

    thrust_N: np.ndarray
    achieved: np.ndarray
    residual_norm: float
    saturated: bool


class Allocator(Protocol):
    """Maps a torque or wrench demand to per-thruster thrusts."""

    def allocate(self, demand: np.ndarray) -> AllocationResult:
        """Thrusts for ``demand`` (see :class:`AllocationResult`)."""
        ...

    def with_mask(self, mask: Sequence[bool] | np.ndarray) -> Allocator:
        """A new allocator, identical but for the availability mask (True = usable)."""
        ...
