"""The flight-software process logic over a real python-can bus (virtual, in-process).

A scripted bench on the other end sends sensor frames and SYNCs; the node must answer each
SYNC with THR_CMD frames for that cycle, reject stale SYNCs, go to SAFE mode (all valves
closed) when IMU frames stop for 3 of their periods, report FSW_FDIR with each status, and
start again cleanly when the bench restarts (SYNC back to 0, or BENCH_STATUS time going
backwards).
"""

from __future__ import annotations

import threading
import time
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import can
import pytest

from bench.scenario.load import load_scenario
from dbc.codec import Encoder, FrameChecker, cycle_time_ns
from dbc.database import load_database
from dbc.quaternion import pack_quaternion
from flight_sw.bench_link import RESTART_QUIET_NS
from flight_sw.config import build_computer
from flight_sw.frames import FULL_ON_OVERLAP_S
from flight_sw.modes import FdirFlag, Mode, SensorFlag
from flight_sw.node import HEARTBEAT_RETRY_S, FlightNode

QUICKSTART = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.toml"
RECV_TIMEOUT_S = 5.0
COUNT_POLL_S = 0.001  # polling the node's counters until a deadline
PERIOD_S = 0.02
IMU_PER_CYCLE = 2
SAFE_AFTER_CYCLES = 2  # 3 IMU periods (30 ms) of silence are over within 2 control cycles
FULL_ON_S = PERIOD_S + FULL_ON_OVERLAP_S
GYRO_LSB_RAD_S = 2e-5  # the scripted gyro steps by one LSB per sample (a live sensor)
HEARTBEAT_WAIT_S = 3.0  # the node repeats FSW_STATUS after 1 s without frames
# once cycling in lockstep it waits longer (the default is 5 s; shortened for the test)
TEST_SILENCE_HEARTBEAT_S = HEARTBEAT_RETRY_S + 0.5


class Bench:
    """Scripted bench side of the bus."""

    def __init__(self, bus: can.BusABC) -> None:
        self.db = load_database()
        self.bus = bus
        self.enc = Encoder(self.db)
        self.chk = FrameChecker(
            self.db,
            accept=frozenset({"THR_CMD_0", "THR_CMD_1", "FSW_STATUS", "FSW_ATT_EST", "FSW_FDIR"}),
        )
        self.n_imu = 0

    def send(self, name: str, sig: dict[str, Any]) -> None:
        self.bus.send(self.enc.message(name, sig))

    def sensors(self, imu: bool = True) -> None:
        if imu:
            for _ in range(IMU_PER_CYCLE):
                self.n_imu += 1
                rate = (self.n_imu % 7) * GYRO_LSB_RAD_S
                self.send("IMU_RATE", {"Valid": 1, "RateX": rate, "RateY": 0.0, "RateZ": 0.0})
        self.send("STR_QUAT", {"Valid": 1, **pack_quaternion((1.0, 0.0, 0.0, 0.0))})

    def bench_status(self, sim_time_s: float) -> None:
        self.send(
            "BENCH_STATUS",
            {"SimTime": sim_time_s, "ActiveFaults": 0, "Health": 0, "FaultCmdCounter": 15,
             "FaultCmdRejected": 0},
        )

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


@pytest.fixture(params=["virtual", "hilbus"])
def setup(request: pytest.FixtureRequest, runtime: Path) -> Iterator[tuple[FlightNode, Bench]]:
    """A FlightNode running its lockstep loop on a private bus (python-can's in-process
    virtual bus, and hilbus, where a cycle's frames go out as one burst), and a bench."""
    channel = f"fsw-{uuid.uuid4().hex[:8]}"
    fsw_bus = can.Bus(interface=request.param, channel=channel)
    bench_bus = can.Bus(interface=request.param, channel=channel)
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
        bench.bench_status(0.0)
        t.join(RECV_TIMEOUT_S)
        fsw_bus.shutdown()
        bench_bus.shutdown()


def test_each_sync_is_answered_for_its_cycle(setup: tuple[FlightNode, Bench]) -> None:
    """THR_CMD carries the SYNC's cycle number and on-times within the period (or full on)."""
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
        # within the period, or a full-on pulse stretched to overlap the next command
        assert all(0.0 <= x <= PERIOD_S or x == pytest.approx(FULL_ON_S) for x in on)
    assert node.fc.mode == Mode.NOMINAL


def test_a_cycle_sends_status_first_and_commands_last(setup: tuple[FlightNode, Bench]) -> None:
    """Cycle 0 (a status cycle): FSW_STATUS, FSW_ATT_EST, FSW_FDIR, then THR_CMD_0 and _1, and
    the node counts each frame it sent."""
    node, bench = setup
    bench.sensors()
    bench.send("SYNC", {"Cycle": 0, "SimTime": 0.0})
    names = []
    while "THR_CMD_1" not in names:
        msg = bench.bus.recv(RECV_TIMEOUT_S)
        assert msg is not None, "no answer to SYNC(0)"
        d = bench.chk.check(msg)
        if d is not None:
            names.append(d.name)
    assert names == ["FSW_STATUS", "FSW_ATT_EST", "FSW_FDIR", "THR_CMD_0", "THR_CMD_1"]
    # the node counts a burst once it is sent: the bench can hear it first
    expected = len(names) + 1  # and the boot heartbeat
    deadline = time.monotonic() + RECV_TIMEOUT_S
    while sum(node.stats.sent.values()) < expected and time.monotonic() < deadline:
        time.sleep(COUNT_POLL_S)
    assert sum(node.stats.sent.values()) == expected, f"counted {node.stats.sent}"
    assert node.stats.sent["THR_CMD_0"] == node.stats.sent["THR_CMD_1"] == 1
    assert node.stats.sent["FSW_STATUS"] == 2  # the boot heartbeat, then cycle 0's


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


