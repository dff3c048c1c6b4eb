"""The live monitor: its picture of the bus (pure), and the terminal UI driven headless by
textual's own test driver over a python-can virtual bus."""

from __future__ import annotations

import asyncio
import uuid

import can
import pytest

from bench.operator.monitor import BusReader, make_app, message_rows, text_picture
from bench.operator.monitor_state import MonitorState
from dbc.codec import Encoder
from dbc.database import load_database

PERIOD_NS = 10_000_000
N_IMU = 20
REFRESH_S = 0.05
WAIT_S = 5.0  # a hang guard for the headless UI test


def _frames() -> list[can.Message]:
    """IMU_RATE at 100 Hz, FSW_STATUS BOOT then NOMINAL, a command opening T05, and one
    IMU_RATE with its CRC broken."""
    db = load_database()
    enc = Encoder(db)
    out = []

    def frame(name: str, sig: dict[str, float | int]) -> can.Message:
        return can.Message(arbitration_id=enc.frame_id(name), data=bytes(enc.encode(name, sig)),
                           is_extended_id=False)

    imu = {s.name: 0 for s in db.get_message_by_name("IMU_RATE").signals
           if s.name not in ("CRC", "AliveCounter")}
    status = {s.name: 0 for s in db.get_message_by_name("FSW_STATUS").signals
              if s.name not in ("CRC", "AliveCounter")}
    cmd = {s.name: 0 for s in db.get_message_by_name("THR_CMD_1").signals
           if s.name not in ("CRC", "AliveCounter")}
    out.append(frame("FSW_STATUS", {**status, "Mode": 0}))
    for k in range(N_IMU):
        out.append(frame("IMU_RATE", {**imu, "Valid": 1, "RateX": 0.001 * k}))
    out.append(frame("FSW_STATUS", {**status, "Mode": 1}))
    out.append(frame("THR_CMD_1", {**cmd, "OnTime_T05": 0.005}))
    bad = frame("IMU_RATE", {**imu, "Valid": 1})
    bad.data[0] ^= 0xFF  # the CRC byte
    out.append(bad)
    return out


def test_state_counts_periods_rejects_and_events() -> None:
    """Counts per message, the 10 ms period, the broken CRC counted by cause and logged,
    the mode change logged, the opening booked to thruster 5."""
    st = MonitorState(load_database())
    for i, msg in enumerate(_frames()):
        st.feed(msg, i * PERIOD_NS)
    s = st.snapshot()
    rows = {m["name"]: m for m in s["messages"]}
    assert rows["IMU_RATE"]["count"] == N_IMU and rows["FSW_STATUS"]["count"] == 2
    assert rows["IMU_RATE"]["period_ms"] == pytest.approx(PERIOD_NS / 1e6)
    assert sum(rows["IMU_RATE"]["rejected"].values()) == 1
    assert s["vehicle"]["mode"] == "NOMINAL"
    assert s["thrusters"][5]["openings"] == 1 and len(s["thrusters"]) == 6
    assert any("mode NOMINAL" in e for e in s["events"])
    assert any("IMU_RATE rejected" in e for e in s["events"])
    assert "IMU_RATE" in text_picture(s)


def test_headless_ui_shows_what_came_over_the_bus() -> None:
    """The app reads a virtual bus in its own thread; its message table shows the counts
    of the frames sent onto the bus."""
    channel = f"mon-{uuid.uuid4().hex[:8]}"
    listen = can.Bus(interface="virtual", channel=channel)
    send = can.Bus(interface="virtual", channel=channel)
    reader = BusReader(listen, MonitorState(load_database()))
    reader.start()
    frames = _frames()

    async def drive() -> list[tuple[str, ...]]:
        app = make_app(reader, "test", REFRESH_S, None)
        async with app.run_test() as pilot:
            for msg in frames:
                send.send(msg)
            waited = 0.0
            while reader.snapshot()["frames"] < len(frames) and waited < WAIT_S:
                await pilot.pause(REFRESH_S)
                waited += REFRESH_S
            app.redraw()  # the picture of every frame, not the last timer's
            await pilot.pause()
            table = app.query_one("#messages")
            return [tuple(str(c) for c in table.get_row_at(i)) for i in range(table.row_count)]

    try:
        shown = asyncio.run(drive())
    finally:
        reader.stop()
        listen.shutdown()
        send.shutdown()
    assert shown == message_rows(reader.snapshot())
    counts = {row[1]: int(row[2]) for row in shown}
    assert counts["IMU_RATE"] == N_IMU and counts["THR_CMD_1"] == 1
