"""Reference for a valve's stage samples: its mean thrust over a step by the trapezoid rule.

The package integrates each thrust segment in closed form
(bench.station.valves.thrust_profile.ThrustProfile.mean_thrust_N); this integrates
``thrust_N`` itself on a grid of whole nanoseconds, ``GRID_NS`` apart, split at the segment
starts and the idle time (where the slope, or for a leak or a degraded factor the thrust
itself, jumps), so each piece is smooth. Trapezoid error per piece: L·h²/12·max|F''|,
with F'' <= Fmax/τ²: for h = 100 ns, τ >= 2 ms, ~2e-10 of the step's mean.
"""

from __future__ import annotations

from itertools import pairwise

from bench.station.valves.valve import Valve

GRID_NS = 100
MEAN_REL_TOL = 1e-9  # the trapezoid's error bound above, with a margin


def step_mean_reference_N(v: Valve, t_ns: int, dt_ns: int) -> float:
    """The mean of ``v.thrust_N`` over [t, t + dt] [N], by the trapezoid rule between kinks."""
    t1 = t_ns + dt_ns
    profile = v._profile  # the segment starts are where the integrand has kinks or jumps
    cuts = sorted({t_ns, t1, *(s[0] for s in profile.segments if t_ns < s[0] < t1),
                   *((profile.idle_from_ns,) if t_ns < profile.idle_from_ns < t1 else ())})
    total = 0.0  # [N·ns]
    for a, b in pairwise(cuts):
        nodes = [*range(a, b, GRID_NS), b]
        # one-sided limits at a jump: the piece starts just after a and ends just before b
        f = [v.thrust_N(n) for n in nodes[:-1]] + [_left_limit(v, b, nodes[-2])]
        total += sum((f[i] + f[i + 1]) * (nodes[i + 1] - nodes[i]) / 2.0
                     for i in range(len(nodes) - 1))
    return total / dt_ns


def _left_limit(v: Valve, b: int, before: int) -> float:
    """The thrust just before ``b``, where a jump may sit: its value 1 ns earlier (off by
    F'·1 ns <= Fmax·5e-7 for τ >= 2 ms, weighted h/2 of the step: ~3e-11 of its mean)."""
    return v.thrust_N(b - 1) if b - 1 > before else v.thrust_N(before)
