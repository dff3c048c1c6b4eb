"""Bus arbitration: priority, errors and retransmission, bus-off, FD frames, and the load
of its deliveries."""

from __future__ import annotations

import itertools
import random

import pytest

from bench.wire.timing.arbiter import (
    ERROR_FRAME_BITS,
    BusArbiter,
    Delivery,
    bus_off_recovery_ns,
    failed_attempt_bits,
)
from bench.wire.timing.classic import frame_bits, wire_time_ns
from bench.wire.timing.fd import FdBits, frame_bits_fd, wire_time_fd_ns
from bench.wire.timing.load import (
    busy_ns_per_window,
    load_per_window,
    load_per_window_by_node,
    mean_peak_load,
)

SEED = 5
BITRATE_125K = 125_000
BITRATE_500K = 500_000
BITRATE_1M = 1_000_000
BITRATE_2M = 2_000_000
NS_PER_BIT_1M = 1_000
ERROR_FLAG_START_BITS_FROM_END = 11  # error flag at the ACK delimiter: + ACK delim, EOF, IFS
ERROR_FRAME_WORST_BITS = 6 + 6 + 8  # flag, superposed flags, delimiter
INTERMISSION_BITS = 3
BUS_OFF_BITS = 128 * 11
LOAD_FRACTION_TOL_NS = 1e-3  # float round-off of fraction * window length, summed


def test_arbitration_lowest_id_first_non_preemptive() -> None:
    """Simultaneous frames go out by ID; a frame on the wire is never pre-empted."""
    arb = BusArbiter(BITRATE_1M)
    s_low = arb.submit(10, 0x040, 130)
    s_sync = arb.submit(0, 0x010, 100)  # alone at t=0: starts immediately
    s_high = arb.submit(10, 0x020, 100)
    d = {x.seq: x for x in arb.resolve()}
    assert d[s_sync].start_ns == 0
    assert d[s_high].start_ns == d[s_sync].end_ns  # waits, then wins against 0x040
    assert d[s_low].start_ns == d[s_high].end_ns
    assert d[s_low].end_ns - d[s_low].start_ns == wire_time_ns(130, BITRATE_1M)


def test_resolve_horizon_keeps_later_frames_pending() -> None:
    """Frames starting after the horizon stay queued for the next resolve."""
    arb = BusArbiter(BITRATE_1M)
    arb.submit(0, 0x10, 100)
    late = arb.submit(1_000_000, 0x10, 100)
    assert [x.seq for x in arb.resolve(500_000)] == [0]
    assert [x.seq for x in arb.resolve()] == [late]


# --- errors in time ----------------------------------------------------------------------


def test_error_frame_bits_worst_case() -> None:
    """ERROR_FRAME_BITS is flag 6 + superposition 6 + delimiter 8."""
    assert ERROR_FRAME_BITS == ERROR_FRAME_WORST_BITS


def test_failed_attempt_costs_error_part_and_error_frame() -> None:
    """One failed attempt: delivered exactly (bits - 11) + error frame + intermission later."""
    bits = frame_bits(0x100, bytes(8))
    arb = BusArbiter(BITRATE_1M)
    seq = arb.submit(0, 0x100, bits, failed_attempts=1, node="fsw")
    (d,) = arb.resolve()
    lost_bits = bits - ERROR_FLAG_START_BITS_FROM_END + ERROR_FRAME_WORST_BITS + INTERMISSION_BITS
    assert (d.seq, d.attempts, d.node) == (seq, 2, "fsw")
    assert d.failed_ns == ((0, lost_bits * NS_PER_BIT_1M),)
    assert d.first_start_ns == 0
    assert d.start_ns == lost_bits * NS_PER_BIT_1M
    assert d.end_ns == (lost_bits + bits) * NS_PER_BIT_1M
    assert arb.error_ns_total == d.error_ns == lost_bits * NS_PER_BIT_1M
    assert arb.busy_ns_total == d.end_ns


