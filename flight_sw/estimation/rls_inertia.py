"""Recursive-least-squares identification of the inertia tensor (seed 001, §2).

What it does: identifies the six unique entries of the inertia tensor
``θ = (J11, J12, J13, J22, J23, J33)`` [kg m²] (body axes, about the centre of mass) from
the body rate and the torque applied, with the RLS algorithm with forgetting factor of
seed 001 §2. Euler's equation (seed 001 eq. (2), ``J ω̇ + ω × J ω = T``) is linear in θ:
``J ω = Ω(ω) θ`` with
    ``Ω(ω) = [[ω1, ω2, ω3, 0, 0, 0], [0, ω1, 0, ω2, ω3, 0], [0, 0, ω1, 0, ω2, ω3]]``
(seed 001's ``J_m ω_m = Ω_m i_m``; its ``i_m`` is garbled in the text as
``[J11 J12 J13 J11 J22 J33]``, the unique entries are meant).

Regressor (the seed's increment form): the seed regresses on increments ``Δ`` between
``t_{k−1}`` and ``t_k`` (momentum form) rather than on differentiated rates. Integrating
eq. (2) over one control period ``h = t_k − t_{k−1}``:
    ``Ω(ω_k − ω_{k−1}) θ + ∫ [ω×] Ω(ω) θ dt = ∫ T dt = h T̄_k``,
where ``T̄_k`` is the mean torque applied over the period (exact in impulse whatever the
pulse shape inside the period). The gyroscopic integral is taken by the trapezoidal rule
(error O(h³), relative ``≈ (|ω̇| h)²/12``). Divided by ``h`` this gives the measurement
equation ``y_k = Φ_k θ`` in torque units:
    ``Φ_k = Ω((ω_k − ω_{k−1})/h) + ½ ([ω_{k−1}×] Ω(ω_{k−1}) + [ω_k×] Ω(ω_k))``,  ``y_k = T̄_k``.

Window (``window_cycles`` = N ≥ 1): the same equation integrated over the last N periods
(``Φ = Ω((ω_k − ω_{k−N})/T) + (1/T) Σ_j ½([ω_{j−1}×]Ω(ω_{j−1}) + [ω_j×]Ω(ω_j)) h_j``,
``y = (1/T) Σ_j T̄_j h_j``, ``T = Σ_j h_j``): rate noise on the differenced rates and the
torque that valve delays carry from one period into the next both shrink by ~N, at the cost
of a slower response (the windows overlap: one update per cycle).

RLS update (seed 001 §2, the three equations after "the RLS algorithm to compute the
updates for θ(t)", with ``Φ`` 3×6 so its ``P Φ`` reads ``P Φᵀ``):
    ``K_k = P_{k−1} Φ_kᵀ [λ I3 + Φ_k P_{k−1} Φ_kᵀ]⁻¹``,
    ``θ_k = θ_{k−1} + K_k (y_k − Φ_k θ_{k−1})``,
    ``P_k = (I6 − K_k Φ_k) P_{k−1} / λ``;
``P_0 = α I6`` (Remark 1: α > 1; λ close to 1). ``P`` is re-symmetrised after every step
and, against covariance wind-up when λ < 1 and the motion does not excite some direction,
scaled down whenever its trace exceeds that of ``P_0`` (constant-trace bound).

Excitation: the identifier also keeps the discounted information matrix
``R_k = λ R_{k−1} + Φ_kᵀ Φ_k`` [(rad/s²)²]; :meth:`RlsInertiaIdentifier.update` returns
the estimate only while ``λ_min(R_k) > min_information`` and the estimate is the inertia
of some body, else None (so a caller keeps its last good inertia): positive definite (the
kernel's Cholesky test) and with principal moments obeying the triangle inequality
``λ_max ≤ λ_1 + λ_2`` (:func:`dbc.validation.physical_inertia`, the test a configured
inertia passes; equivalently the second-moment matrix ``½ tr(J) I − J`` is positive
semi-definite: Wensing, Kim & Slotine 2018). Positive definiteness alone let through
estimates no body has: on the capture scenario at seed 6, just after the
capture (its window mixes the two bodies' data), principal moments (0.005, 3.0, 23.4)
kg m² (0.005 + 3.0 < 23.4); the MRP law, told them, pushed the wrong way for 26 s (a 36°
error, then a tumble), where told nothing it keeps the pre-capture inertia and converges.
With a torque-equation residual of standard deviation σ_T [N m], the estimate's standard
deviation is about ``σ_T / sqrt(λ_min(R))`` [kg m²]. Steps whose regressor is weaker than
``min_regressor_norm`` (Frobenius norm) are skipped entirely (no forgetting either).

Inputs: ``update(t_ns, omega_BN_B, torque_B_Nm)`` once per control cycle: time [ns], the
(estimated) body rate at ``t_ns`` [rad/s], and the mean torque about the centre of mass
actually applied over the period that ended at ``t_ns`` [N m], body axes.
Output: the symmetric 3×3 estimate [kg m²] or None.

Assumptions: rigid body (seed 001 §2: manipulator joints locked after capture), no
external torque other than the control torque, body axes fixed in the body (the seed
works in the principal-axis frame; products of inertia are identified here as well). The
torque passed in is trusted: if the thrusters deliver a different torque (modulation
rounding, a failed valve), the estimate is biased accordingly. Noise on the rate enters
the regressor as well (errors in variables), which biases the estimate by about the
ratio of the rate-difference noise power to the excitation power.

Source: seed 001 ("Attitude control and structure robust control allocation for combined
spacecraft"), §2: Euler
equation (2), the RLS equations with forgetting factor and Remark 1; the regressor
parametrisation of the momentum-based identification the seed cites as [7]. The physical
gate: Traversaro, Brossette, Escande & Nori 2016, "Identification of fully physical
consistent inertial parameters using optimization on manifolds" (IROS; arXiv:1610.08703:
positive definiteness and the triangle inequality); Wensing, Kim & Slotine 2018, "Linear
matrix inequalities for physically consistent inertial parameter identification: a
statistical perspective on the mass distribution" (IEEE RA-L; arXiv:1701.04395: the
second-moment form).

Computation: the per-cycle arithmetic (regressor, window sums, RLS step, gates) runs on
floats in :mod:`flight_sw.estimation.rls_kernel` (compiled), its one implementation; the
tests hold it to a numpy form of the same equations (``tests/flight_sw/estimation/
rls_reference.py``). An innovation matrix ``S`` too ill-conditioned for Cholesky is
solved by the kernel's SVD path (:attr:`RlsInertiaIdentifier.n_svd_steps` counts them); a
step whose result is not finite is skipped (:attr:`RlsInertiaIdentifier.n_refused_steps`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from flight_sw.estimation import rls_kernel as kernel

N_PARAMS = 6  # unique entries of a symmetric 3×3 tensor
N_AXES = 3
NS_PER_S = 1_000_000_000
# (row, column) of each entry of θ = (J11, J12, J13, J22, J23, J33)
THETA_INDEX = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))

DEFAULT_FORGETTING_FACTOR = 0.999  # memory ≈ 1/(1 − λ) = 1000 cycles (20 s at 50 Hz)
DEFAULT_INITIAL_COVARIANCE = 1.0e6  # α [(kg m²)²]: a weak prior (seed 001 Remark 1: α > 1)
DEFAULT_MIN_INFORMATION = 1.0e-2  # [(rad/s²)²]
DEFAULT_MIN_REGRESSOR_NORM = 0.0  # [rad/s²]: 0 = every step is used
DEFAULT_MAX_GAP_S = 1.0  # a longer gap between samples restarts the differencing

_SOURCE = "RlsInertiaParams"


def inertia_matrix(theta: np.ndarray) -> np.ndarray:
    """The symmetric 3×3 tensor [kg m²] of ``θ = (J11, J12, J13, J22, J23, J33)``."""
    j11, j12, j13, j22, j23, j33 = np.asarray(theta, dtype=float).tolist()
    return np.array([[j11, j12, j13], [j12, j22, j23], [j13, j23, j33]])


def inertia_params(inertia_kgm2: np.ndarray) -> np.ndarray:
    """``θ = (J11, J12, J13, J22, J23, J33)`` of a 3×3 tensor (upper triangle, row order)."""
    j = np.asarray(inertia_kgm2, dtype=float)
    return np.array([j[r, c] for r, c in THETA_INDEX])


class _Window:
    """The last N + 1 samples as the kernel takes them: rates [rad/s] and their
    ``[ω×]Ω(ω)``, and the N periods' lengths [s] and mean torques [N m]."""

    def __init__(self, n_periods: int) -> None:
        self.n_periods = n_periods
        self.t_last_ns: int | None = None
        self.omega_B: list[list[float]] = []
        self.gyro: list[list[float]] = []
        self.h_s: list[float] = []
        self.torque_B_Nm: list[list[float]] = []

    @property
    def full(self) -> bool:
        """Whether N periods are held."""
        return len(self.h_s) == self.n_periods

    def clear(self) -> None:
        """Forget every sample (the differencing restarts)."""
        self.t_last_ns = None
        for samples in (self.omega_B, self.gyro, self.h_s, self.torque_B_Nm):
            samples.clear()

    def push(self, t_ns: int, omega_B: list[float], torque_B_Nm: list[float]) -> None:
        """Add the sample at ``t_ns`` with the torque of the period it ends; drop the oldest."""
        if self.t_last_ns is not None:
            self.h_s.append((t_ns - self.t_last_ns) / NS_PER_S)
            self.torque_B_Nm.append(torque_B_Nm)
        self.t_last_ns = t_ns
        self.omega_B.append(omega_B)
        self.gyro.append(kernel.gyroscopic(omega_B))
        if len(self.h_s) > self.n_periods:
            del self.omega_B[0], self.gyro[0], self.h_s[0], self.torque_B_Nm[0]


