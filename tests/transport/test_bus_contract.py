"""Back-to-back contract tests: every bus the project uses behaves the same way.

Two buses A and B opened on the same channel through :func:`transport.spec.open_bus` (like
python-can's back2back tests): frames sent by A arrive at B unchanged and in order, B's
frames arrive at A, :func:`transport.lockstep.send_frames` (one burst where the bus takes
bursts) delivers like single sends, and ``recv`` and
:func:`transport.lockstep.recv_spinning` honour their timeouts. Run for ``virtual`` and
``hilbus`` always, and for ``socketcan:vcan0`` where the kernel has it.
"""

from __future__ import annotations

import threading
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import can
import pytest

from tests.transport.helpers import DEADLINE_S, frame_key
from transport.lockstep import LOCKSTEP_SPIN_S, recv_spinning, send_frames
from transport.spec import open_bus

TIMEOUT_SLACK_S = 0.5
STREAM_N = 300  # more than hilbus queues per socket on Linux: exercises blocking sends
VCAN = Path("/sys/class/net/vcan0")


@dataclass(frozen=True)
class Kind:
    """A bus under contract and what it can carry."""

    interface: str
    error_frames: bool = True  # socketcan delivers error frames only with an error filter
    fd_frames: bool = True  # vcan0 has the classic MTU unless reconfigured
    # python-can's socketcan reports is_rx False for every frame sent from this host
    # (MSG_DONTROUTE), which on vcan0 is every frame
    marks_rx: bool = True

    def spec(self) -> str:
        if self.interface == "socketcan":
            return "socketcan:vcan0"
        return f"{self.interface}:ct-{uuid.uuid4().hex[:8]}"


KINDS = [
    pytest.param(Kind("virtual"), id="virtual"),
    pytest.param(Kind("hilbus"), id="hilbus"),
    pytest.param(
        Kind("socketcan", error_frames=False, fd_frames=False, marks_rx=False),
        id="socketcan",
        marks=pytest.mark.socketcan,
    ),
]


@pytest.fixture(params=KINDS)
def pair(
    request: pytest.FixtureRequest, runtime: Path
) -> Iterator[tuple[can.BusABC, can.BusABC, Kind]]:
    """Buses A and B on one fresh channel of the bus kind under test."""
    kind: Kind = request.param
    if kind.interface == "socketcan" and not VCAN.exists():
        pytest.skip("no SocketCAN interface vcan0 on this kernel")
    spec = kind.spec()
    with open_bus(spec) as a, open_bus(spec) as b:
        yield a, b, kind


def _frames(kind: Kind, base: int) -> list[can.Message]:
    """A stream of varied frames with IDs unique to this test (base + i)."""
    out = []
    for i in range(STREAM_N):
        n = i % 9
        data = bytes((i * 7 + k) & 0xFF for k in range(n))
        if i % 50 == 49:
            out.append(can.Message(arbitration_id=base + i, is_remote_frame=True, dlc=n))
        elif i % 2:
            out.append(
                can.Message(arbitration_id=(base + i) & 0x7FF, is_extended_id=False, data=data)
            )
        else:
            out.append(can.Message(arbitration_id=base + i, data=data))
    if kind.error_frames:
        out.append(can.Message(arbitration_id=0x20000004, is_error_frame=True, data=bytes(8)))
    if kind.fd_frames:
        out.append(
            can.Message(arbitration_id=base, is_fd=True, bitrate_switch=True, data=bytes(64))
        )
    return out


def _transfer(tx: can.BusABC, rx: can.BusABC, sent: list[can.Message]) -> list[can.Message]:
    """Send ``sent`` on tx while a thread receives as many frames of them on rx."""
    wanted = {frame_key(m) for m in sent}
    got: list[can.Message] = []
    failure: list[str] = []

    def receive() -> None:
        deadline = time.monotonic() + DEADLINE_S
        while len(got) < len(sent):
            left = deadline - time.monotonic()
            if left <= 0:
                failure.append(f"only {len(got)}/{len(sent)} frames within {DEADLINE_S} s")
                return
            m = rx.recv(timeout=left)
            if m is not None and frame_key(m) in wanted:  # vcan0 may carry other traffic
                got.append(m)

    receiver = threading.Thread(target=receive, daemon=True)
    receiver.start()
    for m in sent:
        tx.send(m, timeout=DEADLINE_S)
    receiver.join(DEADLINE_S)
    assert not receiver.is_alive() and not failure, failure
    return got


