"""Fault specifications: what a scenario's ``[[faults]]`` entries may say, validated.

One entry = one fault with a start time ``t_s``, an optional ``duration_s`` (0 = until the
end of the run), a ``kind`` and its target and parameters:

- ``stuck_closed`` (``thruster``): the valve never opens (bench/station/valves).
- ``stuck_open`` (``thruster``): the valve opens and stays open (bench/station/valves).
- ``degraded`` (``thruster``; ``factor`` in [0, 1]), ``delayed`` (``extra_delay_s``),
  ``intermittent`` (``dropout_probability`` per pulse), ``leak`` (``thrust_N``),
  ``misaligned`` (``angle_deg``, ``axis_B``): see bench/station/valves/valve.py and thruster_set.py.
- Sensor faults (``sensor`` = ``gyro``, ``accelerometer`` or ``star_tracker``):
  ``bias_jump`` (``jump_rad_s`` [3] for the gyro, ``jump_m_s2`` [3] for the accelerometer,
  ``misalignment_arcsec`` [3] for the star tracker), ``frozen`` (same output, counter still
  advancing), ``outage`` (frames marked invalid), ``noise`` (``factor`` on the white noise).
- ``link_error`` (``message`` or ``node``; ``probability`` in (0, 1]): each matching frame
  fails once on the wire with that probability: error frame, then retransmission after
  re-arbitration (bench/bus/timing).
- ``bus_off`` (``node``): the node's controller goes bus-off; its frames wait for
  ``duration_s`` or, if 0, for the recovery time of 128 x 11 recessive bits.
- ``drop`` (``message`` or ``node``; ``probability``): the frame never reaches its receiver.
- ``delay`` (``message`` or ``node``; ``delay_s``, ``probability``): the frame reaches its
  receiver ``delay_s`` later than the bus would deliver it (a gateway or driver queue).
- ``corrupt`` (``message`` or ``node``; ``probability``): one payload bit flipped after
  the sender's E2E protection (a corrupting gateway): the receiver's CRC must catch it.
- ``duplicate`` (``message`` or ``node``; ``probability``): the frame arrives twice; the
  copy repeats the alive counter and must be rejected.
- ``babbling`` (``can_id``, ``rate_hz``): a babbling node floods the bus with random 8-byte
  frames of that (typically high-priority, unknown) ID at that rate.

Bus faults act on the modelled bus in lockstep runs. In realtime, where there is no
modelled bus, ``drop``, ``corrupt`` and ``duplicate`` (:data:`REALTIME_BUS_KINDS`) still act
on the frames the bench sends and receives; the others (``delay``, ``link_error``,
``bus_off``, ``babbling``) are recorded as not applied and have no effect. Targets are
checked against the scenario's thrusters and the DBC's messages and nodes. Pure data; the
bench node applies them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from bench.scenario.limits import MAX_DURATION_S
from dbc.errors import ConfigError
from dbc.faults import (
    BABBLING,
    BIAS_JUMP,
    BUS_KINDS,
    BUS_OFF,
    DEGRADED,
    DELAY,
    DELAYED,
    FAULT_KINDS,
    FRAME_KINDS,
    INTERMITTENT,
    LEAK,
    MISALIGNED,
    NOISE,
    REALTIME_BUS_KINDS,
    SENSOR_KINDS,
    THRUSTER_KINDS,
)
from dbc.icd import Icd
from dbc.schema import Table

__all__ = ["BUS_KINDS", "FAULT_KINDS", "FRAME_KINDS", "REALTIME_BUS_KINDS", "SENSOR_KINDS",
           "THRUSTER_KINDS", "FaultSpec", "fault_from_command", "parse_faults"]

THRUSTER_PARAMS: dict[str, tuple[tuple[str, float, float], ...]] = {  # (name, lo, hi)
    DEGRADED: (("factor", 0.0, 1.0),),
    DELAYED: (("extra_delay_s", 0.0, 1.0),),
    INTERMITTENT: (("dropout_probability", 0.0, 1.0),),
    LEAK: (("thrust_N", 0.0, 1e3),),
    MISALIGNED: (("angle_deg", -180.0, 180.0),),
}
SENSORS = ("gyro", "accelerometer", "star_tracker")  # FAULT_CMD.Target of sensor faults
BIAS_JUMP_PARAM = {"gyro": "jump_rad_s", "accelerometer": "jump_m_s2",
                   "star_tracker": "misalignment_arcsec"}
MAX_STD_ID = 0x7FF
MAX_RATE_HZ = 20_000.0  # above a 1 Mbit/s bus's capacity for 8-byte frames
BABBLER = "BABBLER"  # the node name of a babbling fault's frames


@dataclass(frozen=True)
class FaultSpec:
    """One scheduled fault."""

    t_s: float
    kind: str
    duration_s: float = 0.0  # 0 = until the end of the run
    thruster: int | None = None
    message: str | None = None
    node: str | None = None
    sensor: str | None = None
    params: dict[str, Any] = field(default_factory=dict)

    def record(self) -> dict[str, Any]:
        """Plain-dict form for summary.json and events.jsonl."""
        out: dict[str, Any] = {"t_s": self.t_s, "kind": self.kind, "duration_s": self.duration_s}
        for key in ("thruster", "message", "node", "sensor"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        out.update(self.params)
        return out


def parse_faults(tables: list[Table], duration_s: float, n_thrusters: int,
                 messages: frozenset[str], nodes: frozenset[str]) -> tuple[FaultSpec, ...]:
    """Validate ``[[faults]]`` tables; sorted by start time."""
    out = []
    for f in tables:
        t_s = f.number("t_s", lo=0.0, hi=duration_s)
        kind = f.string("kind", choices=FAULT_KINDS)
        dur = f.number("duration_s", 0.0, lo=0.0, hi=MAX_DURATION_S)
        if kind in THRUSTER_KINDS:
            k = f.integer("thruster", lo=0)
            if k >= n_thrusters:
                raise f.error("thruster", k, f"a thruster index 0..{n_thrusters - 1}")
            params: dict[str, Any] = {
                name: f.number(name, lo=lo, hi=hi) for name, lo, hi in THRUSTER_PARAMS.get(kind, ())
            }
            if kind == MISALIGNED:
                params["axis_B"] = f.vector3("axis_B")
            spec = FaultSpec(t_s, kind, dur, thruster=k, params=params)
        elif kind in SENSOR_KINDS:
            sensor = f.string("sensor", choices=SENSORS)
            params = {}
            if kind == BIAS_JUMP:
                params[BIAS_JUMP_PARAM[sensor]] = f.vector3(BIAS_JUMP_PARAM[sensor])
            elif kind == NOISE:
                params["factor"] = f.number("factor", lo=0.0)
            spec = FaultSpec(t_s, kind, dur, sensor=sensor, params=params)
        elif kind in FRAME_KINDS:
            message = (f.string("message", choices=tuple(sorted(messages)))
                       if f.has("message") else None)
            node = f.string("node", choices=tuple(sorted(nodes))) if f.has("node") else None
            if (message is None) == (node is None):
                raise f.error("message", None, "exactly one of message = NAME or node = NAME")
            params = {"probability": f.number("probability", 1.0, lo=0.0, lo_open=True, hi=1.0)}
            if kind == DELAY:
                params["delay_s"] = f.number("delay_s", lo=0.0, lo_open=True, hi=1.0)
            spec = FaultSpec(t_s, kind, dur, message=message, node=node, params=params)
        elif kind == BABBLING:
            can_id = f.integer("can_id", lo=0)
            if can_id > MAX_STD_ID:
                raise f.error("can_id", can_id, f"an 11-bit ID 0..{MAX_STD_ID}")
            rate_hz = f.number("rate_hz", lo=0.0, lo_open=True, hi=MAX_RATE_HZ)
            spec = FaultSpec(t_s, kind, dur, node=f.string("node", BABBLER),
                             params={"can_id": can_id, "rate_hz": rate_hz})
        else:  # bus_off
            spec = FaultSpec(t_s, kind, dur, node=f.string("node", choices=tuple(sorted(nodes))))
        f.done()
        out.append(spec)
    return tuple(sorted(out, key=lambda x: x.t_s))


# the single Param of a FAULT_CMD, per kind that takes one
FAULT_CMD_PARAM = {DEGRADED: "factor", MISALIGNED: "angle_deg", DELAYED: "extra_delay_s",
                   INTERMITTENT: "dropout_probability", LEAK: "thrust_N", NOISE: "factor"}
FAULT_CMD_AXIS_B = (0.0, 0.0, 1.0)  # misalignment axis of a FAULT_CMD (not encodable)
FAULT_CMD_SOURCE = "FAULT_CMD"  # where a refused live command's bad value came from
KHZ = 1000.0


def fault_from_command(signals: dict[str, float], icd: Icd, n_thrusters: int,
                       t_s: float) -> FaultSpec:
    """The fault a FAULT_CMD frame describes (see its DBC comments).

    Target is a thruster index (thruster kinds), a sensor index (0 gyro, 1 accelerometer,
    2 star tracker), the CAN ID of a message (frame kinds), the CAN ID to babble with
    (babbling), or a node index into the DBC's node list (bus_off). Param is the kind's one
    parameter: factor, angle (deg, about z_B), extra delay (s), dropout probability, leak
    thrust (N), bias jump on the sensor's x axis, probability (frame kinds, 0 = 1; at most
    1), delay (s) or rate (kHz, babbling). Raises :class:`ConfigError` (source
    ``FAULT_CMD``) naming the signal and value this bench cannot apply.
    """
    code = int(signals["FaultType"])
    kind = icd.fault_kinds.get(code)
    target, param = int(signals["Target"]), float(signals["Param"])
    dur = float(signals["Duration"])
    if kind is None:
        raise ConfigError(FAULT_CMD_SOURCE, "FaultType", code,
                          f"one of {sorted(icd.fault_kinds)} (see the DBC's VAL_ table)")
    if kind in THRUSTER_KINDS:
        if target >= n_thrusters:
            raise ConfigError(FAULT_CMD_SOURCE, "Target", target,
                              f"a thruster index 0..{n_thrusters - 1} for {kind}")
        params: dict[str, Any] = {}
        if kind in FAULT_CMD_PARAM:
            params[FAULT_CMD_PARAM[kind]] = param
        if kind == MISALIGNED:
            params["axis_B"] = FAULT_CMD_AXIS_B
        return FaultSpec(t_s, kind, dur, thruster=target, params=params)
    if kind in SENSOR_KINDS:
        if target >= len(SENSORS):
            raise ConfigError(FAULT_CMD_SOURCE, "Target", target,
                              f"a sensor index 0..{len(SENSORS) - 1} ({', '.join(SENSORS)})")
        sensor = SENSORS[target]
        params = {}
        if kind == NOISE:
            params["factor"] = param
        elif kind == BIAS_JUMP:  # Param on the sensor's x axis, in its units
            params[BIAS_JUMP_PARAM[sensor]] = (param, 0.0, 0.0)
        return FaultSpec(t_s, kind, dur, sensor=sensor, params=params)
    if kind == BUS_OFF:
        if target >= len(icd.nodes):
            raise ConfigError(FAULT_CMD_SOURCE, "Target", target,
                              f"a node index 0..{len(icd.nodes) - 1} ({', '.join(icd.nodes)})")
        return FaultSpec(t_s, kind, dur, node=icd.nodes[target])
    if kind == BABBLING:
        if target > MAX_STD_ID:
            raise ConfigError(FAULT_CMD_SOURCE, "Target", target,
                              f"an 11-bit CAN ID 0..0x{MAX_STD_ID:X} to babble with")
        if not param > 0:
            raise ConfigError(FAULT_CMD_SOURCE, "Param", param, "a babbling rate > 0 kHz")
        return FaultSpec(t_s, kind, dur, node=BABBLER,
                         params={"can_id": target, "rate_hz": param * KHZ})
    message = icd.name_by_id.get(target)
    if message is None:
        raise ConfigError(FAULT_CMD_SOURCE, "Target", target,
                          f"the CAN ID of a DBC message for {kind}")
    if kind == DELAY:
        if not param > 0:
            raise ConfigError(FAULT_CMD_SOURCE, "Param", param, "a delay > 0 s")
        return FaultSpec(t_s, kind, dur, message=message,
                         params={"probability": 1.0, "delay_s": param})
    if param > 1.0:
        raise ConfigError(FAULT_CMD_SOURCE, "Param", param,
                          f"a probability in (0, 1] for {kind} (0 means 1)")
    p = param if param > 0 else 1.0
    return FaultSpec(t_s, kind, dur, message=message, params={"probability": p})
