"""The receive path on recorded frame sequences: a rejected frame is counted by cause and has
no other effect (no counter, no cycle slot, no command); second senders leave evidence."""

from __future__ import annotations

import can
import numpy as np
import pytest

from bench.station.faults import FaultSpec
from bench.wire.receipt import Receipt
from dbc import e2e
from dbc.codec import Encoder, FrameChecker, Reject
from dbc.database import load_database
from dbc.icd import BENCH, FSW, OPERATOR, Icd

DB = load_database()
ICD = Icd.from_database(DB)
T_NS = 1_000_000_000  # any receiver time: the streams below are live (frames close together)
PERIOD_NS = ICD.control_period_ns


def _receipt(faults: list[FaultSpec] | None = None) -> Receipt:
    checker = FrameChecker(DB, accept=ICD.sent_by(FSW) | ICD.sent_by(OPERATOR),
                           own=ICD.sent_by(BENCH))
    specs = faults or []
    counts = dict.fromkeys(("dropped", "delayed", "corrupted", "duplicated", "babbled",
                            "failed_attempts"), 0)
    return Receipt(ICD, checker, np.random.default_rng(1), counts, lambda: specs)


def _command(enc: Encoder, cycle: int, on_s: float = 0.0, frame: int = 0,
             counter: int | None = None) -> can.Message:
    name = ICD.command_frames[frame]
    sig: dict[str, float | int] = dict.fromkeys(ICD.payload[name], 0)
    sig["Cycle"] = cycle % ICD.command_cycle_modulus
    sig[ICD.on_time_signals[frame * ICD.thrusters_per_command]] = on_s
    return can.Message(arbitration_id=ICD.frame_id[name], is_extended_id=False,
                       data=enc.encode(name, sig, counter))


def _taken(r: Receipt, msg: can.Message, cycle: int | None, t_ns: int = T_NS) -> list:
    return [a for a in r.receive(msg, t_ns, cycle) if a.decoded is not None]


def test_genuine_commands_are_taken_once_per_cycle() -> None:
    """One THR_CMD_0 per cycle, counters in sequence: each is taken."""
    r, enc = _receipt(), Encoder(DB)
    for k in range(20):
        assert len(_taken(r, _command(enc, k), k)) == 1
    assert r.second_sender == {}


def test_bad_crc_command_is_rejected_and_the_genuine_one_still_taken() -> None:
    """A THR_CMD_0 with a spoiled CRC is counted ``crc``, not taken, not an injected loss."""
    r, enc = _receipt(), Encoder(DB)
    _taken(r, _command(enc, 0), 0)
    bad = _command(Encoder(DB), 1)
    bad.data = bytearray(bad.data)
    bad.data[0] ^= 0xFF
    (a,) = r.receive(bad, T_NS, 1)
    assert a.decoded is None and a.cause is Reject.CRC and not a.injected_loss
    assert len(_taken(r, _command(enc, 1), 1)) == 1


def test_extended_id_with_a_command_number_is_no_command() -> None:
    """A 29-bit frame numbered like THR_CMD_0 is counted ``extended_id`` and has no name."""
    r, enc = _receipt(), Encoder(DB)
    msg = _command(enc, 0)
    msg.is_extended_id = True
    (a,) = r.receive(msg, T_NS, 0)
    assert a.name is None and a.decoded is None and a.cause is Reject.EXTENDED_ID
    assert len(_taken(r, _command(Encoder(DB), 0), 0)) == 1  # the genuine one is still taken


def test_out_of_range_frame_does_not_consume_the_alive_counter() -> None:
    """A THR_CMD_0 whose ImuCounter is out of range (valid CRC) is rejected ``range``; the
    genuine frame carrying the same alive counter is then taken (not a repeat)."""
    r, enc = _receipt(), Encoder(DB)
    assert len(_taken(r, _command(enc, 0), 0)) == 1
    raw = bytearray(_command(Encoder(DB), 1, counter=1).data)
    raw[2] |= 0xF0  # ImuCounter (bits 20..23) = 15: outside its DBC range 0..14
    raw[0] = e2e.frame_crc(int(DB.get_message_by_name("THR_CMD_0").dbc.attributes[
        "E2EDataID"].value), raw)
    bad = can.Message(arbitration_id=ICD.frame_id["THR_CMD_0"], is_extended_id=False, data=raw)
    (a,) = r.receive(bad, T_NS, 1)
    assert a.decoded is None and a.cause is Reject.RANGE
    assert len(_taken(r, _command(enc, 1), 1)) == 1


