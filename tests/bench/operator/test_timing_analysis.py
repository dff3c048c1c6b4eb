"""Timing analysis on synthetic run folders with known periods, jitter, latencies and load."""

from __future__ import annotations

import json
import math
from pathlib import Path

import can
import numpy as np
import pytest

from bench.operator.analysis.live import LiveOptions, capture, frames_from_messages
from bench.operator.analysis.records import TimingOptions
from bench.operator.analysis.report import format_report, write_histograms, write_json
from bench.operator.analysis.tables import NO_COUNTER, FrameTable
from bench.operator.analysis.timing import RunTiming
from bench.results.writers import CHAIN_COLUMNS
from bench.wire.trace import FRAME_COLUMNS
from dbc.database import load_database
from dbc.errors import ConfigError, RunError
from transport.hilbus import HilMessage

# Tolerances, named: float sums of seconds near 0.1 s carry ~1e-17 s error each.
TIME_TOL_S = 1e-12
TIME_TOL_US = 1e-6
TIME_TOL_MS = 1e-9
PCT_TOL = 1e-9

BITRATE_1M = 1_000_000
BITRATE_125K = 125_000
US = 1e-6
MS = 1e-3
NAN = float("nan")
BITS_8_BYTES = 125  # a typical stuffed length of an 8-byte frame

SYNC, THR_CMD_0, IMU_RATE = 0x010, 0x020, 0x040  # DBC IDs: BENCH, FSW, BENCH senders
IMU_PERIOD_S = 10 * MS  # GenMsgCycleTime of IMU_RATE
CMD_PERIOD_S = 20 * MS  # GenMsgCycleTime of SYNC and THR_CMD_*


def _frame(
    t_ready: float,
    t_rx: float,
    can_id: int,
    counter: int,
    *,
    t_start: float = NAN,
    bits: int = BITS_8_BYTES,
    tx: int = 1,
) -> list[float]:
    return [t_ready, t_start, t_rx, can_id, 8, bits, tx, counter]


def _table(rows: list[list[float]]) -> FrameTable:
    a = np.array(rows, dtype=float).reshape(-1, len(FRAME_COLUMNS))
    return FrameTable.from_columns({c: a[:, i] for i, c in enumerate(FRAME_COLUMNS)})


def _write_run(
    d: Path,
    rows: list[list[float]],
    *,
    mode: str = "lockstep",
    bitrate: int = BITRATE_1M,
    chains: list[list[float]] | None = None,
) -> Path:
    d.mkdir(parents=True, exist_ok=True)
    (d / "summary.json").write_text(json.dumps({"mode": mode, "bitrate_bps": bitrate}))
    with open(d / "frames.csv", "w", encoding="utf-8") as f:
        f.write(",".join(FRAME_COLUMNS) + "\n")
        for r in rows:
            f.write(",".join(f"{v:.10g}" for v in r) + "\n")
    with open(d / "chains.csv", "w", encoding="utf-8") as f:
        f.write(",".join(CHAIN_COLUMNS) + "\n")
        for r in chains or []:
            f.write(",".join(f"{v:.10g}" for v in r) + "\n")
    return d


def _periodic(
    can_id: int,
    period_s: float,
    n: int,
    latency_s: float,
    *,
    jitter_s: float = 0.0,
    tx: int = 1,
) -> list[list[float]]:
    """n frames queued at k*period (+jitter on odd k), received latency later."""
    rows = []
    for k in range(n):
        t = k * period_s + (jitter_s if k % 2 else 0.0)
        rows.append(_frame(t, t + latency_s, can_id, k % 15, tx=tx))
    return rows


# -- a synthetic run ---------------------------------------------------------------------


