"""The seed papers' simulations, each run with ``thruster-hil run`` in lockstep over the bus."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.e2e.conftest import REPO, run_cli, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

SCENARIOS = REPO / "scenarios"
SEED000_MAX_THRUST_N = 5.0  # seed 000: every thrust within 5 N at every instant
SEED003_BOUND_DEG = 3.0  # seed 003 Table 2: steady-state angle error < 3 deg
TENFOLD = 10.0  # issue 3: at least 10x better than the paper's bound
SEED001_INERTIA_KGM2 = np.array([[25.0, 0.8, -0.5], [0.8, 20.0, 0.6], [-0.5, 0.6, 15.0]])
INERTIA_REL_TOL = 0.05  # identified principal moments within 5 % of the truth
# The seed at which the law, handed an inertia no body has just after the capture, tumbled
# (before the identifier's physical gate, docs/reproductions.md).
CAPTURE_TUMBLE_SEED = 6
THRUST_TOL_N = 1e-9
# Issue 24, seed 000 hold (after the later of attitude and position settling): valve
# pulses per second over all 16 thrusters, and the fraction of the run's propellant.
HOLD_PULSES_MAX_PER_S = 20.0
HOLD_PROPELLANT_FRACTION_MAX = 0.10
# Issue 24: an attitude-only manoeuvre on couples leaves at most 5 mm/s (pure torque).
PURE_TORQUE_DV_MAX_M_S = 0.005
SEED003_FINE_POINTING_DEG = 0.02  # issue 24: steady state with sensor noise, on-off valves
SEED003_SETTLING_MAX_S = 6.0  # issue 24
CONTINUOUS = ["--set", "thrusters.valve_model='throttled'",
              "--set", "flight_sw.modulator={kind='proportional'}"]


def _run(name: str, tmp_path: Path, runtime_dir: Path, *extra: str) -> tuple[dict[str, Any], Path]:
    out = tmp_path / name
    r = run_cli(["run", str(SCENARIOS / f"{name}.toml"), "--bus", unique_bus(), *extra],
                out, runtime_dir)
    assert (out / "summary.json").exists(), r.stderr[-2000:]
    return r.summary, out


def _failed(summary: dict[str, Any]) -> list[dict[str, Any]]:
    return [e for e in summary["expectations"] if not e["pass"]]


def _max_thrust_N(run_dir: Path) -> float:
    with io.StringIO(run_text(run_dir, "telemetry.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    cols = [k for k in rows[0] if k.startswith("thrust_T")]
    return max(float(r[k]) for r in rows for k in cols)


@pytest.mark.parametrize("variant", ["on_off", "continuous"])
def test_seed003_three_axis_tracking(tmp_path: Path, runtime_dir: Path, variant: str) -> None:
    """Seed 003: converges within 10 s, steady-state error 10x inside Table 2's bound."""
    extra = CONTINUOUS if variant == "continuous" else []
    s, _ = _run("three_axis_tracking_cascade", tmp_path, runtime_dir, *extra)
    assert s["passed"], _failed(s)
    assert s["steady_state_attitude_error_deg"] <= SEED003_BOUND_DEG / TENFOLD
    if variant == "on_off":
        assert s["steady_state_attitude_error_deg"] <= SEED003_FINE_POINTING_DEG
        assert s["settling_time_s"] <= SEED003_SETTLING_MAX_S


@pytest.mark.parametrize("pure_torque", [True, False])
def test_attitude_only_manoeuvre_leaves_no_net_delta_v(
    tmp_path: Path, runtime_dir: Path, pure_torque: bool
) -> None:
    """Quickstart (seed-003 couples): pure torque leaves ≤ 5 mm/s of delta-v; the torque
    rows alone (pure_torque = false, the papers' allocation) leave over ten times that."""
    s, _ = _run("quickstart", tmp_path, runtime_dir,
                "--set", f"flight_sw.pure_torque={str(pure_torque).lower()}")
    dv = s["net_translation"]["delta_v_m_s"]
    if pure_torque:
        assert dv <= PURE_TORQUE_DV_MAX_M_S
    else:
        assert dv > 10.0 * PURE_TORQUE_DV_MAX_M_S


