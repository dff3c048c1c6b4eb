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

Faults (``set_fault(kind, t_ns, **params)`` / ``clear_fault(kind, t_ns)``; DESIGN.md §7)
    Each takes effect from the next sample (``t_ns``, the event time, must not precede
    the last sample); several may be active at once; setting an active kind again
    replaces its parameters; ``set_fault(None, t_ns)`` clears them all;
    ``faults_active`` lists them (kind → parameters). The random draws go on whatever
    is active, so the noise sequence after a fault is cleared does not depend on it.
    - ``"bias_jump"``, ``jump_rad_s`` (3 numbers [rad/s], body axes): added to the bias
      at the fault time (a step; the bias walk continues from there, ``bias_rad_s``
      includes it); clearing subtracts it again.
    - ``"frozen"`` (no parameter): every sample repeats the last output before the
      fault exactly (the first output if there was none), valid, as a stuck sensor
      whose frame counter still advances (the counter is the bench node's job).
    - ``"outage"`` (no parameter): samples are invalid. ``sample`` raises
      ``SensorOutageError`` (carrying the last valid output), ``measure`` returns it with
      ``valid = False``; the bench sends ``Valid = 0`` or skips the frame.
    - ``"noise"``, ``factor`` [-] ≥ 0: the white-noise σ (angle random walk) is
      multiplied by ``factor`` (bias walk, quantisation and saturation unchanged).
    Precedence: outage, then frozen, then the live output. An inactive fault costs one
    truth test per sample.

The helper ``three_axis_sample`` implements the model for any 3-axis inertial sensor
and is shared with :mod:`bench.station.sensors.accelerometer`, as is the fault machinery
(``InertialSensor``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from mypy_extensions import mypyc_attr

from bench.station.dynamics.rigid_body import Vec3
from dbc import validation as check
from dbc.errors import ConfigError, ThrusterHilError
from dbc.faults import BIAS_JUMP, FROZEN, NOISE, OUTAGE

S_PER_NS = 1e-9
DEFAULT_PERIOD_S = 0.005
"""Nominal sample period (200 Hz IMU) used when none is given."""
NORMALS_PER_SAMPLE = 6
"""Three bias-walk and three white-noise normals per sample."""
AXES = 3
ZERO_VEC3: Vec3 = (0.0, 0.0, 0.0)
"""The output reported by an outage before any valid sample."""
FAULT_BIAS_JUMP = BIAS_JUMP
FAULT_FROZEN = FROZEN
FAULT_OUTAGE = OUTAGE
FAULT_NOISE = NOISE
INERTIAL_FAULT_KINDS = frozenset({FAULT_BIAS_JUMP, FAULT_FROZEN, FAULT_OUTAGE, FAULT_NOISE})
SensorFaultParams = dict[str, float | tuple[float, ...]]
"""Recorded parameters of one active sensor fault: name → number or vector (a copy)."""


class SensorOutageError(ThrusterHilError):
    """Raised by ``sample`` of a sensor in an ``outage``: the measurement is invalid.

    ``sensor`` names the sensor, ``t_ns`` is the sample time, ``last_output`` the last
    valid output (what ``measure`` returns with ``valid = False``).
    """

    def __init__(self, sensor: str, t_ns: int, last_output: Vec3) -> None:
        self.sensor = sensor
        self.t_ns = t_ns
        self.last_output = last_output
        super().__init__(f"{sensor}: outage at t_ns={t_ns}: the sample is invalid")


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


def check_fault_kind(
    kind: str, params: Mapping[str, object], source: str, allowed: Mapping[str, tuple[str, ...]]
) -> None:
    """ConfigError unless ``kind`` is in ``allowed`` and ``params`` are exactly its names."""
    if kind not in allowed:
        raise ConfigError(source, "kind", kind, f"None or one of {sorted(allowed)}")
    names = allowed[kind]
    for key, value in params.items():
        if key not in names:
            raise ConfigError(
                source,
                key,
                value,
                f"no such parameter for {kind!r} (its parameters: {list(names) or 'none'})",
            )
    for key in names:
        if key not in params:
            raise ConfigError(source, key, None, f"a value (required by {kind!r})")


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
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
        given = getattr(self, "bias_rad_s")  # noqa: B009 - uncast (see setup.py)
        put(self, "bias_rad_s", check.triple(src, "bias_rad_s", given))
        for key in ("bias_rw_rad_s_sqrt_s", "arw_rad_sqrt_s", "lsb_rad_s"):
            put(self, key, check.non_negative(src, key, getattr(self, key)))
        put(self, "period_s", check.positive(src, "period_s", self.period_s))
        rng_ = check.limit(src, "range_rad_s", self.range_rad_s)
        if rng_ < self.lsb_rad_s:
            raise ConfigError(src, "range_rad_s", self.range_rad_s, "a range >= lsb_rad_s")
        put(self, "range_rad_s", rng_)
        put(self, "output_limit_rad_s", output_limit(self.lsb_rad_s, rng_))


class InertialSensor:
    """Fault handling shared by the 3-axis inertial sensors (see the module docstring).

    Subclasses set ``_NAME`` and ``_JUMP_KEY`` (the ``bias_jump`` parameter name, with
    its units) and call ``_init_model``; their ``sample`` runs the model on the
    attributes set here and hands the output to ``_faulty`` while a fault is active.
    """

    __slots__ = (
        "_bias",
        "_faults",
        "_jump",
        "_last_out",
        "_limit",
        "_lsb",
        "_period_s",
        "_rng",
        "_t_prev_ns",
        "_walk_density",
        "_white_density",
        "_white_nominal",
        "params",
    )
    _NAME: ClassVar[str] = "inertial sensor"
    _JUMP_KEY: ClassVar[str] = "jump"

    def _init_model(
        self,
        rng: np.random.Generator,
        bias: Vec3,
        white_density: float,
        walk_density: float,
        lsb: float,
        limit: float,
        period_s: float,
    ) -> None:
        self._rng = rng
        self._bias = bias
        self._white_nominal = white_density
        self._white_density = white_density  # × the noise fault's factor
        self._walk_density = walk_density
        self._lsb = lsb
        self._limit = limit
        self._period_s = period_s
        self._t_prev_ns: int | None = None
        self._last_out: Vec3 | None = None  # last output (held by frozen and outage)
        self._faults: dict[str, SensorFaultParams] = {}
        self._jump: Vec3 = ZERO_VEC3  # the active bias jump, included in _bias

    # --- sampling ----------------------------------------------------------------------
    def sample(self, t_ns: int, truth: Vec3, /) -> Vec3:
        """Measured triad at ``t_ns``; raises ``SensorOutageError`` during an outage."""
        raise NotImplementedError

    def measure(self, t_ns: int, truth: Vec3) -> tuple[Vec3, bool]:
        """(measured triad, valid) at ``t_ns``: as ``sample`` but never raises for an outage.

        During an outage the triad is the last valid output ((0, 0, 0) before any).
        """
        try:
            return self.sample(t_ns, truth), True
        except SensorOutageError as outage:
            return outage.last_output, False

    def _faulty(self, t_ns: int, out: Vec3) -> Vec3:
        """The output of a sample while a fault is active (live ``out`` already drawn)."""
        faults = self._faults
        if FAULT_OUTAGE in faults:
            last = self._last_out
            raise SensorOutageError(self._NAME, t_ns, ZERO_VEC3 if last is None else last)
        if FAULT_FROZEN in faults:
            if self._last_out is None:
                self._last_out = out
            return self._last_out
        self._last_out = out
        return out

    # --- faults ------------------------------------------------------------------------
    @classmethod
    def fault_params(cls) -> dict[str, tuple[str, ...]]:
        """The fault kinds of this sensor and their parameter names."""
        return {
            FAULT_BIAS_JUMP: (cls._JUMP_KEY,),
            FAULT_FROZEN: (),
            FAULT_OUTAGE: (),
            FAULT_NOISE: ("factor",),
        }

    @property
    def faults_active(self) -> dict[str, SensorFaultParams]:
        """Active faults: kind → parameters (a copy; empty when healthy)."""
        return {k: dict(v) for k, v in self._faults.items()}

    def set_fault(self, kind: str | None, t_ns: int | None = None, **params: object) -> None:
        """Inject fault ``kind`` (module docstring) from the next sample, or clear all (None).

        ``t_ns`` (optional) is the event time, which must not precede the last sample.
        Bad kinds or parameters raise ``ConfigError``.
        """
        source = f"{self._NAME}.set_fault({kind!r})"
        self._check_event_time(t_ns)
        if kind is None:
            if params:
                key = next(iter(params))
                raise ConfigError(source, key, params[key], "no parameter when clearing (None)")
            for k in list(self._faults):
                self._remove(k)
            return
        check_fault_kind(kind, params, source, self.fault_params())
        recorded: SensorFaultParams = {}
        if kind == FAULT_BIAS_JUMP:
            jump = check.triple(source, self._JUMP_KEY, params[self._JUMP_KEY])
            recorded[self._JUMP_KEY] = jump
            self._remove(kind)
            b = self._bias
            self._bias = (b[0] + jump[0], b[1] + jump[1], b[2] + jump[2])
            self._jump = jump
        elif kind == FAULT_NOISE:
            factor = check.non_negative(source, "factor", params["factor"])
            recorded["factor"] = factor
            self._white_density = self._white_nominal * factor
        self._faults[kind] = recorded

    def clear_fault(self, kind: str, t_ns: int | None = None) -> None:
        """Clear fault ``kind`` from the next sample; a no-op if it is not active."""
        source = f"{self._NAME}.clear_fault({kind!r})"
        if kind not in INERTIAL_FAULT_KINDS:
            raise ConfigError(source, "kind", kind, f"one of {sorted(INERTIAL_FAULT_KINDS)}")
        self._check_event_time(t_ns)
        self._remove(kind)

    def _remove(self, kind: str) -> None:
        """Deactivate ``kind`` and undo its effect on the model (no-op if inactive)."""
        if self._faults.pop(kind, None) is None:
            return
        if kind == FAULT_BIAS_JUMP:
            jump, b = self._jump, self._bias
            self._bias = (b[0] - jump[0], b[1] - jump[1], b[2] - jump[2])
            self._jump = ZERO_VEC3
        elif kind == FAULT_NOISE:
            self._white_density = self._white_nominal

    def _check_event_time(self, t_ns: int | None) -> None:
        prev = self._t_prev_ns
        if t_ns is not None and prev is not None and t_ns < prev:
            raise ValueError(
                f"{self._NAME} fault events must not precede the last sample: {t_ns} < {prev}"
            )


class Gyro(InertialSensor):
    """A gyro triad drawing its noise from ``rng`` (see the module docstring)."""

    __slots__ = ()
    _NAME = "gyro"
    _JUMP_KEY = "jump_rad_s"

    def __init__(self, params: GyroParams, rng: np.random.Generator) -> None:
        self.params = params
        self._init_model(
            rng,
            params.bias_rad_s,
            params.arw_rad_sqrt_s,
            params.bias_rw_rad_s_sqrt_s,
            params.lsb_rad_s,
            params.output_limit_rad_s,
            params.period_s,
        )

    @property
    def bias_rad_s(self) -> Vec3:
        """The current (true) bias [rad/s], for telemetry (a ``bias_jump`` included)."""
        return self._bias

    def sample(self, t_ns: int, omega_BN_B_rad_s: Vec3) -> Vec3:
        """Measured body rate [rad/s] at ``t_ns`` for the true rate ``omega_BN_B_rad_s``.

        Raises ``SensorOutageError`` during an ``outage`` fault (``measure`` returns a flag).
        """
        prev = self._t_prev_ns
        if prev is None:
            dt_s, walk = self._period_s, False
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
