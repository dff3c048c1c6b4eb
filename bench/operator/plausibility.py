"""Plausibility of a vehicle's mass properties: signs of a unit slip, said before a run.

What it does: compares the radius of gyration ``k = √(J_max / m)`` [m] (``J_max`` the largest
diagonal element of the inertia matrix about the centre of mass) with the
farthest thruster's distance from the body origin ``|r_thr_B|`` [m]. Thrusters sit on the
structure, so the mass is distributed over a body of about that size: for every vehicle in
``scenarios/`` the ratio ``k / |r_thr|`` lies in 0.2–1.7, and for a rod of length ``2 L``
it is 0.58. A ratio beyond [:data:`MIN_RATIO`, :data:`MAX_RATIO`] is a body 10× larger than
its thruster layout or 20× smaller, which is what an inertia given in g·m² (×1000, ratio
×31.6) or a mass in grams (ratio ÷31.6) looks like. The run is allowed (a vehicle with
thrusters on long booms is possible) but warned about, with the figures.

Pure function of its inputs; the warnings are plain sentences (summary.json ``warnings``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

# k / |r_thr| outside this band is warned about (see the module docstring).
MIN_RATIO = 0.05
MAX_RATIO = 10.0


def mass_warnings(
    label: str,
    mass_kg: float,
    inertia_B_kgm2: Sequence[Sequence[float]],
    r_thr_B_m: Sequence[Sequence[float]],
) -> list[str]:
    """Warnings for mass properties ``label`` that look like a unit slip (empty if plausible)."""
    arm_m = max((math.sqrt(sum(c * c for c in r)) for r in r_thr_B_m), default=0.0)
    j_max = max(inertia_B_kgm2[i][i] for i in range(3))
    if arm_m <= 0.0 or mass_kg <= 0.0 or j_max <= 0.0:
        return []
    k_m = math.sqrt(j_max / mass_kg)
    ratio = k_m / arm_m
    if MIN_RATIO <= ratio <= MAX_RATIO:
        return []
    hint = ("inertia in g·m² instead of kg·m², or mass in tonnes?" if ratio > MAX_RATIO
            else "inertia in kg·cm² or t·m², or mass in grams?")
    return [f"{label}: mass {mass_kg:g} kg and largest moment of inertia {j_max:g} kg m² give "
            f"a radius of gyration of {k_m:.3g} m, {ratio:.3g}x the farthest thruster's "
            f"distance ({arm_m:.3g} m; plausible: {MIN_RATIO:g}-{MAX_RATIO:g}x): {hint}"]
