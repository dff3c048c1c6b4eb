"""Default settings of the timing analysis, importable without numpy or the DBC.

Cycle-time windows: CANoe's cycle-time checks take the limits from the user; these are the
bench's defaults, ±1 ms absolute and ±10 % relative around ``GenMsgCycleTime`` (a 10 ms
message: 9..11 ms in both; a 100 ms message: 99..101 ms absolute, 90..110 ms relative).
Lockstep runs (modelled bus) stay well inside both; realtime runs on a loaded host may not.
"""

from __future__ import annotations

DEFAULT_WINDOW_MS = 10.0  # bus-load window
DEFAULT_CYCLE_ABS_TOLERANCE_MS = 1.0  # ± around the DBC cycle time
DEFAULT_CYCLE_REL_TOLERANCE_PCT = 10.0  # ± % of the DBC cycle time
DEFAULT_MISSED_GAP_PERIODS = 1.5  # a gap longer than this many cycles misses an instance
DEFAULT_LIVE_DURATION_S = 10.0  # timing --live: listening time from the first frame
DEFAULT_FIRST_FRAME_TIMEOUT_S = 10.0  # timing --live: wait for the first frame
