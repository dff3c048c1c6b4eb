"""JUnit XML of a run: read back with junitparser (the parser CI result publishers use)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from junitparser import Error, Failure, JUnitXml, Skipped

from bench.operator.junit import junit_xml, write_junit

STAMP = "2026-12-06T20:00:00"
SUITE_ATTRS = ("name", "tests", "failures", "errors", "time", "timestamp", "hostname", "id",
               "package")


def _summary(**over: Any) -> dict[str, Any]:
    """A completed run that failed one of three expectations and converged."""
    s: dict[str, Any] = {
        "scenario": "quickstart", "scenario_file": "scenarios/quickstart.toml",
        "mode": "lockstep", "seed": 7, "bus": "hilbus:x", "ended": "completed",
        "wall_time_s": 1.5, "converged": True, "settling_band_deg": 0.5,
        "final_attitude_error_deg": 0.02, "verdict": "FAIL: settling_time_s",
        "abnormal": [], "warnings": [],
        "requirements": {"settling_time_s": "GNC-ATT-012", "converged": "GNC-ATT-001"},
        "expectations": [
            {"name": "settling_time_s", "value": 5.29, "max": 3.0, "pass": False,
             "req": "GNC-ATT-012"},
            {"name": "steady_state_attitude_error_deg", "value": 0.04, "max": 0.1,
             "pass": True},
            {"name": "steady_state_rate_error_deg_s", "value": 0.3, "max": 0.2, "pass": False},
        ],
    }
    s.update(over)
    return s


def _parse(tmp_path: Path, xml: bytes) -> Any:
    path = tmp_path / "j.xml"
    path.write_bytes(xml)
    (suite,) = list(JUnitXml.fromfile(str(path)))
    return suite


def test_one_failure_per_failed_expectation_with_its_requirement(tmp_path: Path) -> None:
    """A case per check (converged + 3 rows), a Failure for each failed one naming value,
    bound and requirement; the suite's counts and required attributes."""
    suite = _parse(tmp_path, junit_xml(_summary(), tmp_path, STAMP, "host"))
    assert (suite.tests, suite.failures, suite.errors) == (4, 2, 0)
    assert all(suite._elem.get(a) is not None for a in SUITE_ATTRS)
    results = {case.name: case.result for case in suite}
    assert list(results) == ["converged", "settling_time_s", "steady_state_attitude_error_deg",
                             "steady_state_rate_error_deg_s"]
    (fail,) = results["settling_time_s"]
    assert isinstance(fail, Failure) and "5.29" in fail.message and "3" in fail.message
    assert "GNC-ATT-012" in fail.message
    assert results["converged"] == [] and results["steady_state_attitude_error_deg"] == []
    props = {p.name: p.value for p in suite.properties()}
    assert props["requirement.converged"] == "GNC-ATT-001" and props["seed"] == "7"


def test_not_converged_fails_its_own_case() -> None:
    """A run whose error does not end in the band: converged is a failure."""
    xml = junit_xml(_summary(converged=False), Path("r"), STAMP, "h").decode()
    assert 'failures="3"' in xml and "settling band" in xml


def test_a_run_that_did_not_complete_is_an_error(tmp_path: Path) -> None:
    """Stopped, crashed, refused or compromised runs carry an Error case saying why, with
    escaped text; their checks are skipped (not judged), not failed."""
    s = _summary(ended="SIGTERM", error="RunError: <bench> & co died", compromised="SYNC forged")
    suite = _parse(tmp_path, junit_xml(s, tmp_path, STAMP, "host"))
    assert (suite.errors, suite.failures, suite.skipped, suite.tests) == (1, 0, 4, 5)
    assert all(isinstance(r, Skipped) for c in suite if c.name != "run" for r in c.result)
    (err,) = next(c for c in suite if c.name == "run").result
    assert isinstance(err, Error)
    assert "SIGTERM" in err.message and "<bench> & co" in err.message and "SYNC" in err.message


def test_no_summary_gives_one_error_case(tmp_path: Path) -> None:
    """A folder without summary.json: the suite named after the scenario, one error."""
    write_junit(tmp_path / "j.xml", tmp_path / "missing", "quickstart", "RunError: no bench")
    (suite,) = list(JUnitXml.fromfile(str(tmp_path / "j.xml")))
    assert suite.name == "quickstart" and (suite.tests, suite.errors) == (1, 1)
    assert "no bench" in next(iter(suite)).result[0].message


def test_written_again_from_the_folder_it_is_the_same_file(tmp_path: Path) -> None:
    """The timestamp comes from summary.json's time: report --junit rewrites it identically."""
    run = tmp_path / "run"
    run.mkdir()
    (run / "summary.json").write_text(json.dumps(_summary()), encoding="utf-8")
    os.utime(run / "summary.json", (1_796_580_000, 1_796_580_000))
    write_junit(tmp_path / "a.xml", run)
    write_junit(tmp_path / "b.xml", run)
    a = (tmp_path / "a.xml").read_bytes()
    assert a == (tmp_path / "b.xml").read_bytes()
    assert b'timestamp="2026-12-06T' in a
