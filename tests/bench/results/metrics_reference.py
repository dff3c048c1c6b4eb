"""The array form of the run's convergence figures: the whole history in numpy.

The reference that bench.results.error_stats (the streaming form the bench uses) is
checked against, exactly: the same definitions, written over whole arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PointingReference:
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
) -> PointingReference:
    """Settling time (from ``t_start_s``), convergence and steady-state errors."""
    if len(t_s) == 0:
        return PointingReference(False, None, float("nan"), float("nan"), float("nan"))
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
    return PointingReference(
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


