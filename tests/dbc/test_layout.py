"""FrameLayout against cantools, back to back: the same bytes and the same values, every message.

The layout is the hot path of both processes; cantools' own ``Message.encode`` /
``Message.decode`` is the reference it must equal exactly (not within a tolerance).
"""

from __future__ import annotations

import random
from typing import Any

import cantools
import numpy as np
import pytest
from cantools.database.can import Database, Message

from dbc import e2e
from dbc.codec import Encoder, data_id
from dbc.database import load_database
from dbc.errors import IcdError
from dbc.layout import FrameLayout

CASES_PER_MESSAGE = 300
E2E_SIGNALS = ("CRC", "AliveCounter")


@pytest.fixture(scope="module")
def db() -> Database:
    """The project's DBC."""
    return load_database()


def _raw_range(s: Any) -> tuple[int, int]:
    if s.is_signed:
        return -(1 << (s.length - 1)), (1 << (s.length - 1)) - 1
    return 0, (1 << s.length) - 1


def _random_values(m: Message, rng: random.Random, on_grid: bool) -> dict[str, float | int]:
    """Physical values within every signal's DBC range: raw grid points or any float."""
    out: dict[str, float | int] = {}
    for s in m.signals:
        lo, hi = float(s.minimum), float(s.maximum)
        if on_grid or not s.conversion.scale or s.conversion.scale == 1:
            r_lo, r_hi = _raw_range(s)
            while True:
                v = s.conversion.raw_to_scaled(rng.randint(r_lo, r_hi), False)
                if lo <= v <= hi:
                    break
            out[s.name] = v
        else:
            out[s.name] = rng.uniform(lo, hi)
    return out


def test_pack_equals_cantools_encode_on_random_values(db: Database) -> None:
    """Grid and off-grid physical values: byte-identical to Message.encode (scaling, strict off)."""
    rng = random.Random(7)
    for m in db.messages:
        layout = FrameLayout(m)
        for k in range(CASES_PER_MESSAGE):
            values = _random_values(m, rng, on_grid=k % 2 == 0)
            expected = m.encode(values, scaling=True, strict=False)
            assert bytes(layout.pack(values)) == expected, (m.name, values)


def test_unpack_equals_cantools_decode_on_random_payloads(db: Database) -> None:
    """Any 8 bytes: the same signal values, of the same types, as Message.decode."""
    rng = random.Random(8)
    for m in db.messages:
        layout = FrameLayout(m)
        for _ in range(CASES_PER_MESSAGE):
            data = rng.randbytes(m.length)
            expected = m.decode(data, decode_choices=False, scaling=True)
            got = layout.unpack(data)
            assert got == expected, m.name
            assert [type(v) for v in got.values()] == [type(expected[k]) for k in got], m.name
            assert layout.unpack(bytearray(data)) == expected


