"""The run's figures of merit and its expectations, from the telemetry's error histories.

In: the scenario (expectations: bands, windows, limits; the manoeuvre's start) and the
attitude [deg], rate [deg/s] and position [m] errors sampled from the manoeuvre's start
(bench.results.telemetry). Out: the summary.json fields ``converged``, settling times
[s], steady-state and final errors, and ``expectations`` (one row per limit the scenario
sets: value, limit, pass). Definitions in bench.results.metrics.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bench.results.metrics import (
    expectation,
    pointing_metrics,
    settling_expectation,
    settling_time_s,
)
from bench.results.telemetry import Telemetry
from bench.scenario.spec import Scenario


def expectations_and_metrics(sc: Scenario, tel: Telemetry) -> dict[str, Any]:
    """Convergence, settling, steady-state errors and the expectations (module docstring)."""
    e = sc.expectations
    t_arr = np.asarray(tel.t_s)
    pm = pointing_metrics(t_arr, np.asarray(tel.att_err_deg), np.asarray(tel.rate_err_deg_s),
                          e.settling_band_deg, e.steady_state_window_s, sc.manoeuvre_start_s)
    pos = np.asarray(tel.pos_err_m)
    pos_final = float(pos[-1]) if len(pos) else 0.0
    pos_ss = float(pos[t_arr >= t_arr[-1] - e.steady_state_window_s].max()) if len(pos) else 0.0
    pos_settling = (settling_time_s(t_arr, pos, e.position_band_m, sc.manoeuvre_start_s)
                    if e.position_band_m is not None else None)
    rate_settling = (
        settling_time_s(t_arr, np.asarray(tel.rate_err_deg_s), e.rate_settling_band_deg_s,
                        sc.manoeuvre_start_s)
        if e.rate_settling_band_deg_s is not None else None)
    rows = (
        settling_expectation("settling_time_s", pm.settling_time_s, e.settling_time_s_max,
                             e.settling_band_deg, "deg"),
        settling_expectation("rate_settling_time_s", rate_settling, e.rate_settling_time_s_max,
                             e.rate_settling_band_deg_s, "deg/s"),
        expectation("steady_state_attitude_error_deg", pm.steady_state_attitude_error_deg,
                    e.steady_state_attitude_error_deg_max),
        expectation("steady_state_rate_error_deg_s", pm.steady_state_rate_error_deg_s,
                    e.steady_state_rate_error_deg_s_max),
        expectation("steady_state_position_error_m", pos_ss,
                    e.steady_state_position_error_m_max),
        expectation("final_position_error_m", pos_final, e.final_position_error_m_max),
        settling_expectation("position_settling_time_s", pos_settling,
                             e.position_settling_time_s_max, e.position_band_m, "m"),
    )
    return {
        "converged": pm.converged,
        "settling_band_deg": e.settling_band_deg,
        "settling_time_s": pm.settling_time_s,
        "steady_state_attitude_error_deg": pm.steady_state_attitude_error_deg,
        "steady_state_rate_error_deg_s": pm.steady_state_rate_error_deg_s,
        "final_attitude_error_deg": pm.final_attitude_error_deg,
        "final_position_error_m": pos_final,
        "steady_state_position_error_m": pos_ss,
        "position_band_m": e.position_band_m,
        "position_settling_time_s": pos_settling,
        "rate_settling_band_deg_s": e.rate_settling_band_deg_s,
        "rate_settling_time_s": rate_settling,
        "expectations": [x for x in rows if x is not None],
    }