def test_run_periods_latency_and_violations(tmp_path: Path) -> None:
    """IMU_RATE 10 ms ±200 us, latency 150 us; THR_CMD_0 latency 0..100 us: known table."""
    d = 200 * US
    rows = _periodic(IMU_RATE, IMU_PERIOD_S, 21, 150 * US, jitter_s=d)
    cmd = _periodic(THR_CMD_0, CMD_PERIOD_S, 101, 0.0, tx=0)
    for k, r in enumerate(cmd):
        r[2] = r[0] + k * US  # latency k us
    rt = RunTiming.load(_write_run(tmp_path, rows + cmd))
    imu = rt.message("IMU_RATE")
    assert (imu.count, imu.sender, imu.cycle_time_ms, imu.time_source) == (21, "BENCH", 10, "t_rx")
    assert imu.period_mean_ms == pytest.approx(10, abs=TIME_TOL_MS)
    assert imu.jitter_std_us == pytest.approx(200, abs=TIME_TOL_US * 1e3)
    assert imu.jitter_pp_us == pytest.approx(400, abs=TIME_TOL_US * 1e3)
    assert imu.latency.p50_us == pytest.approx(150, abs=TIME_TOL_US * 1e3)
    assert (imu.missed_cycles, imu.cycle_violations_abs, imu.cycle_violations_rel) == (0, 0, 0)
    c = rt.message("THR_CMD_0")
    assert (c.latency.p50_us, c.latency.p99_us, c.latency.max_us) == pytest.approx(
        (50, 99, 100), abs=TIME_TOL_US * 1e3
    )
    tight = TimingOptions(cycle_abs_tolerance_ms=0.1, cycle_rel_tolerance_pct=1.0)
    m = RunTiming.load(tmp_path, tight).message("IMU_RATE")
    assert (m.cycle_violations_abs, m.cycle_violations_rel) == (20, 20)  # every 10.2 / 9.8 ms


def test_run_latency_between_messages(tmp_path: Path) -> None:
    """IMU at 10 ms steps (rx +0.2 ms), command queued at +1 ms rx +1.15 ms: age 1150 us."""
    imu = _periodic(IMU_RATE, IMU_PERIOD_S, 20, 0.2 * MS)
    cmd = [
        _frame(k * CMD_PERIOD_S + 1 * MS, k * CMD_PERIOD_S + 1.15 * MS, THR_CMD_0, k % 15, tx=0)
        for k in range(10)
    ]
    rt = RunTiming.load(_write_run(tmp_path, imu + cmd))
    lat = rt.latency("IMU_RATE", "THR_CMD_0")
    assert lat.n == 10
    assert (lat.p50_us, lat.max_us) == pytest.approx((1150, 1150), abs=TIME_TOL_US * 1e3)
    with pytest.raises(ConfigError, match="IMU_RAT"):
        rt.latency("IMU_RAT", "THR_CMD_0")


def test_realtime_bench_frames_use_send_time(tmp_path: Path) -> None:
    """Realtime: a bench frame's reception is unknown (nan): periods from t_ready, no latency."""
    rows = _periodic(IMU_RATE, IMU_PERIOD_S, 11, NAN)
    cmd = [
        _frame(k * CMD_PERIOD_S + 2 * MS, k * CMD_PERIOD_S + 2.5 * MS, THR_CMD_0, k, tx=0)
        for k in range(5)
    ]
    rt = RunTiming.load(_write_run(tmp_path, rows + cmd, mode="realtime"))
    imu = rt.message("IMU_RATE")
    assert imu.time_source == "t_ready" and imu.latency.n == 0
    assert imu.period_mean_ms == pytest.approx(10, abs=TIME_TOL_MS)
    assert rt.latency("IMU_RATE", "THR_CMD_0").max_us == pytest.approx(2500, abs=1e-3)


def test_untimed_rows_are_counted_not_timed(tmp_path: Path) -> None:
    """A boot heartbeat (bits 0, time 0) counts in count but not in periods or latency."""
    rows = [_frame(NAN, 0.0, SYNC, 0, bits=0)] + [
        _frame(k * CMD_PERIOD_S + 0.5, k * CMD_PERIOD_S + 0.5 + 100 * US, SYNC, k + 1)
        for k in range(5)
    ]
    rt = RunTiming.load(_write_run(tmp_path, rows))
    m = rt.message("SYNC")
    assert (m.count, m.latency.n) == (6, 5)
    assert m.period_mean_ms == pytest.approx(20, abs=TIME_TOL_MS)
    assert m.missed_cycles == 0


def test_bus_load_lockstep_windows_and_nodes(tmp_path: Path) -> None:
    """Busy 1.5, 5.5, 10, 5 ms in four 10 ms windows: mean 55 %, peak 100 %; per node."""
    rows = [
        _frame(1 * MS, 2 * MS, SYNC, 0, t_start=1 * MS),  # BENCH
        _frame(9.5 * MS, 10.5 * MS, SYNC, 1, t_start=9.5 * MS),  # BENCH
        _frame(15 * MS, 35 * MS, THR_CMD_0, 0, t_start=15 * MS, tx=0),  # FSW
    ]
    load = RunTiming.load(_write_run(tmp_path, rows)).bus_load()
    assert load.n_windows == 4
    assert load.total.mean_pct == pytest.approx(55, abs=PCT_TOL)
    assert load.total.peak_pct == pytest.approx(100, abs=PCT_TOL)
    assert load.total.peak_window_start_s == pytest.approx(20 * MS, abs=TIME_TOL_S)
    assert load.per_node["BENCH"].peak_pct == pytest.approx(15, abs=PCT_TOL)  # window 0
    assert load.per_node["FSW"].mean_pct == pytest.approx(50, abs=PCT_TOL)  # 20 ms of 40


