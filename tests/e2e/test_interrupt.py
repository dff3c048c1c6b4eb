"""Ctrl-C on a run: exit 130, a complete run folder, and a clean flight-software exit."""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import can
import pytest

from bench.results.record import run_file
from tests.e2e.conftest import QUICKSTART, running, unique_bus

pytestmark = pytest.mark.slow

EXIT_INTERRUPTED = 130  # 128 + SIGINT, as shells report it
SIGNAL_EXIT_BASE = 128
INTERRUPT_AT_PERCENT = 10.0


@pytest.mark.parametrize("mode", ["lockstep", "realtime"])
def test_ctrl_c_exits_130_with_a_complete_folder(
    tmp_path: Path, runtime_dir: Path, mode: str
) -> None:
    """SIGINT to the whole process group, as a terminal sends it, part-way into the run."""
    out = tmp_path / "run"
    args = ["run", str(QUICKSTART), "--bus", unique_bus(), "--mode", mode, "--duration", "20"]
    with running(args, out, runtime_dir, INTERRUPT_AT_PERCENT, own_group=True) as p:
        os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate()
    assert p.returncode == EXIT_INTERRUPTED, err
    assert "stopped by SIGINT" in err and "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert 0.0 < summary["sim_time_s"] < 20.0 and summary["ended"] == "SIGINT"
    events = [json.loads(x) for x in (out / "events.jsonl").read_text().splitlines()]
    assert any(e["event"] == "run_interrupted" for e in events)
    assert "Traceback" not in (out / "fsw.log").read_text(encoding="utf-8")
    assert json.loads((out / "fsw_stats.json").read_text(encoding="utf-8"))["cycles"] > 0
    with can.LogReader(str(run_file(out, "trace.asc"))) as reader:
        assert sum(1 for _ in reader) > 0
    assert all(run_file(out, f).exists() for f in ("telemetry.csv", "attitude_error.png"))


@pytest.mark.parametrize("mode", ["lockstep", "realtime"])
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_leave_a_valid_summary_and_no_leftovers(
    tmp_path: Path, runtime_dir: Path, mode: str, sig: signal.Signals
) -> None:
    """SIGTERM or SIGHUP to the process group (a CI runner, timeout, a closed terminal):
    exit 128 + N, summary.json says how the run ended, no pid file, no bus socket left."""
    out = tmp_path / "run"
    args = ["run", str(QUICKSTART), "--bus", unique_bus(), "--mode", mode, "--duration", "20"]
    with running(args, out, runtime_dir, INTERRUPT_AT_PERCENT, own_group=True) as p:
        os.killpg(p.pid, sig)
        _, err = p.communicate()
    assert p.returncode == SIGNAL_EXIT_BASE + sig, err
    assert f"stopped by {sig.name}" in err and "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["ended"] == sig.name and 0.0 < summary["sim_time_s"] < 20.0
    assert not list(out.glob("*.pid")) and not list(out.glob(".space-*"))
    assert not [f for f in runtime_dir.rglob("*") if f.is_socket()]
