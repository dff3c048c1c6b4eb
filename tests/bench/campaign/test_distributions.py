"""Campaign distributions: ranges, truncation, determinism, and errors that name the key."""

from __future__ import annotations

import numpy as np
import pytest

from bench.campaign.distributions import Choice, Normal, Sweep, Uniform, parse_distribution
from dbc.errors import ConfigError

DRAWS = 2000


def _draws(d: object, seed: int = 1) -> list[float]:
    rng = np.random.default_rng(seed)
    return [d.draw(rng) for _ in range(DRAWS)]  # type: ignore[attr-defined]


def test_uniform_stays_in_its_interval_and_spreads_over_it() -> None:
    """Every draw in [low, high); the sample's extremes near the ends."""
    x = _draws(Uniform(2.0, 3.0))
    assert min(x) >= 2.0 and max(x) < 3.0
    assert min(x) < 2.01 and max(x) > 2.99


def test_truncated_normal_never_leaves_its_window() -> None:
    """clip_sigma = 1: no draw beyond one sigma, and the draws are not all the mean."""
    x = np.array(_draws(Normal(5.0, 2.0, clip_sigma=1.0)))
    assert np.all(np.abs(x - 5.0) <= 2.0)
    assert x.std() > 0.5


def test_same_generator_seed_gives_the_same_draws() -> None:
    """Determinism: the draws are a function of the generator alone."""
    assert _draws(Normal(0.0, 1.0), 7) == _draws(Normal(0.0, 1.0), 7)
    assert _draws(Normal(0.0, 1.0), 7) != _draws(Normal(0.0, 1.0), 8)


def test_choice_weights_and_levels() -> None:
    """A zero weight is never drawn; a sweep's and a choice's levels are their values."""
    c = Choice(("a", "b"), (0.0, 1.0))
    assert set(_draws(c)) == {"b"}
    assert Sweep((1, 2, 3)).levels() == (1, 2, 3) and Uniform(0, 1).levels() == ()


@pytest.mark.parametrize("table, key, says", [
    ({"dist": "gauss"}, "d.dist", "one of uniform, normal"),
    ({"dist": "uniform", "low": 1.0, "high": 1.0}, "d.high", "above low = 1"),
    ({"dist": "normal", "mean": 0.0, "sigma": -1.0}, "d.sigma", ">= 0"),
    ({"dist": "sweep", "values": []}, "d.values", "a list of 1 to"),
    ({"dist": "sweep", "values": [1], "weights": [1.0]}, "d.weights",
     "absent: a sweep distribution takes values"),
    ({"dist": "choice", "values": [1, 2], "weights": [0.0, 0.0]}, "d.weights", "positive sum"),
])
def test_bad_parameters_name_the_key(table: dict[str, object], key: str, says: str) -> None:
    """Each bad parameter: a ConfigError naming the file, the key and what was expected."""
    with pytest.raises(ConfigError) as e:
        parse_distribution("c.toml", "d", table)
    assert e.value.key == key and says in str(e.value) and "c.toml" in str(e.value)
