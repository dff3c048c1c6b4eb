"""Accelerometer triad: bias, bias random walk, velocity random walk, LSB, saturation.

What it does
    ``Accelerometer.sample(t_ns, specific_force_B_m_s2)`` turns the true specific force
    (non-gravitational acceleration of the IMU, body axes) into one measured triad, as
    the IMU reports it in ``IMU_ACCEL``. Deterministic: all random numbers come from the
    ``numpy.random.Generator`` given to the constructor (6 normals per sample).

Inputs / outputs and units
    Input: specific force f_B [m/s²] in body axes, time ``t_ns`` [integer ns]. Output:
    measured f_B [m/s²].

Model: the gyro model of :mod:`bench.station.sensors.gyro` with accelerometer quantities
(IEEE Std 1293-1998, Annex; Farrell, "Aided Navigation", 2008, §4.9) per axis
        b_k   = b_{k−1} + K √Δt · n₁           bias random walk K [m/s²/√s]
        f̃_k  = f_k + b_k + (V / √Δt) · n₂      velocity random walk V [m/s/√s]
        out   = clamp(LSB · round(f̃ / LSB), ±limit)
    Δt is the time since the previous sample (``period_s`` for the first one, whose bias
    is the initial bias exactly).

Faults (``set_fault(kind, t_ns, **params)`` / ``clear_fault(kind, t_ns)``)
    Those of :mod:`bench.station.sensors.gyro` (shared ``InertialSensor``), with accelerometer
    units: ``"bias_jump"`` with ``jump_m_s2`` (3 numbers [m/s²], body axes, added to
    the bias), ``"frozen"`` (output repeats the last sample, still valid),
    ``"outage"`` (``sample`` raises ``SensorOutageError``, ``measure`` returns
    ``valid = False``), ``"noise"`` with ``factor`` [-] ≥ 0 (multiplies the velocity
    random walk σ). ``faults_active`` lists the active ones.

Assumptions
    IMU at the centre of mass (no lever-arm ω×(ω×r) or ω̇×r terms), axes aligned with B,
    no scale-factor error, samples in strictly increasing time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from mypy_extensions import mypyc_attr

from bench.station.dynamics.rigid_body import Vec3
from bench.station.sensors.gyro import (
    DEFAULT_PERIOD_S,
    S_PER_NS,
    InertialSensor,
    output_limit,
    three_axis_sample,
)
from dbc import validation as check
from dbc.errors import ConfigError


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class AccelerometerParams:
    """Accelerometer error model; defaults are ideal and unsaturated at 200 Hz.

    bias_m_s2             initial bias per axis [m/s²]
    vrw_m_s_sqrt_s        velocity random walk V [m/s/√s], ≥ 0
    bias_rw_m_s2_sqrt_s   bias random walk K [m/s²/√s], ≥ 0
    lsb_m_s2              quantisation step [m/s²], ≥ 0 (0: none)
    range_m_s2            saturation magnitude [m/s²], > 0 (may be inf), ≥ lsb
    period_s              nominal sample period [s], > 0
    """

    bias_m_s2: Vec3 = (0.0, 0.0, 0.0)
    vrw_m_s_sqrt_s: float = 0.0
    bias_rw_m_s2_sqrt_s: float = 0.0
    lsb_m_s2: float = 0.0
    range_m_s2: float = math.inf
    period_s: float = DEFAULT_PERIOD_S
    source: str = field(default="AccelerometerParams", compare=False, repr=False, kw_only=True)
    output_limit_m_s2: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        src = self.source
        put = object.__setattr__
        given = getattr(self, "bias_m_s2")  # noqa: B009 - uncast (see setup.py)
        put(self, "bias_m_s2", check.triple(src, "bias_m_s2", given))
        for key in ("vrw_m_s_sqrt_s", "bias_rw_m_s2_sqrt_s", "lsb_m_s2"):
            put(self, key, check.non_negative(src, key, getattr(self, key)))
        put(self, "period_s", check.positive(src, "period_s", self.period_s))
        rng_ = check.limit(src, "range_m_s2", self.range_m_s2)
        if rng_ < self.lsb_m_s2:
            raise ConfigError(src, "range_m_s2", self.range_m_s2, "a range >= lsb_m_s2")
        put(self, "range_m_s2", rng_)
        put(self, "output_limit_m_s2", output_limit(self.lsb_m_s2, rng_))


class Accelerometer(InertialSensor):
    """An accelerometer triad drawing its noise from ``rng`` (see the module docstring)."""

    __slots__ = ()
    _NAME = "accelerometer"
    _JUMP_KEY = "jump_m_s2"

    def __init__(self, params: AccelerometerParams, rng: np.random.Generator) -> None:
        self.params = params
        self._init_model(
            rng,
            params.bias_m_s2,
            params.vrw_m_s_sqrt_s,
            params.bias_rw_m_s2_sqrt_s,
            params.lsb_m_s2,
            params.output_limit_m_s2,
            params.period_s,
        )

    @property
    def bias_m_s2(self) -> Vec3:
        """The current (true) bias [m/s²], for telemetry (a ``bias_jump`` included)."""
        return self._bias

    def sample(self, t_ns: int, specific_force_B_m_s2: Vec3) -> Vec3:
        """Measured specific force [m/s²] at ``t_ns`` for the true ``specific_force_B_m_s2``.

        Raises ``SensorOutageError`` during an ``outage`` fault (``measure`` returns a flag).
        """
        prev = self._t_prev_ns
        if prev is None:
            dt_s, walk = self._period_s, False
        elif t_ns > prev:
            dt_s, walk = (t_ns - prev) * S_PER_NS, True
        else:
            raise ValueError(
                f"accelerometer samples must be in increasing time: {t_ns} after {prev}"
            )
        out, self._bias = three_axis_sample(
            self._rng,
            specific_force_B_m_s2,
            self._bias,
            dt_s,
            walk,
            self._white_density,
            self._walk_density,
            self._lsb,
            self._limit,
        )
        self._t_prev_ns = t_ns
        if self._faults:
            return self._faulty(t_ns, out)
        self._last_out = out
        return out
