"""The realtime loop: it ends on time when slower than the wall clock, loses no frame, and
applies the bus faults that need no modelled bus.

An emulated or overloaded machine (the CI's QEMU guest) runs the plant slower than real
time. The bench is driven here by a clock that runs ``OVERLOAD_SPEEDUP`` times faster than
the wall clock, so it cannot keep up, while a peer floods it with valid flight-software
command frames, as a flight-software process on its own timer does. A second case keeps
the wall clock and sends bursts far larger than the frames the loop reads per pass
(``RT_FRAMES_PER_PASS``): every frame the bus hands the bench must still be handled. The
last cases inject ``drop`` both ways and a ``delay`` (modelled bus only) in realtime.
"""

from __future__ import annotations

import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import can

from bench.node import NS_PER_S, BenchNode, Clock
from bench.realtime import RT_FRAMES_PER_PASS, Realtime
from bench.scenario.load import load_scenario
from bench.station.plant import STEP_NS
from dbc.codec import Encoder, cycle_time_ns
from dbc.database import load_database
from transport.spec import open_bus

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.toml"
OVERLOAD_SPEEDUP = 200  # the bench's clock against the wall clock: far beyond what it keeps up
# with (its own loop alone manages ~100x; the start-up no longer counts as lag)
DURATION_S = 2.0  # of plant time
PEER_GAP_S = 2e-4  # between the peer's frames: a stream the bench never drains by itself
PEER_LIMIT_S = 60.0  # of wall time: the run must end within it, while the peer still sends
IMU_SHARE_MIN = 0.9  # of the IMU samples due in DURATION_S that must have been sent
BURST_DURATION_S = 0.5  # of the wall-clock-paced case
BURSTS = 3
BURST_FRAMES = 4 * RT_FRAMES_PER_PASS  # frames per burst, sent back to back
FIRST_FRAME = 1  # the boot heartbeat, read by wait_for_fsw before the loop starts


@dataclass
class ScaledClock(Clock):
    """A bench clock running ``speedup`` times faster than the wall clock."""

    speedup: int = 1

    def now_ns(self) -> int:
        """Scaled nanoseconds since the clock was made."""
        return (time.monotonic_ns() - self.t0_ns) * self.speedup


@dataclass
class Counts:
    """Frames the bus handed the bench, and frames the realtime loop handled."""

    delivered: int = 0
    handled: int = 0
    sent: list[int] = field(default_factory=lambda: [0])


def _status(enc: Encoder) -> can.Message:
    return enc.message("FSW_STATUS", {
        "Mode": 1, "Cycle": 0, "Overruns": 0, "FdirFlags": 0, "AllocSaturated": 0,
        "AllocResidual": 0.0, "AllocForceResidual": 0.0})


def _commands(spec: str, stop: threading.Event, n_frames: int, sent: list[int]) -> None:
    """FSW_STATUS, then THR_CMD_* frames (valves closed) every PEER_GAP_S until ``stop``."""
    db = load_database()
    enc = Encoder(db)
    bus = open_bus(spec)
    try:
        bus.send(_status(enc))
        deadline = time.monotonic() + PEER_LIMIT_S
        cycle = 0
        while not stop.is_set() and time.monotonic() < deadline:
            for i in range(n_frames):
                name = f"THR_CMD_{i}"
                msg = db.get_message_by_name(name)
                sig = {s.name: 0 for s in msg.signals if s.name not in ("CRC", "AliveCounter")}
                sig["Cycle"] = cycle % 256
                bus.send(enc.message(name, sig))
                sent[0] += 1
                stop.wait(PEER_GAP_S)
            cycle += 1
    finally:
        bus.shutdown()


def _bursts(spec: str, stop: threading.Event, n_frames: int, sent: list[int]) -> None:
    """FSW_STATUS, then BURSTS bursts of BURST_FRAMES status frames, back to back."""
    enc = Encoder(load_database())
    bus = open_bus(spec)
    try:
        bus.send(_status(enc))
        for _ in range(BURSTS):
            for _ in range(BURST_FRAMES):
                bus.send(_status(enc))
                sent[0] += 1
            stop.wait(BURST_DURATION_S / (2 * BURSTS))
    finally:
        bus.shutdown()


def _run(tmp_path: Path, duration_s: float, speedup: int,
         peer: Callable[[str, threading.Event, int, list[int]], None],
         overrides: list[str] | None = None) -> tuple[BenchNode, Counts]:
    """A realtime run of the quickstart against ``peer``; every frame read is counted."""
    db = load_database()
    spec = f"virtual:rt-{uuid.uuid4().hex}"
    bus = open_bus(spec)
    counts = Counts()

    class CountingLoop(Realtime):
        """Counts the frames the realtime loop hands to its frame handler."""

        def frame(self, msg: can.Message) -> None:
            counts.handled += 1
            super().frame(msg)


    scenario = load_scenario(SCENARIO, overrides)
    node = BenchNode(scenario, db, bus, tmp_path, "realtime", 1, spec, realtime_loop=CountingLoop)
    recv = bus.recv

    def counting_recv(timeout: float | None = None) -> can.Message | None:
        msg = recv(timeout=timeout)
        counts.delivered += msg is not None
        return msg

    node.bus.recv = counting_recv  # type: ignore[method-assign]
    stop = threading.Event()
    sender = threading.Thread(target=peer, args=(spec, stop, node.n_cmd_frames, counts.sent))
    # the run in a thread of its own, so that a bench that never ends fails the test
    runner = threading.Thread(target=node.run_realtime,
                              args=(duration_s, ScaledClock(speedup=speedup)), daemon=True)
    sender.start()
    runner.start()
    runner.join(PEER_LIMIT_S)
    ended = not runner.is_alive()
    stop.set()
    sender.join()
    assert ended, f"the realtime run did not end within {PEER_LIMIT_S} s"
    bus.shutdown()
    return node, counts


