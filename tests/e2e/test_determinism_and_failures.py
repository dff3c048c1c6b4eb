"""Lockstep determinism, flight-software death, bad input and a short realtime run."""

from __future__ import annotations

import csv
import io
import json
import sys
from pathlib import Path

import pytest

from bench.operator.cli import EXIT_RUN_ERROR
from bench.results.record import run_file
from tests.e2e.conftest import QUICKSTART, REPO, run_cli, trace_lines, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

SHORT_S = "6"
KILL_AT_CYCLE = 100
CONTROL_PERIOD_S = 0.02
WATCHDOG_PERIODS = 3
EXIT_BAD_INPUT = 2
REALTIME_S = "3"
QUICKSTART_S = 60.0  # the scenario's own duration


def test_same_seed_gives_identical_trace_other_seed_differs(
    tmp_path: Path, runtime_dir: Path
) -> None:
    """Two lockstep runs with one seed are byte-identical by content; another seed is not."""
    runs = [
        run_cli(
            ["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", SHORT_S, "--seed", seed],
            tmp_path / f"r{i}",
            runtime_dir,
        )
        for i, seed in enumerate(("11", "11", "12"))
    ]
    traces = [trace_lines(r.out / "trace.asc") for r in runs]
    assert len(traces[0]) > 1000
    assert traces[0] == traces[1]
    assert traces[0] != traces[2]
    tel = [run_text(r.out, "telemetry.csv").encode() for r in runs]
    assert tel[0] == tel[1]


def test_killed_flight_software_closes_valves_and_keeps_run_folder(
    tmp_path: Path, runtime_dir: Path
) -> None:
    """SIGKILL of the flight software: valves closed within 3 periods, then the run ends as
    a run error (exit 3) naming the flight software's exit, with a complete run folder."""
    cmd = (
        f"{sys.executable} {REPO / 'tests' / 'e2e' / 'fsw_killed.py'} {KILL_AT_CYCLE} "
        "--bus {bus} --mode {mode} --config {config} --stats {stats}"
    )
    r = run_cli(
        ["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", SHORT_S, "--fsw-cmd", cmd],
        tmp_path / "run",
        runtime_dir,
    )
    s = r.summary
    assert r.returncode == EXIT_RUN_ERROR, r.stderr
    assert "flight software exited during the run" in s["error"] and s["ended"] == "error"
    assert "flight software exited during the run" in r.stderr
    assert s["valve_watchdog_trips"] == 1
    events = (r.out / "events.jsonl").read_text().splitlines()
    trip = next(e for e in events if '"valve_watchdog"' in e)
    ev = json.loads(trip)
    assert ev["t_s"] - ev["last_command_s"] <= (WATCHDOG_PERIODS + 1) * CONTROL_PERIOD_S
    assert ev["t_s"] <= KILL_AT_CYCLE * CONTROL_PERIOD_S + (WATCHDOG_PERIODS + 1) * CONTROL_PERIOD_S
    assert s["deadline_misses"]["stalls"] > 0
    assert s["fsw"]["exit_code"] == -9 and s["fsw"]["log_tail"] is not None
    for name in ("trace.asc", "telemetry.csv", "attitude_error.png"):
        assert run_file(r.out, name).stat().st_size > 0
    # after the trip no thruster produces thrust (last telemetry rows)
    with io.StringIO(run_text(r.out, "telemetry.csv"), newline="") as f:
        last = list(csv.DictReader(f))[-1]
    assert all(float(v) == 0.0 for k, v in last.items() if k.startswith("thrust_T"))


def test_bad_scenario_names_file_key_and_value(tmp_path: Path, runtime_dir: Path) -> None:
    """A bad value exits 2 with the file, the dotted key and the value in the message."""
    bad = tmp_path / "bad.toml"
    bad.write_text(QUICKSTART.read_text().replace("max_thrust_N = 15.0", "max_thrust_N = -15.0"))
    r = run_cli(["run", str(bad)], tmp_path / "run", runtime_dir)
    assert r.returncode == EXIT_BAD_INPUT
    assert str(bad) in r.stderr and "thrusters.max_thrust_N" in r.stderr and "-15.0" in r.stderr