def test_a_to_b_unchanged_in_order(pair: tuple[can.BusABC, can.BusABC, Kind]) -> None:
    """Frames sent by A arrive at B with the same IDs, DLCs, data and flags, in order."""
    a, b, kind = pair
    sent = _frames(kind, 0x1A0000)
    got = _transfer(a, b, sent)
    assert [frame_key(m) for m in got] == [frame_key(m) for m in sent]
    if (
        kind.interface != "socketcan"
    ):  # python-can marks locally originated SocketCAN frames is_rx=False
        assert all(m.is_rx for m in got) or not kind.marks_rx


def test_b_to_a_unchanged_in_order(pair: tuple[can.BusABC, can.BusABC, Kind]) -> None:
    """Frames sent by B arrive at A the same way."""
    a, b, kind = pair
    sent = _frames(kind, 0x1B0000)
    got = _transfer(b, a, sent)
    assert [frame_key(m) for m in got] == [frame_key(m) for m in sent]


def test_sender_does_not_receive_its_own(pair: tuple[can.BusABC, can.BusABC, Kind]) -> None:
    """By default a bus does not receive what it sent itself."""
    a, b, kind = pair
    sent = _frames(kind, 0x1C0000)[:5]
    _transfer(a, b, sent)
    own = {frame_key(m) for m in sent}
    while (m := a.recv(timeout=0)) is not None:
        assert frame_key(m) not in own


def test_recv_timeout_semantics(pair: tuple[can.BusABC, can.BusABC, Kind]) -> None:
    """recv(0) does not wait; recv(t) waits about t; a waiting frame returns at once."""
    a, b, kind = pair
    while b.recv(timeout=0) is not None:  # vcan0 may carry other traffic
        pass
    t0 = time.monotonic()
    assert b.recv(timeout=0) is None
    assert time.monotonic() - t0 < TIMEOUT_SLACK_S
    if kind.interface != "socketcan":  # a shared vcan0 may not stay quiet for 0.2 s
        t0 = time.monotonic()
        assert b.recv(timeout=0.2) is None
        assert 0.2 <= time.monotonic() - t0 < 0.2 + TIMEOUT_SLACK_S
    a.send(can.Message(arbitration_id=0x1D0001, data=b"\x01"))
    t0 = time.monotonic()
    m = b.recv(timeout=DEADLINE_S)
    assert m is not None and m.arbitration_id == 0x1D0001
    assert time.monotonic() - t0 < TIMEOUT_SLACK_S


def test_send_frames_arrive_like_single_sends(pair: tuple[can.BusABC, can.BusABC, Kind]) -> None:
    """send_frames: the same frames, unchanged and in order, as sending them one by one."""
    a, b, kind = pair
    sent = _frames(kind, 0x1E0000)[:40]
    got: list[can.Message] = []
    send_frames(a, sent)
    deadline = time.monotonic() + DEADLINE_S
    wanted = {frame_key(m) for m in sent}
    while len(got) < len(sent) and (left := deadline - time.monotonic()) > 0:
        m = b.recv(timeout=left)
        if m is not None and frame_key(m) in wanted:  # vcan0 may carry other traffic
            got.append(m)
    assert [frame_key(m) for m in got] == [frame_key(m) for m in sent]
    send_frames(a, [])  # nothing to send: nothing sent, no error


def test_recv_spinning_timeout_semantics(pair: tuple[can.BusABC, can.BusABC, Kind]) -> None:
    """recv_spinning returns a waiting frame at once and otherwise gives up at its timeout,
    whether the polling phase is shorter or longer than the timeout."""
    a, b, kind = pair
    while b.recv(timeout=0) is not None:  # vcan0 may carry other traffic
        pass
    a.send(can.Message(arbitration_id=0x1F0001, data=b"\x02"))
    t0 = time.monotonic()
    m = recv_spinning(b, DEADLINE_S, LOCKSTEP_SPIN_S)
    assert m is not None and m.arbitration_id == 0x1F0001
    assert time.monotonic() - t0 < TIMEOUT_SLACK_S
    if kind.interface != "socketcan":  # a shared vcan0 may not stay quiet
        for spin_s in (0.0, 0.05, 1.0):
            t0 = time.monotonic()
            assert recv_spinning(b, 0.2, spin_s) is None
            assert 0.2 <= time.monotonic() - t0 < 0.2 + TIMEOUT_SLACK_S, spin_s
