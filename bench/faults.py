"""Fault specifications: what a scenario's ``[[faults]]`` entries may say, validated.

One entry = one fault with a start time ``t_s``, an optional ``duration_s`` (0 = until the
end of the run), a ``kind`` and its target and parameters:

- ``stuck_closed`` (``thruster``): the valve never opens (bench/valves).
- ``stuck_open`` (``thruster``): the valve opens and stays open (bench/valves).
- ``link_error`` (``message`` or ``node``; ``probability`` in (0, 1]): each matching frame
  fails once on the wire with that probability: error frame, then retransmission after
  re-arbitration (bench/bus/timing).
- ``bus_off`` (``node``): the node's controller goes bus-off; its frames wait for
  ``duration_s`` or, if 0, for the recovery time of 128 x 11 recessive bits.

Bus faults act on the modelled bus, so in lockstep runs only (a realtime run records them
as not applicable). Targets are checked against the scenario's thrusters and the DBC's
messages and nodes. Pure data; the bench node applies them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from dbc.schema import Table

THRUSTER_KINDS = ("stuck_closed", "stuck_open")
BUS_KINDS = ("link_error", "bus_off")
FAULT_KINDS = THRUSTER_KINDS + BUS_KINDS


@dataclass(frozen=True)
class FaultSpec:
    """One scheduled fault."""

    t_s: float
    kind: str
    duration_s: float = 0.0  # 0 = until the end of the run
    thruster: int | None = None
    message: str | None = None
    node: str | None = None
    params: dict[str, float] = field(default_factory=dict)

    def record(self) -> dict[str, Any]:
        """Plain-dict form for summary.json and events.jsonl."""
        out: dict[str, Any] = {"t_s": self.t_s, "kind": self.kind, "duration_s": self.duration_s}
        for key in ("thruster", "message", "node"):
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
        dur = f.number("duration_s", 0.0, lo=0.0)
        if kind in THRUSTER_KINDS:
            k = f.integer("thruster", lo=0)
            if k >= n_thrusters:
                raise f.error("thruster", k, f"a thruster index 0..{n_thrusters - 1}")
            spec = FaultSpec(t_s, kind, dur, thruster=k)
        elif kind == "link_error":
            message = (f.string("message", choices=tuple(sorted(messages)))
                       if f.has("message") else None)
            node = f.string("node", choices=tuple(sorted(nodes))) if f.has("node") else None
            if (message is None) == (node is None):
                raise f.error("message", None, "exactly one of message = NAME or node = NAME")
            p = f.number("probability", 1.0, lo=0.0, lo_open=True, hi=1.0)
            spec = FaultSpec(t_s, kind, dur, message=message, node=node, params={"probability": p})
        else:  # bus_off
            spec = FaultSpec(t_s, kind, dur, node=f.string("node", choices=tuple(sorted(nodes))))
        f.done()
        out.append(spec)
    return tuple(sorted(out, key=lambda x: x.t_s))
