"""Link errors and bus-off on the modelled bus: command latency grows by what the model predicts."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import can
import pytest

from bench.results.record import run_file
from bench.wire.timing.arbiter import failed_attempt_bits
from bench.wire.timing.classic import wire_time_ns
from dbc.database import load_database
from tests.e2e.conftest import QUICKSTART, run_cli, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

BITRATE_BPS = 1_000_000
PERIOD_S = 0.02
ERR_FROM_S, ERR_TO_S = 1.0, 2.0
BUS_OFF_S = 2.5
BUS_OFF_FOR_S = 0.005
DELAY_FROM_S, DELAY_FOR_S, DELAY_S = 3.0, 0.5, 0.0005
DURATION_S = "4"
TOL_US = 0.5  # rounding of modelled times to the microsecond in frames.csv/chains.csv
THR_CMD_BITS_MAX = 135  # 8-byte frame, worst-case stuffing
STUFFING_TOL_US = 25.0  # a few stuff bits per frame, over the ~8 frames on the path


def _cmd_rx_s(out: Path) -> dict[int, float]:
    with io.StringIO(run_text(out, "chains.csv"), newline="") as f:
        return {int(r["cycle"]): float(r["t_cmd_rx_s"]) for r in csv.DictReader(f)}


def _latencies_us(out: Path) -> dict[int, float]:
    with io.StringIO(run_text(out, "chains.csv"), newline="") as f:
        return {
            int(r["cycle"]): (float(r["t_cmd_rx_s"]) - float(r["t_imu_tx_s"])) * 1e6
            for r in csv.DictReader(f)
        }


def test_link_errors_and_bus_off_delay_commands_as_modelled(
    tmp_path: Path, runtime_dir: Path
) -> None:
    """A failed attempt costs frame + error frame; bus-off holds the node's frames back."""
    sc = tmp_path / "faults.toml"
    sc.write_text(
        QUICKSTART.read_text()
        + f"\n[[faults]]\nt_s = {ERR_FROM_S}\nduration_s = {ERR_TO_S - ERR_FROM_S}\n"
        'kind = "link_error"\nmessage = "THR_CMD_1"\nprobability = 1.0\n'
        f'\n[[faults]]\nt_s = {BUS_OFF_S}\nduration_s = {BUS_OFF_FOR_S}\nkind = "bus_off"\n'
        'node = "FSW"\n'
        f'\n[[faults]]\nt_s = {DELAY_FROM_S}\nduration_s = {DELAY_FOR_S}\nkind = "delay"\n'
        f'message = "THR_CMD_1"\ndelay_s = {DELAY_S}\n'
    )
    ref = run_cli(
        ["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", DURATION_S],
        tmp_path / "ref",
        runtime_dir,
    )
    run = run_cli(
        ["run", str(sc), "--bus", unique_bus(), "--duration", DURATION_S],
        tmp_path / "faults",
        runtime_dir,
    )
    base, lat = _latencies_us(ref.out), _latencies_us(run.out)
    err_cycles = range(round(ERR_FROM_S / PERIOD_S), round(ERR_TO_S / PERIOD_S))
    for k in err_cycles:
        extra = lat[k] - base[k]
        # THR_CMD_1 (last command frame) fails once: the bits sent until the error plus the
        # error frame and intermission, between the lower and upper frame lengths
        lo = wire_time_ns(failed_attempt_bits(100).nominal_bits, BITRATE_BPS) / 1e3
        hi = wire_time_ns(failed_attempt_bits(THR_CMD_BITS_MAX).nominal_bits, BITRATE_BPS) / 1e3
        assert lo - TOL_US <= extra <= hi + TOL_US, (k, extra)
    k_off = round(BUS_OFF_S / PERIOD_S)
    # the flight software's frames wait for the end of the bus-off interval, then its two
    # command frames win arbitration back to back
    t_rx = _cmd_rx_s(run.out)[k_off]
    off_end = BUS_OFF_S + BUS_OFF_FOR_S
    assert off_end < t_rx <= off_end + 2 * THR_CMD_BITS_MAX / BITRATE_BPS + TOL_US / 1e6
    assert _cmd_rx_s(ref.out)[k_off] < BUS_OFF_S + BUS_OFF_FOR_S / 2  # unaffected reference
    delay_cycles = range(
        round(DELAY_FROM_S / PERIOD_S), round((DELAY_FROM_S + DELAY_FOR_S) / PERIOD_S)
    )
    for k in delay_cycles:  # the delayed frame reaches the valves exactly delay_s later
        assert lat[k] - base[k] == pytest.approx(DELAY_S * 1e6, abs=STUFFING_TOL_US), k
    # elsewhere only stuffing differs (the trajectory, hence the payloads, diverge slightly)
    for k in set(base) - set(err_cycles) - set(delay_cycles) - {k_off}:
        assert lat[k] == pytest.approx(base[k], abs=STUFFING_TOL_US), k
    faults = run.summary["faults"]
    assert [f["kind"] for f in faults] == ["link_error", "bus_off", "delay"]
    # one failed attempt per THR_CMD_1 frame while the link error lasted, none without it,
    # each an error frame in the trace, in time order with the other frames
    assert run.summary["fault_effects"]["failed_attempts"] == len(err_cycles)
    assert ref.summary["fault_effects"]["failed_attempts"] == 0
    trace = list(can.LogReader(str(run_file(run.out, "trace.asc"))))
    errors = [m.timestamp for m in trace if m.is_error_frame]
    assert len(errors) == len(err_cycles)
    assert all(ERR_FROM_S <= t < ERR_TO_S + PERIOD_S for t in errors)
    stamps = [m.timestamp for m in trace]
    assert stamps == sorted(stamps)
    assert not any(m.is_error_frame for m in can.LogReader(str(run_file(ref.out, "trace.asc"))))