def _hold(summary: dict[str, Any], run_dir: Path) -> tuple[float, float]:
    """(valve pulses per second, fraction of the propellant) after settling."""
    t_from = max(summary["settling_time_s"], summary["position_settling_time_s"])
    with io.StringIO(run_text(run_dir, "valve_pulses.csv"), newline="") as f:
        n = sum(1 for r in csv.DictReader(f) if float(r["t_on_s"]) >= t_from)
    with io.StringIO(run_text(run_dir, "telemetry.csv"), newline="") as f:
        tel = [(float(r["t_s"]), float(r["propellant_kg"])) for r in csv.DictReader(f)]
    at_settling = next(p for t, p in tel if t >= t_from)
    total = tel[-1][1]
    return n / (tel[-1][0] - t_from), (total - at_settling) / total


def test_seed000_formation_keeping_nftsm_beats_tsm(tmp_path: Path, runtime_dir: Path) -> None:
    """Seed 000: NFTSM meets its expectations within 5 N per thruster, holds without
    chatter (fine hold: ≤ 20 pulses/s, ≤ 10 % of the propellant after settling) and
    converges before TSM."""
    nftsm, out = _run("formation_keeping_nftsm", tmp_path, runtime_dir)
    assert nftsm["passed"], _failed(nftsm)
    assert _max_thrust_N(out) <= SEED000_MAX_THRUST_N + THRUST_TOL_N
    pulses_per_s, fraction = _hold(nftsm, out)
    assert pulses_per_s <= HOLD_PULSES_MAX_PER_S
    assert fraction <= HOLD_PROPELLANT_FRACTION_MAX
    tsm, _ = _run("formation_keeping_nftsm", tmp_path / "tsm", runtime_dir,
                  "--set", "flight_sw.controller={kind='tsm_dq'}")
    assert tsm["position_settling_time_s"] > nftsm["position_settling_time_s"]


@pytest.mark.parametrize("allocator", ["robust_polytopic", "robust_polyhedral", "robust_lft"])
def test_seed001_mrp_tracking_with_robust_allocation(
    tmp_path: Path, runtime_dir: Path, allocator: str
) -> None:
    """Seed 001: the polynomial MRP trajectory is tracked with each robust allocator."""
    s, out = _run("mrp_trajectory_tracking", tmp_path, runtime_dir,
                  "--set", f"flight_sw.allocator={{kind='{allocator}'}}")
    assert s["passed"], _failed(s)
    stats = json.loads((out / "fsw_stats.json").read_text(encoding="utf-8"))
    assert stats["allocation"]["cycles"] == s["fsw"]["cycles"]


@pytest.mark.parametrize("seed", [None, CAPTURE_TUMBLE_SEED])
def test_seed001_capture_is_identified(tmp_path: Path, runtime_dir: Path,
                                       seed: int | None) -> None:
    """Seed 001 §2: after the capture, RLS identifies the new inertia within 5 % (also at
    the seed that tumbled before estimates no body has were withheld)."""
    extra = () if seed is None else ("--seed", str(seed))
    s, out = _run("capture_inertia_identification", tmp_path, runtime_dir, *extra)
    assert s["passed"], _failed(s)
    assert [e["kind"] for e in s["events"]] == ["capture"]
    stats = json.loads((out / "fsw_stats.json").read_text(encoding="utf-8"))
    j = np.array(stats["inertia_estimate_B_kgm2"])
    ident = s["fsw"]["inertia_identification"]  # reported in summary.json
    assert ident["updates"] > 0 and ident["withheld_unphysical"] > 0  # the gate acted
    rel = np.abs(np.diag(j) - np.diag(SEED001_INERTIA_KGM2)) / np.diag(SEED001_INERTIA_KGM2)
    assert np.all(rel <= INERTIA_REL_TOL), rel
