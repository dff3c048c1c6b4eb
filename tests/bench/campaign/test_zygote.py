"""bench.campaign.zygote: runs forked by a warm process, their exit codes, their ends."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from bench.campaign.zygote import Zygote
from dbc.errors import RunError
from tests.e2e.conftest import QUICKSTART, unique_bus

EXIT_BAD_INPUT = 2  # thruster-hil's exit code for a refused input
RUN_TIMEOUT_S = 1.0  # far shorter than the quickstart's run
GONE_WITHIN_S = 30.0  # a hang guard: a stopped run's processes end within this
RUNS_FOR_LEAK = 5  # a descriptor kept per run shows as 5 more
IN_FLIGHT_FDS = 1  # the last run's connection, which the zygote may not have closed yet


@pytest.fixture(scope="module")
def zygote() -> Iterator[Zygote]:
    """One zygote for the module's tests (its start-up is the imports)."""
    with Zygote() as z:
        yield z


def _gone(pid: int) -> bool:
    """Whether the session led by ``pid`` has no process left, waiting up to GONE_WITHIN_S."""
    deadline = time.monotonic() + GONE_WITHIN_S
    while time.monotonic() < deadline:
        try:
            os.killpg(pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.01)  # polling another process's end: no wait primitive for a group
    return False


def test_a_refused_input_is_exit_2_with_its_reason_on_stderr(
        zygote: Zygote, tmp_path: Path) -> None:
    """A scenario that does not exist: exit 2, and stderr names the path."""
    err = tmp_path / "err.txt"
    missing = tmp_path / "no_such.toml"
    code = zygote.run(["run", str(missing), "--out", str(tmp_path / "o")], dict(os.environ),
                      err, RUN_TIMEOUT_S * 30)
    assert code == EXIT_BAD_INPUT
    assert str(missing) in err.read_text(encoding="utf-8")


def test_a_run_past_its_timeout_is_stopped_with_its_whole_session(
        zygote: Zygote, tmp_path: Path, runtime: Path) -> None:
    """TimeoutExpired after the timeout; the run (supervisor, bench, flight software) is
    gone and its folder completed by its own lifecycle (summary: stopped by SIGTERM)."""
    out = tmp_path / "run"
    args = ["run", str(QUICKSTART), "--bus", unique_bus(), "--no-plots", "--out", str(out)]
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime))
    with pytest.raises(subprocess.TimeoutExpired):
        zygote.run(args, env, tmp_path / "err.txt", RUN_TIMEOUT_S)
    pid = int((out / "bench.pid").read_text()) if (out / "bench.pid").exists() else None
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["ended"] == "SIGTERM"
    if pid is not None:
        assert _gone(pid)
    assert zygote.alive()


def test_a_caller_that_hangs_up_has_its_run_stopped(
        zygote: Zygote, tmp_path: Path, runtime: Path) -> None:
    """A connection closed before its run ended: the zygote stops that run's session."""
    out = tmp_path / "run"
    request = {"argv": ["run", str(QUICKSTART), "--bus", unique_bus(), "--no-plots",
                        "--out", str(out)],
               "env": dict(os.environ, XDG_RUNTIME_DIR=str(runtime)), "cwd": str(tmp_path),
               "console": str(tmp_path / "err.txt")}
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as conn:
        conn.connect(str(zygote.path))
        conn.sendall(json.dumps(request).encode() + b"\n")
        pid = int(json.loads(conn.makefile().readline())["pid"])
    assert _gone(pid)
    assert zygote.alive()


def test_the_zygote_keeps_no_descriptor_per_run(zygote: Zygote, tmp_path: Path) -> None:
    """Runs come and go and the zygote's open descriptors stay as many (each child is
    reaped, none followed by a pidfd: a leak would end every case after ~1000)."""
    fds = Path(f"/proc/{zygote._proc.pid}/fd")

    def refused() -> int:
        return zygote.run(["run", str(tmp_path / "missing.toml"), "--out", str(tmp_path / "o")],
                          dict(os.environ), tmp_path / "err.txt", RUN_TIMEOUT_S * 30)

    assert refused() == EXIT_BAD_INPUT
    before = len(list(fds.iterdir()))
    for _ in range(RUNS_FOR_LEAK):
        assert refused() == EXIT_BAD_INPUT
    assert len(list(fds.iterdir())) - before <= IN_FLIGHT_FDS


def test_a_zygote_closed_during_a_run_lets_the_run_complete_its_folder(
        tmp_path: Path, runtime: Path) -> None:
    """close() while a run goes: the run gets SIGTERM and writes its summary (ended
    SIGTERM); the waiting caller gets a RunError, not a timeout, after the run is gone."""
    import threading

    out = tmp_path / "run"
    args = ["run", str(QUICKSTART), "--bus", unique_bus(), "--no-plots", "--out", str(out)]
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime))
    z = Zygote()
    errors: list[BaseException] = []

    def caller() -> None:
        try:
            z.run(args, env, tmp_path / "err.txt", GONE_WITHIN_S * 4)
        except BaseException as exc:
            errors.append(exc)

    t = threading.Thread(target=caller)
    t.start()
    events = out / "events.jsonl"
    deadline = time.monotonic() + GONE_WITHIN_S
    while time.monotonic() < deadline and not (
            events.exists() and "run_started" in events.read_text(encoding="utf-8")):
        time.sleep(0.01)  # the run's start (its first event), seen from outside
    z.close()
    t.join(GONE_WITHIN_S * 2)
    assert len(errors) == 1 and isinstance(errors[0], RunError), errors
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["ended"] == "SIGTERM"


def test_sigterm_ends_the_zygote_and_it_removes_its_folder() -> None:
    """A SIGTERM to the zygote (a campaign's process group stopped): it exits, and its
    folder (socket, log) is gone with it."""
    import signal

    z = Zygote()
    folder = z.path.parent
    z._proc.send_signal(signal.SIGTERM)
    assert z._proc.wait(GONE_WITHIN_S) == 0
    assert not folder.exists()
    z.close()


def test_closing_the_zygote_ends_it_and_removes_its_folder() -> None:
    """close(): the process ends (its stdin at end of file) and its socket folder goes."""
    z = Zygote()
    folder = z.path.parent
    assert z.alive() and z.path.exists()
    z.close()
    assert not z.alive() and not folder.exists()