def _inertia_tuple(value: object) -> tuple[tuple[float, float, float], ...]:
    sym = check.inertia(_SOURCE, "inertia_guess_B_kgm2", value, physical=True)
    return tuple((float(r[0]), float(r[1]), float(r[2])) for r in sym)


@dataclass(frozen=True)
class RlsInertiaParams:
    """RLS inertia-identification parameters.

    Attributes:
        inertia_guess_B_kgm2: initial estimate θ_0 (3×3, symmetric, some body's inertia)
            [kg m²], body axes about the centre of mass; stored as a tuple of rows.
        forgetting_factor: λ in (0, 1] (1: no forgetting).
        initial_covariance: α > 0 in P_0 = α I6 [(kg m²)²]; the prior weighs 1/α.
        min_information: the estimate is returned only while λ_min(R) ≥ this
            [(rad/s²)²] (≥ 0; 0: as soon as the estimate is positive definite).
        min_regressor_norm: steps with ‖Φ‖_F below this are skipped [rad/s²] (≥ 0).
        max_gap_s: a gap between samples above this [s] (> 0) restarts the differencing.
        window_cycles: periods the Euler equation is integrated over (≥ 1; module docstring).
    """

    inertia_guess_B_kgm2: Sequence[Sequence[float]] | np.ndarray
    forgetting_factor: float = DEFAULT_FORGETTING_FACTOR
    initial_covariance: float = DEFAULT_INITIAL_COVARIANCE
    min_information: float = DEFAULT_MIN_INFORMATION
    min_regressor_norm: float = DEFAULT_MIN_REGRESSOR_NORM
    max_gap_s: float = DEFAULT_MAX_GAP_S
    window_cycles: int = 1

    def __post_init__(self) -> None:
        object.__setattr__(self, "inertia_guess_B_kgm2", _inertia_tuple(self.inertia_guess_B_kgm2))
        s = _SOURCE
        check.number(s, "forgetting_factor", self.forgetting_factor, 0.0, 1.0, lo_open=True)
        check.positive(s, "initial_covariance", self.initial_covariance)
        check.non_negative(s, "min_information", self.min_information)
        check.non_negative(s, "min_regressor_norm", self.min_regressor_norm)
        check.positive(s, "max_gap_s", self.max_gap_s, unit="s")
        check.integer(s, "window_cycles", self.window_cycles, 1)


