"""The parameter validators: what each accepts, and errors naming dataclass, field and value."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc import validation as check
from dbc.errors import ConfigError

SOURCE = "SomeParams"


@pytest.mark.parametrize("bad", [True, "1.0", None, math.nan, math.inf, -math.inf, [1.0]])
def test_number_refuses_non_finite_and_non_numbers(bad: object) -> None:
    """Bools, strings, None, NaN, ±inf and lists are not finite numbers."""
    with pytest.raises(ConfigError) as info:
        check.number(SOURCE, "gain", bad)
    assert (info.value.source, info.value.key) == (SOURCE, "gain")
    assert info.value.value is bad or (isinstance(bad, float) and math.isnan(bad))


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


def test_positive_and_non_negative_boundaries() -> None:
    """0 is non-negative but not positive; the unit appears in the message."""
    assert check.non_negative(SOURCE, "t_s", 0.0) == 0.0
    with pytest.raises(ConfigError, match=r"> 0 \[s\]"):
        check.positive(SOURCE, "t_s", 0.0, unit="s")


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


def test_matrix_shape_and_finiteness() -> None:
    """A matrix is rectangular, of the shape asked, with finite entries."""
    m = check.matrix(SOURCE, "h", ((1.0, 2.0), (3.0, 4.0)), 2, 2)
    assert m.shape == (2, 2) and m.dtype == float
    for bad in (((1.0, 2.0), (3.0,)), ((1.0, math.inf),), (1.0, 2.0), "x"):
        with pytest.raises(ConfigError):
            check.matrix(SOURCE, "h", bad)
    with pytest.raises(ConfigError):
        check.matrix(SOURCE, "h", ((1.0, 2.0),), 2, 2)


def test_inertia_symmetrised_and_positive_definite() -> None:
    """Principal moments become a diagonal; asymmetric or indefinite matrices are refused."""
    np.testing.assert_array_equal(check.inertia(SOURCE, "j", (1.0, 2.0, 3.0)),
                                  np.diag([1.0, 2.0, 3.0]))
    j = np.array([[2.0, 0.1, 0.0], [0.1, 3.0, 0.0], [0.0, 0.0, 4.0]])
    np.testing.assert_array_equal(check.inertia(SOURCE, "j", j), j)
    for bad in (np.diag([1.0, -1.0, 1.0]), j + np.triu(np.ones((3, 3)), 1)):
        with pytest.raises(ConfigError) as info:
            check.inertia(SOURCE, "j", bad)
        assert info.value.key == "j"
