"""The supervisor's wait: the child's status, and its own work done while the child runs."""

from __future__ import annotations

import os
import signal

from bench.operator.lifecycle import held_stop_signals, supervise

CHILD_EXIT = 7


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
