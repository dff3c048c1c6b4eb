"""Parameters of a thruster valve and of its faults: constants, validation, ``ValveParams``.

What it does
    Validates the physical parameters of one valve (``ValveParams``, frozen, with its
    derived nanosecond and inverse fields) and the parameters of a valve fault
    (``check_fault_params``), and holds the constants the valve models share.

Inputs / outputs
    In: the valve's parameters as given by a scenario or a test; a fault's kind and
    parameters as given to ``set_fault``. Out: a ``ValveParams``; the recorded
    (validated) parameters of a fault; or ``ConfigError(source, key, value, expected)``
    naming the bad one.

Fault kinds and their parameters (their effect: :mod:`bench.station.valves.valve`)
    ``stuck_closed`` and ``stuck_open`` (none); ``degraded``: ``factor`` [-] in [0, 1];
    ``delayed``: ``extra_delay_s`` [s] >= 0; ``intermittent``: ``dropout_probability``
    [-] in [0, 1] (optional ``rng``, a ``numpy.random.Generator``, checked but not
    recorded); ``leak``: ``thrust_N`` [N] in (0, max_thrust_N].

Units: seconds in parameters (suffix ``_s``), integer nanoseconds for times (``_ns``),
newtons for thrust. Read by the on-off ``Valve``, the ``ThrottledValve``, their thrust
profile and the thruster set.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from mypy_extensions import mypyc_attr

from dbc import validation as check
from dbc.errors import ConfigError
from dbc.faults import DEGRADED, DELAYED, INTERMITTENT, LEAK, STUCK_CLOSED, STUCK_OPEN

NS_PER_S = 1_000_000_000
S_PER_NS = 1e-9
THRUST_CUTOFF_FRACTION = 1e-9
"""A decaying thrust below this fraction of Fmax is exactly zero (the valve is idle)."""
OPEN_THRESHOLD_FRACTION = 0.1
"""``status`` reports the valve open while the thrust exceeds this fraction of Fmax."""
HISTORY_NS = 10_000_000
"""Thrust history kept before the newest event [ns] (10 plant steps at 1 kHz), so that a
step may be sampled from its start after several events inside it (commands, faults)."""
NEVER_NS = 2**63 - 1
"""A time later than any simulation (idle_from_ns of a valve that never stops)."""
FAULT_STUCK_CLOSED = STUCK_CLOSED
FAULT_STUCK_OPEN = STUCK_OPEN
FAULT_DEGRADED = DEGRADED
FAULT_DELAYED = DELAYED
FAULT_INTERMITTENT = INTERMITTENT
FAULT_LEAK = LEAK
FAULT_PARAMS: Mapping[str, tuple[str, ...]] = {
    FAULT_STUCK_CLOSED: (),
    FAULT_STUCK_OPEN: (),
    FAULT_DEGRADED: ("factor",),
    FAULT_DELAYED: ("extra_delay_s",),
    FAULT_INTERMITTENT: ("dropout_probability",),
    FAULT_LEAK: ("thrust_N",),
}
"""Valve fault kinds and their required parameters (see the module docstring)."""
FAULT_OPTIONAL_PARAMS: Mapping[str, tuple[str, ...]] = {FAULT_INTERMITTENT: ("rng",)}
"""Optional parameters (not recorded in ``faults_active``)."""
FAULT_KINDS = frozenset(FAULT_PARAMS)
NOMINAL_THRUST_FACTOR = 1.0
FaultParams = dict[str, float | tuple[float, ...]]
"""Recorded parameters of one active fault: name → value (number or vector) in the units
of its name (a copy, safe to log; generators are not recorded)."""
_ValveFaultParams = dict[str, float]

# A thrust segment: (t_start_ns, thrust at t_start [N], target thrust [N], 1/τ [1/ns]).


def _require(ok: bool, source: str, key: str, value: object, expected: str) -> None:
    if not ok:
        raise ConfigError(source, key, value, expected)


def check_fault_params(
    kind: str, params: Mapping[str, object], source: str, max_thrust_N: float
) -> _ValveFaultParams:
    """Validate the parameters of a valve fault ``kind``; returns the recorded ones.

    Unknown or missing names and out-of-range values raise ``ConfigError(source, name,
    value, expected)``; the optional ``rng`` is checked to be a numpy Generator but not
    returned.
    """
    _require(kind in FAULT_KINDS, source, "kind", kind, f"None or one of {sorted(FAULT_KINDS)}")
    required = FAULT_PARAMS[kind]
    allowed = required + FAULT_OPTIONAL_PARAMS.get(kind, ())
    for key, value in params.items():
        _require(
            key in allowed,
            source,
            key,
            value,
            f"no such parameter for {kind!r} (its parameters: {list(allowed) or 'none'})",
        )
    for key in required:
        _require(key in params, source, key, None, f"a value (required by {kind!r})")
    if "rng" in params:
        rng = params["rng"]
        _require(isinstance(rng, np.random.Generator), source, "rng", rng, "a numpy Generator")
    out: _ValveFaultParams = {}
    if kind == FAULT_DEGRADED:
        out["factor"] = check.number(source, "factor", params["factor"], 0.0, 1.0)
    elif kind == FAULT_DELAYED:
        out["extra_delay_s"] = check.non_negative(source, "extra_delay_s", params["extra_delay_s"])
    elif kind == FAULT_INTERMITTENT:
        out["dropout_probability"] = check.number(
            source, "dropout_probability", params["dropout_probability"], 0.0, 1.0
        )
    elif kind == FAULT_LEAK:
        # at most the valve's max_thrust_N
        out["thrust_N"] = check.number(
            source, "thrust_N", params["thrust_N"], 0.0, max_thrust_N, lo_open=True, unit="N"
        )
    return out


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class ValveParams:
    """Parameters of one thruster valve; times in seconds, validated on construction.

    ``max_thrust_N`` and ``isp_s`` > 0; ``open_delay_s``, ``close_delay_s`` and
    ``min_on_s`` ≥ 0; ``rise_tau_s`` and ``tail_tau_s`` > 0 (use a small value, e.g.
    1e-6 s, for an ideal valve). Derived nanosecond/inverse fields are precomputed.
    """

    max_thrust_N: float
    isp_s: float
    open_delay_s: float
    close_delay_s: float
    rise_tau_s: float
    tail_tau_s: float
    min_on_s: float
    source: str = field(default="ValveParams", compare=False, repr=False, kw_only=True)
    open_delay_ns: int = field(init=False, repr=False, compare=False)
    close_delay_ns: int = field(init=False, repr=False, compare=False)
    min_on_ns: int = field(init=False, repr=False, compare=False)
    inv_rise_tau_per_ns: float = field(init=False, repr=False, compare=False)
    inv_tail_tau_per_ns: float = field(init=False, repr=False, compare=False)
    cutoff_N: float = field(init=False, repr=False, compare=False)
    open_threshold_N: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        src = self.source
        put = object.__setattr__
        # getattr: the fields as given (compiled code would cast a read to float first)
        for key in ("max_thrust_N", "isp_s", "rise_tau_s", "tail_tau_s"):
            put(self, key, check.positive(src, key, getattr(self, key)))
        for key in ("open_delay_s", "close_delay_s", "min_on_s"):
            put(self, key, check.non_negative(src, key, getattr(self, key)))
        put(self, "open_delay_ns", round(self.open_delay_s * NS_PER_S))
        put(self, "close_delay_ns", round(self.close_delay_s * NS_PER_S))
        put(self, "min_on_ns", round(self.min_on_s * NS_PER_S))
        put(self, "inv_rise_tau_per_ns", 1.0 / (self.rise_tau_s * NS_PER_S))
        put(self, "inv_tail_tau_per_ns", 1.0 / (self.tail_tau_s * NS_PER_S))
        put(self, "cutoff_N", THRUST_CUTOFF_FRACTION * self.max_thrust_N)
        put(self, "open_threshold_N", OPEN_THRESHOLD_FRACTION * self.max_thrust_N)
