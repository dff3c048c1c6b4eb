"""The run's figures of merit and its expectations, from the telemetry's error histories.

In: the scenario (expectations: limits) and the streamed attitude [deg], rate [deg/s] and
position [m] error figures from the manoeuvre's start (bench.results.error_stats, fed by
bench.results.telemetry). Out: the summary.json fields ``converged``, settling times [s],
steady-state and final errors, and ``expectations`` (one row per limit the scenario sets:
value, limit, pass, and ``req``, the requirement ID, where the scenario names one) with
``requirements`` (every row's ID, ``converged`` too). Definitions in
bench.results.error_stats.
"""

from __future__ import annotations

import math
from typing import Any

from bench.results.error_stats import ErrorStats
from bench.results.metrics import expectation, settling_expectation
from bench.scenario.spec import Scenario


def expectations_and_metrics(sc: Scenario, errors: ErrorStats,
                             net_delta_v_m_s: float) -> dict[str, Any]:
    """Convergence, settling, steady-state errors and the expectations (module docstring)."""
    e = sc.expectations
    pm = errors.pointing()
    pe = errors.position_errors()
    pos_final: float | None = pe.final_error_m
    pos_ss: float | None = pe.steady_state_error_m
    if not sc.has_position_reference:  # attitude only: no position to be in error from
        pos_final = pos_ss = None
    pos_settling = None if errors.position is None else errors.position.settling_time_s()
    rate_settling = None if errors.rate is None else errors.rate.settling_time_s()
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
        expectation("net_delta_v_m_s", net_delta_v_m_s, e.net_delta_v_m_s_max),
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
        "expectations": [_with_requirement(x, e.requirement(x["name"])) for x in rows
                         if x is not None],
        "requirements": dict(e.requirements),  # row name -> requirement ID (and "converged")
    }


def _with_requirement(row: dict[str, Any], req: str | None) -> dict[str, Any]:
    """The expectation row with ``req`` (the requirement ID it verifies) when there is one."""
    return row if req is None else {**row, "req": req}


def net_translation(sc: Scenario, r_end_N_m: tuple[float, ...],
                    v_end_N_m_s: tuple[float, ...]) -> dict[str, Any]:
    """How far the vehicle moved and how much its velocity changed over the run [m], [m/s]
    (the net effect of the firing and the disturbances; in an attitude-only run, what the
    force-free thruster sets of ``pure_torque`` leave: each thruster's modulator rounds its
    own on-time, and the halves of a set may travel in different command frames)."""
    return {
        "displacement_m": math.dist(r_end_N_m, sc.r0_N_m),
        "delta_v_m_s": math.dist(v_end_N_m_s, sc.v0_N_m_s),
        "position_reference": sc.has_position_reference,
    }
