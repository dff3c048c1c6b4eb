"""Validators of the project's frozen parameter dataclasses ("finite real number" etc.).

What it does: one small set of checks, in the contract package so that both sides (the
flight software and the bench, which never import each other) use the same ones: every
parameter dataclass of the flight software and of the bench's station calls them from
its ``__post_init__`` (and the strategies, models and fault setters from their
constructors and methods), and :class:`dbc.schema.Table` calls them for the values of a
TOML or JSON table. A bad value is refused the same way everywhere: with
:class:`dbc.errors.ConfigError` ``(source, key, value, expected)``, where ``source`` names
the dataclass (e.g. ``"PwpfParams"``) or the file, ``key`` the field or the dotted key,
``value`` the value given and ``expected`` what would have been accepted, in words
(``"a finite number > 0 [s]"``). The loaders (:mod:`flight_sw.config`,
:mod:`bench.scenario.parse`) re-anchor a dataclass's error in the scenario file and its
dotted key.

Inputs: the value as given (any object). Outputs: the value converted to the type the
dataclass stores (``float``, ``int``, ``bool``, a tuple of floats, a float64 array).
Units: those of the field (its name carries them); the checks convert none, and a
``unit`` argument only puts it in the message (``[s]``). Inertia in kg m².

Rules (the same for every field):
- a "number" is a real number that is not a bool (``True`` is not 1 here); it must be
  finite unless the check says that ``inf`` means "no limit";
- an interval bound is open or closed as the check says, and the message shows it:
  ``(0, 1]``, ``> 0``, ``>= 0``;
- a vector has exactly the length asked, each element checked as a number; a unit vector
  has norm 1 within :data:`UNIT_NORM_TOL` (it is not renormalised);
- a matrix is rectangular with the shape asked, every entry a finite number; an inertia
  is also symmetric and positive definite (and, with ``physical``, its principal moments
  obey the triangle inequality).

Assumptions: none beyond the above; no state. Source: project convention (issue 18, one
meaning per quantity: one validator for "finite real number").
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable

import numpy as np

from dbc.errors import ConfigError

N_AXES = 3
# Relative asymmetry tolerated in an inertia matrix (|J − Jᵀ| ≤ this × max |J|).
INERTIA_SYMMETRY_RTOL = 1e-9
# Relative slack on the principal-moment triangle inequality λ_i ≤ λ_j + λ_k of a physical
# body (a thin plate lies on it).
INERTIA_TRIANGLE_RTOL = 1e-9
# |‖v‖ − 1| tolerated in a unit vector (catches unnormalised or garbled input).
UNIT_NORM_TOL = 1e-6


def is_real(value: object) -> bool:
    """True for a real number that is not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _bounds(lo: float, hi: float, lo_open: bool, hi_open: bool) -> str:
    """An interval in words, with its leading space: `` in (0, 1]``, `` > 0``, or ``""``."""
    has_lo, has_hi = lo > -math.inf, hi < math.inf
    if has_lo and has_hi:
        return f" in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
    if has_lo:
        return f" {'>' if lo_open else '>='} {lo:g}"
    if has_hi:
        return f" {'<' if hi_open else '<='} {hi:g}"
    return ""


def _inside(x: float, lo: float, hi: float, lo_open: bool, hi_open: bool) -> bool:
    """Whether ``x`` lies in the interval (each bound open or closed)."""
    return (lo < x if lo_open else lo <= x) and (x < hi if hi_open else x <= hi)


def _describe(lo: float, hi: float, lo_open: bool, hi_open: bool, allow_inf: bool,
              unit: str) -> str:
    """``expected`` of :func:`number` in words."""
    text = "a number" if allow_inf else "a finite number"
    text += _bounds(lo, hi, lo_open, hi_open)
    if unit:
        text += f" [{unit}]"
    if allow_inf:
        text += " (inf: no limit)"
    return text


