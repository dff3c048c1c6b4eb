"""A monitor that stops reading the portable bus cannot stop a run.

A user watches a running bench with ``python -m can.logger -i hilbus`` and pauses it
(Ctrl-Z, a full pipe): its queue fills. The run must still complete, lose nothing between
bench and flight software, report what the paused member missed, and leave the lockstep
trace exactly as without the monitor (the 1 s the senders are held up is wall-clock time).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.e2e.conftest import QUICKSTART, REPO, run_cli, trace_lines, unique_bus

RUN_S = "2"
LOGGER_READY_TIMEOUT_S = 60


@pytest.mark.slow
def test_paused_logger_does_not_stop_a_lockstep_run(tmp_path: Path, runtime_dir: Path) -> None:
    """A SIGSTOPped can.logger: the run completes, gap-free, counts drops, same trace."""
    bus = unique_bus()
    channel = bus.split(":", 1)[1]
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir), PYTHONUNBUFFERED="1")
    logger = subprocess.Popen(
        [sys.executable, "-m", "can.logger", "-i", "hilbus", "-c", channel],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=REPO, env=env,
    )
    try:
        assert logger.stdout is not None
        line = logger.stdout.readline()  # python-can prints the bus once it is open
        assert "hilbus" in line or "Connected" in line, line
        os.kill(logger.pid, signal.SIGSTOP)
        r = run_cli(["run", str(QUICKSTART), "--bus", bus, "--duration", RUN_S],
                    tmp_path / "run", runtime_dir)
    finally:
        os.kill(logger.pid, signal.SIGCONT)
        logger.kill()
        logger.communicate()
    s = r.summary
    assert "error" not in s, r.stderr
    assert s["fsw"]["bus_overrun_drops"] > 0  # frames of each process the logger missed
    assert s["bus_overrun_drops"] > s["fsw"]["bus_overrun_drops"]  # both processes' drops
    (warning,) = [w for w in s["warnings"] if "did not read" in w]
    assert f"to another member (pid {logger.pid}," in warning  # the logger, named
    assert "to the bench" not in warning and "to the flight software" not in warning
    assert s["deadline_misses"]["stalls"] == 0
    for name, f in s["frames"].items():
        assert not f.get("gaps"), (name, f)
    alone = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", RUN_S],
                    tmp_path / "alone", runtime_dir)
    assert trace_lines(r.out / "trace.asc") == trace_lines(alone.out / "trace.asc")
