"""The quickstart, end to end: two processes over the portable bus, lockstep, full 60 s."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import can
import pytest

from dbc import e2e
from dbc.codec import cycle_time_ns
from dbc.database import load_database
from tests.e2e.conftest import QUICKSTART, Run, run_cli, trace_lines, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

NS_PER_S = 1e9
SETTLING_MAX_S = 10.0
ASC_RESOLUTION_S = 1e-6  # the ASC trace's timestamps have 6 decimals
STEADY_STATE_MAX_DEG = 0.1
RUN_FILES = (  # at the default record level, standard: the trace and tables compressed
    "summary.json",
    "trace.asc.gz",
    "telemetry.csv.gz",
    "valve_pulses.csv.gz",
    "frames.csv.gz",
    "chains.csv.gz",
    "events.jsonl",
    "attitude_error.png",
    "rates.png",
    "thruster_raster.png",
    "fsw_config.json",
)
SUMMARY_KEYS = (
    "scenario",
    "mode",
    "seed",
    "record",
    "bus",
    "sim_time_s",
    "wall_time_s",
    "realtime_factor",
    "converged",
    "settling_time_s",
    "steady_state_attitude_error_deg",
    "steady_state_rate_error_deg_s",
    "propellant_kg",
    "valve_openings",
    "frames",
    "latency_us",
    "deadline_misses",
    "faults",
    "expectations",
)


@pytest.fixture(scope="module")
def quickstart(tmp_path_factory: pytest.TempPathFactory) -> Run:
    """One full lockstep quickstart run."""
    xdg = tmp_path_factory.mktemp("xdg")
    xdg.chmod(0o700)
    return run_cli(
        ["run", str(QUICKSTART), "--bus", unique_bus()], tmp_path_factory.mktemp("qs") / "run", xdg
    )


def test_quickstart_meets_its_expectations(quickstart: Run) -> None:
    """Converges, settles within 10 s and holds 0.1 deg (exit code 0 = every expectation met)."""
    s = quickstart.summary
    assert quickstart.returncode == 0, quickstart.stdout + quickstart.stderr
    assert s["converged"] is True
    assert s["settling_time_s"] <= SETTLING_MAX_S
    assert s["steady_state_attitude_error_deg"] <= STEADY_STATE_MAX_DEG
    assert all(e["pass"] for e in s["expectations"])


def test_run_folder_is_complete(quickstart: Run) -> None:
    """Every output file exists and summary.json has every key the ICD issue fixes."""
    for name in RUN_FILES:
        assert (quickstart.out / name).stat().st_size > 0, name
    assert not (quickstart.out / "telemetry.csv").exists()  # not also written plain
    s = quickstart.summary
    assert set(SUMMARY_KEYS) <= set(s)
    lat = s["latency_us"]["sensor_to_command"]
    assert lat["n"] > 0 and 0 < lat["p50"] <= lat["p99"] <= lat["max"]


CYCLE_PARTS = ("before_sync", "meanwhile", "waiting_for_fsw", "after_commands")
# Each part and the cycle are measured in ns and kept rounded to the microsecond, so a
# part's maximum may exceed the cycle's by that rounding alone.
ROUNDING_US = 1.0


def test_each_lockstep_cycle_is_split_into_its_parts(quickstart: Run) -> None:
    """Every cycle has each part measured once, and no part is longer than a whole cycle."""
    wall = quickstart.summary["lockstep_wall_us"]
    cycle = wall["cycle"]
    period_ns = cycle_time_ns(load_database(), "SYNC")
    assert cycle["n"] == round(quickstart.summary["sim_time_s"] * NS_PER_S / period_ns)
    for part in CYCLE_PARTS:
        assert wall[part]["n"] == cycle["n"], part
        assert 0.0 <= wall[part]["p50"] <= wall[part]["max"] <= cycle["max"] + ROUNDING_US
    assert sum(wall[part]["max"] for part in CYCLE_PARTS) >= cycle["p50"]


def test_frame_counts_match_between_sender_and_receiver(quickstart: Run) -> None:
    """Nothing is lost on the portable bus: sent == received, no rejects, for every message."""
    for name, f in quickstart.summary["frames"].items():
        if f["sent"] is None:
            continue
        assert f["received"] == f["sent"], name
        assert f["rejected"] == {} and f["gaps"] == 0, name


def _trace(path: Path) -> list[can.Message]:
    return list(can.LogReader(str(path)))


def test_trace_decodes_and_counters_advance_without_gaps(quickstart: Run) -> None:
    """The ASC trace opens with can.LogReader; every frame decodes; alive counters step by one."""
    db = load_database()
    last: dict[int, int] = {}
    per_id: dict[int, int] = defaultdict(int)
    t_prev = -1.0
    for msg in _trace(quickstart.out / "trace.asc.gz"):  # python-can reads .asc.gz itself
        m = db.get_message_by_frame_id(msg.arbitration_id)
        m.decode(msg.data)
        c = e2e.counter_of(msg.data)
        if msg.arbitration_id in last:
            assert e2e.counter_delta(last[msg.arbitration_id], c) == 1, (m.name, msg.timestamp)
        last[msg.arbitration_id] = c
        per_id[msg.arbitration_id] += 1
        assert msg.timestamp >= t_prev
        t_prev = msg.timestamp
    assert sum(per_id.values()) == sum(
        f["sent"] for f in quickstart.summary["frames"].values() if f["sent"]
    )


def test_full_record_is_the_standard_one_uncompressed(
    quickstart: Run, tmp_path: Path, runtime_dir: Path
) -> None:
    """--record full writes the same trace and tables as plain text, and no .gz files; the
    trace's BLF, the same frames, is byte for byte the standard level's;
    --no-plots (the same run) leaves out the PNGs only, and says the verdict all the same."""
    full = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--record", "full",
                    "--no-plots", "--duration", str(quickstart.summary["sim_time_s"])],
                   tmp_path / "full", runtime_dir)
    assert full.returncode == 0, full.stderr
    assert full.summary["record"] == "full" and quickstart.summary["record"] == "standard"
    assert not list(full.out.glob("*.gz")) and not list(full.out.glob("*.png"))
    assert "verdict: PASS" in full.stdout and f"run folder: {full.out}" in full.stdout
    for name in ("telemetry.csv", "frames.csv", "chains.csv", "valve_pulses.csv"):
        assert (full.out / name).read_text() == run_text(quickstart.out, name), name
    assert trace_lines(full.out / "trace.asc") == trace_lines(quickstart.out / "trace.asc")
    # and the BLF, at either level, holds the same frames (issue 22)
    asc = list(can.LogReader(full.out / "trace.asc"))
    blf = list(can.LogReader(full.out / "trace.blf"))
    assert len(asc) == len(blf) > 0
    assert (full.out / "trace.blf").read_bytes() == (quickstart.out / "trace.blf").read_bytes()
    assert all((a.arbitration_id, bytes(a.data), a.is_rx) == (b.arbitration_id, bytes(b.data),
                                                              b.is_rx)
               and abs(a.timestamp - b.timestamp) <= ASC_RESOLUTION_S
               for a, b in zip(asc, blf, strict=True))


# what a lean record leaves out; its summary figures are those of the standard record
LEAN_ABSENT = ("trace.asc", "frames.csv", "chains.csv", "valve_pulses.csv")
WALL_CLOCK_KEYS = ("record", "bus", "wall_time_s", "realtime_factor", "lockstep_wall_us",
                   "fsw")


def test_lean_record_keeps_the_summary_the_blf_and_a_tenth_of_the_telemetry(
    quickstart: Run, tmp_path: Path, runtime_dir: Path
) -> None:
    """--record lean (a campaign's cases): the same summary but for wall-clock figures, the
    same trace.blf bytes, the telemetry's every tenth instant, and none of the tables."""
    from bench.results.record import LEAN_TELEMETRY_EVERY

    lean = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--record", "lean",
                    "--no-plots"], tmp_path / "lean", runtime_dir)
    assert lean.returncode == 0, lean.stderr
    s, ref = lean.summary, quickstart.summary
    assert s["record"] == "lean"
    assert {k: v for k, v in s.items() if k not in WALL_CLOCK_KEYS} == {
        k: v for k, v in ref.items() if k not in WALL_CLOCK_KEYS}
    assert (lean.out / "trace.blf").read_bytes() == (quickstart.out / "trace.blf").read_bytes()
    rows = run_text(quickstart.out, "telemetry.csv").splitlines()
    assert run_text(lean.out, "telemetry.csv").splitlines() == (
        rows[:1] + rows[1::LEAN_TELEMETRY_EVERY])
    for name in LEAN_ABSENT:
        assert not list(lean.out.glob(name + "*")), name
