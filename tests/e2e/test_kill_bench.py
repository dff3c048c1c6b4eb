"""SIGKILL of the bench mid-run: the folder is completed and no flight software is left."""

from __future__ import annotations

import json
import os
import selectors
import signal
import uuid
from pathlib import Path

import can
import pytest

from bench.results.record import is_whole, run_file
from tests.e2e.conftest import QUICKSTART, processes_with, running, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

DEADLINE_S = 60.0
MARK_VAR = "THIL_TEST_RUN_MARK"
KILL_AFTER_PERCENT = 30.0


def _all_end(mark: str) -> None:
    """Wait (up to DEADLINE_S each) for every process of the run marked ``mark`` to end;
    then none is left."""
    for pid in processes_with(mark):
        try:
            fd = os.pidfd_open(pid)
        except ProcessLookupError:
            continue
        try:  # the pidfd becomes readable when the process exits
            waiter = selectors.DefaultSelector()
            waiter.register(fd, selectors.EVENT_READ)
            assert waiter.select(timeout=DEADLINE_S), f"process {pid} of the run still running"
            waiter.close()
        finally:
            os.close(fd)
    assert processes_with(mark) == []


def _mark() -> str:
    return f"thil-kill-{uuid.uuid4().hex}"


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc (Linux)")
def test_sigkill_of_bench_leaves_readable_files_and_no_orphan(
    tmp_path: Path, runtime_dir: Path
) -> None:
    """After kill -9 of the bench: partial summary, trace and telemetry parse, FSW exits."""
    out, mark = tmp_path / "run", _mark()
    with running(
        ["run", str(QUICKSTART), "--bus", unique_bus()], out, runtime_dir, KILL_AFTER_PERCENT,
        env_extra={MARK_VAR: mark},
    ) as p:
        os.kill(int((out / "bench.pid").read_text()), signal.SIGKILL)  # the bench, not its
        p.wait(DEADLINE_S)  # supervisor: that one completes the folder and exits
    s = json.loads((out / "summary.json").read_text())
    assert s["partial"] and "signal 9" in s["error"]
    assert s["sim_time_s"] > 0 and s["frames"]["SYNC"]["sent"] > 0
    assert (out / "attitude_error.png").exists()
    # the compressed files the bench left unfinished were sealed: whole gzip files now
    assert "trace.asc.gz" in s["files_sealed"] and "telemetry.csv.gz" in s["files_sealed"]
    assert all(is_whole(out / name) for name in s["files_sealed"])
    assert any("sealed" in line for line in s["abnormal"])
    frames = list(can.LogReader(str(run_file(out, "trace.asc"))))
    assert len(frames) > 1000
    rows = run_text(out, "telemetry.csv").splitlines()
    assert len(rows) > 100 and all(len(r.split(",")) == len(rows[0].split(",")) for r in rows[1:-1])
    # the flight software got SIGTERM and wrote its statistics; the prestart ended with it
    _all_end(mark)
    assert (out / "fsw_stats.json").exists()


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc (Linux)")
def test_sigkill_of_the_command_is_said_in_the_summary(tmp_path: Path, runtime_dir: Path
                                                        ) -> None:
    """kill -9 of the thruster-hil command (its supervisor) mid-run: the bench gets SIGTERM
    from Linux and completes the folder, and summary.json says the command died, not just
    SIGTERM; no bench, prestart or flight software is left."""
    out, mark = tmp_path / "run", _mark()
    with running(["run", str(QUICKSTART), "--bus", unique_bus(), "--no-plots"], out,
                 runtime_dir, KILL_AFTER_PERCENT, env_extra={MARK_VAR: mark}) as p:
        bench_pid = int((out / "bench.pid").read_text())
        p.kill()
        p.wait(DEADLINE_S)
        fd = os.pidfd_open(bench_pid)  # the orphaned bench: readable once it has exited
        try:
            sel = selectors.DefaultSelector()
            sel.register(fd, selectors.EVENT_READ)
            assert sel.select(DEADLINE_S), "the orphaned bench did not end"
            sel.close()
        finally:
            os.close(fd)
    s = json.loads((out / "summary.json").read_text())
    assert s["ended"] == "SIGTERM" and s["supervisor_died"] is True
    assert any("thruster-hil command died" in line for line in s["abnormal"])
    _all_end(mark)
