"""Mass-property plausibility: the radius of gyration against the thruster layout."""

from __future__ import annotations

from pathlib import Path

import pytest

from bench.operator.plausibility import MAX_RATIO, MIN_RATIO, mass_warnings
from bench.operator.run_warnings import scenario_warnings
from bench.scenario.load import load_scenario

SCENARIOS = Path(__file__).resolve().parents[3] / "scenarios"
UNIT = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
G_M2_PER_KG_M2 = 1000.0


@pytest.mark.parametrize("path", sorted(SCENARIOS.glob("*.toml")), ids=lambda p: p.stem)
def test_every_shipped_vehicle_is_plausible(path: Path) -> None:
    """No scenario in scenarios/ trips the unit-slip warning (actual or nominal)."""
    assert not [w for w in scenario_warnings(load_scenario(path)) if "radius of gyration" in w]


def test_inertia_in_g_m2_is_warned_with_its_figures() -> None:
    """The quickstart's inertia written in g·m² (×1000) is a warning naming mass and moment."""
    sc = load_scenario(SCENARIOS / "quickstart.toml")
    r = [t.r_thr_B_m for t in sc.thrusters]
    inertia = tuple(tuple(G_M2_PER_KG_M2 * x for x in row) for row in sc.actual.inertia_B_kgm2)
    assert mass_warnings("[vehicle]", sc.actual.mass_kg, sc.actual.inertia_B_kgm2, r) == []
    (w,) = mass_warnings("[vehicle]", sc.actual.mass_kg, inertia, r)
    assert w.startswith("[vehicle]: mass 100 kg") and "72190 kg m²" in w and "g·m²" in w


@pytest.mark.parametrize(("k_over_arm", "warned"), [
    (MIN_RATIO * 0.99, True), (MIN_RATIO * 1.01, False),
    (MAX_RATIO * 0.99, False), (MAX_RATIO * 1.01, True),
])
def test_band_edges(k_over_arm: float, warned: bool) -> None:
    """A unit-mass body with J = k² and a thruster at 1 m: warned just outside the band only."""
    j = k_over_arm**2
    inertia = tuple(tuple(j * x for x in row) for row in UNIT)
    assert bool(mass_warnings("v", 1.0, inertia, [(1.0, 0.0, 0.0)])) is warned