def test_encoder_frames_equal_cantools_then_e2e(db: Database) -> None:
    """Encoder.encode == cantools encode + e2e.protect, alive counter included."""
    rng = random.Random(9)
    enc = Encoder(db)
    for m in db.messages:
        for k in range(CASES_PER_MESSAGE // 10):
            values = {n: v for n, v in _random_values(m, rng, on_grid=False).items()
                      if n not in E2E_SIGNALS}
            counter = k % e2e.COUNTER_MODULUS
            ref = bytearray(m.encode({"CRC": 0, "AliveCounter": counter, **values},
                                     scaling=True, strict=False))
            assert enc.encode(m.name, values, counter) == e2e.protect(data_id(m), ref, counter)


def test_numpy_scalars_encode_like_floats(db: Database) -> None:
    """np.float64 / np.int64 values (what estimators produce) give the same bytes."""
    m = db.get_message_by_name("IMU_RATE")
    layout = FrameLayout(m)
    values = {"CRC": 0, "AliveCounter": 3, "Valid": 1, "RateX": 0.0123, "RateY": -0.2,
              "RateZ": 1e-4}
    as_numpy = {k: (np.int64(v) if isinstance(v, int) else np.float64(v))
                for k, v in values.items()}
    assert layout.pack(as_numpy) == layout.pack(values)


def test_out_of_range_missing_and_non_numeric_values_name_the_signal(db: Database) -> None:
    """Each bad value raises IcdError naming message, signal and value; nothing is packed."""
    m = db.get_message_by_name("IMU_RATE")
    layout = FrameLayout(m)
    good = {"CRC": 0, "AliveCounter": 0, "Valid": 1, "RateX": 0.0, "RateY": 0.0, "RateZ": 0.0}
    hi = float(next(s for s in m.signals if s.name == "RateX").maximum)
    for bad, shown in ((2 * hi, repr(2 * hi)), (float("nan"), "nan"), ("fast", "'fast'"),
                       (None, "None")):
        with pytest.raises(IcdError, match=rf"IMU_RATE: RateX = {shown}"):
            layout.pack({**good, "RateX": bad})


MIXED_DBC = """VERSION ""
BS_:
BU_: A
BO_ 256 MIXED: 8 A
 SG_ Big : 7|12@0- (0.5,1) [-1000|1000] "" A
 SG_ Little : 16|10@1+ (1,0) [0|1023] "" A
 SG_ Flt : 32|32@1- (1,0) [-1e6|1e6] "" A
SIG_VALTYPE_ 256 Flt : 1;
"""


def test_big_endian_and_float_signals_equal_cantools() -> None:
    """A message with Motorola and IEEE-float signals (the general path) packs and unpacks
    exactly as cantools does."""
    m = cantools.database.load_string(MIXED_DBC, database_format="dbc").get_message_by_name(
        "MIXED")
    layout = FrameLayout(m)
    rng = random.Random(10)
    for _ in range(CASES_PER_MESSAGE):
        values = {"Big": rng.randint(-2048, 2047) * 0.5 + 1, "Little": rng.randint(0, 1023),
                  "Flt": rng.uniform(-1e6, 1e6)}
        values["Big"] = min(max(values["Big"], -1000.0), 1000.0)
        data = m.encode(values, scaling=True, strict=False)
        assert bytes(layout.pack(values)) == data
        assert layout.unpack(data) == m.decode(data, decode_choices=False, scaling=True)


def test_pack_merged_equals_pack_of_the_merged_values(db: Database) -> None:
    """The encoder's path (E2E fields apart from the signals) packs what pack packs, for
    every message, a signal overriding a base field as a merged dict would."""
    rng = random.Random(10)
    for m in db.messages:
        layout = FrameLayout(m)
        for k in range(CASES_PER_MESSAGE // 10):
            values = _random_values(m, rng, on_grid=k % 2 == 0)
            base = {n: values.pop(n) for n in E2E_SIGNALS}
            assert layout.pack_merged(base, values) == layout.pack({**base, **values})
            assert layout.pack_merged({**base, "CRC": 1}, {**values, "CRC": 0}) == \
                layout.pack({**base, **values, "CRC": 0})


def test_pack_merged_keeps_numpy_scalar_arithmetic(db: Database) -> None:
    """float32 values (rounded in float32 by pack, as cantools does) pack the same bytes
    through the encoder's path, and refuse the same out-of-range value."""
    sync = FrameLayout(db.get_message_by_name("SYNC"))
    base = {"CRC": 0, "AliveCounter": 0}
    for t in (2147483.8, 1234.5678, 0.1):
        values = {"Cycle": 7, "SimTime": np.float32(t)}
        assert sync.pack_merged(base, values) == sync.pack({**base, **values})
    quat = FrameLayout(db.get_message_by_name("STR_QUAT"))
    values = {"Valid": 1, "Largest": 0, "C0": np.float32(-0.7077888), "C1": 0.0, "C2": 0.0}
    try:
        expected: bytes | str = bytes(quat.pack({**base, **values}))
    except IcdError as exc:
        expected = str(exc)
    try:
        got: bytes | str = bytes(quat.pack_merged(base, values))
    except IcdError as exc:
        got = str(exc)
    assert got == expected


def test_encoder_names_a_bad_signal(db: Database) -> None:
    """A bad value through the encoder's path raises IcdError naming signal and value."""
    enc = Encoder(db)
    good = {"Valid": 1, "RateX": 0.0, "RateY": 0.0, "RateZ": 0.0}
    for bad, shown in ((1e9, repr(1e9)), (float("nan"), "nan"), ("fast", "'fast'"),
                       (None, "None")):
        with pytest.raises(IcdError, match=rf"IMU_RATE: RateX = {shown}"):
            enc.encode("IMU_RATE", {**good, "RateX": bad})
    with pytest.raises(IcdError, match=r"IMU_RATE: RateY = None"):
        enc.encode("IMU_RATE", {"Valid": 1, "RateX": 0.0, "RateZ": 0.0})
