"""Seed 001's allocation study, its inputs as pure math: torques, matrix, sets, allocators.

What it does: the pieces :mod:`robust_allocation` (the benchmark script beside this one)
compares, for seed 001, sec. 5:

1. the Case-1 control torque history ``Tc(t)`` (seed 001 Fig. 6): the direct parametric MRP
   law (:mod:`flight_sw.control.mrp_direct_parametric`, ``F0 = E``, ``Z = [I3 I3]``) closing
   the loop on the rigid body ``J = diag(25, 20, 15)`` kg m² from ``σ(0)``, ``ω(0)`` of sec. 5,
   tracking the sec. 5 polynomial MRP trajectory
   (:mod:`flight_sw.guidance.mrp_polynomial`) for 100 s; RK4, torque held over each 20 ms
   control step, the body receiving exactly the demanded torque (ideal actuation)
   (:func:`case1_torque_history`);
2. the torque rows of the Table 1 thrusters (8, signed bounds −2.3 ≤ u ≤ 2.35 N;
   :func:`seed001_torque_matrix`) and the allocators compared on them
   (:func:`make_allocators`): the unbounded pseudo-inverse ``B⁺Tc`` (the paper's
   baseline), the same clipped to the bounds, the bounded least-squares QP
   (:mod:`flight_sw.allocation.qp_osqp`) and the three robust allocators of sec. 4:
   polyhedral (Theorem 1, ``ΔB = Σ δᵢBᵢ``, ``Bᵢ = 0.1B, 0.1B, 0.2B, 0.2B``, ``|δᵢ| ≤ 1``),
   polytopic (Theorem 2, same ``Bᵢ``, ``δᵢ ≥ 0``, ``Σδᵢ = 1``) and linear-fractional
   (Theorem 3, ``ΔB = E F H``, ``E = diag(0.1, 0.15, 0.1)``, the printed 3×8 ``H``,
   ``‖F‖ ≤ 1``);
3. the three uncertainty sets (:class:`UncertaintySets`): the exact worst-case residual
   over each (vertex maximum; the S-lemma formula for the LFT set;
   :mod:`flight_sw.allocation.uncertainty`), random admissible perturbations, and one
   fixed worst-case perturbation over a whole run.

Inputs: none (all seed 001 constants). Outputs: numpy arrays; torques [N m], thrusts [N],
times [s]. No clock is read.

Assumptions: the uncertainty sets are those of sec. 5 (``Bᵢ ∝ B``: every vertex is a
multiple of ``B``, so the worst case of a thrust depends only on ``B u``); the fixed
worst-case perturbation is exact for the vertex sets and a local maximiser for the LFT
set.

Sources: seed 001 (MRP control and robust allocation of a combined spacecraft), sec. 3
(control law, Case 1), sec. 4 (eq. 13, Theorems 1–3) and sec. 5 (Table 1, Figs. 6–12).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from types import MappingProxyType

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

# Fixed worst-case F of the LFT set: rank-one candidates from every k-th sample, then
# this many ascent steps F ← polar factor of the gradient (monotone for a convex objective).
LFT_CANDIDATE_STRIDE = 10
LFT_ASCENT_STEPS = 50

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
