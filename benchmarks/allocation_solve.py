"""Solve-time benchmark of the allocators: prints JSON (median / p99 per call, µs).

What it does: times ``allocate`` of every allocation strategy on random demands for three
matrices: the seed-000 16-thruster wrench matrix (6×16, 5 N), the seed-003 8-thruster
torque matrix (3×8, 15 N) and the seed-001 Table 1 torque matrix (3×8, −2.3…2.35 N,
ρ = 0.1, the paper's perturbation structures). Demands are half attainable
(``B·T`` with T uniform in the bounds) and half random directions of the same scale.

Then the first solve (``first_solve``): for every matrix and allocator, a fresh Python
process imports the strategy, builds it and times its first ``allocate``, cold and after
``warm_up()`` (what the flight software does before its first control cycle); medians
over ``--first-repeats`` processes, with the build and warm-up times.

Usage: ``python benchmarks/allocation_solve.py [n_demands] [--first-repeats K]``
(defaults 2000 and 3; ``--first-repeats 0`` skips the fresh processes).
Wall-clock timing is the point of a benchmark; it is not flight code.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from collections.abc import Callable

import numpy as np

from bench.station.valves.layouts import seed000_conventional_16, seed003_cascade_8
from flight_sw.allocation.effectiveness import TORQUE_ROWS, effectiveness_matrix
from flight_sw.allocation.pseudo_inverse import PseudoInverseAllocator, PseudoInverseParams
from flight_sw.allocation.qp_osqp import BoundedQpAllocator, BoundedQpParams
from flight_sw.allocation.robust_lft import RobustLftAllocator, RobustLftParams
from flight_sw.allocation.robust_polyhedral import RobustPolyhedralAllocator
from flight_sw.allocation.robust_polytopic import RobustParams, RobustPolytopicAllocator
from flight_sw.allocation.uncertainty import SEED001_LFT_E_SHAPE, SEED001_LFT_H

DEFAULT_N_DEMANDS = 2000
DEFAULT_FIRST_REPEATS = 3
SEED = 12345
P99 = 99.0
US_PER_S = 1e6
SEED000_DIMS_M = (0.5, 0.1)  # R, L of the four-quad layout
SEED000_THRUST_N = 5.0
SEED003_DIMS_M = (0.45, 0.22)
SEED003_THRUST_N = 15.0
SEED001_BOUNDS_N = (-2.3, 2.35)
_S = 0.375 * math.sqrt(2.0)
SEED001_POSITIONS_M = (
    (0.0, -0.75, 0.75), (-0.75, -0.75, 0.0), (0.0, -0.75, -0.75), (0.75, -0.75, 0.0),
    (_S, -0.75, _S), (-_S, -0.75, _S), (-_S, -0.75, -_S), (_S, -0.75, -_S),
)  # fmt: skip
SEED001_DIRECTIONS = (
    (0, 0, -1), (1, 0, 0), (0, 0, 1), (-1, 0, 0), (-1, 0, 0), (1, 0, 0), (1, 0, 0), (-1, 0, 0),
)  # fmt: skip


def _matrix(geo: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...]) -> np.ndarray:
    return effectiveness_matrix(np.array([g[0] for g in geo]), np.array([g[1] for g in geo]))


def _allocators(lo: float, hi: float, lft_paper: bool) -> dict[str, Callable[[np.ndarray], object]]:
    lft_kw: dict[str, object] = (
        {"e_shape": SEED001_LFT_E_SHAPE, "h_matrix": SEED001_LFT_H} if lft_paper else {}
    )
    out: dict[str, Callable[[np.ndarray], object]] = {
        "qp_osqp": lambda b: BoundedQpAllocator(b, BoundedQpParams(hi, lo)),
        "robust_polyhedral": lambda b: RobustPolyhedralAllocator(b, RobustParams(hi, lo)),
        "robust_polytopic": lambda b: RobustPolytopicAllocator(b, RobustParams(hi, lo)),
        "robust_lft": lambda b: RobustLftAllocator(b, RobustLftParams(hi, lo, **lft_kw)),  # type: ignore[arg-type]
    }
    if lo == 0.0:
        out["pseudo_inverse"] = lambda b: PseudoInverseAllocator(b, PseudoInverseParams(hi))
    return out


def _time(alloc: object, demands: np.ndarray) -> dict[str, float]:
    times = np.empty(len(demands))
    fn = alloc.allocate  # type: ignore[attr-defined]
    for i, d in enumerate(demands):
        t0 = time.perf_counter()
        fn(d)
        times[i] = time.perf_counter() - t0
    return {
        "median_us": round(float(np.median(times)) * US_PER_S, 1),
        "p99_us": round(float(np.percentile(times, P99)) * US_PER_S, 1),
    }


def _cases() -> dict[str, tuple[np.ndarray, float, float, bool]]:
    """Matrix, lower and upper bound [N] and whether the paper's LFT E, H apply, per case."""
    return {
        "seed000_16thr_6row": (
            _matrix(seed000_conventional_16(*SEED000_DIMS_M)),
            0.0,
            SEED000_THRUST_N,
            False,
        ),
        "seed003_8thr_3row": (
            _matrix(seed003_cascade_8(*SEED003_DIMS_M))[TORQUE_ROWS],
            0.0,
            SEED003_THRUST_N,
            False,
        ),
        "seed001_8thr_3row": (
            effectiveness_matrix(
                np.array(SEED001_POSITIONS_M), np.array(SEED001_DIRECTIONS, float)
            )[TORQUE_ROWS],
            *SEED001_BOUNDS_N,
            True,
        ),
    }


