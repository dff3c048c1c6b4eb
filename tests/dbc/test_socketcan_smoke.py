"""Smoke tests of real SocketCAN on vcan0: python-can buses and can-utils see each other.

These need a kernel with vcan (``sudo modprobe vcan; sudo ip link add dev vcan0 type vcan;
sudo ip link set up vcan0``); CI runs them in a QEMU guest (see .ci/README.md). Elsewhere
they skip. Deadlines are generous: Python in the emulated guest is several times slower.
"""

from __future__ import annotations

import contextlib
import shutil
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import can
import pytest

pytestmark = pytest.mark.socketcan

CHANNEL = "vcan0"
N_FRAMES = 100
DEADLINE_S = 60.0


@pytest.fixture(autouse=True)
def _require_vcan0() -> None:
    """Skip unless the kernel has the vcan0 interface."""
    if not Path("/sys/class/net", CHANNEL).exists():
        pytest.skip(
            f"no SocketCAN interface {CHANNEL} on this kernel "
            "(run .ci/run's SocketCAN stage, or create vcan0: see .ci/README.md)"
        )


@pytest.fixture
def buses() -> Iterator[tuple[can.BusABC, can.BusABC]]:
    """Two independent socketcan buses (sockets) on vcan0."""
    with (
        can.Bus(interface="socketcan", channel=CHANNEL) as a,
        can.Bus(interface="socketcan", channel=CHANNEL) as b,
    ):
        yield a, b


def _frame(i: int) -> can.Message:
    """Frame number i: standard and extended IDs, DLC 0..8, a few remote frames."""
    if i % 25 == 24:
        return can.Message(arbitration_id=0x650 + i, is_extended_id=False, is_remote_frame=True)
    n = i % 9
    data = bytes((i * 7 + k) & 0xFF for k in range(n))
    if i % 3 == 0:
        return can.Message(arbitration_id=0x1ABC000 + i, is_extended_id=True, data=data)
    return can.Message(arbitration_id=0x600 + i, is_extended_id=False, data=data)


def _key(m: can.Message) -> tuple[int, bool, bool, int, bytes]:
    return (m.arbitration_id, m.is_extended_id, m.is_remote_frame, m.dlc, bytes(m.data))


def _candump_field(m: can.Message) -> str:
    """The ``ID#DATA`` field candump -L prints for m."""
    ident = f"{m.arbitration_id:08X}" if m.is_extended_id else f"{m.arbitration_id:03X}"
    return f"{ident}#R" if m.is_remote_frame else f"{ident}#{bytes(m.data).hex().upper()}"


@pytest.mark.parametrize("direction", ["A->B", "B->A"])
def test_python_can_frames_pass_unchanged_in_order(
    buses: tuple[can.BusABC, can.BusABC], direction: str
) -> None:
    """100 frames sent on one socketcan bus arrive on the other unchanged and in order."""
    a, b = buses
    tx, rx = (a, b) if direction == "A->B" else (b, a)
    sent = [_frame(i) for i in range(N_FRAMES)]
    for m in sent:
        tx.send(m, timeout=5)
    expected = {_key(m)[:2] for m in sent}
    got: list[can.Message] = []
    deadline = time.monotonic() + DEADLINE_S
    while len(got) < N_FRAMES:
        left = deadline - time.monotonic()
        assert left > 0, f"{direction}: only {len(got)}/{N_FRAMES} frames within {DEADLINE_S} s"
        r = rx.recv(timeout=left)
        if r is not None and (r.arbitration_id, r.is_extended_id) in expected:
            got.append(r)
    assert [_key(m) for m in got] == [_key(m) for m in sent]
    assert all(m.channel == CHANNEL for m in got)


def test_candump_sees_python_can_frames() -> None:
    """candump -L -n 3 vcan0 prints three consecutive frames sent by python-can."""
    candump = shutil.which("candump")
    if candump is None:
        pytest.skip("candump not found (apt-get install can-utils)")
    sent: list[str] = []
    deadline = time.monotonic() + DEADLINE_S
    with (
        subprocess.Popen(
            [candump, "-L", "-n", "3", CHANNEL],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        ) as dump,
        can.Bus(interface="socketcan", channel=CHANNEL) as bus,
    ):
        try:
            # candump has no readiness signal: keep sending distinct frames until it has
            # printed (and exited after) three of them; waiting on it paces the sending.
            i = 0
            while dump.poll() is None:
                assert time.monotonic() < deadline, (
                    f"candump printed < 3 frames within {DEADLINE_S} s ({i} sent)"
                )
                m = _frame(i)
                bus.send(m, timeout=5)
                sent.append(_candump_field(m))
                i += 1
                with contextlib.suppress(subprocess.TimeoutExpired):
                    dump.wait(timeout=0.05)
            out, err = dump.communicate(timeout=DEADLINE_S)
        finally:
            if dump.poll() is None:
                dump.kill()
                dump.communicate()
    assert dump.returncode == 0, f"candump exited {dump.returncode}: {err.strip()}"
    lines = out.splitlines()
    assert len(lines) == 3, out
    fields = []
    for line in lines:
        stamp, iface, field = line.split()
        assert stamp.startswith("(") and stamp.endswith(")"), line
        assert iface == CHANNEL, line
        fields.append(field)
    starts = [j for j in range(len(sent) - 2) if sent[j : j + 3] == fields]
    assert starts, f"candump saw {fields}, not three consecutive of the frames sent: {sent}"
