"""Rate-integrating gyro triad: bias, bias random walk, angle random walk, LSB, saturation.

What it does
    ``Gyro.sample(t_ns, omega_BN_B_rad_s)`` turns the true body rate into one measured
    rate triad, as the IMU reports it in ``IMU_RATE``. Deterministic: every random number
    comes from the ``numpy.random.Generator`` handed to the constructor (one vectorised
    draw of 6 normals per sample), so the same seed gives the same samples.

Inputs / outputs and units
    Input: true ω_BN_B [rad/s] in body axes (the gyro axes are the body axes), time
    ``t_ns`` [integer ns of simulation time]. Output: measured ω [rad/s], body axes.

Model (IEEE Std 952-1997, Annex C; Farrell, "Aided Navigation", 2008, §4.9) per axis
        b_k   = b_{k−1} + K √Δt · n₁          bias (rate) random walk, K [rad/s/√s]
        ω̃_k  = ω_k + b_k + (N / √Δt) · n₂     angle random walk N [rad/√s] seen as white
                                              noise on the rate averaged over Δt
        out   = clamp(LSB · round(ω̃ / LSB), ±limit)
    with n₁, n₂ ~ N(0, 1) independent, Δt the time since the previous sample (the
    nominal ``period_s`` for the first sample, whose bias is the initial bias exactly).
    ``range_rad_s`` is the saturation; ``lsb_rad_s`` = 0 disables quantisation. The output
    limit is the largest multiple of the LSB within the range, so every output is an
    integer number of LSBs and never exceeds the range. Rounding is half-to-even.

Assumptions
    Axes perfectly aligned with B, no scale-factor error or g-sensitivity, noise
    independent between axes, samples in strictly increasing time.

The helper ``three_axis_sample`` implements the model for any 3-axis inertial sensor
and is shared with :mod:`bench.sensors.accelerometer`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bench.dynamics.rigid_body import Vec3
from dbc.errors import ConfigError

S_PER_NS = 1e-9
DEFAULT_PERIOD_S = 0.005
"""Nominal sample period (200 Hz IMU) used when none is given."""
NORMALS_PER_SAMPLE = 6
"""Three bias-walk and three white-noise normals per sample."""
AXES = 3


def output_limit(lsb: float, range_limit: float) -> float:
    """Largest representable magnitude: the range, rounded down to a whole number of LSBs."""
    if lsb > 0.0 and math.isfinite(range_limit):
        return math.floor(range_limit / lsb) * lsb
    return range_limit


def three_axis_sample(
    rng: np.random.Generator,
    truth: Vec3,
    bias: Vec3,
    dt_s: float,
    walk: bool,
    white_density: float,
    walk_density: float,
    lsb: float,
    limit: float,
) -> tuple[Vec3, Vec3]:
    """One sample of the module's model: returns (measured triad, bias after the walk).

    ``white_density`` is ARW/VRW (σ = density/√Δt), ``walk_density`` the bias random walk
    (σ = density·√Δt, applied only if ``walk``); ``limit`` from ``output_limit``.
    """
    n = rng.standard_normal(NORMALS_PER_SAMPLE).tolist()
    bx, by, bz = bias
    if walk:
        sw = walk_density * math.sqrt(dt_s)
        bx += sw * n[0]
        by += sw * n[1]
        bz += sw * n[2]
    sn = white_density / math.sqrt(dt_s)
    out = [truth[0] + bx + sn * n[3], truth[1] + by + sn * n[4], truth[2] + bz + sn * n[5]]
    for i in range(AXES):
        x = out[i]
        if lsb > 0.0:
            x = round(x / lsb) * lsb
        if x > limit:
            x = limit
        elif x < -limit:
            x = -limit
        out[i] = x
    return (out[0], out[1], out[2]), (bx, by, bz)


def check_vec3(value: object, source: str, key: str) -> Vec3:
    """``value`` as a finite 3-tuple of floats, or ConfigError naming ``key``."""
    expected = "3 finite numbers"
    try:
        seq = tuple(float(x) for x in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise ConfigError(source, key, value, expected) from None
    if len(seq) != AXES or not all(math.isfinite(x) for x in seq):
        raise ConfigError(source, key, value, expected)
    return (seq[0], seq[1], seq[2])


def check_number(
    value: object, source: str, key: str, *, positive: bool, allow_inf: bool = False
) -> float:
    """``value`` as a float ≥ 0 (> 0 if ``positive``; +inf only if ``allow_inf``)."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    if ok:
        x = float(value)  # type: ignore[arg-type]
        ok = (math.isfinite(x) or (allow_inf and x == math.inf)) and (
            x > 0.0 if positive else x >= 0.0
        )
    if not ok:
        expected = "a number > 0" if positive else "a number >= 0"
        raise ConfigError(source, key, value, expected + ("" if allow_inf else " (finite)"))
    return float(value)  # type: ignore[arg-type]