def test_stale_command_consumes_neither_counter_nor_slot() -> None:
    """A valid THR_CMD_0 of the previous cycle is ``stale``; the awaited one is then taken."""
    r = _receipt()
    enc = Encoder(DB)
    _taken(r, _command(enc, 4), 4)
    stale = _command(enc, 4, counter=1)  # a new counter, an old cycle
    (a,) = r.receive(stale, T_NS, 5)
    assert a.decoded is None and a.cause is Reject.STALE and a.passed_checks
    assert len(_taken(r, _command(enc, 5, counter=1), 5)) == 1


def test_second_valid_command_for_a_cycle_is_a_second_sender() -> None:
    """Two different valid THR_CMD_0 for one cycle: the first is taken, the second is
    ``second_sender`` evidence (lockstep and realtime)."""
    for cycle in (7, None):
        r = _receipt()
        genuine, forger = Encoder(DB), Encoder(DB)
        assert len(_taken(r, _command(genuine, 7, on_s=0.002), cycle)) == 1
        forged = _command(forger, 7, on_s=0.02, counter=5)
        (a,) = r.receive(forged, T_NS, cycle)
        assert a.decoded is None and a.cause is Reject.SECOND_SENDER
        assert r.second_sender == {"THR_CMD_0": 1}


def test_replayed_old_frame_is_a_sequence_regression() -> None:
    """A frame whose counter is 1..3 behind the live stream's is ``sequence`` evidence."""
    r, enc = _receipt(), Encoder(DB)
    frames = [_command(enc, k) for k in range(5)]
    for k, msg in enumerate(frames):
        assert len(_taken(r, msg, k)) == 1
    (a,) = r.receive(frames[2], T_NS, 5)
    assert a.cause is Reject.SEQUENCE and r.second_sender == {"THR_CMD_0": 1}


def test_a_new_sequence_after_silence_is_taken() -> None:
    """After the stream has been quiet for longer than its live window, any counter starts a
    new sequence (a restarted sender), even one 1..3 behind the last."""
    r, enc = _receipt(), Encoder(DB)
    for k in range(3):
        _taken(r, _command(enc, k), k)
    restarted = _command(Encoder(DB), 3, counter=0)  # 2 behind counter 2
    assert len(_taken(r, restarted, 3, t_ns=T_NS + 10 * PERIOD_NS)) == 1


def test_own_message_from_another_node_is_evidence_only_when_well_formed() -> None:
    """A valid SYNC heard by the bench is ``unexpected`` evidence; a malformed one is
    counted by its fault and is no evidence."""
    r, enc = _receipt(), Encoder(DB)
    sync = enc.message("SYNC", {"Cycle": 3, "SimTime": 0.06})
    (a,) = r.receive(sync, T_NS, 3)
    assert a.cause is Reject.UNEXPECTED and r.second_sender == {"SYNC": 1}
    bad = enc.message("SYNC", {"Cycle": 4, "SimTime": 0.08})
    bad.data = bytearray(bad.data)
    bad.data[0] ^= 1
    (b,) = r.receive(bad, T_NS, 4)
    assert b.cause is Reject.CRC and r.second_sender == {"SYNC": 1}


@pytest.mark.parametrize("kind, lost, taken", [("drop", True, 0), ("corrupt", True, 0),
                                                ("duplicate", False, 1)])
def test_injected_bus_faults_on_commands(kind: str, lost: bool, taken: int) -> None:
    """drop and corrupt (p = 1) lose the command (the bench stops waiting for it);
    duplicate delivers it once and counts the copy as a repeated counter."""
    fault = FaultSpec(0.0, kind, message="THR_CMD_0", params={"probability": 1.0})
    r, enc = _receipt([fault]), Encoder(DB)
    arrivals = r.receive(_command(enc, 0), T_NS, 0)
    assert any(a.injected_loss for a in arrivals) is lost
    assert sum(a.decoded is not None for a in arrivals) == taken
    if kind == "duplicate":
        assert [a.cause for a in arrivals] == [None, Reject.COUNTER]
    assert r.second_sender == {}
