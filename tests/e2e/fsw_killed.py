"""Test helper: our flight software, which SIGKILLs itself after N control cycles.

Usage: fsw_killed.py N [flight_sw arguments...]
"""

from __future__ import annotations

import os
import signal
import sys

from flight_sw import __main__ as fsw_main
from flight_sw.node import FlightNode

kill_at = int(sys.argv[1])
_original = FlightNode.run_cycle


def _run_cycle(self: FlightNode, cycle: int, t_ns: int) -> None:
    if cycle >= kill_at:
        os.kill(os.getpid(), signal.SIGKILL)
    _original(self, cycle, t_ns)


FlightNode.run_cycle = _run_cycle  # type: ignore[method-assign]
sys.exit(fsw_main.main(sys.argv[2:]))