@dataclass(frozen=True)
class GyroParams:
    """Gyro error model; defaults are an ideal, unsaturated gyro sampled at 200 Hz.

    bias_rad_s            initial bias per axis [rad/s]
    bias_rw_rad_s_sqrt_s  bias (rate) random walk K [rad/s/√s], ≥ 0
    arw_rad_sqrt_s        angle random walk N [rad/√s], ≥ 0
    lsb_rad_s             quantisation step [rad/s], ≥ 0 (0: none)
    range_rad_s           saturation magnitude [rad/s], > 0 (may be inf), ≥ lsb
    period_s              nominal sample period [s], > 0 (Δt of the first sample)
    """

    bias_rad_s: Vec3 = (0.0, 0.0, 0.0)
    bias_rw_rad_s_sqrt_s: float = 0.0
    arw_rad_sqrt_s: float = 0.0
    lsb_rad_s: float = 0.0
    range_rad_s: float = math.inf
    period_s: float = DEFAULT_PERIOD_S
    source: str = field(default="GyroParams", compare=False, repr=False, kw_only=True)
    output_limit_rad_s: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        src = self.source
        put = object.__setattr__
        put(self, "bias_rad_s", check_vec3(self.bias_rad_s, src, "bias_rad_s"))
        for key in ("bias_rw_rad_s_sqrt_s", "arw_rad_sqrt_s", "lsb_rad_s"):
            put(self, key, check_number(getattr(self, key), src, key, positive=False))
        put(self, "period_s", check_number(self.period_s, src, "period_s", positive=True))
        rng_ = check_number(self.range_rad_s, src, "range_rad_s", positive=True, allow_inf=True)
        if rng_ < self.lsb_rad_s:
            raise ConfigError(src, "range_rad_s", self.range_rad_s, "a range >= lsb_rad_s")
        put(self, "range_rad_s", rng_)
        put(self, "output_limit_rad_s", output_limit(self.lsb_rad_s, rng_))


class Gyro:
    """A gyro triad drawing its noise from ``rng`` (see the module docstring)."""

    __slots__ = ("_bias", "_rng", "_t_prev_ns", "params")

    def __init__(self, params: GyroParams, rng: np.random.Generator) -> None:
        self.params = params
        self._rng = rng
        self._bias: Vec3 = params.bias_rad_s
        self._t_prev_ns: int | None = None

    @property
    def bias_rad_s(self) -> Vec3:
        """The current (true) bias [rad/s], for telemetry."""
        return self._bias

    def sample(self, t_ns: int, omega_BN_B_rad_s: Vec3) -> Vec3:
        """Measured body rate [rad/s] at ``t_ns`` for the true rate ``omega_BN_B_rad_s``."""
        p = self.params
        prev = self._t_prev_ns
        if prev is None:
            dt_s, walk = p.period_s, False
        elif t_ns > prev:
            dt_s, walk = (t_ns - prev) * S_PER_NS, True
        else:
            raise ValueError(f"gyro samples must be in increasing time: {t_ns} after {prev}")
        out, self._bias = three_axis_sample(
            self._rng,
            omega_BN_B_rad_s,
            self._bias,
            dt_s,
            walk,
            p.arw_rad_sqrt_s,
            p.bias_rw_rad_s_sqrt_s,
            p.lsb_rad_s,
            p.output_limit_rad_s,
        )
        self._t_prev_ns = t_ns
        return out