def number(
    source: str,
    key: str,
    value: object,
    lo: float = -math.inf,
    hi: float = math.inf,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
    allow_inf: bool = False,
    unit: str = "",
) -> float:
    """``value`` as a float in the interval given (finite unless ``allow_inf``).

    Raises ConfigError(source, key, value, expected) otherwise.
    """
    ok = is_real(value)
    x = float(value) if ok else math.nan  # type: ignore[arg-type]
    ok = ok and (math.isfinite(x) or (allow_inf and x == math.inf))
    ok = ok and _inside(x, lo, hi, lo_open, hi_open)
    if not ok:
        raise ConfigError(source, key, value,
                          _describe(lo, hi, lo_open, hi_open, allow_inf, unit))
    return x


def positive(source: str, key: str, value: object, unit: str = "") -> float:
    """A finite number > 0."""
    return number(source, key, value, 0.0, lo_open=True, unit=unit)


def non_negative(source: str, key: str, value: object, unit: str = "") -> float:
    """A finite number >= 0."""
    return number(source, key, value, 0.0, unit=unit)


def limit(source: str, key: str, value: object, unit: str = "") -> float:
    """A number > 0, where ``inf`` means no limit (an output or rate limit)."""
    return number(source, key, value, 0.0, lo_open=True, allow_inf=True, unit=unit)


def integer(source: str, key: str, value: object, lo: int | None = None,
            hi: int | None = None) -> int:
    """An int (not a bool), at least ``lo`` and at most ``hi`` when given."""
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    n = int(value) if ok else 0  # type: ignore[call-overload]
    if not ok or (lo is not None and n < lo) or (hi is not None and n > hi):
        raise ConfigError(source, key, value, integer_range(lo, hi))
    return n


def integer_range(lo: int | None, hi: int | None) -> str:
    """``expected`` of :func:`integer` in words: ``an integer in [0, 10]``, ``>= 1``."""
    if lo is not None and hi is not None:
        return f"an integer in [{lo}, {hi}]"
    if lo is not None:
        return f"an integer >= {lo}"
    return "an integer" if hi is None else f"an integer <= {hi}"


def flag(source: str, key: str, value: object) -> bool:
    """A bool (``true`` or ``false``)."""
    if not isinstance(value, bool):
        raise ConfigError(source, key, value, "true or false")
    return value


def vector(
    source: str,
    key: str,
    value: object,
    size: int | None,
    lo: float = -math.inf,
    hi: float = math.inf,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
    unit: str = "",
) -> tuple[float, ...]:
    """``size`` finite numbers (any non-empty length when None), each in [lo, hi]."""
    count = "a non-empty list of" if size is None else str(size)
    bound = _bounds(lo, hi, lo_open, hi_open)
    expected = f"{count} finite numbers{bound}" + (f" [{unit}]" if unit else "")
    items = list(value) if isinstance(value, Iterable) and not isinstance(value, str) else []
    if not items or (size is not None and len(items) != size):
        raise ConfigError(source, key, value, expected)
    out: list[float] = []
    for v in items:
        ok = is_real(v) and math.isfinite(float(v))
        if not (ok and _inside(float(v), lo, hi, lo_open, hi_open)):
            raise ConfigError(source, key, value, expected)
        out.append(float(v))
    return tuple(out)


def triple(source: str, key: str, value: object, lo: float = -math.inf,
           hi: float = math.inf, *, lo_open: bool = False, hi_open: bool = False,
           unit: str = "") -> tuple[float, float, float]:
    """Three finite numbers (a per-axis gain or vector), each in [lo, hi]."""
    x = vector(source, key, value, N_AXES, lo, hi, lo_open=lo_open, hi_open=hi_open,
               unit=unit)
    return x[0], x[1], x[2]


def unit_vector(source: str, key: str, value: object, size: int = N_AXES,
                tol: float = UNIT_NORM_TOL) -> tuple[float, ...]:
    """``size`` finite numbers whose Euclidean norm is 1 within ``tol`` (not renormalised)."""
    x = vector(source, key, value, size)
    norm = math.sqrt(sum(c * c for c in x))
    if not abs(norm - 1.0) <= tol:
        raise ConfigError(source, key, value,
                          f"a unit vector (|norm - 1| <= {tol:g}; its norm is {norm:.6g})")
    return x


