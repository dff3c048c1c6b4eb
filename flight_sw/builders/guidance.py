"""Builders of the moving references: ``[manoeuvre] kind`` other than ``step``.

What it does: one builder per ``kind`` (:data:`GUIDANCE`): seed 001's polynomial MRP
trajectory (``mrp_coefficients`` per axis, highest power first in the file, ``t_start_s``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from types import MappingProxyType

from dbc.schema import Table
from flight_sw.builders.vehicle import NS_PER_S, Vehicle
from flight_sw.guidance.base import AttitudeGuidance
from flight_sw.guidance.mrp_polynomial import MrpPolynomialGuidance


def _mrp_polynomial(t: Table, v: Vehicle) -> AttitudeGuidance:
    """Seed 001 §5: ``mrp_coefficients`` per axis, highest power first, τ = t − t_start_s."""
    coeffs = t.raw("mrp_coefficients")
    ok = (
        isinstance(coeffs, list)
        and len(coeffs) == 3
        and all(
            isinstance(c, list)
            and c
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in c)
            for c in coeffs
        )
    )
    if not ok:
        raise t.error("mrp_coefficients", coeffs, "3 lists of numbers (highest power first)")
    try:
        return MrpPolynomialGuidance(
            sigma_coeffs=tuple(tuple(float(x) for x in reversed(c)) for c in coeffs),
            t0_ns=round(t.number("t_start_s", 0.0, lo=0.0) * NS_PER_S),
            duration_s=math.inf,  # the bench's reference does not stop either
        )
    except ValueError as exc:
        raise t.error("mrp_coefficients", coeffs, str(exc)) from exc


GUIDANCE: Mapping[str, Callable[[Table, Vehicle], AttitudeGuidance]] = MappingProxyType({
    "mrp_polynomial": _mrp_polynomial
})
