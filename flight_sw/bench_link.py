"""The flight software's view of the bench: which SYNC and BENCH_STATUS frames count, and when
the bench restarted.

In: SYNC and BENCH_STATUS frames that passed the ICD's checks (dbc.codec.FrameChecker.
inspect, not yet taken), with this process's clock reading [ns] at receipt. Out: the
decision for each (run cycle k at time t_k; the bench restarted; stale: rejected and
counted), and the bench's time as last heard. A frame is taken (its alive counter moves
on) only when it counts.

Rules (docs/icd.md, "Restarts"): a SYNC whose cycle is not newer than the last one taken
is stale, unless it goes back to 0 or more than ``STALE_SYNC_WINDOW`` cycles back, which is
a bench restart; a BENCH_STATUS whose time goes backwards is a bench restart. A restart is
taken only after the bench has been quiet (no frame of it taken) for at least
``restart_quiet_ns`` of this process's clock: a restarted bench is silent far longer (it
waits for our heartbeat). Without that quiet period the frame is a replay or a forgery:
stale, counted in ``restarts_refused``. Times in SimTime signals have a 1 ms LSB.
"""

from __future__ import annotations

from enum import Enum

from dbc.codec import Decoded, FrameChecker, Reject

STALE_SYNC_WINDOW = 2  # a SYNC at most this many cycles behind the last one is stale
RESTART_QUIET_NS = 200_000_000  # bench silence [ns] before a restart is taken
MS_PER_S = 1000
NS_PER_MS = 1_000_000


def sim_time_ns(t_s: float) -> int:
    """A SimTime signal [s] (1 ms LSB) on the ns time axis."""
    return round(float(t_s) * MS_PER_S) * NS_PER_MS


class Verdict(Enum):
    """What a SYNC or BENCH_STATUS frame means."""

    TAKEN = "taken"  # counts: run its cycle (SYNC), or the bench's new time (BENCH_STATUS)
    RESTART = "restart"  # the bench started a new run
    STALE = "stale"  # rejected and counted


class BenchLink:
    """The bench as the flight software sees it (see the module docstring)."""

    def __init__(self, checker: FrameChecker, restart_quiet_ns: int = RESTART_QUIET_NS) -> None:
        self.checker = checker
        self.restart_quiet_ns = restart_quiet_ns
        self.last_sync_ns: int | None = None  # the time of the last SYNC run
        self.sync_cycle = -1
        self.bench_time_ns: int | None = None  # newest BENCH_STATUS SimTime
        self.heard_ns: int | None = None  # our clock when a bench frame was last taken
        self.restarts_refused = 0

    def quiet(self, now_ns: int) -> bool:
        """The bench has been silent long enough for a restart to be genuine."""
        return self.heard_ns is None or now_ns - self.heard_ns >= self.restart_quiet_ns

    def take(self, d: Decoded, now_ns: int) -> None:
        """The frame counts: its alive counter moves on; the bench was heard."""
        self.checker.accept(d)
        self.heard_ns = now_ns

    def _stale(self, d: Decoded, refused_restart: bool) -> Verdict:
        self.checker.reject(d.name, Reject.STALE)
        self.restarts_refused += refused_restart
        return Verdict.STALE

    def sync(self, d: Decoded, now_ns: int) -> Verdict:
        """A SYNC: TAKEN (run its cycle), RESTART (run it after restarting) or STALE."""
        cycle = int(d.signals["Cycle"])
        if self.last_sync_ns is not None and cycle <= self.sync_cycle:
            if cycle != 0 and self.sync_cycle - cycle <= STALE_SYNC_WINDOW:
                return self._stale(d, False)
            if not self.quiet(now_ns):
                return self._stale(d, True)
            self.take(d, now_ns)
            return Verdict.RESTART
        self.take(d, now_ns)
        return Verdict.TAKEN

    def ran(self, d: Decoded) -> tuple[int, int]:
        """Record SYNC ``d``'s cycle as run; returns (cycle, its time [ns])."""
        cycle, t_ns = int(d.signals["Cycle"]), sim_time_ns(d.signals["SimTime"])
        self.last_sync_ns, self.sync_cycle = t_ns, cycle
        return cycle, t_ns

    def bench_status(self, d: Decoded, now_ns: int) -> Verdict:
        """A BENCH_STATUS: TAKEN (the bench's time moves on), RESTART (it went back after a
        quiet bench) or STALE (it went back while the bench was live)."""
        bench_ns = sim_time_ns(d.signals["SimTime"])
        last = self.bench_time_ns
        if last is not None and bench_ns < last:
            if not self.quiet(now_ns):
                return self._stale(d, True)
            self.take(d, now_ns)
            self.bench_time_ns = bench_ns
            return Verdict.RESTART
        self.take(d, now_ns)
        self.bench_time_ns = bench_ns
        return Verdict.TAKEN

    def restarted(self, bench_ns: int | None = None) -> None:
        """A new run of the bench: the cycle bookkeeping starts again."""
        self.last_sync_ns = None
        self.sync_cycle = -1
        self.bench_time_ns = bench_ns