def test_bad_flight_software_value_names_key_and_value(tmp_path: Path, runtime_dir: Path) -> None:
    """A [flight_sw] value only the flight software checks: exit 2 with its key and value."""
    r = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", "1",
                 "--set", 'flight_sw.modulator.kind="pwfp"'], tmp_path / "run", runtime_dir)
    assert r.returncode == EXIT_BAD_INPUT, r.stderr
    assert "refused its configuration" in r.stderr
    assert "flight_sw.modulator.kind" in r.stderr and "'pwfp'" in r.stderr
    assert "flight_sw.modulator.kind" in r.summary["fsw"]["refused"]  # from its stats file
    assert (tmp_path / "run" / "fsw.log").exists()  # the run folder still says what happened


def test_realtime_run_measures_latency(tmp_path: Path, runtime_dir: Path) -> None:
    """A short realtime run reports measured sensor-to-command latency and deadline counters."""
    r = run_cli(
        [
            "run",
            str(QUICKSTART),
            "--bus",
            unique_bus(),
            "--mode",
            "realtime",
            "--duration",
            REALTIME_S,
        ],
        tmp_path / "run",
        runtime_dir,
    )
    s = r.summary
    lat = s["latency_us"]["sensor_to_command"]
    assert s["mode"] == "realtime"
    assert lat["n"] > 0 and lat["p50"] > 0
    assert {"bench_late", "fsw_overruns"} <= set(s["deadline_misses"])
    assert s["wall_time_s"] >= float(REALTIME_S)


def test_realtime_quickstart_converges_over_its_60_s(tmp_path: Path, runtime_dir: Path) -> None:
    """The quickstart in realtime for its whole 60 s: converges, every expectation holds."""
    r = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--mode", "realtime"],
                tmp_path / "run", runtime_dir)
    s = r.summary
    assert s["sim_time_s"] == pytest.approx(QUICKSTART_S, abs=CONTROL_PERIOD_S)
    assert s["converged"], s["expectations"]
    assert s["expectations"] and all(e["pass"] for e in s["expectations"]), s["expectations"]
    assert s["fsw"]["mode"] != "SAFE"
    assert s["latency_us"]["sensor_to_command"]["p99"] is not None
    assert "total" in s["deadline_misses"]


RESTART_AT_CYCLE = 50
MAX_RESTART_STALLS = 3  # cycles lost while the new process boots


def test_flight_software_restart_is_detected_and_the_run_continues(
    tmp_path: Path, runtime_dir: Path
) -> None:
    """The flight software dies and boots again: the bench records the restart and resumes."""
    fsw_args = "--bus {bus} --mode {mode} --config {config} --stats {stats}"
    killed = f"{sys.executable} {REPO / 'tests' / 'e2e' / 'fsw_killed.py'} {RESTART_AT_CYCLE}"
    cmd = f"sh -c '{killed} {fsw_args}; exec {sys.executable} -m flight_sw {fsw_args}'"
    r = run_cli(
        ["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", SHORT_S, "--fsw-cmd", cmd],
        tmp_path / "run",
        runtime_dir,
    )
    s = r.summary
    events = [json.loads(x)["event"] for x in (r.out / "events.jsonl").read_text().splitlines()]
    assert s["fsw_restarts"] == 1
    assert "fsw_restart" in events
    assert 1 <= s["deadline_misses"]["stalls"] <= MAX_RESTART_STALLS
    # after the restart every cycle is answered again
    cycles = round(float(SHORT_S) / CONTROL_PERIOD_S)
    assert s["frames"]["THR_CMD_0"]["received"] >= cycles - MAX_RESTART_STALLS


def test_run_in_which_no_valve_opens_is_warned(tmp_path: Path, runtime_dir: Path) -> None:
    """10 kN thrusters on the quickstart: the modulators never fire, and the run says so."""
    r = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", "2",
                 "--set", "thrusters.max_thrust_N=10000"], tmp_path / "run", runtime_dir)
    assert r.summary["valve_openings"]["total"] == 0
    assert any(w.startswith("no valve opened") for w in r.summary["warnings"])
