"""Scenario expectations: limits as numbers or with the requirement ID they verify."""

from __future__ import annotations

from pathlib import Path

import pytest

from bench.scenario.expectations import CONVERGED
from bench.scenario.load import load_scenario
from dbc.errors import ConfigError

QUICKSTART = Path(__file__).resolve().parents[3] / "scenarios" / "quickstart.toml"


def test_a_limit_may_name_its_requirement() -> None:
    """{ max, req } sets the same limit as a number and records the ID under the row name;
    converged_req names the convergence check's requirement."""
    sc = load_scenario(QUICKSTART, [
        'expectations.settling_time_s_max={max=7.5, req="GNC-ATT-012"}',
        'expectations.converged_req="GNC-ATT-001"',
    ])
    e = sc.expectations
    assert e.settling_time_s_max == 7.5
    assert e.requirement("settling_time_s") == "GNC-ATT-012"
    assert e.requirement(CONVERGED) == "GNC-ATT-001"
    assert e.requirement("steady_state_attitude_error_deg") is None
    plain = load_scenario(QUICKSTART).expectations
    assert plain.requirements == () and plain.settling_time_s_max is not None


@pytest.mark.parametrize(("value", "why"), [
    ('""', "requirement ID"),
    ('"GNC ATT 12"', "requirement ID"),
    ('"-starts-with-dash"', "requirement ID"),
    ('"' + "A" * 65 + '"', "requirement ID"),
    ("12", "requirement ID"),
])
def test_bad_requirement_ids_are_refused_by_key(value: str, why: str) -> None:
    """A requirement ID that is empty, spaced, too long or not a string: ConfigError
    naming the dotted key."""
    with pytest.raises(ConfigError) as info:
        load_scenario(QUICKSTART, [f"expectations.settling_time_s_max={{max=7.5, req={value}}}"])
    assert "expectations.settling_time_s_max.req" in str(info.value) and why in str(info.value)
    with pytest.raises(ConfigError, match=r"expectations\.converged_req"):
        load_scenario(QUICKSTART, [f"expectations.converged_req={value}"])


def test_inline_limit_takes_only_max_and_req() -> None:
    """A misspelt key inside the inline table is refused, and max is required."""
    with pytest.raises(ConfigError, match=r"expectations\.settling_time_s_max\.reqq"):
        load_scenario(QUICKSTART, ['expectations.settling_time_s_max={max=7.5, reqq="R-1"}'])
    with pytest.raises(ConfigError, match=r"expectations\.settling_time_s_max\.max"):
        load_scenario(QUICKSTART, ['expectations.settling_time_s_max={req="R-1"}'])


NET_DV_LIMIT_M_S = 0.005


def test_net_delta_v_limit_becomes_an_expectation_row() -> None:
    """net_delta_v_m_s_max: a row with the run's delta-v, its limit and pass/fail (above it
    fails), named like the summary's net_translation.delta_v_m_s; negative refused."""
    from bench.results.error_stats import ErrorStats
    from bench.results.summary import expectations_and_metrics

    sc = load_scenario(QUICKSTART, [f"expectations.net_delta_v_m_s_max={NET_DV_LIMIT_M_S}"])
    assert sc.expectations.net_delta_v_m_s_max == NET_DV_LIMIT_M_S
    errors = ErrorStats(sc.expectations.settling_band_deg, sc.expectations.steady_state_window_s,
                        0.0)
    errors.add(0.0, 0.0, 0.0, 0.0)
    for dv, ok in ((0.5 * NET_DV_LIMIT_M_S, True), (2.0 * NET_DV_LIMIT_M_S, False)):
        rows = expectations_and_metrics(sc, errors, dv)["expectations"]
        (row,) = [r for r in rows if r["name"] == "net_delta_v_m_s"]
        assert row["value"] == dv and row["max"] == NET_DV_LIMIT_M_S and row["pass"] is ok
    with pytest.raises(ConfigError, match=r"expectations\.net_delta_v_m_s_max"):
        load_scenario(QUICKSTART, ["expectations.net_delta_v_m_s_max=-1.0"])
