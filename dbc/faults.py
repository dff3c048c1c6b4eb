"""The fault kinds of the ICD: their names, as FAULT_CMD.FaultType's value table defines them.

A scenario's ``[[faults]]`` and a live FAULT_CMD name the same kinds; the bench applies
them (valves, sensors, the modelled bus). This module is the one place their names are
written; ``tests/dbc/test_icd_facts.py`` checks that they are exactly the non-zero
entries of the DBC's ``VAL_`` table of ``FAULT_CMD.FaultType`` (whose codes
:class:`dbc.icd.Icd` reads), so the DBC and the code cannot drift apart.

Groups: thruster faults (target: a thruster index), sensor faults (target: a sensor),
frame faults (target: a message or a node; each matching frame's fate is drawn), bus
faults (frame faults, a node going bus-off, a babbling node), and the bus faults that need
no modelled bus (they act in realtime runs too).
"""

from __future__ import annotations

from typing import Final

STUCK_CLOSED: Final = "stuck_closed"
STUCK_OPEN: Final = "stuck_open"
DEGRADED: Final = "degraded"
MISALIGNED: Final = "misaligned"
DELAYED: Final = "delayed"
INTERMITTENT: Final = "intermittent"
LEAK: Final = "leak"
DROP: Final = "drop"
DELAY: Final = "delay"
CORRUPT: Final = "corrupt"
DUPLICATE: Final = "duplicate"
BABBLING: Final = "babbling"
BUS_OFF: Final = "bus_off"
LINK_ERROR: Final = "link_error"
BIAS_JUMP: Final = "bias_jump"
FROZEN: Final = "frozen"
OUTAGE: Final = "outage"
NOISE: Final = "noise"

THRUSTER_KINDS: Final = (STUCK_CLOSED, STUCK_OPEN, DEGRADED, DELAYED, INTERMITTENT, LEAK,
                         MISALIGNED)
SENSOR_KINDS: Final = (BIAS_JUMP, FROZEN, OUTAGE, NOISE)
FRAME_KINDS: Final = (LINK_ERROR, DROP, DELAY, CORRUPT, DUPLICATE)
BUS_KINDS: Final = (*FRAME_KINDS, BUS_OFF, BABBLING)
REALTIME_BUS_KINDS: Final = frozenset({DROP, CORRUPT, DUPLICATE})  # need no modelled bus
FAULT_KINDS: Final = THRUSTER_KINDS + BUS_KINDS + SENSOR_KINDS
