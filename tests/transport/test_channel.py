"""Tests of :mod:`transport.channel`: channel directories come and go with their members.

The last member leaving removes its channel's directory; a member joining while it leaves
still joins; directories and sockets that dead processes left behind are swept away by
the next member to join, and nothing else is touched. Every test has a private runtime
directory.
"""

from __future__ import annotations

import os
import socket
import subprocess
import threading
from pathlib import Path

import can
import pytest

from tests.transport.helpers import DEADLINE_S, recv_n
from transport import channel as channel_mod
from transport.channel import bus_root, channel_dir, sweep
from transport.hilbus import HilBus

RACE_ROUNDS = 200  # joins and leaves per thread (2 x 300 hit the race ~17 times here)
RACERS = 2


def _dead_pid() -> int:
    """The pid of a process that has ended (reused by another only after a long while)."""
    with subprocess.Popen(["true"]) as p:
        p.wait(DEADLINE_S)
    return p.pid


def _dead_member(directory: Path) -> Path:
    """A member socket file as a killed process leaves it: its pid dead, nothing bound."""
    for d in (directory.parent, directory):
        d.mkdir(mode=0o700, exist_ok=True)
    path = directory / f"{_dead_pid()}-0badf00d.sock"
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
        s.bind(os.fspath(path))
    return path


def test_the_last_member_leaving_removes_the_channel_directory(channel: str) -> None:
    """The directory stays while a member is left and goes with the last one."""
    a = HilBus(channel)
    with HilBus(channel):
        a.shutdown()
        assert channel_dir(channel).is_dir()
    assert not channel_dir(channel).exists()
    assert bus_root().is_dir()


def test_a_member_joining_as_the_last_one_leaves_creates_the_directory_again(
    channel: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The directory removed between a joiner's check and its bind: the joiner creates it
    again, binds, and frames reach it."""
    real_secure_dir = channel_mod.secure_dir
    removed: list[Path] = []

    def secure_then_lose(path: Path) -> None:
        real_secure_dir(path)
        if path == channel_dir(channel) and not removed:
            os.rmdir(path)  # the last member's rmdir lands right here
            removed.append(path)

    monkeypatch.setattr(channel_mod, "secure_dir", secure_then_lose)
    with HilBus(channel) as b, HilBus(channel) as a:
        assert removed == [channel_dir(channel)] and b.path.exists()
        a.send(can.Message(arbitration_id=0x21))
        assert recv_n(b, 1)[0].arbitration_id == 0x21


def test_members_joining_and_leaving_at_once_always_join(channel: str) -> None:
    """Threads that join and leave one channel over and over, so that its directory keeps
    being removed and created, never fail to join; nothing is left afterwards."""
    errors: list[BaseException] = []

    def churn() -> None:
        try:
            for _ in range(RACE_ROUNDS):
                with HilBus(channel) as bus:
                    assert bus.path.exists()
        except BaseException as exc:  # inspected below
            errors.append(exc)

    threads = [threading.Thread(target=churn, daemon=True) for _ in range(RACERS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(DEADLINE_S)
        assert not t.is_alive(), "a thread is still joining and leaving"
    assert not errors, f"{len(errors)} joins failed, e.g. {errors[0]!r}"
    assert not channel_dir(channel).exists()


def test_joining_sweeps_what_dead_processes_left(runtime: Path, channel: str) -> None:
    """A member joining any channel removes dead members' sockets and the channel
    directories they leave empty, and empty channel directories."""
    dead = _dead_member(bus_root() / "dead")
    (bus_root() / "empty").mkdir(mode=0o700)
    mixed = _dead_member(bus_root() / "mixed")
    with HilBus("mixed") as live, HilBus(channel):
        assert not dead.exists() and not dead.parent.exists()
        assert not (bus_root() / "empty").exists()
        assert not mixed.exists() and live.path.exists()


def test_the_sweep_touches_nothing_but_dead_members(runtime: Path, channel: str) -> None:
    """Live members, sockets of live processes, other files and directories that are not
    private stay where they are."""
    with HilBus(channel) as live:
        orphan = live.directory / f"{os.getpid()}-0badcafe.sock"  # refuses, pid alive
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
            s.bind(os.fspath(orphan))
        foreign = bus_root() / "notes"
        foreign.mkdir(mode=0o700)
        (foreign / "README").write_text("not a member")
        shared = bus_root() / "shared"
        shared.mkdir(mode=0o700)
        shared.chmod(0o755)
        dead_in_shared = _dead_member(shared)
        sweep(bus_root())
        assert live.path.exists() and orphan.exists()
        assert (foreign / "README").exists() and dead_in_shared.exists()
        orphan.unlink()


def test_a_member_that_cannot_bind_leaves_no_directory(runtime: Path, channel: str) -> None:
    """A socket that cannot be bound (it already is): BusInitError, and the channel
    directory made for it is removed again."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as sock:
        sock.bind(os.fspath(runtime / "elsewhere.sock"))
        path = channel_dir(channel) / "1-00.sock"
        with pytest.raises(can.CanInitializationError, match="cannot bind"):
            channel_mod.join(sock, path)
    assert bus_root().is_dir() and not channel_dir(channel).exists()
