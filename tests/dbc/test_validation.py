"""The parameter validators: what each accepts, and errors naming dataclass, field and value."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from dbc import validation as check
from dbc.errors import ConfigError

SOURCE = "SomeParams"
KEY = "gain"
LO, HI = 0.0, 1.0  # a closed unit interval
INSIDE = 0.5
ABOVE = 2.0  # beyond HI
NEAR_ONE = 1.0 + 0.1 * check.UNIT_NORM_TOL  # a norm within the unit-vector tolerance
OFF_ONE = 1.0 + 10.0 * check.UNIT_NORM_TOL  # a norm beyond it
# An inertia [kg m²]: symmetric, positive definite, with products of inertia.
J_GOOD = ((2.0, 0.1, 0.0), (0.1, 3.0, 0.0), (0.0, 0.0, 4.0))
J_ASYMMETRIC = ((2.0, 0.1, 0.0), (0.0, 3.0, 0.0), (0.0, 0.0, 4.0))
J_INDEFINITE = ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0))
J_FLAT_PLATE = (1.0, 1.0, 2.0)  # principal moments on the triangle inequality: a body
J_NO_BODY = (1.0, 1.0, 3.0)  # beyond it: positive definite, but no body has it


def _same(a: object, b: object) -> bool:
    """Equal, or the same NaN (an error keeps the value as given)."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return a is b
    return a == b


def _refused(call: Callable[[object], object], value: object) -> ConfigError:
    """The ConfigError ``call(value)`` raises, checked to name SOURCE, KEY and the value."""
    with pytest.raises(ConfigError) as info:
        call(value)
    err = info.value
    assert (err.source, err.key) == (SOURCE, KEY)
    assert _same(err.value, value)
    assert str(err).startswith(f"{SOURCE}: {KEY} = ")
    return err


@pytest.mark.parametrize("bad", [True, False, "1.0", None, math.nan, math.inf, -math.inf,
                                 [1.0], np.bool_(True)])
def test_number_refuses_non_finite_and_non_numbers(bad: object) -> None:
    """Bools, strings, None, NaN, ±inf and lists are not finite numbers."""
    err = _refused(lambda v: check.number(SOURCE, KEY, v), bad)
    assert err.expected == "a finite number"


@pytest.mark.parametrize("good", [0, INSIDE, np.float64(INSIDE), np.int64(1), np.float32(HI)])
def test_number_takes_ints_floats_and_numpy_scalars(good: object) -> None:
    """Python and numpy reals are numbers, returned as a float of the same value."""
    x = check.number(SOURCE, KEY, good, LO, HI)
    assert type(x) is float and x == float(good)  # type: ignore[arg-type]


@pytest.mark.parametrize("bad", [LO - INSIDE, ABOVE, math.nan, math.inf])
def test_number_out_of_range_says_the_interval(bad: float) -> None:
    """A number outside [lo, hi] is refused, the message giving the interval and unit."""
    err = _refused(lambda v: check.number(SOURCE, KEY, v, LO, HI, unit="s"), bad)
    assert err.expected == "a finite number in [0, 1] [s]"


def test_number_bounds_open_and_closed() -> None:
    """Closed bounds accept the bound, open ones refuse it; the message says which."""
    assert check.number(SOURCE, "x", 0, 0.0, 1.0) == 0.0
    assert check.number(SOURCE, "x", 1, 0.0, 1.0) == 1.0
    with pytest.raises(ConfigError, match=r"in \(0, 1\]"):
        check.number(SOURCE, "x", 0.0, 0.0, 1.0, lo_open=True)
    with pytest.raises(ConfigError, match=r"in \[0, 1\)"):
        check.number(SOURCE, "x", 1.0, 0.0, 1.0, hi_open=True)


def test_limit_takes_inf_but_not_zero() -> None:
    """An output limit is > 0, with inf meaning none."""
    assert check.limit(SOURCE, "max_force_N", math.inf) == math.inf
    with pytest.raises(ConfigError, match="inf: no limit"):
        check.limit(SOURCE, "max_force_N", 0.0)
    with pytest.raises(ConfigError):
        check.limit(SOURCE, "max_force_N", math.nan)
    _refused(lambda v: check.limit(SOURCE, KEY, v), -math.inf)


def test_positive_and_non_negative_boundaries() -> None:
    """0 is non-negative but not positive; the unit appears in the message."""
    assert check.non_negative(SOURCE, "t_s", 0.0) == 0.0
    with pytest.raises(ConfigError, match=r"> 0 \[s\]"):
        check.positive(SOURCE, "t_s", 0.0, unit="s")
    assert _refused(lambda v: check.non_negative(SOURCE, KEY, v), math.inf).expected == (
        "a finite number >= 0")


def test_integer_and_flag() -> None:
    """Integers exclude bools and floats; flags are bools only."""
    assert check.integer(SOURCE, "n", 3, 1) == 3
    for bad in (True, 2.0, 0):
        with pytest.raises(ConfigError):
            check.integer(SOURCE, "n", bad, 1)
    assert check.flag(SOURCE, "on", False) is False
    with pytest.raises(ConfigError):
        check.flag(SOURCE, "on", 1)


