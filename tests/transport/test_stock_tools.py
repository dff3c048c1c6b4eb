"""python-can's stock tools on the portable bus, run as real processes on private channels.

``python -m can.logger``, ``can.player`` (``-i hilbus -c CHANNEL``) and ``can.bridge``
(``--bus1-interface hilbus --bus1-channel A --bus2-interface hilbus --bus2-channel B``):
frames sent by a member of the channel reach them, and theirs reach us, unchanged and in
order. Waits are on real output lines, frames and process exits, never on sleeping.
"""

from __future__ import annotations

import contextlib
import signal
import subprocess
import sys
import uuid
from collections.abc import Iterator
from pathlib import Path

import can
import pytest

from tests.transport.helpers import DEADLINE_S, Lines, env_for, frame_key, recv_n
from transport.channel import channel_dir
from transport.hilbus import HilBus

pytestmark = pytest.mark.slow  # each starts a python-can process (about a second)

PLAYER_GAP_S = 0.001  # between the frames of the replayed log (the player keeps the gaps)
# can.bridge's statement between its ready line and its Ctrl-C handler (see _interrupt)
BRIDGE_UNGUARDED_LINE = 'print(f"CAN Bridge (Started on {datetime.now()})")'


def _sigint_default() -> None:
    """In the child: Ctrl-C reaches it as from a terminal, even when this run's SIGINT is
    ignored (a background job inherits SIG_IGN, and so would the tool: seen in CI)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@contextlib.contextmanager
def _tool(
    module: str, args: list[str], runtime: Path
) -> Iterator[tuple[subprocess.Popen[str], Lines]]:
    """``python -m MODULE ARGS`` with its output lines; killed on the way out if running."""
    with subprocess.Popen(
        [sys.executable, "-m", module, *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**env_for(runtime), "PYTHONFAULTHANDLER": "1"},  # SIGABRT dumps its stacks
        cwd=runtime,
        preexec_fn=_sigint_default,
    ) as proc:
        try:
            assert proc.stdout is not None
            yield proc, Lines(proc.stdout)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


def _interrupt(
    proc: subprocess.Popen[str], lines: Lines, what: str, unguarded_line: str | None = None
) -> None:
    """Ctrl-C to a tool that shuts its buses down on it; fails (with its stacks) if it
    does not end in time, or ends with an error.

    ``unguarded_line``: a statement of the tool's own that runs after its ready line and
    before its ``except KeyboardInterrupt`` takes over (can.bridge prints "Started" first,
    then enters its try); Ctrl-C landing there ends it with KeyboardInterrupt at that line,
    the tool's race, not the bus's: accepted, and only there.
    """
    proc.send_signal(signal.SIGINT)
    try:
        code = proc.wait(DEADLINE_S)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGABRT)  # where is it stuck? (faulthandler)
        pytest.fail(f"{what} ignored Ctrl-C for {DEADLINE_S} s; its stacks:\n"
                    f"{''.join(lines.rest())}")
    output = [ln.strip() for ln in lines.rest()]
    if code == -signal.SIGINT and unguarded_line is not None:
        code_lines = [ln for ln in output if set(ln) - set("^~ ")]  # no caret markers
        assert code_lines[-2:] == [unguarded_line, "KeyboardInterrupt"], "\n".join(output)
        return
    assert code == 0, f"{what} exited {code}:\n" + "\n".join(output)


def test_can_logger_prints_frames(runtime: Path, channel: str) -> None:
    """python -m can.logger -i hilbus -c CHANNEL prints frames sent on the channel."""
    with _tool("can.logger", ["-i", "hilbus", "-c", channel], runtime) as (logger, lines):
        lines.wait_for("Connected to HilBus")
        with HilBus(channel) as bus:
            bus.send(can.Message(arbitration_id=0x123, is_extended_id=False, data=b"\xca\xfe"))
            bus.send(can.Message(arbitration_id=0x1BADBEE, data=b"\x01\x02\x03"))
            first = lines.wait_for("ID:")
            second = lines.wait_for("ID:")
        assert "123" in first and "ca fe" in first and channel in first
        assert "1badbee" in second.lower() and "01 02 03" in second
        _interrupt(logger, lines, "can.logger")
    assert not channel_dir(channel).exists()  # every member left: the channel is gone


def _log_file(path: Path) -> list[can.Message]:
    """A candump-format log of standard, extended, remote and FD frames, as read back."""
    frames = [
        can.Message(arbitration_id=0x100 + i, is_extended_id=False, data=bytes([i, 1, 2]))
        for i in range(3)
    ]
    frames += [
        can.Message(arbitration_id=0x1ABCDE0, data=b"\x01\x02\x03\x04"),
        can.Message(arbitration_id=0x200, is_extended_id=False, is_remote_frame=True),
        can.Message(arbitration_id=0x300, is_extended_id=False, is_fd=True,
                    bitrate_switch=True, data=bytes(range(12))),
    ]
    with can.Logger(path) as log:
        for i, m in enumerate(frames):
            m.timestamp = i * PLAYER_GAP_S
            log(m)
    with can.LogReader(path) as reader:
        return list(reader)


def test_can_player_replays_a_log_onto_the_channel(runtime: Path, channel: str) -> None:
    """python -m can.player -i hilbus -c CHANNEL FILE: every frame of the file arrives, as
    the player read it, in order; the player ends by itself."""
    log = runtime / "replay.log"
    expected = _log_file(log)
    with HilBus(channel) as bus, _tool(
        "can.player", ["-i", "hilbus", "-c", channel, str(log)], runtime
    ) as (player, lines):
        got = recv_n(bus, len(expected))
        assert [frame_key(m) for m in got] == [frame_key(m) for m in expected]
        assert player.wait(DEADLINE_S) == 0, "".join(lines.rest())
        assert bus.recv(timeout=0) is None


def test_can_bridge_joins_two_channels_both_ways(runtime: Path) -> None:
    """python -m can.bridge between two hilbus channels: frames sent on either arrive on
    the other, in order, until Ctrl-C stops it."""
    ch1, ch2 = (f"br{k}-{uuid.uuid4().hex[:8]}" for k in (1, 2))
    args = ["--bus1-interface", "hilbus", "--bus1-channel", ch1,
            "--bus2-interface", "hilbus", "--bus2-channel", ch2]
    with HilBus(ch1) as on1, HilBus(ch2) as on2, _tool("can.bridge", args, runtime) as (
        bridge, lines
    ):
        lines.wait_for("CAN Bridge (Started")
        one_to_two = [can.Message(arbitration_id=0x10 + i, data=bytes([i])) for i in range(5)]
        two_to_one = [can.Message(arbitration_id=0x20 + i, is_fd=True, data=bytes(16))
                      for i in range(5)]
        for m in one_to_two:
            on1.send(m)
        for m in two_to_one:
            on2.send(m)
        assert [frame_key(m) for m in recv_n(on2, 5)] == [frame_key(m) for m in one_to_two]
        assert [frame_key(m) for m in recv_n(on1, 5)] == [frame_key(m) for m in two_to_one]
        _interrupt(bridge, lines, "can.bridge", BRIDGE_UNGUARDED_LINE)
        assert on1.recv(timeout=0) is None and on2.recv(timeout=0) is None