def test_bus_load_realtime_places_bits_at_arrival(tmp_path: Path) -> None:
    """125 bits at 125 kbit/s = 1 ms ending at the arrival: 3 frames in 2 windows of 5 ms."""
    rows = [
        _frame(NAN, 2 * MS, SYNC, 0, tx=0),  # busy 1..2 ms
        _frame(NAN, 5.5 * MS, SYNC, 1, tx=0),  # busy 4.5..5.5: half in each window
        _frame(NAN, 9 * MS, SYNC, 2, tx=0),  # busy 8..9
    ]
    rt = RunTiming.load(_write_run(tmp_path, rows, mode="realtime", bitrate=BITRATE_125K))
    load = rt.bus_load(window_ms=5.0)
    assert load.n_windows == 2
    assert load.total.peak_pct == pytest.approx(30, abs=PCT_TOL)  # 1.5 ms of 5 in both
    assert load.total.mean_pct == pytest.approx(30, abs=PCT_TOL)


def test_rta_bound_and_flag(tmp_path: Path) -> None:
    """SYNC at 1 Mbit/s, top priority: R = B + C = 135 + 135 us (8-byte frames); 300 us flags."""
    ok = _periodic(SYNC, CMD_PERIOD_S, 5, 200 * US)
    rt = RunTiming.load(_write_run(tmp_path / "ok", ok))
    assert rt.message("SYNC").bound_us == pytest.approx(270, abs=TIME_TOL_US)
    assert rt.flagged() == []
    bad = _periodic(SYNC, CMD_PERIOD_S, 5, 200 * US)
    bad[3][2] = bad[3][0] + 300 * US
    rt_bad = RunTiming.load(_write_run(tmp_path / "bad", bad))
    assert rt_bad.flagged() == ["SYNC"] and rt_bad.message("SYNC").above_bound


def test_chain_percentiles(tmp_path: Path) -> None:
    """Last command 1.2 ms after the IMU sample; on even cycles the firing frame (1.0 ms)
    opens a valve 3 ms later: command->valve is measured from that frame, not the last."""
    chains = [
        [
            k,
            (2 * k) % 15,
            k * CMD_PERIOD_S,
            k * CMD_PERIOD_S + 1.2 * MS,
            k * CMD_PERIOD_S + 1.0 * MS if k % 2 == 0 else NAN,
            k * CMD_PERIOD_S + 4 * MS if k % 2 == 0 else NAN,
        ]
        for k in range(10)
    ]
    ch = RunTiming.load(_write_run(tmp_path, [], chains=chains)).chain()
    assert (ch.cycles, ch.cycles_without_valve) == (10, 5)
    assert ch.imu_to_command.p99_us == pytest.approx(1200, abs=TIME_TOL_US * 1e3)
    assert ch.command_to_valve.max_us == pytest.approx(3000, abs=TIME_TOL_US * 1e3)
    assert (ch.imu_to_valve.p50_us, ch.imu_to_valve.n) == pytest.approx((4000, 5), abs=1e-3)


def test_chain_of_an_older_run_folder_measures_from_the_last_command(tmp_path: Path) -> None:
    """chains.csv without t_fire_cmd_rx_s (written before it existed) still loads."""
    d = _write_run(tmp_path, [])
    old = [c for c in CHAIN_COLUMNS if c != "t_fire_cmd_rx_s"]
    (d / "chains.csv").write_text(",".join(old) + f"\n0,0,0,{1.2 * MS},{4 * MS}\n")
    ch = RunTiming.load(d).chain()
    assert ch.command_to_valve.max_us == pytest.approx(2800, abs=TIME_TOL_US * 1e3)


def test_missing_and_truncated_files(tmp_path: Path) -> None:
    """No summary: RunError; a half-written last line of frames.csv is dropped."""
    with pytest.raises(RunError, match=r"summary\.json"):
        RunTiming.load(tmp_path)
    d = _write_run(tmp_path / "r", _periodic(SYNC, CMD_PERIOD_S, 3, 100 * US))
    with open(d / "frames.csv", "a", encoding="utf-8") as f:
        f.write("0.06,nan,0.0601")  # the writer died mid-line
    assert RunTiming.load(d).message("SYNC").count == 3


