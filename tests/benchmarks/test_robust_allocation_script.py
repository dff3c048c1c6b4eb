"""Smoke test of benchmarks/robust_allocation.py (seed 001 Figs. 7–12) on a short horizon."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "robust_allocation.py"
MODULE_NAME = "benchmarks_robust_allocation"
HORIZON_S = 5.0
PLOT_HORIZON_S = 1.0
N_RANDOM = 20
# Robust worst case may exceed the clipped pseudo-inverse's by solver tolerance only [N m].
WORST_CASE_TOL_NM = 1e-9
BOUND_TOL_N = 1e-9
CONTROL_STEP_S = 0.02
EXPECTED_PLOTS = 3


def _load() -> ModuleType:
    # as ``python benchmarks/robust_allocation.py`` does: its directory on sys.path, for the
    # module beside it (seed001_allocation)
    if str(SCRIPT.parent) not in sys.path:
        sys.path.insert(0, str(SCRIPT.parent))
    spec = importlib.util.spec_from_file_location(MODULE_NAME, SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[MODULE_NAME] = module  # dataclasses resolve annotations through sys.modules
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def script() -> ModuleType:
    """The benchmark script loaded as a module."""
    return _load()


@pytest.fixture(scope="module")
def result(script: ModuleType) -> tuple[Any, dict[str, dict[str, np.ndarray]], dict[str, Any]]:
    """(comparison, worst-case residuals, report) on the short horizon."""
    cmp = script.run(HORIZON_S, N_RANDOM)
    worst = script.worst_case_residuals(cmp)
    return cmp, worst, script.summarise(cmp, worst)


def test_torque_history_has_one_sample_per_control_step(result: Any) -> None:
    """Tc is sampled every 20 ms over the horizon, finite, and not identically zero."""
    cmp, _, _ = result
    assert cmp.demand.shape == (round(HORIZON_S / CONTROL_STEP_S), 3)
    assert np.allclose(np.diff(cmp.t_s), CONTROL_STEP_S)
    assert np.all(np.isfinite(cmp.demand)) and np.max(np.abs(cmp.demand)) > 0.0


def test_bounded_allocators_respect_the_bounds(script: ModuleType, result: Any) -> None:
    """QP and robust thrusts stay within −2.3 … 2.35 N at every sample."""
    cmp, _, report = result
    for name in (script.QP, *script.ROBUST):
        u = cmp.thrust[name]
        assert np.all(u >= script.SEED001_LOWER_N - BOUND_TOL_N), name
        assert np.all(u <= script.SEED001_UPPER_N + BOUND_TOL_N), name
        assert report["allocators"][name]["bound_violation_samples"] == 0


def test_robust_worst_case_is_no_larger_than_clipped_pseudo_inverse(
    script: ModuleType, result: Any
) -> None:
    """Each robust allocator's worst case over its own set ≤ the clipped B⁺'s, every sample."""
    _, worst, _ = result
    for name in script.ROBUST:
        s = script.SETS[name]
        excess = worst[name][s] - worst[script.PINV_CLIPPED][s]
        assert float(np.max(excess)) <= WORST_CASE_TOL_NM, (name, float(np.max(excess)))


def test_unbounded_pseudo_inverse_reproduces_the_demand(script: ModuleType, result: Any) -> None:
    """B B⁺ Tc = Tc (B has full row rank), so its nominal residual is round-off only."""
    _, _, report = result
    assert report["allocators"][script.PINV]["nominal_residual_Nm"]["max"] < BOUND_TOL_N


def test_report_has_every_key_and_is_json(script: ModuleType, result: Any) -> None:
    """The report names every allocator with every metric, per set where applicable."""
    _, _, report = result
    report = json.loads(json.dumps(report))
    assert set(report["allocators"]) == set(script.ALLOCATORS)
    for name, metrics in report["allocators"].items():
        assert set(metrics) == set(script.METRIC_KEYS), name
        assert set(metrics["worst_case_residual_Nm"]) == set(script.SET_NAMES)
        assert set(metrics["random_perturbation_rms_Nm"]) == set(script.SET_NAMES)
        assert set(metrics["nominal_residual_Nm"]) == {"max", "rms"}
        assert set(metrics["solve_time_us"]) == {"median", "p99"}


def test_main_prints_json_and_writes_the_plots(
    script: ModuleType, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The command line prints the JSON report and writes the three PNGs."""
    script.main(
        ["--duration-s", str(PLOT_HORIZON_S), "--random", str(N_RANDOM), "--plots", str(tmp_path)]
    )
    report = json.loads(capsys.readouterr().out)
    paths = [Path(p) for p in report["plots"]]
    assert len(paths) == EXPECTED_PLOTS
    assert all(p.parent == tmp_path and p.stat().st_size > 0 for p in paths)