def test_safe_mode_entry_is_reported_in_the_same_cycle(setup: tuple[FlightNode, Bench]) -> None:
    """The cycle that enters SAFE sends FSW_STATUS (Mode SAFE) at once, between status cycles."""
    node, bench = setup
    for k in range(3):  # cycle 0 is a status cycle; 1..4 are not
        bench.sensors()
        got = bench.sync(k)
        assert ("FSW_STATUS" in got) == (k == 0)
    reports = []
    for k in range(3, 3 + SAFE_AFTER_CYCLES):
        bench.sensors(imu=False)
        reports.append(bench.sync(k).get("FSW_STATUS"))
    assert k % node.status_every != 0  # not a regular status cycle
    sent = [r for r in reports if r is not None]
    assert len(sent) == 1 and sent[0]["Mode"] == Mode.SAFE
    assert int(sent[0]["FdirFlags"]) & FdirFlag.SAFE_LATCHED


def test_fsw_fdir_is_sent_with_each_status(setup: tuple[FlightNode, Bench]) -> None:
    """Status cycles carry FSW_FDIR: all 8 thrusters available, no failure, no sensor flag."""
    _, bench = setup
    bench.sensors()
    got = bench.sync(0)
    fdir = got["FSW_FDIR"]
    assert fdir["AvailableMask"] == 0xFF and fdir["FailedThruster"] == 31
    assert fdir["FailureKind"] == 0 and fdir["SensorFlags"] == 0


def test_sync_back_to_zero_is_a_bench_restart(setup: tuple[FlightNode, Bench]) -> None:
    """SYNC(0) after SYNC(6) from a bench that was quiet (here: no quiet period asked):
    answered, the computer starts again, SensorFlags bit 3 set."""
    node, bench = setup
    node.link.restart_quiet_ns = 0
    for k in range(7):
        bench.sensors()
        bench.sync(k)
    assert node.fc.mode == Mode.NOMINAL
    bench.sensors()
    got = bench.sync(0)
    assert got["THR_CMD_0"]["Cycle"] == 0
    assert node.fc.restarts == 1 and node.stats.restarts == 1
    assert got["FSW_FDIR"]["SensorFlags"] & SensorFlag.BENCH_RESTART
    assert got["FSW_STATUS"]["FdirFlags"] & FdirFlag.BENCH_RESTART
    for k in range(1, 6):
        bench.sensors()
        got = bench.sync(k)
        assert got["THR_CMD_0"]["Cycle"] == k
    assert node.fc.mode == Mode.NOMINAL
    assert node.checker.summary()["SYNC"]["rejected"] == {}


def test_bench_time_going_backwards_is_a_restart(setup: tuple[FlightNode, Bench]) -> None:
    """BENCH_STATUS SimTime 0.1 s then 0.0 s from a quiet bench: restart; the next SYNC(0)
    is answered."""
    node, bench = setup
    node.link.restart_quiet_ns = 0
    for k in range(6):
        bench.sensors()
        if k == 5:
            bench.bench_status(0.1)
        bench.sync(k)
    bench.bench_status(0.0)
    bench.sensors()
    got = bench.sync(0)
    assert got["THR_CMD_0"]["Cycle"] == 0
    assert node.fc.restarts == 1


def test_heartbeat_resumes_when_the_bench_goes_quiet(setup: tuple[FlightNode, Bench]) -> None:
    """Once cycling, after its lockstep silence (not 1 s) the node sends FSW_STATUS alone."""
    node, bench = setup
    node.lockstep_silence_heartbeat_s = TEST_SILENCE_HEARTBEAT_S
    for k in range(3):
        bench.sensors()
        bench.sync(k)
    assert bench.bus.recv(HEARTBEAT_RETRY_S) is None  # a bench paused this long is not gone
    msg = bench.bus.recv(HEARTBEAT_WAIT_S)
    assert msg is not None
    d = bench.chk.check(msg)
    assert d is not None and d.name == "FSW_STATUS"
    assert d.signals["Mode"] == Mode.NOMINAL


def test_replayed_sync_zero_from_a_live_bench_is_stale_not_a_restart(
        setup: tuple[FlightNode, Bench]) -> None:
    """The first SYNC(0), replayed while the bench answers every cycle: rejected as stale
    (a refused restart), never a restart; the next genuine SYNC is answered as usual."""
    node, bench = setup
    assert node.link.restart_quiet_ns == RESTART_QUIET_NS
    for k in range(4):
        bench.sensors()
        bench.sync(k)
    bench.send("SYNC", {"Cycle": 0, "SimTime": 0.0})  # a valid frame: a fresh alive counter
    bench.sensors()
    got = bench.sync(4)
    assert got["THR_CMD_0"]["Cycle"] == 4
    assert node.fc.restarts == 0 and node.stats.restarts == 0
    assert node.link.restarts_refused == 1
    assert node.checker.summary()["SYNC"]["rejected"] == {"stale": 1}


def test_own_messages_from_another_node_are_counted_unexpected(
        setup: tuple[FlightNode, Bench]) -> None:
    """A well-formed THR_CMD_0 sent by someone else is counted ``unexpected`` by the flight
    software (a second sender of its messages), and changes nothing."""
    node, bench = setup
    bench.sensors()
    bench.sync(0)
    sig = dict.fromkeys(node.icd.payload["THR_CMD_0"], 0)
    bench.bus.send(bench.enc.message("THR_CMD_0", sig))
    bench.sensors()
    got = bench.sync(1)
    assert got["THR_CMD_0"]["Cycle"] == 1
    assert node.checker.summary()["THR_CMD_0"]["rejected"] == {"unexpected": 1}
