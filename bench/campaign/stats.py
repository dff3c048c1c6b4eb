"""A campaign's statistics from its rows: pass rates with intervals, percentiles, worst
cases, sensitivities. Pure (rows in, dicts out).

- Pass rate of each requirement (each expectation of the scenario, plus
  ``failure_isolated`` in a failure study, plus ``passed``: all of them) over the cases
  that completed, with the Wilson score interval at :data:`CONFIDENCE` (Wilson 1927,
  J. Am. Stat. Assoc. 22:209, eq. for the interval without continuity correction):
  centre (p̂ + z²/2n)/(1 + z²/n), half-width z·sqrt(p̂(1−p̂)/n + z²/4n²)/(1 + z²/n).
- Percentiles (:data:`PERCENTILES`, linear interpolation) of every figure.
- The worst cases of each figure (largest values first) with their seeds and values.
- Sensitivity: Spearman's rank correlation of each figure with each dispersed value
  (ties get mean ranks; a constant column has none), ``scipy.stats.spearmanr``, with its
  two-sided p-value: with few cases and many dispersed keys, some correlations are large
  by chance (read those with p above :data:`SIGNIFICANCE` as noise).
Cases recorded as errors are counted (``errors``) and left out of every rate and figure.
A settling time a case never reached (:data:`WORST_WHEN_MISSING`) is counted as
``missing`` beside its percentiles, and such cases head its worst list (value None): a
campaign whose slowest cases never settled must not look fast.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

CONFIDENCE = 0.95
Z_95 = 1.959963984540054
"""Standard normal quantile of (1 + CONFIDENCE)/2."""
PERCENTILES = (5, 50, 95, 99)
MIN_SENSITIVITY_CASES = 3
WORST_WHEN_MISSING = ("settling_time_s",)
"""Figures whose absence in a completed case means the worst outcome (never settled)."""
SIGNIFICANCE = 0.05
"""A rank correlation needs at least this many cases with both values."""


def wilson_interval(passes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """The Wilson score interval of a proportion (module docstring); (0, 1) for n = 0."""
    if n == 0:
        return (0.0, 1.0)
    p = passes / n
    z2 = z * z
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = z * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def _ok(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [r for r in rows if r["status"] == "ok"]


def pass_rates(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per requirement: passes, cases, rate and its interval (module docstring)."""
    ok = _ok(rows)
    names: dict[str, None] = {}
    for r in ok:
        names.update(dict.fromkeys(r["requirements"]))
    out = {}
    for name in [*names, "passed"]:
        vals = [r["passed"] if name == "passed" else r["requirements"][name]
                for r in ok if name == "passed" or name in r["requirements"]]
        k, n = sum(vals), len(vals)
        lo, hi = wilson_interval(k, n)
        out[name] = {"passes": k, "cases": n, "rate": k / n if n else None,
                     "ci_low": lo, "ci_high": hi}
    return out


def _figure_columns(rows: list[dict[str, Any]]) -> dict[str, list[tuple[int, float]]]:
    cols: dict[str, list[tuple[int, float]]] = {}
    for r in _ok(rows):
        for k, v in r["figures"].items():
            if v is not None:
                cols.setdefault(k, []).append((r["case"], float(v)))
    return cols


def _missing(rows: list[dict[str, Any]], figure: str) -> list[dict[str, Any]]:
    """Completed cases without ``figure`` where that means the worst (never settled)."""
    if figure not in WORST_WHEN_MISSING:
        return []
    return [r for r in _ok(rows) if r["figures"].get(figure) is None]


def percentiles(rows: list[dict[str, Any]]) -> dict[str, dict[str, float]]:
    """Per figure: its percentiles, minimum, maximum, mean and count over the cases that
    have it, and ``missing``: cases that never reached it (module docstring)."""
    out = {}
    for k, pairs in _figure_columns(rows).items():
        x = np.array([v for _, v in pairs])
        d = {f"p{p}": float(np.percentile(x, p)) for p in PERCENTILES}
        d.update(min=float(x.min()), max=float(x.max()), mean=float(x.mean()), n=len(x),
                 missing=len(_missing(rows, k)))
        out[k] = d
    return out


def worst_cases(rows: list[dict[str, Any]], count: int) -> dict[str, list[dict[str, Any]]]:
    """Per figure: the ``count`` cases with the largest values (seed and values kept)."""
    by_case = {r["case"]: r for r in rows}
    out = {}
    for k, pairs in _figure_columns(rows).items():
        never: list[tuple[int, float | None]] = [(r["case"], None) for r in _missing(rows, k)]
        top = (never + sorted(pairs, key=lambda p: (-p[1], p[0])))[:count]
        out[k] = [{"case": i, "name": by_case[i]["name"], "value": v,
                   "seed": by_case[i]["seed"], "values": by_case[i]["values"]}
                  for i, v in top]
    return out


def sensitivities(rows: list[dict[str, Any]]) -> dict[str, dict[str, dict[str, float]]]:
    """Per figure, per dispersed key: Spearman's ``rho`` and its ``p`` (module docstring),
    largest |rho| first."""
    from scipy.stats import spearmanr

    ok = _ok(rows)
    keys: dict[str, None] = {}
    for r in ok:
        keys.update(dict.fromkeys(k for k, v in r["values"].items()
                                  if isinstance(v, int | float) and not isinstance(v, bool)))
    out: dict[str, dict[str, dict[str, float]]] = {}
    for fig in _figure_columns(rows):
        per: dict[str, dict[str, float]] = {}
        for key in keys:
            pairs = [(r["values"][key], r["figures"][fig]) for r in ok
                     if r["figures"].get(fig) is not None and key in r["values"]]
            if len(pairs) < MIN_SENSITIVITY_CASES:
                continue
            x, y = np.array(pairs, dtype=float).T
            if np.ptp(x) == 0.0 or np.ptp(y) == 0.0:
                continue
            res = spearmanr(x, y)
            rho, p = float(res.statistic), float(res.pvalue)
            if math.isfinite(rho):
                per[key] = {"rho": rho, "p": p}
        out[fig] = dict(sorted(per.items(), key=lambda kv: -abs(kv[1]["rho"])))
    return out


def statistics(rows: list[dict[str, Any]], worst: int) -> dict[str, Any]:
    """Everything above, with the counts of cases run, completed and in error."""
    ok = _ok(rows)
    return {"cases": len(rows), "completed": len(ok), "errors": len(rows) - len(ok),
            "confidence": CONFIDENCE, "pass_rates": pass_rates(rows),
            "percentiles": percentiles(rows), "worst": worst_cases(rows, worst),
            "sensitivity": sensitivities(rows)}
