"""The flight-software process logic over a real python-can bus (virtual, in-process).

A scripted bench on the other end sends sensor frames and SYNCs; the node must answer each
SYNC with THR_CMD frames for that cycle, reject stale SYNCs, and go to SAFE mode (all valves
closed) when IMU frames stop for 3 of their periods.
"""

from __future__ import annotations

import threading
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import can
import pytest

from bench.scenario import load_scenario
from dbc import load_database
from dbc.codec import Encoder, FrameChecker, cycle_time_ns
from dbc.quaternion import pack_quaternion
from flight_sw.config import build_computer
from flight_sw.modes import FdirFlag, Mode
from flight_sw.node import FlightNode

QUICKSTART = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.toml"
RECV_TIMEOUT_S = 5.0
PERIOD_S = 0.02
IMU_PER_CYCLE = 2
SAFE_AFTER_CYCLES = 2  # 3 IMU periods (30 ms) of silence are over within 2 control cycles


class Bench:
    """Scripted bench side of the bus."""

    def __init__(self, bus: can.BusABC) -> None:
        self.db = load_database()
        self.bus = bus
        self.enc = Encoder(self.db)
        self.chk = FrameChecker(
            self.db, accept=frozenset({"THR_CMD_0", "THR_CMD_1", "FSW_STATUS", "FSW_ATT_EST"})
        )

    def send(self, name: str, sig: dict[str, Any]) -> None:
        self.bus.send(self.enc.message(name, sig))

    def sensors(self, imu: bool = True) -> None:
        if imu:
            for _ in range(IMU_PER_CYCLE):
                self.send("IMU_RATE", {"Valid": 1, "RateX": 0.0, "RateY": 0.0, "RateZ": 0.0})
        self.send("STR_QUAT", {"Valid": 1, **pack_quaternion((1.0, 0.0, 0.0, 0.0))})

    def sync(self, k: int) -> dict[str, dict[str, float]]:
        """SYNC(k), then collect the answer up to the last THR_CMD frame."""
        self.send("SYNC", {"Cycle": k, "SimTime": k * PERIOD_S})
        got: dict[str, dict[str, float]] = {}
        while "THR_CMD_1" not in got:
            msg = self.bus.recv(RECV_TIMEOUT_S)
            assert msg is not None, f"no answer to SYNC({k})"
            d = self.chk.check(msg)
            if d is not None:
                got[d.name] = d.signals  # type: ignore[assignment]
        return got


@pytest.fixture
def setup() -> Iterator[tuple[FlightNode, Bench]]:
    """A FlightNode running its lockstep loop on a private virtual bus, and a bench."""
    channel = f"fsw-{uuid.uuid4().hex[:8]}"
    fsw_bus = can.Bus(interface="virtual", channel=channel)
    bench_bus = can.Bus(interface="virtual", channel=channel)
    db = load_database()
    fc = build_computer(
        load_scenario(QUICKSTART).fsw_config(),
        cycle_time_ns(db, "THR_CMD_0"),
        cycle_time_ns(db, "IMU_RATE"),
        {"IMU_RATE": cycle_time_ns(db, "IMU_RATE"), "STR_QUAT": cycle_time_ns(db, "STR_QUAT")},
    )
    node = FlightNode(db, fsw_bus, fc)
    t = threading.Thread(target=node.run_lockstep, daemon=True)
    t.start()
    bench = Bench(bench_bus)
    heartbeat = bench.bus.recv(RECV_TIMEOUT_S)
    assert heartbeat is not None and bench.chk.check(heartbeat) is not None
    try:
        yield node, bench
    finally:
        node._stop = True
        bench.send("BENCH_STATUS", {"SimTime": 0.0, "ActiveFaults": 0, "Health": 0})
        t.join(RECV_TIMEOUT_S)
        fsw_bus.shutdown()
        bench_bus.shutdown()


def test_each_sync_is_answered_for_its_cycle(setup: tuple[FlightNode, Bench]) -> None:
    """THR_CMD carries the SYNC's cycle number and on-times within the period."""
    node, bench = setup
    for k in range(5):
        bench.sensors()
        got = bench.sync(k)
        assert got["THR_CMD_0"]["Cycle"] == k and got["THR_CMD_1"]["Cycle"] == k
        on = [
            v
            for f in ("THR_CMD_0", "THR_CMD_1")
            for n, v in got[f].items()
            if n.startswith("OnTime")
        ]
        assert all(0.0 <= x <= PERIOD_S for x in on)
    assert node.fc.mode == Mode.NOMINAL


def test_stale_sync_is_rejected_and_counted(setup: tuple[FlightNode, Bench]) -> None:
    """A SYNC whose cycle does not advance is counted as stale, not answered."""
    node, bench = setup
    bench.sensors()
    bench.sync(3)
    bench.send("SYNC", {"Cycle": 2, "SimTime": 2 * PERIOD_S})
    bench.sensors()
    got = bench.sync(4)
    assert got["THR_CMD_0"]["Cycle"] == 4
    assert node.checker.summary()["SYNC"]["rejected"] == {"stale": 1}


def test_imu_silence_latches_safe_mode_with_valves_closed(setup: tuple[FlightNode, Bench]) -> None:
    """IMU frames stop: within 2 cycles the mode is SAFE, IMU_LOST flagged, every on-time 0."""
    node, bench = setup
    for k in range(3):
        bench.sensors()
        bench.sync(k)
    for k in range(3, 3 + SAFE_AFTER_CYCLES):
        bench.sensors(imu=False)
        got = bench.sync(k)
    assert node.fc.mode == Mode.SAFE
    assert all(
        v == 0
        for f in ("THR_CMD_0", "THR_CMD_1")
        for n, v in got[f].items()
        if n.startswith("OnTime")
    )
    bench.sensors()  # IMU back: safe mode stays latched
    got = bench.sync(10)
    assert node.fc.mode == Mode.SAFE
    status = node.fc.cycle(11 * 20_000_000)
    assert status.fdir_flags & FdirFlag.SAFE_LATCHED
