"""Limits shared by a scenario's keys and the command line's options that override them.

``[scenario] duration_s`` and ``--duration``: at least one control period (the DBC's
``GenMsgCycleTime`` of THR_CMD_0: a run shorter than one cycle commands nothing) and at
most :data:`MAX_DURATION_S` (11.6 days of simulated time: far beyond any bench run, and
small enough that every time in nanoseconds stays an exact int64). ``seed`` and ``--seed``:
an integer in [0, :data:`SEED_MAX`] (an int64, as readers of summary.json take it). Plain
constants, no imports: the pure station reads them too (a fault's duration).
"""

from __future__ import annotations

INT64_MAX = 2**63 - 1

MAX_DURATION_S = 1e6
SEED_MAX = INT64_MAX
NS_PER_S = 1e9
PERIOD_MESSAGE = "THR_CMD_0"  # the control cycle's command frame
