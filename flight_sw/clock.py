"""The flight software's only wall-clock reader. Models take ``t_ns`` as an argument."""

from __future__ import annotations

import time


class MonotonicClock:
    """Monotonic time in integer nanoseconds since construction."""

    def __init__(self) -> None:
        self._t0 = time.monotonic_ns()

    def now_ns(self) -> int:
        """Nanoseconds since this clock was made."""
        return time.monotonic_ns() - self._t0
