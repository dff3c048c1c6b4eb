"""The supervisor's wait (the child's status, its own work meanwhile) and a forked child's exit."""

from __future__ import annotations

import os
import signal

from bench.operator.lifecycle import exit_now, held_stop_signals, stop_on_signals, supervise

CHILD_EXIT = 7
ESCAPED_EXIT = 99  # a child that went on past exit_now


def test_supervise_runs_its_work_then_returns_the_childs_status() -> None:
    """``meanwhile`` runs once, while the child lives; the child's exit code comes back."""
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: exits once the parent's work has been done
        os.close(write_end)
        os.read(read_end, 1)
        os._exit(CHILD_EXIT)
    os.close(read_end)
    calls: list[bool] = []

    def meanwhile() -> None:
        calls.append(True)
        os.write(write_end, b"x")  # the child can only end after this ran

    status, signum = supervise(pid, meanwhile)
    os.close(write_end)
    assert calls == [True] and signum is None
    assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == CHILD_EXIT


def test_stop_signals_are_held_inside_the_block_and_restored_after() -> None:
    """SIGTERM inside held_stop_signals does not stop the block; it is listed, in order,
    and the previous handler is back afterwards."""
    before = signal.getsignal(signal.SIGTERM)
    with held_stop_signals() as held:
        os.kill(os.getpid(), signal.SIGTERM)
        os.kill(os.getpid(), signal.SIGHUP)
        reached = True
    assert reached and held == [signal.SIGTERM, signal.SIGHUP]
    assert signal.getsignal(signal.SIGTERM) is before


class _StoppedWhileFlushing:
    """A stream whose flush sends this process SIGTERM: a stop landing as a child exits."""

    def flush(self) -> None:
        os.kill(os.getpid(), signal.SIGTERM)


def test_exit_now_exits_with_its_code_when_a_stop_lands_on_the_way_out() -> None:
    """A forked child under stop_on_signals, stopped while it flushes, still ends with its
    own code at exit_now (it never goes on into its parent's code)."""
    pid = os.fork()
    if pid == 0:  # the child: exit_now must not return, even as the signal lands
        try:
            stop_on_signals()
            exit_now(CHILD_EXIT, (_StoppedWhileFlushing(),))  # type: ignore[arg-type]
        finally:
            os._exit(ESCAPED_EXIT)
    _, status = os.waitpid(pid, 0)
    assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == CHILD_EXIT
