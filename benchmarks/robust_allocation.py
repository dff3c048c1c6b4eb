"""Seed 001 robust-allocation comparison (its Figs. 7–12): JSON figures and plots.

What it does: reruns the allocation study of seed 001, sec. 5, off the bus, as pure math:

1. the Case-1 control torque history ``Tc(t)`` (seed 001 Fig. 6): the direct parametric MRP
   law (:mod:`flight_sw.control.mrp_direct_parametric`, ``F0 = E``, ``Z = [I3 I3]``) closing
   the loop on the rigid body ``J = diag(25, 20, 15)`` kg m² from ``σ(0)``, ``ω(0)`` of sec. 5,
   tracking the sec. 5 polynomial MRP trajectory
   (:mod:`flight_sw.guidance.mrp_polynomial`) for 100 s; RK4, torque held over each 20 ms
   control step, the body receiving exactly the demanded torque (ideal actuation);
2. every ``Tc(t_k)`` allocated on the Table 1 thrusters (8, signed bounds
   −2.3 ≤ u ≤ 2.35 N) by: the unbounded pseudo-inverse ``B⁺Tc`` (the paper's baseline),
   the same clipped to the bounds, the bounded least-squares QP
   (:mod:`flight_sw.allocation.qp_osqp`) and the three robust allocators of sec. 4:
   polyhedral (Theorem 1, ``ΔB = Σ δᵢBᵢ``, ``Bᵢ = 0.1B, 0.1B, 0.2B, 0.2B``, ``|δᵢ| ≤ 1``),
   polytopic (Theorem 2, same ``Bᵢ``, ``δᵢ ≥ 0``, ``Σδᵢ = 1``) and linear-fractional
   (Theorem 3, ``ΔB = E F H``, ``E = diag(0.1, 0.15, 0.1)``, the printed 3×8 ``H``,
   ``‖F‖ ≤ 1``);
3. per allocator (JSON on stdout): thrust range, samples violating the bounds, nominal
   residual ``‖B u − Tc‖`` (max, rms), the exact worst-case residual over each of the three
   uncertainty sets (vertex maximum; the S-lemma formula for the LFT set;
   :mod:`flight_sw.allocation.uncertainty`) — max and rms over time, the rms realised
   torque error ``‖(B + ΔB) u − Tc‖`` under random admissible perturbations (fixed seed,
   the same draws for every allocator), and the solve time (median / p99, µs);
4. with ``--plots DIR`` (default docs/img/reproductions): the thrusts of the 8 actuators
   (Figs. 7, 9, 11), ``Tc`` against the realised torque under one fixed worst-case
   perturbation of each set (Figs. 8, 10, 12), and the worst-case residuals over time.

Items 1 and 2, the uncertainty sets and their worst cases are in ``seed001_allocation.py``
beside this script (imported from there; running the script puts its directory on
``sys.path``); this script times the allocations, summarises them and plots.

Usage: ``python benchmarks/robust_allocation.py [--plots DIR] [--no-plots]
[--duration-s S]``. Wall-clock solve timing is the point of a benchmark; the rest is pure.

Inputs: none (all seed 001 constants). Outputs: JSON (thrust [N], residuals [N m],
times [µs]) and PNG files ``robust_allocation_*.png``.

Assumptions: the uncertainty sets are those of sec. 5 (``Bᵢ ∝ B``: every vertex is a
multiple of ``B``, so the worst case of a thrust depends only on ``B u``); the paper's
Figs. 8, 10, 12 do not say which perturbation they apply, so the fixed one here is the
worst over the whole run for the robust allocator shown (exact for the vertex sets, a
local maximiser for the LFT set).

Sources: seed 001 (MRP control and robust allocation of a combined spacecraft), sec. 3
(control law, Case 1), sec. 4 (eq. 13, Theorems 1–3) and sec. 5 (Table 1, Figs. 6–12).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from seed001_allocation import (  # beside this script (benchmarks/ is on sys.path)
    ALLOCATORS,
    CONTROL_STEP_S,
    LFT,
    PINV,
    PINV_CLIPPED,
    POLYHEDRAL,
    POLYTOPIC,
    QP,
    ROBUST,
    SEED001_DURATION_S,
    SEED001_LOWER_N,
    SEED001_UPPER_N,
    SET_NAMES,
    SETS,
    UncertaintySets,
    case1_torque_history,
    make_allocators,
    seed001_torque_matrix,
)

REPO = Path(__file__).resolve().parents[1]
DEFAULT_PLOT_DIR = REPO / "docs" / "img" / "reproductions"
PLOT_PREFIX = "robust_allocation_"
PLOT_DPI = 90
# The torque transient lasts ~1 s of the 100 s: time axes are linear up to this, log after.
PLOT_LINEAR_TIME_S = 1.0
# Worst-case residuals are drawn on a log axis floored here [N m].
PLOT_RESIDUAL_FLOOR_NM = 1e-8
TIME_LABEL = "t [s] (linear to 1 s, log after)"

# A thrust counts as violating its bounds beyond this [N].
BOUND_TOL_N = 1e-9
# Random admissible perturbations: draws per uncertainty set, generator seed.
DEFAULT_N_RANDOM = 200
RANDOM_SEED = 20240607
P99 = 99.0
US_PER_S = 1e6
SIGNIFICANT_DIGITS = 6

METRIC_KEYS = (
    "thrust_max_N",
    "thrust_min_N",
    "bound_violation_samples",
    "nominal_residual_Nm",
    "worst_case_residual_Nm",
    "random_perturbation_rms_Nm",
    "solve_time_us",
)

@dataclass(frozen=True)
class Comparison:
    """Everything the report and the plots need.

    Attributes:
        t_s: sample times [s] (K); demand: Tc [N m] (K×3).
        thrust: per allocator, thrusts [N] (K×8); solve_s: per allocator, times [s] (K).
        sets: the uncertainty sets; random: per set name, random ``B + ΔB`` (R×3×8).
    """

    t_s: np.ndarray
    demand: np.ndarray
    thrust: dict[str, np.ndarray]
    solve_s: dict[str, np.ndarray]
    sets: UncertaintySets
    random: dict[str, np.ndarray]


def run(duration_s: float = SEED001_DURATION_S, n_random: int = DEFAULT_N_RANDOM) -> Comparison:
    """Torque history, allocation by every allocator, random perturbations (fixed seed)."""
    t_s, demand = case1_torque_history(duration_s)
    b0 = seed001_torque_matrix()
    thrust: dict[str, np.ndarray] = {}
    solve_s: dict[str, np.ndarray] = {}
    for name, alloc in make_allocators(b0).items():
        out = np.empty((len(demand), b0.shape[1]))
        times = np.empty(len(demand))
        for k, v in enumerate(demand):
            t0 = time.perf_counter()
            out[k] = alloc(v)
            times[k] = time.perf_counter() - t0
        thrust[name], solve_s[name] = out, times
    sets = UncertaintySets.seed001(b0)
    rng = np.random.default_rng(RANDOM_SEED)
    random = {s: sets.random_matrices(s, rng, n_random) for s in SET_NAMES}
    return Comparison(t_s, demand, thrust, solve_s, sets, random)


def _num(x: float) -> float:
    """``x`` rounded to :data:`SIGNIFICANT_DIGITS` significant digits (for the JSON)."""
    return float(f"{x:.{SIGNIFICANT_DIGITS}g}")


def _stats(x: np.ndarray) -> dict[str, float]:
    return {"max": _num(float(np.max(x))), "rms": _num(float(np.sqrt(np.mean(x * x))))}


def worst_case_residuals(cmp: Comparison) -> dict[str, dict[str, np.ndarray]]:
    """Per allocator, per set name: the exact worst-case residual [N m] at every sample."""
    return {
        a: {s: cmp.sets.worst_case(s, cmp.thrust[a], cmp.demand) for s in SET_NAMES}
        for a in ALLOCATORS
    }


def summarise(cmp: Comparison, worst: dict[str, dict[str, np.ndarray]]) -> dict[str, Any]:
    """The JSON report: per allocator the figures of the module docstring."""
    lo, hi = SEED001_LOWER_N, SEED001_UPPER_N
    b0 = cmp.sets.b0
    out: dict[str, Any] = {
        "horizon_s": _num(float(cmp.t_s[-1] + CONTROL_STEP_S)),
        "samples": len(cmp.t_s),
        "bounds_N": [lo, hi],
        "demand_norm_max_Nm": _num(float(np.max(np.linalg.norm(cmp.demand, axis=1)))),
        "random_draws_per_set": int(next(iter(cmp.random.values())).shape[0]),
        "allocators": {},
    }
    for a in ALLOCATORS:
        u = cmp.thrust[a]
        nominal = np.linalg.norm(u @ b0.T - cmp.demand, axis=1)
        violating = np.any((u > hi + BOUND_TOL_N) | (u < lo - BOUND_TOL_N), axis=1)
        rand: dict[str, float] = {}
        for s, mats in cmp.random.items():
            r = np.einsum("jmn,kn->jkm", mats, u) - cmp.demand[None]
            rand[s] = _num(float(np.sqrt(np.mean(np.sum(r * r, axis=2)))))
        times = cmp.solve_s[a]
        out["allocators"][a] = {
            "thrust_max_N": _num(float(np.max(u))),
            "thrust_min_N": _num(float(np.min(u))),
            "bound_violation_samples": int(np.sum(violating)),
            "nominal_residual_Nm": _stats(nominal),
            "worst_case_residual_Nm": {s: _stats(worst[a][s]) for s in SET_NAMES},
            "random_perturbation_rms_Nm": rand,
            "solve_time_us": {
                "median": round(float(np.median(times)) * US_PER_S, 1),
                "p99": round(float(np.percentile(times, P99)) * US_PER_S, 1),
            },
        }
    return out


def plot(cmp: Comparison, worst: dict[str, dict[str, np.ndarray]], out_dir: Path) -> list[Path]:
    """Write the three PNGs (thrusts, real vs computed torque, worst-case residuals)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    t = cmp.t_s
    lo, hi = SEED001_LOWER_N, SEED001_UPPER_N
    titles = {
        PINV: "pseudo-inverse B⁺Tc (unbounded)",
        PINV_CLIPPED: "pseudo-inverse, clipped",
        QP: "bounded least squares (QP)",
        POLYHEDRAL: "robust, polyhedral set (Thm 1)",
        POLYTOPIC: "robust, polytopic set (Thm 2)",
        LFT: "robust, LFT ΔB = EFH (Thm 3)",
    }
    paths = []

    def time_axis(ax: Any) -> None:
        ax.set_xscale("symlog", linthresh=PLOT_LINEAR_TIME_S)
        ax.set_xlim(0.0, t[-1])
        ax.grid(alpha=0.3, which="both")

    # (a) thrusts of the 8 actuators (seed 001 Figs. 7, 9, 11).
    fig, axes = plt.subplots(2, 3, figsize=(15, 7.5), sharex=True, sharey=True)
    for ax, a in zip(axes.flat, ALLOCATORS, strict=True):
        for i in range(cmp.thrust[a].shape[1]):
            ax.plot(t, cmp.thrust[a][:, i], lw=1.0, label=f"u{i + 1}")
        for bound in (lo, hi):
            ax.axhline(bound, color="k", ls="--", lw=0.8)
        ax.set_title(titles[a], fontsize=10)
        time_axis(ax)
    for ax in axes[-1]:
        ax.set_xlabel(TIME_LABEL)
    for ax in axes[:, 0]:
        ax.set_ylabel("thrust [N]")
    axes[0, 0].legend(ncol=4, fontsize=7, loc="lower right")
    fig.suptitle("Seed 001 Case-1 torques on the Table 1 thrusters (bounds −2.3 / 2.35 N dashed)")
    fig.tight_layout()
    paths.append(out_dir / f"{PLOT_PREFIX}thrust.png")
    fig.savefig(paths[-1], dpi=PLOT_DPI)
    plt.close(fig)

    # (b) real torque vs computed under one fixed worst-case perturbation (Figs. 8, 10, 12).
    fig, axes = plt.subplots(3, 3, figsize=(15, 9), sharex=True)
    for col, a in enumerate(ROBUST):
        s = SETS[a]
        b_true = cmp.sets.fixed_worst(s, cmp.thrust[a], cmp.demand)
        real = cmp.thrust[a] @ b_true.T
        real_pinv = cmp.thrust[PINV_CLIPPED] @ b_true.T
        for row in range(3):
            ax = axes[row, col]
            ax.plot(t, cmp.demand[:, row], "k", lw=1.6, label="Tc (computed)")
            ax.plot(t, real[:, row], "C0", lw=1.0, label=f"real, {a}")
            ax.plot(t, real_pinv[:, row], "C3", ls=":", lw=1.0, label="real, clipped B⁺")
            time_axis(ax)
            if col == 0:
                ax.set_ylabel(f"T{'xyz'[row]} [N m]")
        axes[0, col].set_title(f"{titles[a]}: its worst fixed ΔB", fontsize=10)
        axes[0, col].legend(fontsize=7)
        axes[-1, col].set_xlabel(TIME_LABEL)
    fig.suptitle("Real torque (B + ΔB)u vs computed Tc")
    fig.tight_layout()
    paths.append(out_dir / f"{PLOT_PREFIX}torque.png")
    fig.savefig(paths[-1], dpi=PLOT_DPI)
    plt.close(fig)

    # (c) worst-case residual over each set, all allocators.
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5), sharex=True)
    for ax, s in zip(axes, SET_NAMES, strict=True):
        for a in ALLOCATORS:
            ax.plot(t, np.maximum(worst[a][s], PLOT_RESIDUAL_FLOOR_NM), lw=1.0, label=a)
        ax.set_title(f"worst-case residual over the {s} set", fontsize=10)
        ax.set_xlabel(TIME_LABEL)
        ax.set_yscale("log")
        time_axis(ax)
    axes[0].set_ylabel("max ‖(B + ΔB)u − Tc‖ [N m]")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    paths.append(out_dir / f"{PLOT_PREFIX}worst_case.png")
    fig.savefig(paths[-1], dpi=PLOT_DPI)
    plt.close(fig)
    return paths


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the comparison, print the JSON report, write the plots; returns the report."""
    p = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    p.add_argument("--plots", type=Path, default=DEFAULT_PLOT_DIR, help="PNG directory")
    p.add_argument("--no-plots", action="store_true", help="skip the plots")
    p.add_argument("--duration-s", type=float, default=SEED001_DURATION_S)
    p.add_argument("--random", type=int, default=DEFAULT_N_RANDOM, help="draws per set")
    args = p.parse_args(argv)
    cmp = run(args.duration_s, args.random)
    worst = worst_case_residuals(cmp)
    report = summarise(cmp, worst)
    if not args.no_plots:
        report["plots"] = [str(path) for path in plot(cmp, worst, args.plots)]
    json.dump(report, sys.stdout, indent=2)
    sys.stdout.write("\n")
    return report


if __name__ == "__main__":
    main()
