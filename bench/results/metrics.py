"""Run metrics from truth telemetry: convergence, settling, steady-state errors, latency.

Pure functions over arrays. Inputs: sample times [s], attitude error angle [deg] between
true attitude and the manoeuvre's target, rate error [deg/s]. Settling time is the first
time after which the error stays inside the band until the end; converged means settled
and the final error inside the band. Steady-state errors are maxima over the last window,
or over the time since settling if that is shorter (a run shorter than the window).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from dbc.records import percentile_summary

NS_PER_US = 1e3
LATENCY_DIGITS = 3  # 1 ns in microseconds


@dataclass(frozen=True)
class PointingMetrics:
    """Convergence figures of one run."""

    converged: bool
    settling_time_s: float | None
    steady_state_attitude_error_deg: float
    steady_state_rate_error_deg_s: float
    final_attitude_error_deg: float


def pointing_metrics(
    t_s: np.ndarray,
    att_err_deg: np.ndarray,
    rate_err_deg_s: np.ndarray,
    band_deg: float,
    window_s: float,
    t_start_s: float = 0.0,
) -> PointingMetrics:
    """Settling time (from ``t_start_s``), convergence and steady-state errors."""
    if len(t_s) == 0:
        return PointingMetrics(False, None, float("nan"), float("nan"), float("nan"))
    outside = np.nonzero(att_err_deg > band_deg)[0]
    final = float(att_err_deg[-1])
    if len(outside) == 0:
        settling: float | None = 0.0
    elif outside[-1] == len(t_s) - 1:
        settling = None
    else:
        settling = float(t_s[outside[-1] + 1] - t_start_s)
    # the steady state starts at settling: the last window, or less if settling came later
    start = t_s[-1] - window_s
    if settling is not None:
        start = max(start, t_start_s + settling)
    last = t_s >= start
    return PointingMetrics(
        converged=settling is not None and final <= band_deg,
        settling_time_s=settling,
        steady_state_attitude_error_deg=float(np.max(att_err_deg[last])),
        steady_state_rate_error_deg_s=float(np.max(rate_err_deg_s[last])),
        final_attitude_error_deg=final,
    )


def settling_time_s(
    t_s: np.ndarray, err: np.ndarray, band: float, t_start_s: float = 0.0
) -> float | None:
    """First time (from ``t_start_s``) after which ``err`` stays within ``band``; None if never.

    Same rule as the attitude settling time of ``pointing_metrics`` (e.g. for the position
    error [m] against ``position_band_m``).
    """
    if len(t_s) == 0:
        return None
    outside = np.nonzero(err > band)[0]
    if len(outside) == 0:
        return 0.0
    if outside[-1] == len(t_s) - 1:
        return None
    return float(t_s[outside[-1] + 1] - t_start_s)


def latency_summary(samples_ns: list[int]) -> dict[str, Any]:
    """p50, p99, max in microseconds (1 ns resolution) and the sample count."""
    return percentile_summary(samples_ns, NS_PER_US, LATENCY_DIGITS)


def expectation(
    name: str, value: float | None, limit: float | None, note: str | None = None
) -> dict[str, Any] | None:
    """One expectation row: value, limit, pass (value <= limit), optional note; None if no limit."""
    if limit is None:
        return None
    ok = value is not None and bool(np.isfinite(value)) and value <= limit
    row: dict[str, Any] = {"name": name, "value": value, "max": limit, "pass": ok}
    if note is not None:
        row["note"] = note
    return row


def settling_expectation(
    name: str, value: float | None, limit: float | None, band: float | None, unit: str
) -> dict[str, Any] | None:
    """A settling-time row; a settling time of 0 is noted as never having left the band.

    That pass says nothing about convergence from an offset (e.g. a tracking run that
    starts on its reference): the note makes it visible in summary.json and on the console.
    """
    note = f"never outside the {band:g} {unit} band" if value == 0.0 and band else None
    return expectation(name, value, limit, note)