def test_overloaded_realtime_run_ends_at_its_duration(tmp_path: Path) -> None:
    """A bench behind the wall clock ends at the run's duration with sensors sent throughout."""
    node, counts = _run(tmp_path, DURATION_S, OVERLOAD_SPEEDUP, _commands)
    summary = node.close(DURATION_S)
    end_ns = round(DURATION_S * NS_PER_S)
    assert end_ns <= node.plant.t_ns < end_ns + STEP_NS
    imu_due = DURATION_S * NS_PER_S / cycle_time_ns(node.db, "IMU_RATE")
    assert node.sent["IMU_RATE"] >= IMU_SHARE_MIN * imu_due
    assert counts.delivered == counts.handled + FIRST_FRAME  # no frame read, then dropped
    misses = summary["deadline_misses"]
    assert misses["bench_late"] > 0
    assert misses["bench_max_lag_ms"] > node.period_ns / 1e6


def test_bursts_beyond_a_pass_are_all_handled(tmp_path: Path) -> None:
    """Bursts of several passes' worth of frames: each frame read is handled, none lost."""
    node, counts = _run(tmp_path, BURST_DURATION_S, 1, _bursts)
    node.close(BURST_DURATION_S)
    assert counts.sent[0] == BURSTS * BURST_FRAMES
    assert counts.delivered == counts.handled + FIRST_FRAME
    assert counts.handled >= counts.sent[0]  # every burst frame (and the heartbeat) handled


def _fault(kind: str, target: str, extra: str = "") -> list[str]:
    return [f'faults=[{{t_s = 0.0, kind = "{kind}", {target}, probability = 1.0{extra}}}]']


def test_drop_in_realtime_acts_on_received_frames(tmp_path: Path) -> None:
    """drop FSW_STATUS (p = 1): every status frame read during the run is dropped, counted."""
    node, counts = _run(tmp_path, BURST_DURATION_S, 1, _bursts,
                        _fault("drop", 'message = "FSW_STATUS"'))
    summary = node.close(BURST_DURATION_S)
    assert summary["faults"][0].get("applied", True)
    assert summary["fault_effects"]["dropped"] == counts.handled == BURSTS * BURST_FRAMES
    assert summary["frames"]["FSW_STATUS"]["received"] == FIRST_FRAME  # the boot heartbeat


def test_drop_in_realtime_acts_on_sent_frames(tmp_path: Path) -> None:
    """drop IMU_RATE (p = 1): the bench sends none, and counts each one dropped."""
    node, _ = _run(tmp_path, BURST_DURATION_S, 1, _bursts, _fault("drop", 'message = "IMU_RATE"'))
    summary = node.close(BURST_DURATION_S)
    imu_due = BURST_DURATION_S * NS_PER_S / cycle_time_ns(node.db, "IMU_RATE")
    assert node.sent.get("IMU_RATE", 0) == 0
    assert summary["fault_effects"]["dropped"] >= IMU_SHARE_MIN * imu_due


def test_delay_in_realtime_is_recorded_as_not_applied(tmp_path: Path) -> None:
    """delay needs the modelled bus: recorded with applied = false and why, no effect."""
    node, _ = _run(tmp_path, BURST_DURATION_S, 1, _bursts,
                   _fault("delay", 'message = "IMU_RATE"', ", delay_s = 0.01"))
    summary = node.close(BURST_DURATION_S)
    rec = summary["faults"][0]
    assert rec["applied"] is False and "lockstep" in rec["why"]
    assert summary["fault_effects"]["delayed"] == 0
    assert node.sent["IMU_RATE"] > 0



STALL_NS = 130_000_000  # 6.5 control periods


@dataclass
class FixedClock(Clock):
    """A clock that reads ``at_ns`` (no wall clock)."""

    at_ns: int = 0

    def now_ns(self) -> int:
        """The fixed reading."""
        return self.at_ns


def test_a_command_that_finds_the_plant_behind_counts_it_late(tmp_path: Path) -> None:
    """A command frame arriving 130 ms after the plant's time: counted before it catches up."""
    db = load_database()
    spec = f"virtual:rt-{uuid.uuid4().hex}"
    bus = open_bus(spec)
    node = BenchNode(load_scenario(SCENARIO), db, bus, tmp_path, "realtime", 1, spec)
    msg = db.get_message_by_name("THR_CMD_0")
    sig = {s.name: 0 for s in msg.signals if s.name not in ("CRC", "AliveCounter")}
    Realtime(node, FixedClock(at_ns=STALL_NS)).frame(Encoder(db).message("THR_CMD_0", sig))
    bus.shutdown()
    misses = node.close(0.0)["deadline_misses"]
    assert misses["bench_late"] == 1
    assert misses["bench_max_lag_ms"] == STALL_NS / 1e6
