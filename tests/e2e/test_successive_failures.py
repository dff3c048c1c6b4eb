"""Thrusters failing one after another over the bus: FDIR isolates each, and the summary
says when full control was lost and which seed-004 triples were left (issue 20)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.e2e.conftest import REPO, run_cli, unique_bus

pytestmark = pytest.mark.slow

SCENARIO = REPO / "scenarios" / "fdir_16thr.toml"
CANTED = 'thrusters.layout="seed000_canted_16"'
FAILED = (0, 1, 2, 3, 5, 6, 9, 10, 12, 14)  # leaves 4, 7, 8, 11, 13, 15
FIRST_FAULT_S, EVERY_S = 6.0, 4.0
DURATION_S = "50"  # the last fault at 42 s, isolated within a second
SURVIVORS = "(4, 7, 8, 11, 13, 15)"
SURVIVOR_TRIPLES = 3  # tests/flight_sw/fdir/test_layout_check.py, the same six


def test_each_isolation_is_reconfigured_and_the_loss_of_control_is_reported(
    tmp_path: Path, runtime_dir: Path
) -> None:
    """Ten stuck-closed thrusters of the canted 16, one every 4 s: each is isolated (the
    last FSW_FDIR names the last), and the warnings say when full control was lost and
    that three triples of the six survivors still qualify for underactuated control."""
    faults = ", ".join(f'{{t_s={FIRST_FAULT_S + i * EVERY_S}, kind="stuck_closed", '
                       f"thruster={k}}}" for i, k in enumerate(FAILED))
    r = run_cli(["run", str(SCENARIO), "--bus", unique_bus(), "--duration", DURATION_S,
                 "--record", "lean", "--no-plots", "--set", CANTED,
                 "--set", f"faults=[{faults}]"], tmp_path / "run", runtime_dir)
    s = r.summary
    assert s["fdir"]["failed_thruster"] == FAILED[-1], r.stderr[-2000:]
    assert s["fdir"]["available_mask"] == sum(1 << k for k in range(16) if k not in FAILED)
    lost = [w for w in s["warnings"] if "full control is lost" in w]
    assert lost, s["warnings"]
    assert SURVIVORS in lost[-1] and f"{SURVIVOR_TRIPLES} triple(s)" in lost[-1]
    assert all("flight software: after the isolation at" in w for w in lost)
    assert any(SURVIVORS in line for line in r.stdout.splitlines() if "WARNING" in line)