def _first_solve_child(case: str, kind: str, warm: bool) -> None:
    """In a fresh process: build one allocator, optionally warm it up, time its first solve."""
    b, lo, hi, paper = _cases()[case]
    demand = np.random.default_rng(SEED).uniform(lo, hi, b.shape[1]) @ b.T
    t0 = time.perf_counter()
    alloc = _allocators(lo, hi, paper)[kind](b)
    t1 = time.perf_counter()
    if warm:
        alloc.warm_up()  # type: ignore[attr-defined]
    t2 = time.perf_counter()
    alloc.allocate(demand)  # type: ignore[attr-defined]
    t3 = time.perf_counter()
    print(json.dumps([(t1 - t0) * US_PER_S, (t2 - t1) * US_PER_S, (t3 - t2) * US_PER_S]))


def _first_solve(repeats: int) -> dict[str, dict[str, dict[str, float]]]:
    """Median first-solve, build and warm-up times [µs] over fresh processes."""
    out: dict[str, dict[str, dict[str, float]]] = {}
    for case, (_, lo, hi, paper) in _cases().items():
        out[case] = {}
        for kind in _allocators(lo, hi, paper):
            runs: dict[bool, list[list[float]]] = {False: [], True: []}
            for _ in range(repeats):
                for warm in (False, True):
                    cmd = [sys.executable, __file__, "--first-child", case, kind, str(int(warm))]
                    done = subprocess.run(cmd, capture_output=True, text=True, check=True)
                    runs[warm].append(json.loads(done.stdout))
            cold, warm_runs = np.array(runs[False]), np.array(runs[True])
            out[case][kind] = {
                "build_us": round(float(np.median(cold[:, 0])), 1),
                "first_cold_us": round(float(np.median(cold[:, 2])), 1),
                "warm_up_us": round(float(np.median(warm_runs[:, 1])), 1),
                "first_after_warm_up_us": round(float(np.median(warm_runs[:, 2])), 1),
            }
    return out


def main(argv: list[str]) -> None:
    """Run the benchmark and print the JSON report."""
    if len(argv) > 1 and argv[1] == "--first-child":
        _first_solve_child(argv[2], argv[3], argv[4] == "1")
        return
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("n_demands", nargs="?", type=int, default=DEFAULT_N_DEMANDS)
    parser.add_argument("--first-repeats", type=int, default=DEFAULT_FIRST_REPEATS,
                        help="fresh processes per allocator for the first-solve times (0: skip)")
    args = parser.parse_args(argv[1:])
    n = args.n_demands
    rng = np.random.default_rng(SEED)
    report: dict[str, dict[str, dict[str, float]]] = {}
    for name, (b, lo, hi, paper) in _cases().items():
        half = n // 2
        scale = float(np.abs(b).max()) * hi
        demands = np.vstack(
            [
                rng.uniform(lo, hi, (half, b.shape[1])) @ b.T,
                rng.normal(size=(n - half, b.shape[0])) * scale,
            ]
        )
        report[name] = {k: _time(f(b), demands) for k, f in _allocators(lo, hi, paper).items()}
    full: dict[str, object] = {"per_call": report}
    if args.first_repeats > 0:
        full["first_solve"] = _first_solve(args.first_repeats)
    print(json.dumps(full, indent=2))


if __name__ == "__main__":
    main(sys.argv)