def _fault(kind: str, target: str, **params: object) -> str:
    body = "".join(f"{k} = {v!r}\n".replace("'", '"') for k, v in params.items())
    return f'\n[[faults]]\nkind = "{kind}"\n{target}\n{body}'


DROP_P = 0.1
DROP_SIGMAS = 5.0  # binomial tolerance on the drop fraction


def test_frame_faults_have_their_counted_effects(tmp_path: Path, runtime_dir: Path) -> None:
    """drop ~ p; corrupt -> CRC rejects; duplicate -> counter rejects; babbling -> unknown IDs."""
    sc = tmp_path / "frame_faults.toml"
    sc.write_text(
        QUICKSTART.read_text()
        + _fault("drop", 'message = "IMU_RATE"', t_s=0.0, probability=DROP_P)
        + _fault("corrupt", 'message = "STR_QUAT"', t_s=1.0, duration_s=1.0)
        + _fault("duplicate", 'message = "THR_CMD_0"', t_s=2.0, duration_s=1.0)
        + _fault("babbling", "can_id = 1", t_s=3.0, duration_s=0.5, rate_hz=2000.0)
    )
    s = run_cli(
        ["run", str(sc), "--bus", unique_bus(), "--duration", DURATION_S],
        tmp_path / "run",
        runtime_dir,
    ).summary
    eff, frames = s["fault_effects"], s["frames"]
    offered = frames["IMU_RATE"]["sent"] + eff["dropped"]
    sigma = (offered * DROP_P * (1 - DROP_P)) ** 0.5
    assert abs(eff["dropped"] - DROP_P * offered) <= DROP_SIGMAS * sigma
    assert frames["IMU_RATE"]["gaps"] == eff["dropped"]  # the receiver sees them as gaps
    assert frames["STR_QUAT"]["rejected"] == {"crc": eff["corrupted"]} and eff["corrupted"] > 0
    assert frames["THR_CMD_0"]["rejected"] == {"counter": eff["duplicated"]}
    assert s["rejected_other"]["FSW"] == {"unknown_id": eff["babbled"]}
    assert s["deadline_misses"]["stalls"] == 0


def _first_imu_loss_s(out: Path) -> float | None:
    """When the flight software must declare the IMU lost: the first cycle time t_k such
    that cycles k-1 and k brought no IMU_RATE frame (its watchdog sees frames at SYNC, and
    allows LOST_AFTER_PERIODS = 3 IMU periods, 30 ms, of silence); None if never."""
    imu_id = load_database().get_message_by_name("IMU_RATE").frame_id
    with io.StringIO(run_text(out, "frames.csv"), newline="") as f:
        sent_s = [float(r["t_ready_s"]) for r in csv.DictReader(f)
                  if int(float(r["id"])) == imu_id and r["tx"] == "1"]
    cycles_with_imu = {math.ceil(round(t / PERIOD_S, 6)) for t in sent_s}
    last = max(cycles_with_imu)
    for k in range(2, last + 1):
        if k - 1 not in cycles_with_imu and k not in cycles_with_imu:
            return k * PERIOD_S
    return None


def test_ten_percent_loss_of_every_sensor_message_converges_or_goes_safe(
    tmp_path: Path, runtime_dir: Path
) -> None:
    """10 % random loss of every sensor message: converges, or SAFE exactly when the IMU was lost.

    At 10 % loss, 4 IMU samples in a row are lost about once a minute: that is an IMU loss
    (silence > 3 periods) and must latch SAFE in that cycle, and not before.
    """
    sc = tmp_path / "loss.toml"
    sc.write_text(
        QUICKSTART.read_text()
        + "".join(
            _fault("drop", f'message = "{m}"', t_s=0.0, probability=DROP_P)
            for m in ("IMU_RATE", "IMU_ACCEL", "STR_QUAT", "THR_STATUS")
        )
    )
    r = run_cli(["run", str(sc), "--bus", unique_bus()], tmp_path / "run", runtime_dir)
    assert "error" not in r.summary, r.stderr
    lost_s = _first_imu_loss_s(r.out)
    with io.StringIO(run_text(r.out, "telemetry.csv"), newline="") as f:
        safe_s = next((float(x["t_s"]) for x in csv.DictReader(f) if x["fsw_mode"] == "2"), None)
    if lost_s is None:
        assert safe_s is None
        assert r.returncode == 0, r.stdout
        assert r.summary["converged"] and all(e["pass"] for e in r.summary["expectations"])
    else:  # SAFE from the cycle of the loss (telemetry every 10 ms, mode as reported)
        assert safe_s is not None and lost_s <= safe_s <= lost_s + 2 * PERIOD_S, (lost_s, safe_s)
