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
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from bench.station.valves.layouts import seed001_table1_16
from flight_sw import mrp
from flight_sw import quaternion as qt
from flight_sw.allocation.effectiveness import TORQUE_ROWS, effectiveness_matrix
from flight_sw.allocation.qp_osqp import BoundedQpAllocator, BoundedQpParams
from flight_sw.allocation.robust_lft import RobustLftAllocator, RobustLftParams
from flight_sw.allocation.robust_polyhedral import RobustPolyhedralAllocator
from flight_sw.allocation.robust_polytopic import RobustParams, RobustPolytopicAllocator
from flight_sw.allocation.uncertainty import (
    SEED001_BASIS_WEIGHTS,
    SEED001_LFT_E_SHAPE,
    SEED001_LFT_H,
    SEED001_RHO,
    lft_worst_case_perturbation,
    lft_worst_case_residual,
    polyhedral_vertices,
    polytopic_vertices,
    relative_basis,
)
from flight_sw.control.mrp_direct_parametric import MrpDirectParametric, MrpDirectParametricParams
from flight_sw.guidance.mrp_polynomial import MrpPolynomialGuidance

REPO = Path(__file__).resolve().parents[1]
DEFAULT_PLOT_DIR = REPO / "docs" / "img" / "reproductions"
PLOT_PREFIX = "robust_allocation_"
PLOT_DPI = 90
# The torque transient lasts ~1 s of the 100 s: time axes are linear up to this, log after.
PLOT_LINEAR_TIME_S = 1.0
# Worst-case residuals are drawn on a log axis floored here [N m].
PLOT_RESIDUAL_FLOOR_NM = 1e-8
TIME_LABEL = "t [s] (linear to 1 s, log after)"

# Seed 001 sec. 5: inertia [kg m²], initial MRP and rate [rad/s], Case 1, 100 s.
SEED001_INERTIA_KGM2 = ((25.0, 0.0, 0.0), (0.0, 20.0, 0.0), (0.0, 0.0, 15.0))
SEED001_SIGMA0 = (0.08381, 0.101, 0.1205)
SEED001_OMEGA0_RAD_S = (0.087266, 0.043633, 0.05236)
SEED001_CASE = 1
SEED001_DURATION_S = 100.0
CONTROL_STEP_S = 0.02
NS_PER_S = 1_000_000_000
HALF = 0.5
RK4_MID = 0.5
RK4_WEIGHTS = (1.0, 2.0, 2.0, 1.0)
RK4_SUM = 6.0

# Seed 001 sec. 5: signed thrust bounds [N]; Table 1's geometry comes from the bench's
# layout (its first 8 valves are the paper's actuators; R = L = 0.75 m).
SEED001_LOWER_N = -2.3
SEED001_UPPER_N = 2.35
SEED001_ARM_M = 0.75
SEED001_ACTUATORS = 8

# A thrust counts as violating its bounds beyond this [N].
BOUND_TOL_N = 1e-9
# Random admissible perturbations: draws per uncertainty set, generator seed.
DEFAULT_N_RANDOM = 200
RANDOM_SEED = 20240607
# Fixed worst-case F of the LFT set: rank-one candidates from every k-th sample, then
# this many ascent steps F ← polar factor of the gradient (monotone for a convex objective).
LFT_CANDIDATE_STRIDE = 10
LFT_ASCENT_STEPS = 50
P99 = 99.0
US_PER_S = 1e6
SIGNIFICANT_DIGITS = 6

PINV = "pseudo_inverse"
PINV_CLIPPED = "pseudo_inverse_clipped"
QP = "bounded_qp"
POLYHEDRAL = "robust_polyhedral"
POLYTOPIC = "robust_polytopic"
LFT = "robust_lft"
ALLOCATORS = (PINV, PINV_CLIPPED, QP, POLYHEDRAL, POLYTOPIC, LFT)
ROBUST = (POLYHEDRAL, POLYTOPIC, LFT)
# Uncertainty sets, named after the robust allocator designed for each.
SETS = MappingProxyType({POLYHEDRAL: "polyhedral", POLYTOPIC: "polytopic", LFT: "lft"})
SET_NAMES = tuple(SETS.values())

METRIC_KEYS = (
    "thrust_max_N",
    "thrust_min_N",
    "bound_violation_samples",
    "nominal_residual_Nm",
    "worst_case_residual_Nm",
    "random_perturbation_rms_Nm",
    "solve_time_us",
)

