"""The distributions a campaign draws a dispersed value from: pure, seeded by the caller.

- ``uniform``: ``low``, ``high``; every value in [low, high) equally likely.
- ``normal``: ``mean``, ``sigma``, truncated at ``mean ± clip_sigma·sigma`` (default
  :data:`DEFAULT_CLIP_SIGMA`) by redrawing, so a tail value that would build an impossible
  vehicle is never drawn and the draw stays a function of the generator alone.
- ``choice``: ``values``, one drawn with equal probability (or ``weights``).
- ``sweep``: ``values``, each used in turn by a full-factorial study (a Monte Carlo draws
  from them as a ``choice``).

Each has ``draw(rng)`` (one value from a ``numpy.random.Generator``) and ``levels()`` (the
values a full-factorial study takes: a sweep's or a choice's values; a continuous
distribution has none and is refused there). Parameters are checked on construction; an
error names the campaign file and key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from dbc import validation as check
from dbc.errors import ConfigError

DEFAULT_CLIP_SIGMA = 3.0
"""A truncated normal keeps draws within this many standard deviations of its mean."""
MAX_REDRAWS = 10_000
"""Redraws of a truncated normal before giving up (at clip_sigma ≥ 0.5, the chance of
needing this many is below 1e-1000)."""
MIN_CLIP_SIGMA = 0.5
MAX_LEVELS = 1000
"""Values of one sweep or choice (a factorial over a few of them is already thousands)."""

Value = float | int | str | bool


class Distribution(Protocol):
    """One dispersed quantity's distribution."""

    def draw(self, rng: np.random.Generator) -> Value:
        """One value."""

    def levels(self) -> tuple[Value, ...]:
        """The values of a full-factorial study (empty: continuous)."""


@dataclass(frozen=True)
class Uniform:
    low: float
    high: float

    def draw(self, rng: np.random.Generator) -> Value:
        return float(rng.uniform(self.low, self.high))

    def levels(self) -> tuple[Value, ...]:
        return ()


@dataclass(frozen=True)
class Normal:
    mean: float
    sigma: float
    clip_sigma: float = DEFAULT_CLIP_SIGMA

    def draw(self, rng: np.random.Generator) -> Value:
        if self.sigma == 0.0:
            return self.mean
        for _ in range(MAX_REDRAWS):
            x = float(rng.normal(self.mean, self.sigma))
            if abs(x - self.mean) <= self.clip_sigma * self.sigma:
                return x
        raise RuntimeError("truncated normal: no draw inside the window")  # pragma: no cover

    def levels(self) -> tuple[Value, ...]:
        return ()


@dataclass(frozen=True)
class Choice:
    values: tuple[Value, ...]
    weights: tuple[float, ...] | None = None

    def draw(self, rng: np.random.Generator) -> Value:
        p = None if self.weights is None else np.asarray(self.weights) / sum(self.weights)
        return self.values[int(rng.choice(len(self.values), p=p))]

    def levels(self) -> tuple[Value, ...]:
        return self.values


@dataclass(frozen=True)
class Sweep(Choice):
    pass


KINDS = ("uniform", "normal", "choice", "sweep")
PARAMETERS = {"uniform": {"low", "high"}, "normal": {"mean", "sigma", "clip_sigma"},
              "choice": {"values", "weights"}, "sweep": {"values"}}


def parse_distribution(source: str, key: str, t: dict[str, Any]) -> Distribution:
    """The distribution a dispersion table describes (``dist`` and its parameters); every
    other key of ``t`` is the caller's. Errors name ``source`` and ``key``."""
    kind = t.get("dist")
    if kind not in KINDS:
        raise ConfigError(source, f"{key}.dist", kind, "one of " + ", ".join(KINDS))
    for k in sorted(set(t) & DIST_KEYS - {"dist"} - PARAMETERS[kind]):
        raise ConfigError(source, f"{key}.{k}", t[k], f"absent: a {kind} distribution takes "
                          + ", ".join(sorted(PARAMETERS[kind])))
    if kind == "uniform":
        lo = check.number(source, f"{key}.low", t.get("low"))
        hi = check.number(source, f"{key}.high", t.get("high"))
        if not hi > lo:
            raise ConfigError(source, f"{key}.high", hi, f"a number above low = {lo:g}")
        return Uniform(lo, hi)
    if kind == "normal":
        mean = check.number(source, f"{key}.mean", t.get("mean"))
        sigma = check.number(source, f"{key}.sigma", t.get("sigma"), 0.0)
        clip = check.number(source, f"{key}.clip_sigma", t.get("clip_sigma", DEFAULT_CLIP_SIGMA),
                            MIN_CLIP_SIGMA)
        return Normal(mean, sigma, clip)
    values = t.get("values")
    if not isinstance(values, list) or not 1 <= len(values) <= MAX_LEVELS:
        raise ConfigError(source, f"{key}.values", values,
                          f"a list of 1 to {MAX_LEVELS} values")
    for i, v in enumerate(values):
        if isinstance(v, float) and not math.isfinite(v):
            raise ConfigError(source, f"{key}.values[{i}]", v, "a finite number")
        if not isinstance(v, int | float | str | bool):
            raise ConfigError(source, f"{key}.values[{i}]", v, "a number, string or boolean")
    weights = None
    if "weights" in t:
        weights = check.vector(source, f"{key}.weights", t["weights"], len(values), 0.0)
        if sum(weights) <= 0.0:
            raise ConfigError(source, f"{key}.weights", list(weights), "a positive sum")
    cls = Choice if kind == "choice" else Sweep
    return cls(tuple(values), weights)


DIST_KEYS = frozenset({"dist", "low", "high", "mean", "sigma", "clip_sigma", "values", "weights"})
"""Keys of a dispersion table that belong to its distribution."""
