"""Campaign statistics: Wilson intervals against the textbook quadratic, percentiles,
worst cases and rank correlations on known data."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from bench.campaign.stats import (
    SIGNIFICANCE,
    Z_95,
    pass_rates,
    percentiles,
    sensitivities,
    wilson_interval,
    worst_cases,
)

TOL = 1e-12
ROOT_TOL = 1e-9  # numpy.roots' accuracy on a quadratic with coefficients near 1


def _textbook_wilson(k: int, n: int, z: float) -> tuple[float, float]:
    """The interval's ends as the roots of (p̂ − p)² = z² p (1 − p) / n."""
    ph = k / n
    a = 1 + z * z / n
    b = -(2 * ph + z * z / n)
    c = ph * ph
    lo, hi = sorted(np.roots([a, b, c]).real)
    return float(lo), float(hi)


@pytest.mark.parametrize("k, n", [(0, 10), (3, 10), (10, 10), (187, 200), (1, 1)])
def test_wilson_matches_the_textbook_roots(k: int, n: int) -> None:
    """Closed form == roots of the score equation (both ends)."""
    lo, hi = wilson_interval(k, n)
    tlo, thi = _textbook_wilson(k, n, Z_95)
    assert lo == pytest.approx(max(0.0, tlo), abs=ROOT_TOL)
    assert hi == pytest.approx(min(1.0, thi), abs=ROOT_TOL)


def test_wilson_known_value() -> None:
    """8 of 10 at 95 %: [0.4902, 0.9433] (Newcombe 1998, Table I, method 3)."""
    lo, hi = wilson_interval(8, 10)
    assert (round(lo, 4), round(hi, 4)) == (0.4902, 0.9433)


def _row(i: int, passed: bool, fig: float | None, x: float, status: str = "ok") -> dict[str, Any]:
    return {"case": i, "name": f"{i:04d}", "seed": i, "status": status, "passed": passed,
            "requirements": {"settling_time_s": passed}, "figures": {"f": fig},
            "values": {"x": x, "label": "a"}}


def test_errors_are_left_out_of_rates_and_figures() -> None:
    """An error row counts nowhere: 2 of 3 completed cases pass."""
    rows = [_row(0, True, 1.0, 0.0), _row(1, True, 2.0, 1.0), _row(2, False, 3.0, 2.0),
            _row(3, False, None, 3.0, status="error")]
    r = pass_rates(rows)
    assert (r["passed"]["passes"], r["passed"]["cases"]) == (2, 3)
    assert r["settling_time_s"]["cases"] == 3


def test_worst_cases_largest_first_with_seeds() -> None:
    """The two largest values, largest first, each with its seed."""
    rows = [_row(i, True, v, i) for i, v in enumerate([3.0, 9.0, 1.0, 7.0])]
    w = worst_cases(rows, 2)["f"]
    assert [(x["case"], x["value"], x["seed"]) for x in w] == [(1, 9.0, 1), (3, 7.0, 3)]


def test_a_case_that_never_settled_heads_the_worst_and_is_counted() -> None:
    """Settling None (never settled) is the worst, not left out: first in the worst list,
    counted as missing beside percentiles taken over the cases that settled."""
    rows = [_row(i, True, 0.0, float(i)) for i in range(3)]
    for r, t in zip(rows, (5.0, None, 6.0), strict=True):
        r["figures"] = {"settling_time_s": t}
    w = worst_cases(rows, 2)["settling_time_s"]
    assert [(x["case"], x["value"]) for x in w] == [(1, None), (2, 6.0)]
    p = percentiles(rows)["settling_time_s"]
    assert (p["n"], p["missing"], p["max"]) == (2, 1, 6.0)


def test_rank_correlation_of_monotone_and_reversed_data() -> None:
    """A figure increasing with x: rho = +1; a constant key or a string: not reported."""
    rows = [_row(i, True, float(i) ** 3, float(i)) for i in range(6)]
    s = sensitivities(rows)["f"]
    assert list(s) == ["x"] and s["x"]["rho"] == pytest.approx(1.0, abs=TOL)
    assert s["x"]["p"] < SIGNIFICANCE
    rows = [_row(i, True, -float(i), float(i)) for i in range(6)]
    assert sensitivities(rows)["f"]["x"]["rho"] == pytest.approx(-1.0, abs=TOL)


def test_rank_correlation_p_value_of_unrelated_data() -> None:
    """A figure alternating with x (rho 0.09 on 6 cases) is not significant."""
    rows = [_row(i, True, float(i % 2), float(i)) for i in range(6)]
    assert sensitivities(rows)["f"]["x"]["p"] > SIGNIFICANCE
