"""Example timing tests, written as a user of thruster-hil writes them (the ``hil_run`` fixture).

They run in this project's CI, in lockstep: bus times are modelled (bit-exact frame
lengths, arbitration by ID), so every figure is deterministic and the limits can be tight.
Wall-clock measurements (``--hil-mode realtime``) belong in ``benchmarks/``, never in
pass/fail tests. See docs/timing-tests.md.
"""

from __future__ import annotations

import pytest

from bench.operator.pytest_plugin import HilRun, HilRunner

QUICKSTART = "scenarios/quickstart.toml"  # relative to where pytest runs, or the rootdir
DURATION_S = 5.0  # 250 control cycles

# Requirements under test (illustrative figures for the quickstart vehicle):
IMU_TO_COMMAND_P99_MAX_US = 2000.0  # a command is computed from IMU data at most 2 ms old
IMU_TO_VALVE_MAX_US = 5000.0  # ... and opens a valve within 5 ms of the IMU sample
VALVE_OPEN_DELAY_US = 3000.0  # the quickstart's open_delay_s: command frame -> valve open
MODELLED_TIME_TOL_US = 0.01  # lockstep times are exact nanoseconds, written to 10 digits
BUS_LOAD_PEAK_MAX_PCT = 30.0  # at 1 Mbit/s, in any 10 ms window
SLOW_BITRATE_BPS = 125_000
SLOW_BUS_LATENCY_FACTOR_MIN = 4.0  # 8x longer frames; queueing behind bench frames adds more


@pytest.fixture
def run(hil_run: HilRunner) -> HilRun:
    """One lockstep quickstart run, shared by every test of this session that asks for it."""
    return hil_run(QUICKSTART, duration_s=DURATION_S)


def test_imu_to_command_latency(run: HilRun) -> None:
    """IMU sample -> first thruster command: p99 below 2 ms."""
    assert run.latency("IMU_RATE", "THR_CMD_0").p99_us < IMU_TO_COMMAND_P99_MAX_US


def test_valve_opens_on_fresh_data(run: HilRun) -> None:
    """Age of the IMU data when a valve opens: never above 5 ms."""
    chain = run.chain()
    assert chain.imu_to_valve.n > 0
    assert chain.imu_to_valve.max_us < IMU_TO_VALVE_MAX_US


def test_valve_opens_its_delay_after_its_command(run: HilRun) -> None:
    """The frame that commands a firing -> that valve open: the valve's opening delay."""
    c = run.chain().command_to_valve
    assert c.n > 0
    assert c.p50_us == pytest.approx(VALVE_OPEN_DELAY_US, abs=MODELLED_TIME_TOL_US)
    assert c.max_us == pytest.approx(VALVE_OPEN_DELAY_US, abs=MODELLED_TIME_TOL_US)


def test_every_periodic_message_on_time(run: HilRun) -> None:
    """No missed cycles and no cycle-time violations (±1 ms, ±10 % of GenMsgCycleTime)."""
    for m in run.timing.messages.values():
        if m.cycle_time_ms is None:
            continue
        assert m.missed_cycles == 0, m
        assert (m.cycle_violations_abs, m.cycle_violations_rel) == (0, 0), m


def test_latency_within_worst_case_bound(run: HilRun) -> None:
    """Every message's measured maximum latency is within its response-time bound."""
    assert run.timing.flagged() == []
    sync = run.message("SYNC")
    assert sync.bound_us is not None and sync.latency.max_us <= sync.bound_us


def test_bus_load_peak(run: HilRun) -> None:
    """Bus load in the busiest 10 ms window stays below 30 %."""
    assert run.bus_load().total.peak_pct < BUS_LOAD_PEAK_MAX_PCT


def test_slow_bus_costs_latency_but_stays_bounded(run: HilRun, hil_run: HilRunner) -> None:
    """At 125 kbit/s a command frame takes over 4x longer than at 1 Mbit/s, within its bound."""
    slow = hil_run(
        QUICKSTART, duration_s=DURATION_S, overrides=[f"bus.bitrate_bps={SLOW_BITRATE_BPS}"]
    )
    assert slow.summary["bitrate_bps"] == SLOW_BITRATE_BPS
    fast_cmd, slow_cmd = run.message("THR_CMD_0"), slow.message("THR_CMD_0")
    assert slow_cmd.latency.p50_us > SLOW_BUS_LATENCY_FACTOR_MIN * fast_cmd.latency.p50_us
    assert slow.chain().imu_to_command.p50_us > run.chain().imu_to_command.p50_us
    assert slow.timing.flagged() == []