def test_vector_length_and_elements() -> None:
    """A vector has the length asked and every element checked."""
    assert check.triple(SOURCE, "k", (1, 2, 3), 0.0, lo_open=True) == (1.0, 2.0, 3.0)
    for bad in ((1.0, 2.0), (1.0, 2.0, 0.0), (1.0, math.nan, 2.0), "abc", 3.0):
        with pytest.raises(ConfigError) as info:
            check.triple(SOURCE, "k", bad, 0.0, lo_open=True)
        assert info.value.key == "k"
    assert check.vector(SOURCE, "w", [1.0], None) == (1.0,)
    with pytest.raises(ConfigError):
        check.vector(SOURCE, "w", [], None)


@pytest.mark.parametrize("bad", [(INSIDE, INSIDE), (INSIDE,) * 4, (INSIDE, math.nan, INSIDE),
                                 (INSIDE, math.inf, INSIDE), (INSIDE, True, INSIDE),
                                 (INSIDE, ABOVE, INSIDE), "abc", None])
def test_vector_refuses_length_non_finite_bool_and_range(bad: object) -> None:
    """Wrong length, NaN, inf, a bool or an element out of [lo, hi]: refused, naming all."""
    err = _refused(lambda v: check.vector(SOURCE, KEY, v, check.N_AXES, LO, HI), bad)
    assert err.expected == "3 finite numbers in [0, 1]"


def test_unit_vector_within_tolerance_only() -> None:
    """A norm within the tolerance is a unit vector (kept as given); beyond it is refused."""
    assert check.unit_triple(SOURCE, KEY, (0.0, 0.0, NEAR_ONE)) == (0.0, 0.0, NEAR_ONE)
    err = _refused(lambda v: check.unit_triple(SOURCE, KEY, v), (0.0, OFF_ONE, 0.0))
    assert err.expected.startswith("a unit vector (|norm - 1| <= 1e-06")
    _refused(lambda v: check.unit_vector(SOURCE, KEY, v, check.N_AXES + 1), (1.0, 0.0, 0.0))
    _refused(lambda v: check.unit_triple(SOURCE, KEY, v), (1.0, math.nan, 0.0))


def test_matrix_shape_and_finiteness() -> None:
    """A matrix is rectangular, of the shape asked, with finite entries."""
    m = check.matrix(SOURCE, "h", ((1.0, 2.0), (3.0, 4.0)), 2, 2)
    assert m.shape == (2, 2) and m.dtype == float
    for bad in (((1.0, 2.0), (3.0,)), ((1.0, math.inf),), (1.0, 2.0), "x"):
        with pytest.raises(ConfigError):
            check.matrix(SOURCE, "h", bad)
    with pytest.raises(ConfigError):
        check.matrix(SOURCE, "h", ((1.0, 2.0),), 2, 2)


@pytest.mark.parametrize("bad", [((1.0, True), (0.0, 1.0)), ((1.0, "2"), (0.0, 1.0)),
                                 ((1.0, math.nan), (0.0, 1.0)), np.eye(2, dtype=bool)])
def test_matrix_entries_are_numbers_not_bools_or_strings(bad: object) -> None:
    """A bool, a numeric string or NaN is no matrix entry (as for a single number)."""
    err = _refused(lambda v: check.matrix(SOURCE, KEY, v, 2, 2), bad)
    assert err.expected == "a 2x2 matrix of finite numbers"


def test_inertia_symmetrised_and_positive_definite() -> None:
    """Principal moments become a diagonal; asymmetric or indefinite matrices are refused."""
    np.testing.assert_array_equal(check.inertia(SOURCE, "j", (1.0, 2.0, 3.0)),
                                  np.diag([1.0, 2.0, 3.0]))
    j = np.array(J_GOOD)
    np.testing.assert_array_equal(check.inertia(SOURCE, "j", j), j)
    for bad in (np.diag([1.0, -1.0, 1.0]), j + np.triu(np.ones((3, 3)), 1)):
        with pytest.raises(ConfigError) as info:
            check.inertia(SOURCE, "j", bad)
        assert info.value.key == "j"


@pytest.mark.parametrize(
    ("bad", "says"),
    [
        (J_ASYMMETRIC, "a symmetric matrix"),
        (J_INDEFINITE, "a positive-definite matrix"),
        (((0.0,) * 3,) * 3, "a positive-definite matrix"),
        (J_GOOD[:2], "3x3"),
        ((1.0, math.nan, 1.0), "3x3"),
        ((1.0, True, 1.0), "3x3"),
    ],
)
def test_inertia_says_which_property_failed(bad: object, says: str) -> None:
    """Asymmetric, not positive definite, wrong shape or not finite: the message says which."""
    assert says in _refused(lambda v: check.inertia(SOURCE, KEY, v), bad).expected


def test_inertia_physical_asks_the_triangle_inequality() -> None:
    """``physical``: moments beyond the triangle inequality are refused, on it accepted."""
    assert check.inertia(SOURCE, KEY, J_NO_BODY).shape == (check.N_AXES, check.N_AXES)
    np.testing.assert_array_equal(check.inertia(SOURCE, KEY, J_FLAT_PLATE, physical=True),
                                  np.diag(J_FLAT_PLATE))
    err = _refused(lambda v: check.inertia(SOURCE, KEY, v, physical=True), J_NO_BODY)
    assert "triangle inequality" in err.expected
