"""The ``[expectations]`` table of a scenario: limits, bands and requirement IDs.

In: the scenario's ``[expectations]`` table (dbc.schema.Table) and the run's duration [s].
Out: :class:`bench.scenario.spec.Expectations`. Each limit (a key ending in ``_max``) is a
number, or an inline table that also names the requirement it verifies:
``settling_time_s_max = { max = 10.0, req = "GNC-ATT-012" }``; ``converged_req`` names the
requirement of the convergence check (the attitude error ends inside
``settling_band_deg``). Requirement IDs appear in summary.json's expectation rows, the
console, the JUnit file (``--junit``) and the report. Every bad value is a ConfigError
naming the scenario file and the dotted key.
"""

from __future__ import annotations

import re

from bench.scenario.spec import Expectations
from dbc.schema import Table

LIMIT_SUFFIX = "_max"
# A requirement ID: letters, digits and . _ : / -, starting with a letter or digit
REQUIREMENT_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9._:/-]{0,63}")
REQUIREMENT_HELP = ("a requirement ID: 1 to 64 letters, digits or . _ : / -, starting with "
                    "a letter or digit (e.g. \"GNC-ATT-012\")")
CONVERGED = "converged"  # the expectation row name of the convergence check


def _requirement(t: Table, key: str) -> str:
    """The requirement ID at ``key`` (checked against :data:`REQUIREMENT_ID`)."""
    value = t.raw(key)
    if not (isinstance(value, str) and REQUIREMENT_ID.fullmatch(value)):
        raise t.error(key, value, REQUIREMENT_HELP)
    return value


def _limit(t: Table, key: str, reqs: dict[str, str]) -> float | None:
    """The limit at ``key`` (a number ≥ 0, or ``{ max = ..., req = ... }``), None if absent;
    a requirement ID goes into ``reqs`` under the row's name (``key`` without ``_max``)."""
    if not t.has(key):
        return None
    if not isinstance(t.raw(key), dict):
        return t.number(key, lo=0.0)
    sub = t.table(key)
    limit = sub.number("max", lo=0.0)
    if sub.raw("req", None) is not None:
        reqs[key.removesuffix(LIMIT_SUFFIX)] = _requirement(sub, "req")
    sub.done()
    return limit


def parse_expectations(et: Table, duration_s: float) -> Expectations:
    """The expectations of a scenario whose run lasts ``duration_s`` (module docstring)."""
    reqs: dict[str, str] = {}
    if et.has("converged_req"):
        reqs[CONVERGED] = _requirement(et, "converged_req")
    exp = Expectations(
        settling_band_deg=et.number("settling_band_deg", 0.5, lo=0.0, lo_open=True),
        settling_time_s_max=_limit(et, "settling_time_s_max", reqs),
        steady_state_attitude_error_deg_max=_limit(et, "steady_state_attitude_error_deg_max",
                                                   reqs),
        steady_state_rate_error_deg_s_max=_limit(et, "steady_state_rate_error_deg_s_max", reqs),
        steady_state_position_error_m_max=_limit(et, "steady_state_position_error_m_max", reqs),
        final_position_error_m_max=_limit(et, "final_position_error_m_max", reqs),
        position_band_m=et.number("position_band_m", lo=0.0, lo_open=True)
        if et.has("position_band_m") else None,
        position_settling_time_s_max=_limit(et, "position_settling_time_s_max", reqs),
        rate_settling_band_deg_s=et.number("rate_settling_band_deg_s", lo=0.0, lo_open=True)
        if et.has("rate_settling_band_deg_s") else None,
        rate_settling_time_s_max=_limit(et, "rate_settling_time_s_max", reqs),
        net_delta_v_m_s_max=_limit(et, "net_delta_v_m_s_max", reqs),
        steady_state_window_s=et.number(
            "steady_state_window_s", 10.0, lo=0.0, lo_open=True, hi=duration_s
        ),
        requirements=tuple(sorted(reqs.items())),
    )
    for key, band in (("position_settling_time_s_max", "position_band_m"),
                      ("rate_settling_time_s_max", "rate_settling_band_deg_s")):
        if et.has(key) and not et.has(band):
            raise et.error(key, et.raw(key, None), f"set together with {band} (the band it "
                           "settles into)")
    et.done()
    return exp
