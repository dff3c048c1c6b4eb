"""The DBC itself meets the interface requirements of DESIGN §4."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.codec import Encoder, FrameChecker, data_id
from dbc.database import load_database
from dbc.quaternion import pack_quaternion, unpack_quaternion

ARCSEC_RAD = math.pi / 180 / 3600
STR_QUANT_PER_AXIS_MAX_ARCSEC = 9.5  # documented in dbc/quaternion.py
N_ATTITUDES = 20000
SEED = 4
ON_TIME_RESOLUTION_MAX_S = 1e-4
MIN_THRUSTERS = 16
EVENT_MESSAGES = {"FAULT_CMD"}
PRIORITY_ORDER = [
    "SYNC",
    "THR_CMD_0",
    "IMU_RATE",
    "STR_QUAT",
    "THR_STATUS",
    "FSW_STATUS",
    "BENCH_STATUS",
    "FAULT_CMD",
]


@pytest.fixture(scope="module")
def db():  # type: ignore[no-untyped-def]
    """The project's DBC."""
    return load_database()


def test_every_frame_has_e2e_protection_in_the_same_place(db) -> None:  # type: ignore[no-untyped-def]
    """CRC in byte 0, alive counter in the low nibble of byte 1, a unique data ID."""
    ids = set()
    for m in db.messages:
        crc, ctr = m.get_signal_by_name("CRC"), m.get_signal_by_name("AliveCounter")
        assert (crc.start, crc.length, ctr.start, ctr.length) == (0, 8, 8, 4), m.name
        ids.add(data_id(m))
        assert m.length == 8 and not m.is_extended_frame
    assert len(ids) == len(db.messages)


def test_cyclic_frames_have_cycle_times(db) -> None:  # type: ignore[no-untyped-def]
    """Every periodic frame carries GenMsgCycleTime."""
    for m in db.messages:
        if m.name not in EVENT_MESSAGES:
            assert m.cycle_time and m.cycle_time > 0, m.name


def test_signals_fit_and_do_not_overlap(db) -> None:  # type: ignore[no-untyped-def]
    """No two signals share a bit and all fit in the frame; every signal has a range."""
    for m in db.messages:
        used: set[int] = set()
        for s in m.signals:
            bits = set(range(s.start, s.start + s.length))
            assert not bits & used, (m.name, s.name)
            assert max(bits) < 8 * m.length
            used |= bits
            assert s.minimum is not None and s.maximum is not None, (m.name, s.name)


def test_valve_commands_cover_16_thrusters_at_0_1_ms(db) -> None:  # type: ignore[no-untyped-def]
    """THR_CMD_0..3 carry on-times for >= 16 thrusters with <= 0.1 ms resolution."""
    on_times = [
        s
        for m in db.messages
        if m.name.startswith("THR_CMD_")
        for s in m.signals
        if s.name.startswith("OnTime_T")
    ]
    assert len({s.name for s in on_times}) >= MIN_THRUSTERS
    assert all(s.scale <= ON_TIME_RESOLUTION_MAX_S for s in on_times)


def test_attitude_quantisation_is_bounded_at_every_attitude(db) -> None:  # type: ignore[no-untyped-def]
    """STR_QUAT round trip error per axis stays under its documented bound, near 180 deg too."""
    enc, chk = Encoder(db), FrameChecker(db)
    rng = np.random.default_rng(SEED)
    qs = rng.standard_normal((N_ATTITUDES, 4))
    qs[: N_ATTITUDES // 10, 0] *= 1e-3  # many rotations close to 180 deg (q0 ~ 0)
    worst = 0.0
    for q in qs / np.linalg.norm(qs, axis=1, keepdims=True):
        d = chk.check(enc.message("STR_QUAT", {"Valid": 1, **pack_quaternion(q)}))
        assert d is not None
        r = np.array(unpack_quaternion(d.signals))
        # rotation error vector of q^-1 r, per axis: 2 * vector part of the error quaternion
        e0 = q @ r
        ev = q[0] * r[1:] - r[0] * q[1:] - np.cross(q[1:], r[1:])
        worst = max(worst, float(np.max(np.abs(2 * np.sign(e0) * ev))))
    assert worst / ARCSEC_RAD <= STR_QUANT_PER_AXIS_MAX_ARCSEC


def test_priority_order_by_id(db) -> None:  # type: ignore[no-untyped-def]
    """Sync, then valve commands, IMU, star tracker, valve status, FSW, bench, faults."""
    ids = [db.get_message_by_name(n).frame_id for n in PRIORITY_ORDER]
    assert ids == sorted(ids)