def test_json_and_report_outputs(tmp_path: Path) -> None:
    """timing.json is strict JSON (no NaN), the table names every message, PNGs are written."""
    rows = _periodic(IMU_RATE, IMU_PERIOD_S, 11, NAN) + _periodic(SYNC, CMD_PERIOD_S, 6, 120 * US)
    chains = [[0, 0, 0.0, 1.2 * MS, 1.0 * MS, 4 * MS]]
    rt = RunTiming.load(_write_run(tmp_path, rows, mode="realtime", chains=chains))
    path = write_json(rt, tmp_path)
    data = json.loads(path.read_text(encoding="utf-8"))
    json.dumps(data, allow_nan=False)
    assert set(data["messages"]) == {"SYNC", "IMU_RATE"}
    text = format_report(rt)
    assert "IMU_RATE" in text and "bus load" in text and "chain IMU->valve" in text
    assert {p.name for p in write_histograms(rt, tmp_path)} == {
        "latency_hist.png",
        "chain_age_hist.png",
    }


def test_unknown_id_gets_hex_name(tmp_path: Path) -> None:
    """An ID outside the DBC is reported as 0x... with sender '?' and no bound."""
    rt = RunTiming.load(_write_run(tmp_path, _periodic(0x123, IMU_PERIOD_S, 3, 100 * US)))
    m = rt.message("0x123")
    assert (m.sender, m.cycle_time_ms, m.bound_us, m.cycle_violations_abs) == (
        "?",
        None,
        None,
        None,
    )


def test_run_timing_rejects_bad_mode() -> None:
    """mode must be lockstep, realtime or live."""
    with pytest.raises(ConfigError, match="mode"):
        RunTiming(_table([]), mode="fast", bitrate_bps=BITRATE_1M)


# -- live capture ------------------------------------------------------------------------


def test_frames_from_messages_times_counters_and_error_frames() -> None:
    """Times relative to the first frame, tx time from hilbus, counters only for DBC IDs."""
    db = load_database()
    t0 = 1000.0
    msgs = [
        HilMessage(
            timestamp=t0,
            arbitration_id=IMU_RATE,
            data=bytes([0, 3, 0, 0, 0, 0, 0, 0]),
            is_extended_id=False,
            tx_timestamp=t0 - 50 * US,
        ),
        can.Message(timestamp=t0 + 0.01, is_error_frame=True),
        can.Message(
            timestamp=t0 + 0.02, arbitration_id=0x123, data=bytes([0, 7]), is_extended_id=False
        ),
    ]
    cap = frames_from_messages(msgs, db)
    f = cap.frames
    assert cap.error_frames == 1 and len(f) == 2
    assert f.t_rx_s.tolist() == pytest.approx([0.0, 0.02], abs=TIME_TOL_S)
    assert f.t_ready_s[0] == pytest.approx(-50 * US, abs=TIME_TOL_S) and math.isnan(f.t_ready_s[1])
    assert f.counter.tolist() == [3, NO_COUNTER]
    assert (f.bits > 0).all()


def test_capture_records_until_duration() -> None:
    """capture() returns every queued frame and stops on its clock; no frame: RunError."""
    db = load_database()
    channel = "timing-analysis-test"
    tx_bus = can.Bus(interface="virtual", channel=channel)
    rx_bus = can.Bus(interface="virtual", channel=channel)
    try:
        n = 5
        for k in range(n):
            tx_bus.send(
                can.Message(
                    arbitration_id=IMU_RATE,
                    data=bytes([0, k, 0, 0, 0, 0, 0, 0]),
                    is_extended_id=False,
                )
            )
        ticks = iter(range(10_000))

        def clock() -> float:  # 1 ms per call: the loop ends after ~20 reads
            return next(ticks) * MS

        cap = capture(rx_bus, LiveOptions(duration_s=20 * MS), db, clock=clock)
        assert len(cap.frames) == n
        assert cap.frames.counter.tolist() == list(range(n))
        with pytest.raises(RunError, match="no frame"):
            capture(rx_bus, LiveOptions(duration_s=1.0, first_frame_timeout_s=10 * MS), db)
    finally:
        tx_bus.shutdown()
        rx_bus.shutdown()


def test_live_options_validation() -> None:
    """Non-positive durations and bitrates are rejected."""
    with pytest.raises(ConfigError, match="duration_s"):
        LiveOptions(duration_s=0.0)
    with pytest.raises(ConfigError, match="bitrate_bps"):
        LiveOptions(duration_s=1.0, bitrate_bps=-5)


# -- command line ------------------------------------------------------------------------


