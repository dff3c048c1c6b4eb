"""Tests of the portable bus :mod:`transport.hilbus`: members, channels, permissions,
stale and stopped members, shutdown, other processes.

Every test runs in its own private runtime directory on a channel of its own. Waits are
bounded by deadlines on real events (frames, output lines), never by sleeping.
"""

from __future__ import annotations

import os
import signal
import socket
import stat
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import can
import pytest

from dbc.errors import BusError
from tests.transport.helpers import (
    DEADLINE_S,
    QUEUE_OVERFILL_N,
    Collector,
    Lines,
    env_for,
    recv_n,
)
from transport.channel import bus_root, channel_dir
from transport.hilbus import HilBus, tx_timestamp_of


def test_permissions_of_directories_and_socket(channel: str) -> None:
    """Channel directories are 0700 and owned by us; member sockets are 0600."""
    with HilBus(channel) as bus:
        for d in (bus_root(), channel_dir(channel)):
            st = os.lstat(d)
            assert stat.S_ISDIR(st.st_mode)
            assert stat.S_IMODE(st.st_mode) == 0o700
            assert st.st_uid == os.getuid()
        st = os.lstat(bus.path)
        assert stat.S_ISSOCK(st.st_mode)
        assert stat.S_IMODE(st.st_mode) == 0o600
        assert bus.path.parent == channel_dir(channel)
        assert bus.path.name.startswith(f"{os.getpid()}-")


def test_permissive_directory_is_refused(runtime: Path, channel: str) -> None:
    """An existing bus directory with group/other permissions is refused, naming it."""
    root = bus_root()
    root.mkdir(mode=0o700)
    root.chmod(0o755)
    with pytest.raises(BusError, match=str(root)):
        HilBus(channel)


def test_symlinked_directory_is_refused(runtime: Path, channel: str) -> None:
    """A symlink in place of the bus directory is refused, naming it."""
    target = runtime / "elsewhere"
    target.mkdir(mode=0o700)
    bus_root().symlink_to(target)
    with pytest.raises(BusError, match=str(bus_root())):
        HilBus(channel)


@pytest.mark.parametrize("bad", ["", "a/b", ".", "..", "x y", "ch\u00e9", "a\0b", "../up"])
def test_bad_channel_name_raises(runtime: Path, bad: str) -> None:
    """A channel name outside [A-Za-z0-9_.-]+ (or . / ..) raises BusError naming it."""
    with pytest.raises(BusError, match="channel") as info:
        HilBus(bad)
    assert repr(bad) in str(info.value)


def test_too_long_socket_path_raises(channel: str) -> None:
    """A channel name too long for a Unix socket path raises BusError."""
    with pytest.raises(BusError, match="longer than"):
        HilBus("c" * 120)


def test_send_timeout_when_a_member_does_not_read(pair: tuple[HilBus, HilBus]) -> None:
    """A member that never reads makes send(timeout=t) fail after t, not hang."""
    a, _b = pair
    t0 = time.monotonic()
    with pytest.raises(can.CanOperationError, match="not reading"):
        for i in range(QUEUE_OVERFILL_N):
            a.send(can.Message(arbitration_id=i), timeout=0.1)
    assert time.monotonic() - t0 < DEADLINE_S


def test_shutdown_wakes_blocked_send_and_recv(pair: tuple[HilBus, HilBus]) -> None:
    """shutdown() in one thread ends a send blocked on a full member and a recv(None)."""
    a, _b = pair
    with pytest.raises(can.CanOperationError, match="not reading"):
        for i in range(QUEUE_OVERFILL_N):  # fill B's queue (B never reads)
            a.send(can.Message(arbitration_id=i), timeout=0.05)
    errors: dict[str, BaseException] = {}

    def call(tag: str, fn: Callable[[], object]) -> None:
        try:
            fn()
        except BaseException as exc:  # inspected below
            errors[tag] = exc

    threads = [
        threading.Thread(target=call, args=("send", lambda: a.send(can.Message())), daemon=True),
        threading.Thread(target=call, args=("recv", lambda: a.recv(timeout=None)), daemon=True),
    ]
    for t in threads:
        t.start()
    a.shutdown()
    for t in threads:
        t.join(DEADLINE_S)
        assert not t.is_alive(), "a thread stayed blocked after shutdown()"
    assert sorted(errors) == ["recv", "send"]
    assert all(isinstance(e, can.CanOperationError) for e in errors.values()), errors


def test_member_joining_after_a_send_receives(channel: str) -> None:
    """A member that joins right after another's send gets that member's next frame."""
    with HilBus(channel) as a:
        a.send(can.Message(arbitration_id=1))  # scans: nobody there
        with HilBus(channel) as b:
            a.send(can.Message(arbitration_id=2))
            assert recv_n(b, 1)[0].arbitration_id == 2


def test_shutdown_unlinks_socket_and_is_idempotent(channel: str) -> None:
    """shutdown() removes the member's socket file; a second shutdown is harmless."""
    bus = HilBus(channel)
    assert bus.path.exists()
    bus.shutdown()
    assert not bus.path.exists()
    bus.shutdown()
    with pytest.raises(can.CanOperationError):
        bus.send(can.Message())


def test_python_can_entry_point_and_detect_configs(channel: str) -> None:
    """can.Bus(interface='hilbus') works and detect_available_configs lists live channels."""
    with can.Bus(interface="hilbus", channel=channel) as bus:
        assert isinstance(bus, HilBus)
        configs = can.detect_available_configs(interfaces=["hilbus"])
        assert {"interface": "hilbus", "channel": channel} in configs
    assert {"interface": "hilbus", "channel": channel} not in can.detect_available_configs(
        interfaces=["hilbus"]
    )