class RlsInertiaIdentifier:
    """RLS identifier of the inertia tensor (implements ``InertiaIdentifier``).

    The per-cycle arithmetic runs in :mod:`flight_sw.estimation.rls_kernel` on floats
    (an ill-conditioned ``S`` included: its SVD path).
    """

    def __init__(self, params: RlsInertiaParams) -> None:
        self._params = params
        self._theta: list[float] = inertia_params(np.array(params.inertia_guess_B_kgm2)).tolist()
        self._p = _scaled_identity(params.initial_covariance)
        self._info = _scaled_identity(0.0)
        self._window = _Window(params.window_cycles)
        self._n_updates = 0
        self._n_svd_steps = 0
        self._n_refused_steps = 0
        self._n_unphysical = 0

    @property
    def params(self) -> RlsInertiaParams:
        """The parameters this identifier was built with."""
        return self._params

    @property
    def inertia_B_kgm2(self) -> np.ndarray:
        """The current estimate (3×3, symmetric) [kg m²], whether excited or not."""
        return inertia_matrix(np.array(self._theta))

    @property
    def covariance(self) -> np.ndarray:
        """A copy of P (6×6) [(kg m²)²] in the order of θ."""
        return np.array(self._p)

    @property
    def min_information(self) -> float:
        """λ_min of the discounted information matrix R [(rad/s²)²]."""
        return float(np.linalg.eigvalsh(np.array(self._info))[0])

    @property
    def n_updates(self) -> int:
        """RLS steps taken since construction or the last reset."""
        return self._n_updates

    @property
    def n_svd_steps(self) -> int:
        """Steps whose innovation matrix ``S`` failed the Cholesky gate and was solved by
        the kernel's SVD path (since construction; a reset keeps the count)."""
        return self._n_svd_steps

    @property
    def n_refused_steps(self) -> int:
        """Steps skipped because their result was not finite (since construction)."""
        return self._n_refused_steps

    @property
    def n_unphysical(self) -> int:
        """Calls of :meth:`update` (cycles) whose estimate was withheld as no body's inertia
        (positive definite, but a principal moment above the sum of the other two), since
        construction (a reset keeps the count)."""
        return self._n_unphysical

    def reset(self, inertia_guess_B_kgm2: np.ndarray | None = None) -> None:
        """Restart after a known mass-property change (e.g. a capture).

        ``inertia_guess_B_kgm2`` (3×3) replaces the estimate; None keeps the current one
        and only resets the covariance to ``α I6`` (re-opens the identifier). The
        information and the previous rate sample are cleared either way (the period
        across the change is not used).
        """
        if inertia_guess_B_kgm2 is not None:
            guess = np.array(_inertia_tuple(inertia_guess_B_kgm2))
            self._theta = inertia_params(guess).tolist()
        self._p = _scaled_identity(self._params.initial_covariance)
        self._info = _scaled_identity(0.0)
        self._window.clear()
        self._n_updates = 0

    def update(
        self, t_ns: int, omega_BN_B: np.ndarray, torque_B_Nm: np.ndarray
    ) -> np.ndarray | None:
        """Take the rate at ``t_ns`` and the mean torque of the period ending at ``t_ns``.

        Returns the current estimate (3×3) [kg m²] if excited enough and some body's
        inertia (module docstring), else None. A non-finite input, a non-increasing time
        or a gap above ``max_gap_s`` drops the pair of samples (the differencing restarts).
        """
        w = _vector3(omega_BN_B)
        tau = _vector3(torque_B_Nm)
        win = self._window
        if not all(math.isfinite(x) for x in w + tau):
            win.clear()
            return self._output()
        if win.t_last_ns is not None:
            dt_s = (t_ns - win.t_last_ns) / NS_PER_S
            if not 0.0 < dt_s <= self._params.max_gap_s:
                win.clear()
        win.push(t_ns, w, tau)
        if not win.full:
            return self._output()
        phi, y = kernel.window_equation(
            win.h_s, win.omega_B[0], win.omega_B[-1], win.gyro, win.torque_B_Nm
        )
        sq = 0.0  # left to right (sum() of floats is compensated from Python 3.12)
        for row in phi:
            for v in row:
                sq += v * v
        if math.sqrt(sq) < self._params.min_regressor_norm:
            return self._output()
        self._step(phi, y)
        return self._output()

    def _step(self, phi: list[list[float]], y: list[float]) -> None:
        """One RLS step (seed 001 §2) with the constant-trace bound on P."""
        lam = self._params.forgetting_factor
        trace_cap = N_PARAMS * self._params.initial_covariance
        out = kernel.rls_step(self._p, self._theta, self._info, phi, y, lam, trace_cap)
        if out is None:  # not finite (overflow): the estimate keeps its last value
            self._n_refused_steps += 1
            return
        self._p, self._theta, self._info, by_svd = out
        if by_svd:
            self._n_svd_steps += 1
        self._n_updates += 1

    def _output(self) -> np.ndarray | None:
        """The estimate while ``λ_min(R) > min_information`` and it is some body's inertia
        (positive definite, the triangle inequality: module docstring)."""
        if self._n_updates == 0:
            return None
        if not kernel.exceeds(self._info, self._params.min_information):
            return None
        j11, j12, j13, j22, j23, j33 = self._theta
        j = [[j11, j12, j13], [j12, j22, j23], [j13, j23, j33]]
        if not kernel.exceeds(j, 0.0):
            return None
        estimate = np.array(j)
        if not check.physical_inertia(estimate):
            self._n_unphysical += 1
            return None
        return estimate


def _scaled_identity(value: float) -> list[list[float]]:
    """``value · I6`` as a list of rows."""
    return [[value if r == c else 0.0 for c in range(N_PARAMS)] for r in range(N_PARAMS)]


def _vector3(value: np.ndarray) -> list[float]:
    """A 3-vector as a list of floats."""
    out: list[float] = np.asarray(value, dtype=float).reshape(N_AXES).tolist()
    return out