def unit_triple(source: str, key: str, value: object,
              tol: float = UNIT_NORM_TOL) -> tuple[float, float, float]:
    """A unit 3-vector (a direction in some axes), as :func:`unit_vector`."""
    x = unit_vector(source, key, value, N_AXES, tol)
    return x[0], x[1], x[2]


def _real_array(value: object) -> np.ndarray | None:
    """``value`` (nested sequences or an array) as float64, or None unless every entry is a
    real number that is not a bool (:func:`is_real`; a ragged nesting is refused too)."""
    try:
        entries = np.array(value, dtype=object)
    except (TypeError, ValueError):
        return None
    if not all(is_real(x) for x in entries.ravel()):
        return None
    return entries.astype(float)


def matrix(source: str, key: str, value: object, rows: int | None = None,
           cols: int | None = None) -> np.ndarray:
    """A rectangular matrix of finite numbers as a float64 array (any size when None)."""
    shape = f"{'m' if rows is None else rows}x{'n' if cols is None else cols}"
    expected = f"a {shape} matrix of finite numbers"
    arr = _real_array(value)
    if arr is None:
        raise ConfigError(source, key, value, expected)
    ok = arr.ndim == 2 and arr.size > 0 and bool(np.all(np.isfinite(arr)))
    ok = ok and (rows is None or arr.shape[0] == rows) and (cols is None or arr.shape[1] == cols)
    if not ok:
        raise ConfigError(source, key, value, expected)
    return arr


def inertia(source: str, key: str, value: object, *, physical: bool = False) -> np.ndarray:
    """A symmetric positive-definite 3×3 inertia [kg m²] (or its 3 principal moments).

    Returns the symmetrised 3×3 float64 array ``(J + Jᵀ)/2``; the asymmetry tolerated is
    :data:`INERTIA_SYMMETRY_RTOL` × the largest |entry|. With ``physical`` the principal
    moments must also obey the triangle inequality λ_max ≤ (λ_1 + λ_2)(1 +
    :data:`INERTIA_TRIANGLE_RTOL`), as those of any rigid body do. The message says which
    property failed.
    """
    arr = _real_array(value)
    if arr is not None and arr.shape == (N_AXES,):
        arr = np.diag(arr)
    if arr is None or arr.shape != (N_AXES, N_AXES) or not np.all(np.isfinite(arr)):
        raise ConfigError(source, key, value, "a symmetric positive-definite 3x3 matrix "
                          "(or 3 moments) of finite numbers")
    scale = float(np.max(np.abs(arr)))
    if not np.allclose(arr, arr.T, rtol=0.0, atol=INERTIA_SYMMETRY_RTOL * scale):
        raise ConfigError(source, key, value, "a symmetric matrix (|J_ij - J_ji| <= "
                          f"{INERTIA_SYMMETRY_RTOL:g} max|J|)")
    sym = 0.5 * (arr + arr.T)
    moments = np.linalg.eigvalsh(sym)  # ascending
    if not float(moments[0]) > 0.0:
        raise ConfigError(source, key, value,
                          "a positive-definite matrix (every principal moment > 0)")
    if physical and not _obeys_triangle(moments):
        raise ConfigError(source, key, value, "principal moments obeying the triangle "
                          "inequality (a physical body)")
    return sym


def _obeys_triangle(moments: np.ndarray) -> bool:
    """Ascending principal moments with λ_max ≤ (λ_1 + λ_2)(1 + INERTIA_TRIANGLE_RTOL)."""
    return float(moments[2]) <= (float(moments[0]) + float(moments[1])) * (
        1.0 + INERTIA_TRIANGLE_RTOL)


def physical_inertia(sym: np.ndarray) -> bool:
    """Whether the symmetric 3×3 ``sym`` [kg m²] is some body's inertia: positive definite,
    its principal moments obeying the triangle inequality (as :func:`inertia` with
    ``physical`` checks a configured one). For a computed estimate: no exception."""
    moments = np.linalg.eigvalsh(sym)  # ascending
    return bool(float(moments[0]) > 0.0) and _obeys_triangle(moments)


def instance(source: str, key: str, value: object, cls: type) -> None:
    """``value`` is an instance of ``cls``."""
    if not isinstance(value, cls):
        raise ConfigError(source, key, value, cls.__name__)
