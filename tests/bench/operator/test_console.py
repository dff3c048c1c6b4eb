"""The console summary of a run says why it failed and when a pass is vacuous."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from bench.operator.console import print_summary

BAND_DEG = 0.5


def _summary(**changes: Any) -> dict[str, Any]:
    s: dict[str, Any] = {
        "scenario": "s", "mode": "lockstep", "bus": "hilbus:x", "seed": 1, "sim_time_s": 10.0,
        "wall_time_s": 1.0, "realtime_factor": 10.0, "converged": True,
        "settling_band_deg": BAND_DEG, "settling_time_s": 2.0,
        "steady_state_attitude_error_deg": 0.01, "steady_state_rate_error_deg_s": 0.01,
        "propellant_kg": 0.01, "valve_openings": {"total": 3},
        "latency_us": {"sensor_to_command": {"p50": 1.0, "p99": 2.0, "max": 3.0, "n": 5}},
        "deadline_misses": {}, "expectations": [],
    }
    s.update(changes)
    return s


def test_not_converged_without_expectations_prints_a_fail_line(
    capsys: pytest.CaptureFixture[str]
) -> None:
    """A run that did not converge says so in a FAIL line even with no expectations."""
    print_summary(_summary(converged=False, settling_time_s=None), Path("r"))
    out = capsys.readouterr().out
    assert f"FAIL converged: the attitude error did not end inside the {BAND_DEG:g} deg" in out
    print_summary(_summary(), Path("r"))
    assert "FAIL" not in capsys.readouterr().out


def test_vacuous_settling_is_labelled(capsys: pytest.CaptureFixture[str]) -> None:
    """Settling 0 reads 'never left the band'; an expectation's note is printed after it."""
    row = {"name": "settling_time_s", "value": 0.0, "max": 20.0, "pass": True,
           "note": "never outside the 0.5 deg band"}
    print_summary(_summary(settling_time_s=0.0, expectations=[row]), Path("r"))
    out = capsys.readouterr().out
    assert "settling 0.00 s (never left the band)" in out
    assert "PASS settling_time_s = 0.0000 (max 20.0; never outside the 0.5 deg band)" in out
