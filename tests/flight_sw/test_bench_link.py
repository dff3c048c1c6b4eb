"""Which SYNC and BENCH_STATUS frames count, and when the bench restarted (known answers)."""

from __future__ import annotations

from dbc.codec import Decoded, Encoder, FrameChecker
from dbc.database import load_database
from dbc.icd import BENCH, Icd
from flight_sw.bench_link import RESTART_QUIET_NS, STALE_SYNC_WINDOW, BenchLink, Verdict

DB = load_database()
ICD = Icd.from_database(DB)
PERIOD_S = ICD.control_period_ns / 1e9
LIVE_NS = 1_000_000  # 1 ms between frames: a live bench


class Bench:
    """Encodes the bench's frames and checks them as the flight software does."""

    def __init__(self) -> None:
        self.enc = Encoder(DB)
        self.checker = FrameChecker(DB, accept=ICD.sent_by(BENCH))
        self.link = BenchLink(self.checker)
        self.now_ns = 0

    def frame(self, name: str, signals: dict[str, float | int]) -> Decoded:
        self.now_ns += LIVE_NS
        d = self.checker.inspect(self.enc.message(name, signals), self.now_ns)
        assert d is not None
        return d

    def sync(self, k: int) -> Verdict:
        d = self.frame("SYNC", {"Cycle": k, "SimTime": k * PERIOD_S})
        verdict = self.link.sync(d, self.now_ns)
        if verdict is not Verdict.STALE:
            self.link.ran(d)
        return verdict

    def status(self, t_s: float) -> Verdict:
        d = self.frame("BENCH_STATUS", {"SimTime": t_s, "ActiveFaults": 0, "Health": 0,
                                        "FaultCmdCounter": ICD.fault_cmd_counter_none,
                                        "FaultCmdRejected": 0})
        return self.link.bench_status(d, self.now_ns)


def test_cycles_in_order_are_taken_and_recorded() -> None:
    """SYNC 0..4: each taken; the last cycle and its time are kept."""
    b = Bench()
    assert [b.sync(k) for k in range(5)] == [Verdict.TAKEN] * 5
    assert b.link.sync_cycle == 4 and b.link.last_sync_ns == round(4 * PERIOD_S * 1e9)


def test_a_recent_old_sync_is_stale_and_takes_no_counter() -> None:
    """A SYNC up to STALE_SYNC_WINDOW cycles back is stale; the next one still counts."""
    b = Bench()
    for k in range(6):
        b.sync(k)
    assert b.sync(5 - STALE_SYNC_WINDOW) is Verdict.STALE
    assert b.sync(6) is Verdict.TAKEN
    assert b.checker.summary()["SYNC"]["rejected"] == {"stale": 1}
    assert b.link.restarts_refused == 0


def test_sync_zero_from_a_live_bench_is_a_refused_restart() -> None:
    """SYNC(0) while the bench answers every millisecond: stale, a refused restart."""
    b = Bench()
    for k in range(6):
        b.sync(k)
    assert b.sync(0) is Verdict.STALE
    assert b.link.restarts_refused == 1


def test_sync_zero_after_a_quiet_bench_is_a_restart() -> None:
    """SYNC(0) after the bench was silent for RESTART_QUIET_NS: a restart."""
    b = Bench()
    for k in range(6):
        b.sync(k)
    b.now_ns += RESTART_QUIET_NS
    assert b.sync(0) is Verdict.RESTART


def test_bench_time_going_back_is_a_restart_only_after_quiet() -> None:
    """BENCH_STATUS 0.5 s then 0.1 s: stale while live; after a quiet period, a restart."""
    b = Bench()
    assert b.status(0.5) is Verdict.TAKEN
    assert b.status(0.1) is Verdict.STALE and b.link.restarts_refused == 1
    assert b.link.bench_time_ns == 500_000_000
    b.now_ns += RESTART_QUIET_NS
    assert b.status(0.1) is Verdict.RESTART and b.link.bench_time_ns == 100_000_000
