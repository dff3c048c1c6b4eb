"""Pure parts of the orchestrator: warnings derived from the scenario and the run."""

from __future__ import annotations

import json
import os
import signal
import uuid
from pathlib import Path

import pytest

from bench.operator import bench_process, orchestrator
from bench.operator.lifecycle import Stopped
from bench.operator.run_warnings import duration_warnings, overrun_warning
from bench.scenario.load import load_scenario
from dbc.errors import ConfigError, RefusedConfigError

SCENARIOS = Path(__file__).resolve().parents[3] / "scenarios"
QUICKSTART = SCENARIOS / "quickstart.toml"
FAULTS = """
[[faults]]
t_s = 20.0
kind = "stuck_open"
thruster = 2

[[faults]]
t_s = 40.0
kind = "stuck_closed"
thruster = 5
"""


def test_run_too_short_for_its_steady_state_window_is_warned() -> None:
    """Quickstart: settling allowed 10 s, window 10 s; a 10 s run is warned, 20 s and 60 s not."""
    sc = load_scenario(QUICKSTART)
    e = sc.expectations
    needed_s = sc.manoeuvre_start_s + (e.settling_time_s_max or 0.0) + e.steady_state_window_s
    assert duration_warnings(sc, sc.duration_s) == []
    assert duration_warnings(sc, needed_s) == []
    (w,) = duration_warnings(sc, needed_s / 2)
    assert f"at least {needed_s:g} s" in w and "steady-state window" in w


def test_run_that_ends_before_scheduled_faults_and_events_is_warned(tmp_path: Path) -> None:
    """--duration before a fault or capture time: a warning names each one that never acts."""
    path = tmp_path / "faulty.toml"
    path.write_text(QUICKSTART.read_text(encoding="utf-8") + FAULTS, encoding="utf-8")
    sc = load_scenario(path)
    assert not [w for w in duration_warnings(sc, sc.duration_s) if "never act" in w]
    (w,) = [w for w in duration_warnings(sc, 30.0) if "never act" in w]
    assert "1 of the scenario's [[faults]]" in w and "stuck_closed at 40 s" in w
    (w,) = [w for w in duration_warnings(sc, 20.0) if "never act" in w]
    assert "2 of the scenario's [[faults]]" in w and "stuck_open at 20 s" in w
    capture = load_scenario(SCENARIOS / "capture_inertia_identification.toml")
    (event,) = capture.events
    (w,) = [w for w in duration_warnings(capture, event.t_s) if "never act" in w]
    assert "[[events]]" in w and f"capture at {event.t_s:g} s" in w


def test_bench_refusing_its_input_before_the_run_says_why(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A ConfigError inside the bench process: RefusedConfigError naming it, summary.json too."""
    bad = ConfigError("q.toml", "vehicle.k", 1.0, "something the bench takes")

    def refuse(*_args: object, **_kwargs: object) -> None:
        raise bad

    monkeypatch.setattr(bench_process, "BenchNode", refuse)
    sc = load_scenario(QUICKSTART)
    opts = orchestrator.RunOptions(mode="lockstep", bus=f"virtual:r-{uuid.uuid4().hex}",
                                   seed=1, out=tmp_path / "run", duration_s=1.0, fsw_cmd=None)
    with pytest.raises(RefusedConfigError) as info:
        orchestrator.run_scenario(sc, opts)
    assert str(bad) in str(info.value) and "the bench" in str(info.value)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text(encoding="utf-8"))
    assert summary["refused"] == str(bad) and summary["passed"] is False


def _opts(tmp_path: Path) -> orchestrator.RunOptions:
    return orchestrator.RunOptions(mode="lockstep", bus=f"virtual:s-{uuid.uuid4().hex}",
                                   seed=1, out=tmp_path / "run", duration_s=1.0, fsw_cmd=None)


def _stopped_summary(tmp_path: Path, sig: signal.Signals) -> dict[str, object]:
    """The folder a stop left: summary.json says how it ended, no error, no reserve file."""
    out = tmp_path / "run"
    summary: dict[str, object] = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["ended"] == sig.name and summary["partial"] is True
    assert "error" not in summary and summary["verdict"].startswith(f"STOPPED by {sig.name}")
    assert not list(out.glob(".space-*")) and not list(out.glob("*.pid"))
    return summary


def test_a_stop_before_the_bench_is_forked_completes_the_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """SIGTERM once the folder has its first files, before the bench exists: held, then
    Stopped (exit 143) with a summary that says so; the handlers are back as they were."""
    real_reserve = orchestrator.DiskReserve

    def reserve_then_signal(folder: Path) -> object:
        os.kill(os.getpid(), signal.SIGTERM)  # held: nothing acts on it yet
        return real_reserve(folder)

    monkeypatch.setattr(orchestrator, "DiskReserve", reserve_then_signal)
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Stopped) as info:
        orchestrator.run_scenario(load_scenario(QUICKSTART), _opts(tmp_path))
    assert info.value.signum == signal.SIGTERM and info.value.summary is not None
    assert _stopped_summary(tmp_path, signal.SIGTERM)["stopped_when"] == \
        "before the bench process started"
    assert signal.getsignal(signal.SIGTERM) is before


def test_a_bench_stopped_before_its_summary_is_a_stop_not_a_run_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The group's SIGTERM reaches the bench while it is still setting up (no summary.json
    yet): Stopped naming it and a partial summary, not a run error (exit 3)."""

    def stopped_while_building(*_args: object, **_kwargs: object) -> None:
        os.kill(os.getppid(), signal.SIGTERM)  # the supervisor gets it too, as a group does
        raise Stopped(signal.SIGTERM)

    monkeypatch.setattr(bench_process, "BenchNode", stopped_while_building)
    with pytest.raises(Stopped) as info:
        orchestrator.run_scenario(load_scenario(QUICKSTART), _opts(tmp_path))
    assert info.value.signum == signal.SIGTERM
    assert _stopped_summary(tmp_path, signal.SIGTERM)["stopped_when"] == \
        "before the bench wrote summary.json"


def test_overrun_warning_names_the_member_that_stalled() -> None:
    """Drops are attributed per receiving pid: the bench, the flight software or another."""
    w = overrun_warning({77: 3}, {10: 6, 77: 1}, bench_pid=10, fsw_pid=20,
                                     stall_s=0.01)
    assert w.startswith("10 frames were dropped for bus members that did not read for 10 ms")
    assert "6 from the flight software to the bench (pid 10)" in w
    assert "3 from the bench to another member (pid 77" in w
    assert "1 from the flight software to another member (pid 77" in w
