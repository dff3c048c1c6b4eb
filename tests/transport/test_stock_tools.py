"""python-can's stock tools on the portable bus, run as real processes on a private channel.

``python -m can.logger`` (and the player and bridge) with ``-i hilbus -c CHANNEL``: frames
sent by a member of the channel reach them, and theirs reach us. Waits are on real output
lines and frames, never on sleeping.
"""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import can
import pytest

from tests.transport.helpers import DEADLINE_S, Lines, env_for
from transport.channel import channel_dir
from transport.hilbus import HilBus


def test_can_logger_prints_frames(runtime: Path, channel: str) -> None:
    """python -m can.logger -i hilbus -c CHANNEL prints frames sent on the channel."""
    with subprocess.Popen(
        [sys.executable, "-m", "can.logger", "-i", "hilbus", "-c", channel],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**env_for(runtime), "PYTHONFAULTHANDLER": "1"},  # SIGABRT dumps its stacks
        cwd=runtime,
        # Ctrl-C reaches it as from a terminal, even when this run's SIGINT is ignored (a
        # background job inherits SIG_IGN, and so would the logger: seen in CI)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    ) as logger:
        try:
            assert logger.stdout is not None
            lines = Lines(logger.stdout)
            lines.wait_for("Connected to HilBus")
            with HilBus(channel) as bus:
                bus.send(can.Message(arbitration_id=0x123, is_extended_id=False, data=b"\xca\xfe"))
                bus.send(can.Message(arbitration_id=0x1BADBEE, data=b"\x01\x02\x03"))
                first = lines.wait_for("ID:")
                second = lines.wait_for("ID:")
            assert "123" in first and "ca fe" in first and channel in first
            assert "1badbee" in second.lower() and "01 02 03" in second
            logger.send_signal(signal.SIGINT)  # can.logger shuts the bus down on Ctrl-C
            try:
                logger.wait(DEADLINE_S)
            except subprocess.TimeoutExpired:
                logger.send_signal(signal.SIGABRT)  # where is it stuck? (faulthandler)
                pytest.fail("can.logger ignored Ctrl-C for "
                            f"{DEADLINE_S} s; its stacks:\n{''.join(lines.rest())}")
        finally:
            if logger.poll() is None:
                logger.kill()
                logger.wait()
    assert not channel_dir(channel).exists()  # every member left: the channel is gone