def test_stale_socket_of_killed_process_is_removed(runtime: Path, channel: str) -> None:
    """A member killed without shutdown is dropped and its socket file unlinked on send."""
    code = (
        "import sys; from transport.hilbus import HilBus; "
        f"b = HilBus({channel!r}); print(b.path, flush=True); sys.stdin.read()"
    )
    with HilBus(channel) as a, HilBus(channel) as b:
        with subprocess.Popen(
            [sys.executable, "-c", code],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=env_for(runtime),
            cwd=runtime,
        ) as child:
            assert child.stdout is not None
            stale = Path(Lines(child.stdout).wait_for(channel).strip())
            assert stale.exists()
            child.send_signal(signal.SIGKILL)
            child.wait(DEADLINE_S)
        assert stale.exists()
        a.send(can.Message(arbitration_id=0x55))
        assert not stale.exists()
        assert recv_n(b, 1)[0].arbitration_id == 0x55


def test_stale_socket_of_live_process_is_skipped_not_unlinked(channel: str) -> None:
    """A refusing socket whose pid is alive is skipped but left in place."""
    with HilBus(channel) as a, HilBus(channel) as b:
        orphan = channel_dir(channel) / f"{os.getpid()}-0badcafe.sock"
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
            s.bind(os.fspath(orphan))
        a.send(can.Message(arbitration_id=0x56))
        assert recv_n(b, 1)[0].arbitration_id == 0x56
        assert orphan.exists()
        orphan.unlink()


ECHO_CODE = """
import can
from transport.hilbus import HilBus
with HilBus({channel!r}) as bus:
    bus.send(can.Message(arbitration_id=0x700))  # ready
    while True:
        m = bus.recv(timeout=30)
        if m is None or m.arbitration_id == 0x7FF:
            break
        bus.send(can.Message(arbitration_id=m.arbitration_id + 1, data=m.data[::-1],
                             is_extended_id=m.is_extended_id))
"""


def test_cross_process_exchange(runtime: Path, channel: str) -> None:
    """Frames go to a second OS process and its replies come back, in order."""
    with (
        HilBus(channel) as bus,
        subprocess.Popen(
            [sys.executable, "-c", ECHO_CODE.format(channel=channel)],
            env=env_for(runtime),
            cwd=runtime,
        ) as child,
    ):
        try:
            assert recv_n(bus, 1)[0].arbitration_id == 0x700
            for i in range(QUEUE_OVERFILL_N):
                bus.send(can.Message(arbitration_id=0x100 + 2 * i, data=bytes([i, 1, 2])))
            got = recv_n(bus, QUEUE_OVERFILL_N)
            assert [(m.arbitration_id, bytes(m.data)) for m in got] == [
                (0x101 + 2 * i, bytes([2, 1, i])) for i in range(QUEUE_OVERFILL_N)
            ]
            assert all(m.is_rx and tx_timestamp_of(m) is not None for m in got)
            bus.send(can.Message(arbitration_id=0x7FF))
            assert child.wait(DEADLINE_S) == 0
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()


STALL_S = 0.25  # member_stall_s of the sender in the overrun tests


def _drain_all(bus: HilBus) -> list[can.Message]:
    """Every frame queued for ``bus`` now (it has stopped receiving new ones)."""
    got = []
    while (m := bus.recv(timeout=0)) is not None:
        got.append(m)
    return got


def test_member_that_stops_reading_is_overrun_while_others_get_every_frame(channel: str) -> None:
    """A non-reading member holds the sender up once, then loses frames; the others lose none."""
    with HilBus(channel, member_stall_s=STALL_S) as a, HilBus(channel) as b, \
            HilBus(channel) as stuck:
        collector = Collector(b, QUEUE_OVERFILL_N)
        collector.start()
        t0 = time.monotonic()
        for i in range(QUEUE_OVERFILL_N):
            a.send(can.Message(arbitration_id=i))
        # one stall, not one per frame (that would be QUEUE_OVERFILL_N * STALL_S = 50 s)
        assert time.monotonic() - t0 < DEADLINE_S
        assert [m.arbitration_id for m in collector.result()] == list(range(QUEUE_OVERFILL_N))
        kept = _drain_all(stuck)
        assert 0 < a.overrun_drops < QUEUE_OVERFILL_N
        assert len(kept) + a.overrun_drops == QUEUE_OVERFILL_N  # each frame delivered or counted
        ids = [m.arbitration_id for m in kept]
        assert ids == sorted(ids) and ids[0] == 0  # the oldest were kept, in order
        # it reads again: the next frame reaches it, and nothing more is dropped
        a.send(can.Message(arbitration_id=0x7FF))
        m = stuck.recv(timeout=DEADLINE_S)
        assert m is not None and m.arbitration_id == 0x7FF
        drops = a.overrun_drops
        a.send(can.Message(arbitration_id=0x7FE))
        assert a.overrun_drops == drops


@pytest.mark.parametrize("bad", [-1.0, "soon", float("nan")])
def test_bad_member_stall_is_refused(channel: str, bad: object) -> None:
    """member_stall_s must be seconds >= 0 or None; the error names the value."""
    with pytest.raises(BusError, match="member_stall_s"):
        HilBus(channel, member_stall_s=bad)  # type: ignore[arg-type]
