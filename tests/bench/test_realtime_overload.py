"""A realtime bench slower than the wall clock still ends on time and keeps sending sensors.

An emulated or overloaded machine (the CI's QEMU guest) runs the plant slower than real
time. The bench is driven here by a clock that runs ``CLOCK_SPEEDUP`` times faster than
the wall clock, so it cannot keep up, while a peer floods it with valid flight-software
command frames, as a flight-software process on its own timer does.
"""

from __future__ import annotations

import threading
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

from bench.node import NS_PER_S, BenchNode, Clock
from bench.plant import STEP_NS
from bench.scenario import load_scenario
from dbc import load_database
from dbc.bus import open_bus
from dbc.codec import Encoder, cycle_time_ns

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.toml"
CLOCK_SPEEDUP = 200  # the bench's clock against the wall clock: far beyond what it keeps up with
DURATION_S = 2.0  # of plant time
PEER_GAP_S = 2e-4  # between the peer's frames: a stream the bench never drains by itself
PEER_LIMIT_S = 60.0  # of wall time: the run must end within it, while the peer still floods
IMU_SHARE_MIN = 0.9  # of the IMU samples due in DURATION_S that must have been sent


@dataclass
class FastClock(Clock):
    """A bench clock running CLOCK_SPEEDUP times faster than the wall clock."""

    def now_ns(self) -> int:
        """Scaled nanoseconds since the clock was made."""
        return (time.monotonic_ns() - self.t0_ns) * CLOCK_SPEEDUP


def _flood_commands(spec: str, stop: threading.Event, n_frames: int) -> None:
    """Send FSW_STATUS, then THR_CMD_* frames (valves closed) until ``stop`` or the limit."""
    db = load_database()
    enc = Encoder(db)
    bus = open_bus(spec)
    try:
        bus.send(enc.message("FSW_STATUS", {
            "Mode": 1, "Cycle": 0, "Overruns": 0, "FdirFlags": 0, "AllocSaturated": 0,
            "AllocResidual": 0.0, "AllocForceResidual": 0.0}))
        deadline = time.monotonic() + PEER_LIMIT_S
        cycle = 0
        while not stop.is_set() and time.monotonic() < deadline:
            for i in range(n_frames):
                name = f"THR_CMD_{i}"
                msg = db.get_message_by_name(name)
                sig = {s.name: 0 for s in msg.signals if s.name not in ("CRC", "AliveCounter")}
                sig["Cycle"] = cycle % 256
                bus.send(enc.message(name, sig))
                stop.wait(PEER_GAP_S)
            cycle += 1
    finally:
        bus.shutdown()


def test_overloaded_realtime_run_ends_at_its_duration(tmp_path: Path) -> None:
    """A bench behind the wall clock ends at the run's duration with sensors sent throughout."""
    sc = load_scenario(SCENARIO)
    db = load_database()
    spec = f"virtual:overload-{uuid.uuid4().hex}"
    bus = open_bus(spec)
    node = BenchNode(sc, db, bus, tmp_path, "realtime", 1, spec)
    stop = threading.Event()
    peer = threading.Thread(target=_flood_commands, args=(spec, stop, node.n_cmd_frames))
    # the run in a thread of its own, so that a bench that never ends fails the test
    runner = threading.Thread(target=node.run_realtime, args=(DURATION_S, FastClock()),
                              daemon=True)
    peer.start()
    runner.start()
    runner.join(PEER_LIMIT_S)
    finished_while_flooded = not runner.is_alive() and peer.is_alive()
    stop.set()
    peer.join()
    assert finished_while_flooded, f"the realtime run did not end within {PEER_LIMIT_S} s"
    bus.shutdown()
    summary = node.close(DURATION_S)
    end_ns = round(DURATION_S * NS_PER_S)
    assert end_ns <= node.plant.t_ns < end_ns + STEP_NS
    imu_due = DURATION_S * NS_PER_S / cycle_time_ns(db, "IMU_RATE")
    assert node.sent["IMU_RATE"] >= IMU_SHARE_MIN * imu_due
    misses = summary["deadline_misses"]
    assert misses["bench_late"] > 0
    assert misses["bench_max_lag_ms"] > node.period_ns / 1e6
