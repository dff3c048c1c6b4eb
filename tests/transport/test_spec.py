"""Tests of :mod:`transport.spec`: bus specs, opening buses, per-mode options, buffers.

Buses are opened on channels of their own in a private runtime directory (``runtime``).
"""

from __future__ import annotations

import os
import socket
import time
import uuid
from pathlib import Path

import can
import pytest

from dbc.errors import BusError
from transport.hilbus import MEMBER_STALL_S
from transport.spec import (
    REALTIME_MEMBER_STALL_S,
    SOCKETCAN_RCVBUF_BYTES,
    BusSpec,
    default_bus_spec,
    enlarge_receive_buffer,
    mode_options,
    open_bus,
)

DEADLINE_S = 30.0
STREAM_N = 300  # more than hilbus queues per socket on Linux: fills a stopped member's queue
VCAN = Path("/sys/class/net/vcan0")


@pytest.mark.parametrize(
    ("spec", "interface", "channel", "options"),
    [
        ("socketcan:vcan0", "socketcan", "vcan0", ()),
        ("hilbus:default", "hilbus", "default", ()),
        ("pcan:PCAN_USBBUS1?bitrate=1000000", "pcan", "PCAN_USBBUS1", (("bitrate", "1000000"),)),
        ("virtual:a:b", "virtual", "a:b", ()),
    ],
)
def test_bus_spec_parse(
    spec: str, interface: str, channel: str, options: tuple[object, ...]
) -> None:
    """Valid specs parse into interface, channel and options, and print back."""
    bs = BusSpec.parse(spec)
    assert (bs.interface, bs.channel, bs.options) == (interface, channel, options)
    assert str(bs) == spec
    assert bs.is_portable == (interface == "hilbus")


@pytest.mark.parametrize("spec", ["vcan0", "", ":vcan0", "socketcan:", ":", "?bitrate=1"])
def test_bus_spec_parse_errors(spec: str) -> None:
    """A spec without INTERFACE:CHANNEL raises BusError naming the spec."""
    with pytest.raises(BusError, match="expected INTERFACE:CHANNEL") as info:
        BusSpec.parse(spec)
    assert repr(spec) in str(info.value)


def test_bus_spec_malformed_options_raise_bus_error() -> None:
    """A malformed ?query raises BusError naming the spec."""
    with pytest.raises(BusError, match="bitrate"):
        BusSpec.parse("socketcan:vcan0?bitrate")


def test_default_bus_spec(tmp_path: Path) -> None:
    """socketcan:vcan0 where sys_net has vcan0, else the portable hilbus:default."""
    assert default_bus_spec(tmp_path) == "hilbus:default"
    (tmp_path / "vcan0").mkdir()
    assert default_bus_spec(tmp_path) == "socketcan:vcan0"


def test_open_bus_errors_name_the_spec(runtime: Path) -> None:
    """Unknown interfaces and bad hilbus channels raise BusError naming the problem."""
    with pytest.raises(BusError, match="nosuchinterface:x"):
        open_bus("nosuchinterface:x")
    with pytest.raises(BusError, match="'bad name'"):
        open_bus("hilbus:bad name")


def test_open_bus_passes_options(runtime: Path) -> None:
    """Spec options and keyword arguments reach the bus (receive_own_messages here)."""
    with open_bus(f"hilbus:ct-{uuid.uuid4().hex[:8]}?receive_own_messages=true") as bus:
        bus.send(can.Message(arbitration_id=0x33))
        m = bus.recv(timeout=DEADLINE_S)
        assert m is not None and m.arbitration_id == 0x33 and not m.is_rx


def test_realtime_on_the_portable_bus_does_not_wait_for_a_stopped_member() -> None:
    """Realtime hilbus: member_stall_s is the short realtime one (a spec option wins);
    lockstep and other interfaces get no extra option."""
    assert mode_options("hilbus:x", "realtime") == {"member_stall_s": REALTIME_MEMBER_STALL_S}
    assert mode_options("hilbus:x?member_stall_s=2", "realtime") == {}
    assert mode_options("hilbus:x", "lockstep") == {}
    assert mode_options("socketcan:vcan0", "realtime") == {}


def test_a_realtime_send_to_a_stopped_member_is_held_only_the_realtime_stall(
    runtime: Path,
) -> None:
    """A member that never reads: once its queue is full, a realtime sender waits at most
    about REALTIME_MEMBER_STALL_S once (not hilbus's 1 s), then drops to it and counts."""
    spec = f"hilbus:rt-{uuid.uuid4().hex[:8]}"
    with open_bus(spec, **mode_options(spec, "realtime")) as tx, open_bus(spec):
        t0 = time.monotonic()
        for _ in range(STREAM_N):
            tx.send(can.Message(arbitration_id=0x33, data=b"\x00" * 8))
        held_s = time.monotonic() - t0
        assert tx.overrun_drops > 0  # type: ignore[attr-defined]
        assert held_s < MEMBER_STALL_S  # hilbus's lockstep stall alone would be 1 s


def test_enlarge_receive_buffer_grows_the_socket_buffer() -> None:
    """The receive buffer grows past the kernel default; as root it reaches the request."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        before = sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)
        granted = enlarge_receive_buffer(sock, size_bytes=4 * before)
        assert granted >= before
        if os.geteuid() == 0:  # SO_RCVBUFFORCE: the kernel doubles what it is given
            assert granted >= 4 * before


@pytest.mark.socketcan
def test_socketcan_bus_has_the_large_receive_buffer() -> None:
    """open_bus gives a socketcan bus the receive buffer that absorbs a burst of frames."""
    if not VCAN.exists():
        pytest.skip("no SocketCAN interface vcan0 on this kernel")
    with (
        can.Bus(interface="socketcan", channel="vcan0") as plain,
        open_bus("socketcan:vcan0") as bus,
    ):
        default = plain.socket.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)  # type: ignore[attr-defined]
        granted = bus.socket.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)  # type: ignore[attr-defined]
        assert granted >= default
        if os.geteuid() == 0:  # SO_RCVBUFFORCE: the request itself, not capped by rmem_max
            assert granted >= SOCKETCAN_RCVBUF_BYTES > default
