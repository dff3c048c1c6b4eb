"""The control-allocation interface and the base every allocation strategy extends.

What it does: defines :class:`Allocator`, the interface the flight computer calls,
:class:`AllocationResult`, its immutable output, and :class:`ControlAllocation`, the base
of every strategy (after PX4's ``ControlAllocation``: one object holds the effectiveness
matrix, the per-thruster thrust bounds and the availability mask, and turns a solve into
a checked result). A strategy extends it and implements only :meth:`ControlAllocation._solve`,
the thrusts of the available thrusters for one demand; the base does the rest, once for
all strategies:

- set-up: the effectiveness matrix checked (m×n, 1 ≤ m ≤ 6, finite) and frozen; the
  bounds ``lower_N``/``upper_N`` expanded to per-thruster vectors (n,) [N] and checked
  (finite, ``lo ≤ hi``); the mask parsed (n booleans, True = usable); the available
  columns ``B_a``, bounds ``lo_a``/``hi_a``, an orthonormal basis of ``range(B_a)`` and the
  "demand reproduced" tolerance derived from them;
- reconfiguration: :meth:`ControlAllocation.with_mask` builds a new instance of the same
  strategy with the same matrix and parameters for another mask (FDIR isolating a
  thruster), so an allocator in use is never mutated;
- each call: the demand checked (shape (m,); a non-finite demand or no usable thruster
  gives all zeros, an infinite or the demand's residual, flagged saturated unless zero),
  the strategy's thrusts scattered to all n thrusters (masked ones exactly 0),
  ``achieved = B T``, the residual, and — unless the strategy decided it — the saturation
  flag: a residual left inside ``range(B_a)`` beyond the tolerance.

Inputs: ``demand``: the demanded body torque [N m] (m = 3) or wrench [N; N m] (m = 6),
body axes, in the row order of the effectiveness matrix
(:mod:`flight_sw.allocation.effectiveness`). Bounds per thruster [N] (one number is
expanded to every thruster): ``[0, T_max,i]`` for on-off thrusters, signed for the
bidirectional actuators of seed 001. Output: :class:`AllocationResult`.

Assumptions: on-off thrusters whose mean thrust over a control period is commanded as a
fraction of their maximum by the modulators downstream; thrusters independent.

Sources: PX4 Autopilot, ``src/lib/control_allocation/control_allocation/ControlAllocation.hpp``
(effectiveness, limits and ``allocate()`` shared by the allocation methods); Bordignon
1996, "Constrained Control Allocation for Systems with Redundant Control Effectors", PhD
thesis, Virginia Tech, ch. 2 (``m = B u`` with per-effector limits).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar

import numpy as np

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw.allocation.dense import mat_vec, norm

MAX_DEMAND_DIM = 6
# Singular values below RANK_RTOL × the largest count as zero (rank, least-norm solutions).
RANK_RTOL = 1e-10
# A residual below ATTAINED_RTOL × max(1, bound range × largest column norm) counts as zero.
ATTAINED_RTOL = 1e-9
# Warm-up demands: B·T with the thrusters alternately at these fractions of their range
# (attainable, not cancelling on symmetric layouts), and each axis alone at this multiple
# of its reach (saturating: the bounded paths).
WARM_UP_FRACTIONS = (0.2, 0.8)
WARM_UP_BEYOND_REACH = 2.0

BoundSpec = float | tuple[float, ...]
A = TypeVar("A", bound="ControlAllocation")


@dataclass(frozen=True, slots=True)
class AllocationResult:
    """The outcome of one allocation (arrays are read-only).

    Attributes:
        thrust_N: thrust per thruster [N], shape (n,), each within its bounds.
        achieved: ``B @ thrust_N``, same shape and units as the demand.
        residual_norm: ``‖demand − achieved‖`` (Euclidean, demand units).
        saturated: True when the thrust bounds prevented reproducing the attainable part
            of the demand (the demand was scaled down or bounded); a residual caused only
            by a direction no thruster can produce is not saturation.
    """

    thrust_N: np.ndarray
    achieved: np.ndarray
    residual_norm: float
    saturated: bool


class Allocator(Protocol):
    """Maps a torque or wrench demand to per-thruster thrusts."""

    def allocate(self, demand: np.ndarray) -> AllocationResult:
        """Thrusts for ``demand`` (see :class:`AllocationResult`)."""
        ...

    def with_mask(self, mask: Sequence[bool] | np.ndarray) -> Allocator:
        """A new allocator, identical but for the availability mask (True = usable)."""
        ...

    def warm_up(self) -> None:
        """Pay the first-call costs before the first control cycle; results unchanged."""
        ...


def frozen(a: np.ndarray) -> np.ndarray:
    """``a``, made read-only."""
    a.setflags(write=False)
    return a


def check_bound_spec(source: str, key: str, value: object) -> None:
    """Raise ConfigError unless ``value`` is a finite number or a non-empty tuple of them."""
    if isinstance(value, tuple):
        check.vector(source, key, value, None)
    else:
        check.number(source, key, value)


def thrust_bounds(
    source: str, lower_N: BoundSpec, upper_N: BoundSpec, n: int
) -> tuple[np.ndarray, np.ndarray]:
    """Per-thruster bound arrays (n,) from scalar or per-thruster specs; checks lo ≤ hi."""
    out = []
    for key, spec in (("lower_N", lower_N), ("upper_N", upper_N)):
        arr = np.array(spec, dtype=float).reshape(-1)
        if arr.size == 1:
            arr = np.full(n, float(arr[0]))
        if arr.shape != (n,) or not np.all(np.isfinite(arr)):
            raise ConfigError(source, key, spec, f"a finite number or {n} finite numbers")
        out.append(arr)
    lo, hi = out
    bad = np.flatnonzero(lo > hi)
    if bad.size:
        i = int(bad[0])
        raise ConfigError(source, f"lower_N[{i}]", float(lo[i]), f"<= upper_N[{i}]")
    return lo, hi


def check_effectiveness(source: str, effectiveness: np.ndarray) -> np.ndarray:
    """A float copy of the m×n effectiveness matrix (1 <= m <= 6, finite), read-only."""
    b = np.array(effectiveness, dtype=float)
    if b.ndim != 2 or not (1 <= b.shape[0] <= MAX_DEMAND_DIM) or b.shape[1] == 0:
        raise ConfigError(source, "effectiveness", b.shape, "an m×n array, 1 <= m <= 6")
    if not np.all(np.isfinite(b)):
        raise ConfigError(source, "effectiveness", "non-finite", "finite values")
    return frozen(b)


def parse_mask(source: str, mask: Sequence[bool] | np.ndarray | None, n: int) -> np.ndarray:
    """The availability mask as a read-only bool array (n,); None means all usable."""
    if mask is None:
        arr = np.ones(n, dtype=bool)
    else:
        raw = np.asarray(mask)
        if raw.shape != (n,) or raw.dtype != bool:
            raise ConfigError(source, "mask", mask, f"{n} booleans (True = usable)")
        arr = raw.copy()
    return frozen(arr)


def range_basis_T(b_a: np.ndarray) -> np.ndarray:
    """Rows: an orthonormal basis of range(b_a) (rank × m; 0 × m if b_a has no rank)."""
    m = b_a.shape[0]
    if b_a.size == 0:
        return np.zeros((0, m))
    u, s, _ = np.linalg.svd(b_a, full_matrices=False)
    rank = int(np.sum(s > RANK_RTOL * s[0])) if s.size and s[0] > 0 else 0
    return u[:, :rank].T.copy()


def attained_tolerance(b_a: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """Residual [demand units] below which a demand counts as reproduced."""
    col = float(np.max(np.linalg.norm(b_a, axis=0))) if b_a.size else 0.0
    span = float(np.max(np.maximum(np.abs(lo), np.abs(hi)))) if lo.size else 0.0
    return ATTAINED_RTOL * max(1.0, col * span)


def trivial_result(d: np.ndarray, n: int) -> AllocationResult:
    """All-zero thrust for a non-finite demand (infinite residual) or no usable thruster."""
    finite = bool(np.all(np.isfinite(d)))
    residual = norm(d.tolist()) if finite else math.inf
    m = d.shape[0]
    return AllocationResult(frozen(np.zeros(n)), frozen(np.zeros(m)), residual, residual > 0.0)


def check_demand(d: object, m: int) -> np.ndarray:
    """The demand as a float array of shape (m,); ValueError otherwise."""
    arr = np.asarray(d, dtype=float)
    if arr.shape != (m,):
        raise ValueError(f"demand has shape {arr.shape}, expected ({m},)")
    return arr


class ControlAllocation:
    """Effectiveness matrix, per-thruster bounds and availability; ``allocate()`` around a solve.

    Subclasses set :attr:`_source` (their name, for errors), call ``__init__`` with their
    parameters and bounds, and implement :meth:`_solve`; a subclass whose constructor
    takes more than ``(effectiveness, params, mask)`` returns those extra arguments from
    :meth:`_rebuild_args` so that :meth:`with_mask` can rebuild it.
    """

    _source = "ControlAllocation"

    def __init__(
        self,
        effectiveness: np.ndarray,
        params: Any,
        mask: Sequence[bool] | np.ndarray | None,
        lower_N: BoundSpec,
        upper_N: BoundSpec,
    ) -> None:
        src = self._source
        b = check_effectiveness(src, effectiveness)
        n = b.shape[1]
        lo, hi = thrust_bounds(src, lower_N, upper_N, n)
        self._b = b
        self._params = params
        self._mask = parse_mask(src, mask, n)
        self._avail = np.flatnonzero(self._mask)
        self._all_available = bool(self._mask.all())
        self._lo, self._hi = frozen(lo), frozen(hi)
        self._lo_a, self._hi_a = lo[self._avail], hi[self._avail]
        self._b_a = b[:, self._avail]
        self._range_T = range_basis_T(self._b_a)
        # as lists of rows for the per-cycle products (dense.mat_vec: no BLAS)
        self._b_rows: list[list[float]] = b.tolist()
        self._range_T_rows: list[list[float]] = self._range_T.tolist()
        self._attained_tol = attained_tolerance(self._b_a, self._lo_a, self._hi_a)

    # --- introspection -----------------------------------------------------------------

    @property
    def params(self) -> Any:
        """The parameters this allocator was built with."""
        return self._params

    @property
    def mask(self) -> np.ndarray:
        """The availability mask (read-only; True = usable)."""
        return self._mask

    @property
    def effectiveness(self) -> np.ndarray:
        """The full m×n effectiveness matrix (read-only, masked columns included)."""
        return self._b

    @property
    def bounds_N(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-thruster (lower, upper) thrust bounds [N] (read-only; masked ones still listed)."""
        return self._lo, self._hi

    # --- reconfiguration ---------------------------------------------------------------

    def _rebuild_args(self) -> tuple[Any, ...]:
        """Constructor arguments after ``(effectiveness, params, mask)`` (none by default)."""
        return ()

    def with_mask(self: A, mask: Sequence[bool] | np.ndarray) -> A:
        """A new allocator of the same kind for the same thrusters with availability ``mask``."""
        return type(self)(self._b, self._params, mask, *self._rebuild_args())

    # --- start-up ----------------------------------------------------------------------

    # True when a solve leaves no state behind (no warm start): warm_up then runs on the
    # instance itself instead of a sibling.
    _stateless = False

    def warm_up(self) -> None:
        """Pay the first-call costs (numpy's and the solver's first calls, lazily built
        tables) before the first control cycle, on demands inside and beyond the thrusters'
        reach (:data:`WARM_UP_FRACTIONS`, :data:`WARM_UP_BEYOND_REACH`). A strategy that
        warm-starts is warmed through a sibling with the same mask, so this instance's state,
        and so every later result, is what it would have been without the warm-up."""
        target = self if self._stateless else self.with_mask(self._mask)
        for d in self._warm_up_demands():
            target.allocate(d)

    def _warm_up_demands(self) -> list[np.ndarray]:
        lo, hi = self._lo_a, self._hi_a
        low, high = WARM_UP_FRACTIONS
        mix = np.where(np.arange(lo.size) % 2 == 0, low, high)
        reach = np.abs(self._b_a) @ np.maximum(np.abs(lo), np.abs(hi))
        beyond = WARM_UP_BEYOND_REACH * np.diag(reach)
        return [self._b_a @ (lo + mix * (hi - lo)), *beyond]

    # --- allocation --------------------------------------------------------------------

    def _solve(self, d: np.ndarray) -> tuple[np.ndarray, bool | None]:
        """Thrusts [N] of the available thrusters for the finite demand ``d`` (within their
        bounds), and the saturation flag if the strategy decides it (None: the base tests
        the residual left in ``range(B_a)``)."""
        raise NotImplementedError

    def allocate(self, demand: np.ndarray) -> AllocationResult:
        """Thrusts [N] for the torque/wrench ``demand`` (see the module docstring)."""
        m, n = self._b.shape
        d = check_demand(demand, m)
        if self._avail.size == 0 or not all(map(math.isfinite, d.tolist())):
            return trivial_result(d, n)
        t_a, saturated = self._solve(d)
        if self._all_available:
            thrust = t_a
        else:
            thrust = np.zeros(n)
            thrust[self._avail] = t_a
        achieved = mat_vec(self._b_rows, thrust.tolist())
        r = [d_i - a_i for d_i, a_i in zip(d.tolist(), achieved, strict=True)]
        if saturated is None:
            saturated = norm(mat_vec(self._range_T_rows, r)) > self._attained_tol
        return AllocationResult(frozen(thrust), frozen(np.array(achieved)), norm(r), saturated)
