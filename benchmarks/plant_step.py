"""Micro-benchmark of the plant step: RK4 of the rigid body plus the thruster wrench.

Prints JSON: microseconds per 1 kHz plant step (median and minimum over batches), for
- ``active8_wrench3_rk4``: 8 firing thrusters, ``ThrusterSet.wrench_B`` ×3 + ``rk4_step``
  (``..._account``: plus ``account``, the bookkeeping that path needs);
- ``active8_stage_wrenches_rk4``: 8 firing thrusters, ``stage_wrenches`` (wrenches and
  bookkeeping in one pass) + ``rk4_step``;
- ``idle_wrench3_rk4`` / ``idle_stage_wrenches_rk4``: the same with every valve idle;
- ``rk4_step`` alone and ``thrust_N`` of one active valve.
Budget (see the plant models' brief): ~15 µs per step for ≥ 20× real time at 1 kHz.

Usage: ``python benchmarks/plant_step.py [--batches N] [--steps-per-batch M]``.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import sys
import time
from collections.abc import Callable

from bench.station.dynamics.rigid_body import (
    MassProperties,
    State,
    make_state,
    quat_normalize,
    rk4_step,
)
from bench.station.valves.params import ValveParams
from bench.station.valves.thruster_set import ThrusterGeometry, ThrusterSet

DT_NS = 1_000_000
DT_S = DT_NS * 1e-9
HALF_NS = DT_NS // 2
N_THRUSTERS = 8
ARM_M = 0.45
OFFSET_M = 0.22
LONG_ON_NS = 10**15
WARM_UP_NS = 20 * DT_NS
NS_PER_US = 1e3
DEFAULT_BATCHES = 101
DEFAULT_STEPS = 500


def _thrusters() -> ThrusterSet:
    geo = []
    for k in range(N_THRUSTERS):
        ang = 2.0 * math.pi * k / N_THRUSTERS
        x = ARM_M if k % 2 == 0 else -ARM_M
        geo.append(
            ThrusterGeometry(
                (x, OFFSET_M * math.cos(ang), OFFSET_M * math.sin(ang)),
                (0.0, -math.sin(ang), math.cos(ang)),
            )
        )
    params = ValveParams(
        max_thrust_N=10.0,
        isp_s=220.0,
        open_delay_s=0.003,
        close_delay_s=0.004,
        rise_tau_s=0.002,
        tail_tau_s=0.004,
        min_on_s=0.005,
    )
    return ThrusterSet(geo, params)


def _timing_us(step: Callable[[int], None], batches: int, steps: int) -> dict[str, float]:
    """Median and minimum over batches of the mean wall time per call of ``step(t_ns)``.

    The minimum is the figure least disturbed by other processes on a shared machine.
    """
    per_step = []
    t = WARM_UP_NS
    for _ in range(batches):
        t0 = time.perf_counter_ns()
        for _k in range(steps):
            step(t)
            t += DT_NS
        per_step.append((time.perf_counter_ns() - t0) / steps / NS_PER_US)
    return {
        "median_us": round(statistics.median(per_step), 3),
        "min_us": round(min(per_step), 3),
    }


def main(argv: list[str] | None = None) -> None:
    """Run the benchmark and print its JSON."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--batches", type=int, default=DEFAULT_BATCHES)
    ap.add_argument("--steps-per-batch", type=int, default=DEFAULT_STEPS)
    args = ap.parse_args(argv)
    nb, ns = args.batches, args.steps_per_batch

    mp = MassProperties(60.0, ((15.95, -0.3, 0.2), (-0.3, 22.0, 0.4), (0.2, 0.4, 24.0)))
    holder: list[State] = [make_state(quat_normalize((0.9, 0.1, -0.2, 0.3)), (0.01, -0.02, 0.03))]

    active = _thrusters()
    for i in range(N_THRUSTERS):
        active.command(0, i, LONG_ON_NS)
    idle = _thrusters()

    def wrench3(ts: ThrusterSet, account: bool) -> Callable[[int], None]:
        def step(t: int) -> None:
            w0 = ts.wrench_B(t)
            wm = ts.wrench_B(t + HALF_NS)
            w1 = ts.wrench_B(t + DT_NS)
            holder[0] = rk4_step(holder[0], DT_S, w0, wm, w1, mp)
            if account:
                ts.account(t, DT_NS)

        return step

    def staged(ts: ThrusterSet) -> Callable[[int], None]:
        def step(t: int) -> None:
            w0, wm, w1 = ts.stage_wrenches(t, DT_NS)
            holder[0] = rk4_step(holder[0], DT_S, w0, wm, w1, mp)

        return step

    zero = (0.0,) * 6

    def rk4_only(_t: int) -> None:
        holder[0] = rk4_step(holder[0], DT_S, zero, zero, zero, mp)

    valve = active.valves[0]

    def thrust(t: int) -> None:
        valve.thrust_N(t)

    result = {
        "benchmark": "plant_step",
        "python": platform.python_version(),
        "machine": platform.machine(),
        "step_dt_s": DT_S,
        "thrusters": N_THRUSTERS,
        "batches": nb,
        "steps_per_batch": ns,
        "active8_wrench3_rk4": _timing_us(wrench3(active, False), nb, ns),
        "active8_wrench3_rk4_account": _timing_us(wrench3(active, True), nb, ns),
        "active8_stage_wrenches_rk4": _timing_us(staged(active), nb, ns),
        "idle_wrench3_rk4": _timing_us(wrench3(idle, False), nb, ns),
        "idle_stage_wrenches_rk4": _timing_us(staged(idle), nb, ns),
        "rk4_step": _timing_us(rk4_only, nb, ns),
        "thrust_N": _timing_us(thrust, nb, ns),
    }
    json.dump(result, sys.stdout, indent=2)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