Allocate = Callable[[np.ndarray], np.ndarray]


def seed001_torque_matrix() -> np.ndarray:
    """3×8 torque rows of the seed-001 Table 1 effectiveness matrix [N m/N]."""
    geo = seed001_table1_16(SEED001_ARM_M, SEED001_ARM_M)[:SEED001_ACTUATORS]
    r_thr_B = np.array([r for r, _ in geo])
    d_thr_B = np.array([d for _, d in geo])
    return effectiveness_matrix(r_thr_B, d_thr_B)[TORQUE_ROWS]


def case1_torque_history(duration_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``(t_s, Tc)``: the Case-1 control torques [N m] (K×3) at every 20 ms control step."""
    inertia = np.array(SEED001_INERTIA_KGM2)
    j_inv = np.linalg.inv(inertia)
    ctrl = MrpDirectParametric(MrpDirectParametricParams.from_case(SEED001_CASE), inertia)
    guidance = MrpPolynomialGuidance()
    dt_s = CONTROL_STEP_S
    dt_ns = round(dt_s * NS_PER_S)
    n_steps = round(duration_s / dt_s)
    q = mrp.to_quaternion(np.array(SEED001_SIGMA0))
    w = np.array(SEED001_OMEGA0_RAD_S)

    def deriv(q_: np.ndarray, w_: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q_dot = HALF * qt.multiply(q_, np.concatenate(([0.0], w_)))
        return q_dot, j_inv @ (tau - np.cross(w_, inertia @ w_))

    torques = np.empty((n_steps, 3))
    for k in range(n_steps):
        t_ns = k * dt_ns
        ref = guidance.reference(t_ns)
        c_BR = qt.to_dcm(q) @ qt.to_dcm(ref.q_RN).T
        tau = ctrl.torque_B_Nm(t_ns, q, w, ref.q_RN, c_BR @ ref.omega_RN_R, c_BR @ ref.domega_RN_R)
        torques[k] = tau
        k1 = deriv(q, w, tau)
        k2 = deriv(q + RK4_MID * dt_s * k1[0], w + RK4_MID * dt_s * k1[1], tau)
        k3 = deriv(q + RK4_MID * dt_s * k2[0], w + RK4_MID * dt_s * k2[1], tau)
        k4 = deriv(q + dt_s * k3[0], w + dt_s * k3[1], tau)
        ks = (k1, k2, k3, k4)
        dq = sum(c * k[0] for c, k in zip(RK4_WEIGHTS, ks, strict=True))
        dw = sum(c * k[1] for c, k in zip(RK4_WEIGHTS, ks, strict=True))
        q = qt.normalise(q + dt_s / RK4_SUM * dq)
        w = w + dt_s / RK4_SUM * dw
    return np.arange(n_steps) * dt_s, torques


@dataclass(frozen=True)
class UncertaintySets:
    """The three seed-001 sec. 5 uncertainty sets of ``B``.

    Attributes:
        b0: nominal 3×8 torque matrix.
        polyhedral: distinct corner matrices of ``Δ_I`` (K×3×8).
        polytopic: vertex matrices ``B + Bᵢ`` of ``Δ_P`` (K×3×8).
        e: LFT ``E`` (3×3), h: LFT ``H`` (3×8).
    """

    b0: np.ndarray
    polyhedral: np.ndarray
    polytopic: np.ndarray
    e: np.ndarray
    h: np.ndarray

    @classmethod
    def seed001(cls, b0: np.ndarray) -> UncertaintySets:
        """The sets of seed 001 sec. 5 (ρ = 0.1, weights 1, 1, 2, 2; E, H as printed)."""
        basis = relative_basis(b0, SEED001_RHO, SEED001_BASIS_WEIGHTS)
        return cls(
            b0=b0,
            polyhedral=polyhedral_vertices(b0, basis),
            polytopic=polytopic_vertices(b0, basis),
            e=SEED001_RHO * np.array(SEED001_LFT_E_SHAPE),
            h=np.array(SEED001_LFT_H),
        )

    def vertices(self, name: str) -> np.ndarray:
        """Vertex stack of the vertex set ``name`` (polyhedral or polytopic)."""
        return self.polyhedral if name == SETS[POLYHEDRAL] else self.polytopic

    def worst_case(self, name: str, thrust: np.ndarray, demand: np.ndarray) -> np.ndarray:
        """Exact worst-case residual [N m] per sample (thrust K×8, demand K×3) over ``name``."""
        if name == SETS[LFT]:
            return np.array(
                [
                    lft_worst_case_residual(self.b0, self.e, self.h, u, v)
                    for u, v in zip(thrust, demand, strict=True)
                ]
            )
        r = np.einsum("jmn,kn->jkm", self.vertices(name), thrust) - demand[None]
        return np.asarray(np.sqrt(np.max(np.sum(r * r, axis=2), axis=0)))

    def random_matrices(self, name: str, rng: np.random.Generator, count: int) -> np.ndarray:
        """``count`` admissible ``B + ΔB`` (count×3×8) drawn at random from set ``name``."""
        basis = relative_basis(self.b0, SEED001_RHO, SEED001_BASIS_WEIGHTS)
        q = basis.shape[0]
        if name == SETS[POLYHEDRAL]:
            delta = rng.uniform(-1.0, 1.0, (count, q))
        elif name == SETS[POLYTOPIC]:
            delta = rng.dirichlet(np.ones(q), count)
        else:
            p, r = self.e.shape[1], self.h.shape[0]
            g = rng.normal(size=(count, p, r))
            f = g / np.linalg.norm(g, ord=2, axis=(1, 2))[:, None, None]
            f *= rng.uniform(0.0, 1.0, count)[:, None, None]
            return np.asarray(self.b0[None] + np.einsum("ij,kjl,ln->kin", self.e, f, self.h))
        return np.asarray(self.b0[None] + np.einsum("kq,qmn->kmn", delta, basis))

    def fixed_worst(self, name: str, thrust: np.ndarray, demand: np.ndarray) -> np.ndarray:
        """One ``B + ΔB`` maximising ``Σₖ ‖(B + ΔB)uₖ − Tcₖ‖²`` over the run (3×8).

        Exact for the vertex sets (a convex function of δ peaks at a vertex); for the LFT
        set the best rank-one per-sample worst case, improved by ascent steps
        ``F ← U Vᵀ`` of the gradient's SVD (each step cannot decrease the convex sum).
        """
        if name != SETS[LFT]:
            verts = self.vertices(name)
            r = np.einsum("jmn,kn->jkm", verts, thrust) - demand[None]
            return np.asarray(verts[int(np.argmax(np.sum(r * r, axis=(1, 2))))])
        res = thrust @ self.b0.T - demand  # K×3
        hv = thrust @ self.h.T  # K×r

        def total(f: np.ndarray) -> float:
            z = res + hv @ f.T @ self.e.T
            return float(np.sum(z * z))

        cands = [
            lft_worst_case_perturbation(self.b0, self.e, self.h, u, v)
            for u, v in zip(
                thrust[::LFT_CANDIDATE_STRIDE], demand[::LFT_CANDIDATE_STRIDE], strict=True
            )
        ]
        f = max(cands, key=total)
        for _ in range(LFT_ASCENT_STEPS):
            grad = self.e.T @ (res + hv @ f.T @ self.e.T).T @ hv
            u_, _, vt = np.linalg.svd(grad)
            f = u_ @ vt
        return np.asarray(self.b0 + self.e @ f @ self.h)


def make_allocators(b0: np.ndarray) -> dict[str, Allocate]:
    """The six allocators compared, each mapping a torque demand [N m] to thrusts [N]."""
    pinv = np.linalg.pinv(b0)
    lo, hi = SEED001_LOWER_N, SEED001_UPPER_N
    qp = BoundedQpAllocator(b0, BoundedQpParams(upper_N=hi, lower_N=lo))
    robust = RobustParams(upper_N=hi, lower_N=lo, rho=SEED001_RHO)
    poly_h = RobustPolyhedralAllocator(b0, robust)
    poly_t = RobustPolytopicAllocator(b0, robust)
    lft = RobustLftAllocator(
        b0,
        RobustLftParams(
            upper_N=hi,
            lower_N=lo,
            rho=SEED001_RHO,
            e_shape=SEED001_LFT_E_SHAPE,
            h_matrix=SEED001_LFT_H,
        ),
    )
    return {
        PINV: lambda v: pinv @ v,
        PINV_CLIPPED: lambda v: np.clip(pinv @ v, lo, hi),
        QP: lambda v: qp.allocate(v).thrust_N,
        POLYHEDRAL: lambda v: poly_h.allocate(v).thrust_N,
        POLYTOPIC: lambda v: poly_t.allocate(v).thrust_N,
        LFT: lambda v: lft.allocate(v).thrust_N,
    }


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
