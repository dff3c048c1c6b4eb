"""Encoder/FrameChecker: round trips, and every bad frame counted under its own cause."""

from __future__ import annotations

import can
import pytest

from dbc import e2e
from dbc.codec import Encoder, FrameChecker, Reject, data_id
from dbc.database import load_database
from dbc.errors import IcdError

IMU = {"Valid": 1, "RateX": 0.1, "RateY": -0.2, "RateZ": 0.00002}
RATE_LSB = 2e-5


@pytest.fixture(scope="module")
def db():  # type: ignore[no-untyped-def]
    """The project's DBC."""
    return load_database()


def _frame(data: bytes, can_id: int = 0x040, **kw: object) -> can.Message:
    return can.Message(arbitration_id=can_id, is_extended_id=False, data=data, **kw)  # type: ignore[arg-type]


def test_round_trip_within_one_lsb(db) -> None:  # type: ignore[no-untyped-def]
    """Encoded signals decode to the same values within one LSB."""
    enc, chk = Encoder(db), FrameChecker(db)
    d = chk.check(enc.message("IMU_RATE", IMU))
    assert d is not None and d.name == "IMU_RATE"
    for k, v in IMU.items():
        assert d.signals[k] == pytest.approx(v, abs=RATE_LSB / 2 + 1e-12)


def test_counter_advances_and_wraps(db) -> None:  # type: ignore[no-untyped-def]
    """The alive counter runs 0..14 and wraps, accepted without gaps."""
    enc, chk = Encoder(db), FrameChecker(db)
    seen = [chk.check(enc.message("IMU_RATE", IMU)) for _ in range(40)]
    assert [d.counter for d in seen if d] == [i % 15 for i in range(40)]
    assert chk.stats["IMU_RATE"].gaps == 0


def test_bad_frames_are_counted_by_cause(db) -> None:  # type: ignore[no-untyped-def]
    """Unknown ID, DLC, CRC, repeated counter, range, error and remote frames each count once."""
    enc, chk = Encoder(db), FrameChecker(db)
    good = bytes(enc.encode("IMU_RATE", IMU))
    assert chk.check(_frame(good)) is not None
    assert chk.check(_frame(good)) is None  # same counter again
    assert chk.check(_frame(good[:7])) is None
    bad_crc = bytearray(enc.encode("IMU_RATE", IMU))
    bad_crc[5] ^= 0x10
    assert chk.check(_frame(bytes(bad_crc))) is None
    assert chk.check(_frame(good, can_id=0x555)) is None
    assert chk.check(can.Message(arbitration_id=0x040, is_error_frame=True)) is None
    assert (
        chk.check(
            can.Message(arbitration_id=0x040, is_extended_id=False, is_remote_frame=True, dlc=8)
        )
        is None
    )
    # FAULT_CMD.FaultType has 6 bits but its DBC range is 0..18: raw 63 is out of range
    fault = enc.encode(
        "FAULT_CMD", {"Action": 1, "FaultType": 1, "Target": 0, "Duration": 0, "Param": 0}
    )
    fault[1] |= 0xC0  # FaultType bits 14, 15
    fault[2] |= 0x0F  # FaultType bits 16..19
    e2e.protect(data_id(db.get_message_by_name("FAULT_CMD")), fault, e2e.counter_of(fault))
    assert chk.check(_frame(bytes(fault), can_id=0x7E0)) is None
    s = chk.summary()
    assert s["IMU_RATE"]["rejected"] == {
        Reject.COUNTER.value: 1,
        Reject.DLC.value: 1,
        Reject.CRC.value: 1,
        Reject.REMOTE_FRAME.value: 1,
    }
    assert s["0x555"]["rejected"] == {Reject.UNKNOWN_ID.value: 1}
    assert s["error_frame"]["rejected"] == {Reject.ERROR_FRAME.value: 1}
    assert s["FAULT_CMD"]["rejected"] == {Reject.RANGE.value: 1}


def test_counter_jump_is_accepted_and_gap_counted(db) -> None:  # type: ignore[no-untyped-def]
    """Lost frames show up as a gap; the new frame is still used."""
    enc, chk = Encoder(db), FrameChecker(db)
    chk.check(enc.message("IMU_RATE", IMU))
    for _ in range(3):
        enc.message("IMU_RATE", IMU)  # lost on the bus
    d = chk.check(enc.message("IMU_RATE", IMU))
    assert d is not None and d.gap == 3


def test_accept_filter_ignores_other_known_frames(db) -> None:  # type: ignore[no-untyped-def]
    """A receiver ignores (without counting) frames it does not consume."""
    enc = Encoder(db)
    chk = FrameChecker(db, accept=frozenset({"SYNC"}))
    assert chk.check(enc.message("IMU_RATE", IMU)) is None
    assert chk.summary() == {}


def test_encode_out_of_range_raises_naming_message(db) -> None:  # type: ignore[no-untyped-def]
    """Encoding a value outside the DBC range is a programming error, reported clearly."""
    with pytest.raises(IcdError, match="IMU_RATE"):
        Encoder(db).encode("IMU_RATE", {"Valid": 1, "RateX": 5.0, "RateY": 0, "RateZ": 0})
    with pytest.raises(IcdError, match="NOPE"):
        Encoder(db).encode("NOPE", {})
