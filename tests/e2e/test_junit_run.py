"""`--junit`: a CI server's view of real runs, failing and broken (slow: real processes)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from junitparser import Error, Failure, JUnitXml

from tests.e2e.conftest import QUICKSTART, run_cli, unique_bus

pytestmark = pytest.mark.slow

SHORT_S = "12"
EXIT_FAILED, EXIT_RUN_ERROR = 1, 3


def test_failing_run_has_one_failure_per_failed_expectation(tmp_path: Path,
                                                             runtime_dir: Path) -> None:
    """An impossible settling limit with its requirement ID: exit 1, one JUnit failure per
    FAIL line of the console, the ID in it; report --junit writes the same file again."""
    junit = tmp_path / "results.xml"
    run = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", SHORT_S,
                   "--no-plots", "--junit", str(junit),
                   "--set", 'expectations.settling_time_s_max={max=0.5, req="GNC-ATT-012"}',
                   "--set", "expectations.steady_state_attitude_error_deg_max=1e-6"],
                  tmp_path / "run", runtime_dir)
    assert run.returncode == EXIT_FAILED, run.stderr
    fail_lines = [x for x in run.stdout.splitlines() if x.startswith("  FAIL ")]
    (suite,) = list(JUnitXml.fromfile(str(junit)))
    failures = [r for case in suite for r in case.result if isinstance(r, Failure)]
    assert len(failures) == len(fail_lines) == suite.failures >= 2
    assert any("GNC-ATT-012" in f.message for f in failures)
    assert "  FAIL settling_time_s [GNC-ATT-012] = " in run.stdout
    again = tmp_path / "again.xml"
    done = subprocess.run([sys.executable, "-m", "bench.operator.entry", "report", str(run.out),
                           "--junit", str(again)], capture_output=True, text=True,
                          check=False)
    assert done.returncode == EXIT_FAILED, done.stderr
    assert again.read_bytes() == junit.read_bytes()


def test_a_run_whose_flight_software_dies_is_a_junit_error(tmp_path: Path,
                                                           runtime_dir: Path) -> None:
    """Flight software that exits at once: exit 3, and the JUnit file has the error."""
    junit = tmp_path / "results.xml"
    run = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", SHORT_S,
                   "--no-plots", "--junit", str(junit), "--fsw-cmd", "false"],
                  tmp_path / "run", runtime_dir)
    assert run.returncode == EXIT_RUN_ERROR, run.stderr
    (suite,) = list(JUnitXml.fromfile(str(junit)))
    errors = [r for case in suite for r in case.result if isinstance(r, Error)]
    assert suite.errors == 1 and len(errors) == 1
    assert "flight-software process exited" in errors[0].message
