"""hilbus's errors are python-can's: ``except can.CanError`` catches every one of them.

Constructor failures are :class:`can.CanInitializationError` (and ValueError where an
argument is out of range), failed operations :class:`can.CanOperationError` (a send that
times out also :class:`can.CanTimeoutError`), and all are the project's
:class:`~dbc.errors.BusError`, which the command-line tools report with exit 2.
"""

from __future__ import annotations

import uuid
from pathlib import Path
from typing import Any

import can
import pytest

from bench.operator import cli
from dbc.errors import BusError
from tests.transport.helpers import QUEUE_OVERFILL_N
from transport.channel import bus_root
from transport.hilbus import HilBus

EXIT_BAD_INPUT = 2
SEND_TIMEOUT_S = 0.05


@pytest.mark.parametrize(
    "kwargs",
    [{"channel": "a/b"}, {"channel": "c" * 120}, {"member_stall_s": -1.0}],
    ids=["bad-channel-name", "path-too-long", "bad-member-stall"],
)
def test_a_bad_argument_is_a_python_can_initialization_error_and_a_value_error(
    runtime: Path, kwargs: dict[str, Any]
) -> None:
    """An argument out of range, through can.Bus as any python-can program opens a bus."""
    args: dict[str, Any] = {"channel": f"e-{uuid.uuid4().hex[:8]}", **kwargs}
    with pytest.raises(can.CanInitializationError) as info:
        can.Bus(interface="hilbus", **args)
    assert isinstance(info.value, ValueError) and isinstance(info.value, BusError)


def test_an_unusable_directory_is_a_python_can_initialization_error(runtime: Path) -> None:
    """A bus directory with group/other permissions: CanInitializationError naming it."""
    bus_root().mkdir(mode=0o700)
    bus_root().chmod(0o755)
    with pytest.raises(can.CanInitializationError, match=str(bus_root())) as info:
        can.Bus(interface="hilbus", channel="x")
    assert isinstance(info.value, BusError) and not isinstance(info.value, ValueError)


def test_failed_operations_are_python_can_operation_errors(channel: str) -> None:
    """A frame that cannot exist, a listen-only send, an unsupported state, and sends and
    receives after shutdown raise CanOperationError (the project's BusError too)."""
    with HilBus(channel) as a:
        with pytest.raises(can.CanOperationError, match="9 data bytes") as info:
            a.send(can.Message(arbitration_id=1, data=bytes(9)))
        assert isinstance(info.value, BusError)
        a.state = can.BusState.PASSIVE
        with pytest.raises(can.CanOperationError, match="listen-only") as info:
            a.send(can.Message(arbitration_id=1))
        assert isinstance(info.value, BusError)
        with pytest.raises(can.CanOperationError, match="unsupported") as info:
            a.state = can.BusState.ERROR
        assert isinstance(info.value, BusError)
    with pytest.raises(can.CanOperationError, match="shut down") as info:
        a.send(can.Message())
    assert isinstance(info.value, BusError)
    with pytest.raises(can.CanOperationError, match="shut down") as info:
        a.recv(timeout=0)
    assert isinstance(info.value, BusError)


def test_a_send_that_times_out_is_a_python_can_timeout_error(
    pair: tuple[HilBus, HilBus],
) -> None:
    """A member that never reads makes send(timeout) raise CanTimeoutError, which is also
    a CanOperationError (what python-can's socketcan raises for a full transmit queue)."""
    a, _b = pair
    with pytest.raises(can.CanTimeoutError, match="not reading") as info:
        for i in range(QUEUE_OVERFILL_N):
            a.send(can.Message(arbitration_id=i), timeout=SEND_TIMEOUT_S)
    assert isinstance(info.value, can.CanOperationError) and isinstance(info.value, BusError)


def test_the_cli_reports_a_hilbus_error_as_a_bus_error_with_exit_2(
    channel: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A hilbus error raised while a command runs: one line naming it, exit 2, no traceback."""

    def send_after_shutdown(*_args: object, **_kwargs: object) -> int:
        bus = HilBus(channel)
        bus.shutdown()
        bus.send(can.Message())
        return 0

    monkeypatch.setattr(cli, "_cmd_run", send_after_shutdown)
    code = cli.main(["run", "scenario.toml"])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT
    assert "error: hilbus: send on a bus that was shut down" in err and "Traceback" not in err
