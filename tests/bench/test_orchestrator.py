"""Pure parts of the orchestrator: warnings derived from the scenario and the run."""

from __future__ import annotations

from pathlib import Path

from bench.orchestrator import duration_warnings
from bench.scenario import load_scenario

QUICKSTART = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.toml"


def test_run_too_short_for_its_steady_state_window_is_warned() -> None:
    """Quickstart: settling allowed 10 s, window 10 s; a 10 s run is warned, 20 s and 60 s not."""
    sc = load_scenario(QUICKSTART)
    e = sc.expectations
    needed_s = sc.manoeuvre_start_s + (e.settling_time_s_max or 0.0) + e.steady_state_window_s
    assert duration_warnings(sc, sc.duration_s) == []
    assert duration_warnings(sc, needed_s) == []
    (w,) = duration_warnings(sc, needed_s / 2)
    assert f"at least {needed_s:g} s" in w and "steady-state window" in w