def test_cli_timing_strict_exit_and_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`timing DIR --json --strict`: JSON on stdout, files written, exit 1 only when flagged."""
    from bench.operator.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, main

    ok = _write_run(tmp_path / "ok", _periodic(SYNC, CMD_PERIOD_S, 5, 200 * US))
    assert main(["timing", str(ok), "--json", "--strict"]) == EXIT_OK
    assert json.loads(capsys.readouterr().out)["flags"] == []
    assert (ok / "timing.json").is_file() and (ok / "latency_hist.png").is_file()
    bad_rows = _periodic(SYNC, CMD_PERIOD_S, 5, 200 * US)
    bad_rows[2][2] = bad_rows[2][0] + 300 * US  # above the 270 us bound
    bad = _write_run(tmp_path / "bad", bad_rows)
    assert main(["timing", str(bad), "--strict"]) == EXIT_FAILED
    assert "FLAG" in capsys.readouterr().out
    assert main(["timing", str(bad)]) == EXIT_OK
    assert main(["timing", str(ok), "--window-ms", "0"]) == EXIT_BAD_INPUT
    assert main(["timing"]) == EXIT_BAD_INPUT


def test_message_sent_but_never_on_the_trace_is_all_missed(tmp_path: Path) -> None:
    """THR_CMD_0 sent 50 times (summary.json) but absent from frames.csv: 50 missed, unheard."""
    d = _write_run(tmp_path / "run", _periodic(IMU_RATE, IMU_PERIOD_S, 100, 100 * US))
    summary = json.loads((d / "summary.json").read_text())
    summary["frames"] = {"THR_CMD_0": {"sender": "FSW", "sent": 50, "received": 0},
                         "IMU_RATE": {"sender": "BENCH", "sent": 100, "received": 100}}
    (d / "summary.json").write_text(json.dumps(summary))
    rt = RunTiming.load(d)
    cmd = rt.messages["THR_CMD_0"]
    assert (cmd.count, cmd.missed_cycles) == (0, 50)
    assert rt.unheard() == ["THR_CMD_0"] and rt.messages["IMU_RATE"].missed_cycles == 0
    assert list(rt.messages) == ["THR_CMD_0", "IMU_RATE"]  # in ID order
    assert "sent but never received: THR_CMD_0 (50 frames sent)" in format_report(rt)


def test_a_lean_run_is_refused_naming_what_it_lacks(tmp_path: Path) -> None:
    """A folder recorded at the lean level has no frames.csv: a ConfigError (bad input)
    naming the level and how to get the whole folder, not a missing-file run error."""
    from bench.operator.analysis.timing import RunTiming
    from dbc.errors import ConfigError

    (tmp_path / "summary.json").write_text(json.dumps({"record": "lean"}), encoding="utf-8")
    with pytest.raises(ConfigError, match="lean") as err:
        RunTiming.load(tmp_path)
    assert "campaign rerun" in str(err.value)



FSW_STATUS = 0x090  # DBC ID; GenMsgSendType "CyclicAndSpontanX", GenMsgCycleTime 100 ms
STATUS_PERIOD_S = 100 * MS


def _cyclic_with_extra_and_late(can_id: int, period_s: float) -> list[list[float]]:
    """Frames at k·period for k = 0..10, one more at 4.3 periods, and the one at 9 periods
    sent half a period late."""
    times = [k * period_s for k in range(11) if k != 9] + [4.3 * period_s, 9.5 * period_s]
    return [_frame(t, t + 100 * US, can_id, k % 15, tx=0) for k, t in enumerate(sorted(times))]


def test_an_event_frame_of_a_cyclic_and_event_message_is_no_violation(tmp_path: Path) -> None:
    """FSW_STATUS (sent every 100 ms and at once on a mode change, per the DBC's send type):
    the extra frame between two cyclic ones is no violation, the late one still is; the same
    pattern on IMU_RATE (plain cyclic) is a violation each way."""
    rows = (_cyclic_with_extra_and_late(FSW_STATUS, STATUS_PERIOD_S)
            + _cyclic_with_extra_and_late(IMU_RATE, IMU_PERIOD_S))
    rt = RunTiming.load(_write_run(tmp_path, sorted(rows, key=lambda r: r[2])))
    s = rt.message("FSW_STATUS")
    assert s.count == 12
    assert (s.cycle_violations_abs, s.cycle_violations_rel) == (1, 1)  # 8 -> 9.5 periods
    i = rt.message("IMU_RATE")
    assert (i.cycle_violations_abs, i.cycle_violations_rel) == (4, 4)  # 4.3 (2), 9.5 (2)