def test_higher_priority_frame_wins_rearbitration() -> None:
    """A higher-priority frame queued during the error frame goes before the retry."""
    bits = frame_bits(0x100, bytes(8))
    arb = BusArbiter(BITRATE_1M)
    s_fail = arb.submit(0, 0x100, bits, failed_attempts=1)
    flag_ns = (bits - ERROR_FLAG_START_BITS_FROM_END) * NS_PER_BIT_1M
    s_high = arb.submit(flag_ns + 5 * NS_PER_BIT_1M, 0x050, 100)
    s_low = arb.submit(flag_ns + 5 * NS_PER_BIT_1M, 0x200, 100)
    d = {x.seq: x for x in arb.resolve()}
    assert d[s_high].start_ns == d[s_fail].failed_ns[0][1]
    assert d[s_fail].start_ns == d[s_high].end_ns
    assert d[s_low].start_ns == d[s_fail].end_ns


def test_fd_failed_attempt_costs_twelve_nominal_bits_more() -> None:
    """An FD attempt sends its data phase in full; - 11 + 20 + 3 nominal bits = + 12."""
    fd = frame_bits_fd(0x123, bytes(range(64)))
    extra = ERROR_FRAME_WORST_BITS + INTERMISSION_BITS - ERROR_FLAG_START_BITS_FROM_END
    assert failed_attempt_bits(fd) == FdBits(fd.nominal_bits + extra, fd.data_bits)
    arb = BusArbiter(BITRATE_500K, data_bitrate_bps=BITRATE_2M)
    arb.submit(0, 0x123, fd, failed_attempts=2)
    (d,) = arb.resolve()
    one = wire_time_fd_ns(fd, BITRATE_500K, BITRATE_2M)
    fail = wire_time_fd_ns(failed_attempt_bits(fd), BITRATE_500K, BITRATE_2M)
    assert fail == one + wire_time_ns(extra, BITRATE_500K)
    assert (d.attempts, d.start_ns, d.end_ns - d.start_ns) == (3, 2 * fail, one)


def test_retry_across_resolve_horizon_is_not_lost() -> None:
    """A frame failing before the horizon and succeeding after it is delivered later."""
    arb = BusArbiter(BITRATE_1M)
    arb.submit(0, 0x10, 100, failed_attempts=1)
    assert arb.resolve(50_000) == []
    (d,) = arb.resolve()
    assert d.attempts == 2


# --- bus-off -------------------------------------------------------------------------------


@pytest.mark.parametrize("bitrate_bps", [BITRATE_125K, BITRATE_1M])
def test_bus_off_delays_node_by_recovery_time(bitrate_bps: int) -> None:
    """A node in bus-off sends after exactly 1408 bit times; other nodes are unaffected."""
    t_off = 1_000_000
    recovery = bus_off_recovery_ns(bitrate_bps)
    assert recovery == BUS_OFF_BITS * 1_000_000_000 // bitrate_bps
    arb = BusArbiter(bitrate_bps)
    assert arb.bus_off("fsw", t_off) == t_off + recovery
    s_off = arb.submit(t_off, 0x010, 100, node="fsw")
    s_other = arb.submit(t_off, 0x700, 100, node="bench")
    s_after = arb.submit(t_off + 2 * recovery, 0x010, 100, node="fsw")
    d = {x.seq: x for x in arb.resolve()}
    assert d[s_other].start_ns == t_off
    assert d[s_off].start_ns - d[s_off].ready_ns == recovery
    assert d[s_after].start_ns == d[s_after].ready_ns


def test_bus_off_explicit_window_and_frame_on_wire() -> None:
    """A frame on the wire at bus-off completes; the next waits for the window's end."""
    arb = BusArbiter(BITRATE_1M)
    arb.bus_off("fsw", 50_000, 400_000)
    s_on_wire = arb.submit(0, 0x10, 100, node="fsw")
    s_next = arb.submit(0, 0x20, 100, node="fsw")
    d = {x.seq: x for x in arb.resolve()}
    assert d[s_on_wire].end_ns == 100_000
    assert d[s_next].start_ns == 400_000
    with pytest.raises(ValueError):
        arb.bus_off("", 0)


