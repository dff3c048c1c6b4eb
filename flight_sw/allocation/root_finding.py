"""Safeguarded Newton search for the root of an increasing function on an interval.

What it does: :func:`monotone_root` finds ``ψ(x) = 0`` for an increasing ``ψ`` on
``[a, b]`` from a start ``x0``: Newton steps where they stay inside the current
sign-change bracket and shrink fast enough, bisection otherwise (geometric when the
bracket spans more than :data:`GEOMETRIC_BISECTION_RATIO`, for roots near 0). The robust
allocators use it for their one-dimensional dual (polytopic: λ ∈ [0, 1]) and τ search
(linear-fractional: θ ∈ (0, 1)); the caller's ``evaluate`` may end the search early on
its own certificate (a duality gap, a Newton decrement).

Inputs: ``evaluate(x) -> (ψ(x), ψ'(x), done)`` (ψ' may be 0 or non-finite when unknown),
the start and the interval. Output: the last point evaluated. Units: the caller's.

Assumptions: ψ increasing on ``[a, b]``. Deterministic: bounded evaluations, no time
limit.

Source: the safeguarded Newton–bisection hybrid ``rtsafe`` of Press et al. 2007,
"Numerical Recipes", 3rd ed., sec. 9.4.
"""

from __future__ import annotations

import math
from collections.abc import Callable

# Give up after this many evaluations or when the bracket shrinks below ROOT_XTOL × its
# initial width (no time limit: deterministic).
MAX_ROOT_ITER = 60
ROOT_XTOL = 1e-15
# A Newton step longer than this fraction of the previous step is replaced by bisection.
NEWTON_SHRINK = 0.5
# Bisect geometrically when the bracket spans more than this ratio (root near 0).
GEOMETRIC_BISECTION_RATIO = 4.0


def monotone_root(
    evaluate: Callable[[float], tuple[float, float, bool]],
    x0: float,
    a: float,
    b: float,
    max_iter: int = MAX_ROOT_ITER,
) -> float:
    """The last point evaluated by a safeguarded Newton search for ``ψ(x) = 0`` on ``[a, b]``.

    ``evaluate(x)`` returns ``(ψ(x), ψ'(x), done)`` for an increasing ``ψ`` (``ψ'`` may be
    0 or non-finite when unknown); ``done`` ends the search (the caller's own certificate).
    Newton steps that leave the current sign-change bracket are replaced by bisection
    (geometric when the bracket spans more than :data:`GEOMETRIC_BISECTION_RATIO`). It
    also stops when ψ keeps its sign at an end of ``[a, b]`` (the root lies at or beyond
    that end), or after ``max_iter`` evaluations or when the bracket is narrower
    than :data:`ROOT_XTOL` × ``(b − a)``. Deterministic (no time limit).
    """
    lo, hi, lo_seen, hi_seen = a, b, False, False
    x = min(max(x0, a), b)
    width = b - a
    last_step = math.inf
    for _ in range(max_iter):
        psi, dpsi, done = evaluate(x)
        if done or psi == 0.0:
            return x
        if psi < 0.0:
            lo, lo_seen = x, True
            if x >= b:
                return x
        else:
            hi, hi_seen = x, True
            if x <= a:
                return x
        if hi - lo <= ROOT_XTOL * width:
            return x
        cand = x - psi / dpsi if math.isfinite(dpsi) and dpsi > 0.0 else math.nan
        slow = abs(cand - x) > NEWTON_SHRINK * last_step  # not converging: bisect (rtsafe)
        if not lo < cand < hi or slow:
            if cand >= hi and not hi_seen:
                cand = hi
            elif cand <= lo and not lo_seen:
                cand = lo
            elif lo > 0.0 and hi > GEOMETRIC_BISECTION_RATIO * lo:
                cand = math.sqrt(lo * hi)
            else:
                cand = 0.5 * (lo + hi)
        last_step = abs(cand - x)
        x = cand
    return x
