"""Frames heard before the flight software's first valid frame are traced, bad ones too."""

from __future__ import annotations

import uuid
from pathlib import Path

import can

from bench.node import BenchNode
from bench.results.record import run_file
from bench.scenario.load import load_scenario
from dbc.codec import Encoder
from dbc.database import load_database
from transport.spec import open_bus

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.toml"
UNKNOWN_ID = 0x7FE  # not in the DBC
CRC_BYTE = 0  # E2E profile 1 style: the CRC-8 is byte 0


def _status(enc: Encoder) -> can.Message:
    return enc.message("FSW_STATUS", {
        "Mode": 1, "Cycle": 0, "Overruns": 0, "FdirFlags": 0, "AllocSaturated": 0,
        "AllocResidual": 0.0, "AllocForceResidual": 0.0})


def test_wait_for_fsw_traces_every_frame_heard(tmp_path: Path) -> None:
    """An unknown ID and a bad-CRC status before the valid heartbeat: all three in trace.asc."""
    db = load_database()
    spec = f"virtual:st-{uuid.uuid4().hex}"
    bench_bus, peer = open_bus(spec), open_bus(spec)
    try:
        node = BenchNode(load_scenario(SCENARIO), db, bench_bus, tmp_path, "lockstep", 1, spec)
        enc = Encoder(db)
        bad = _status(enc)
        bad.data[CRC_BYTE] ^= 0xFF
        sent = [can.Message(arbitration_id=UNKNOWN_ID, is_extended_id=False, data=b"\x01"),
                bad, _status(enc)]
        for msg in sent:
            peer.send(msg)
        node.wait_for_fsw()
        summary = node.close(0.0)
    finally:
        peer.shutdown()
        bench_bus.shutdown()
    with can.LogReader(str(run_file(tmp_path, "trace.asc"))) as reader:
        traced = [m for m in reader if not m.is_error_frame]
    assert [m.arbitration_id for m in traced] == [m.arbitration_id for m in sent]
    assert [bytes(m.data) for m in traced] == [bytes(m.data) for m in sent]
    assert all(m.timestamp == 0.0 and m.is_rx for m in traced)
    status = summary["frames"]["FSW_STATUS"]
    assert status["received"] == 2 and sum(status["rejected"].values()) == 1  # the bad CRC