# --- CAN FD in the arbiter ----------------------------------------------------------------


def test_fd_frame_wire_time_in_arbiter() -> None:
    """FD frame: arbitration bits at the nominal rate + data bits at the data rate."""
    fd = frame_bits_fd(0x123, bytes(32))
    arb = BusArbiter(BITRATE_500K, data_bitrate_bps=BITRATE_2M)
    arb.submit(0, 0x123, fd)
    arb.submit(0, 0x124, 111)  # classic frame on the same bus
    first, second = arb.resolve()
    assert first.end_ns - first.start_ns == wire_time_fd_ns(fd, BITRATE_500K, BITRATE_2M)
    assert second.end_ns - second.start_ns == wire_time_ns(111, BITRATE_500K)
    with pytest.raises(ValueError):
        BusArbiter(BITRATE_500K).submit(0, 0x123, fd)


# --- bus load ------------------------------------------------------------------------------


def _random_traffic(seed: int) -> tuple[BusArbiter, list[Delivery], dict[int, str]]:
    rng = random.Random(seed)
    arb = BusArbiter(BITRATE_500K, data_bitrate_bps=BITRATE_2M)
    arb.bus_off("valves", 3_000_000)
    node_of = {}
    for _ in range(400):
        node = rng.choice(("bench", "fsw", "valves"))
        can_id = rng.randrange(0x800)
        data = rng.randbytes(rng.randrange(9))
        bits = frame_bits_fd(can_id, data) if rng.random() < 0.3 else frame_bits(can_id, data)
        fails = rng.choice((0, 0, 0, 1, 2))
        seq = arb.submit(rng.randrange(20_000_000), can_id, bits, failed_attempts=fails, node=node)
        node_of[seq] = node
    return arb, arb.resolve(), node_of


def test_arbitration_never_overlaps() -> None:
    """Attempts and error frames of all frames are disjoint and start after ready."""
    _, deliveries, _ = _random_traffic(SEED)
    intervals = sorted(iv for d in deliveries for iv in d.busy_intervals())
    assert all(a[1] <= b[0] for a, b in itertools.pairwise(intervals))
    assert all(d.ready_ns <= d.first_start_ns for d in deliveries)


def test_load_windows_sum_to_busy_time() -> None:
    """Busy time per window (total and per node) sums to the arbiter's busy time."""
    arb, deliveries, node_of = _random_traffic(SEED)
    t1 = max(d.end_ns for d in deliveries)
    window = 1_000_000 + 7  # does not divide the run: partial last window
    busy = busy_ns_per_window(deliveries, window, 0, t1)
    assert sum(b for _, b in busy) == arb.busy_ns_total
    assert arb.error_ns_total == sum(d.error_ns for d in deliveries) > 0
    loads = load_per_window(deliveries, window, 0, t1)
    assert [s for s, _ in loads] == list(range(0, t1, window))
    assert all(0.0 <= f <= 1.0 for _, f in loads)
    as_ns = sum(f * (min(s + window, t1) - s) for s, f in loads)
    assert as_ns == pytest.approx(arb.busy_ns_total, abs=LOAD_FRACTION_TOL_NS * len(loads))
    per_node = load_per_window_by_node(deliveries, window, 0, t1)
    assert per_node == load_per_window_by_node(deliveries, window, 0, t1, node_of)
    node_ns = sum(f * (min(s + window, t1) - s) for ws in per_node.values() for s, f in ws)
    assert node_ns == pytest.approx(arb.busy_ns_total, abs=LOAD_FRACTION_TOL_NS * 3 * len(loads))
    mean, peak = mean_peak_load(deliveries, window, 0, t1)
    assert mean == arb.busy_ns_total / t1
    assert peak == max(f for _, f in loads) >= mean
