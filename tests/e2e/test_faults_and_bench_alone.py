"""Scheduled thruster faults act and are recorded; the bench pairs with external flight software."""

from __future__ import annotations

import json
import os
import selectors
import subprocess
import sys
from pathlib import Path

import pytest

from tests.e2e.conftest import QUICKSTART, REPO, run_cli, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

FAULT_T_S = 1.0
STUCK = 3
CLEAR_AFTER_S = 0.5
SHORT_S = "3"
START_DEADLINE_S = 60.0


def _with_faults(tmp_path: Path, kind: str, duration_s: float = 0.0) -> Path:
    sc = tmp_path / f"{kind}.toml"
    sc.write_text(
        QUICKSTART.read_text()
        + f'\n[[faults]]\nt_s = {FAULT_T_S}\nkind = "{kind}"\nthruster = {STUCK}\n'
        + f"duration_s = {duration_s}\n"
    )
    return sc


def _thrust(out: Path, thruster: int) -> list[tuple[float, float]]:
    rows = run_text(out, "telemetry.csv").splitlines()
    col = rows[0].split(",").index(f"thrust_T{thruster:02d}_N")
    return [(float(r.split(",")[0]), float(r.split(",")[col])) for r in rows[1:]]


@pytest.mark.parametrize("kind", ["stuck_closed", "stuck_open"])
def test_scheduled_thruster_fault_is_applied_and_recorded(
    tmp_path: Path, runtime_dir: Path, kind: str
) -> None:
    """The fault appears in summary.json and events.jsonl at its time and acts on the valve."""
    r = run_cli(
        ["run", str(_with_faults(tmp_path, kind)), "--bus", unique_bus(), "--duration", SHORT_S],
        tmp_path / "run",
        runtime_dir,
    )
    faults = r.summary["faults"]
    assert [(f["kind"], f["thruster"], f["t_s"]) for f in faults] == [(kind, STUCK, FAULT_T_S)]
    assert "cleared_t_s" not in faults[0]  # no duration: active to the end
    events = [json.loads(x) for x in (r.out / "events.jsonl").read_text().splitlines()]
    assert any(e["event"] == "fault_injected" and e["t_s"] == FAULT_T_S for e in events)
    after = [f for t, f in _thrust(r.out, STUCK) if t > FAULT_T_S + 0.05]
    if kind == "stuck_closed":
        assert max(after) == 0.0
    else:
        assert min(after) > 0.9 * 15.0


def test_timed_fault_clearing_is_in_the_summary(tmp_path: Path, runtime_dir: Path) -> None:
    """A fault with a duration: its summary record says when and why it was cleared."""
    r = run_cli(
        ["run", str(_with_faults(tmp_path, "stuck_closed", CLEAR_AFTER_S)), "--bus",
         unique_bus(), "--duration", SHORT_S], tmp_path / "run", runtime_dir,
    )
    (f,) = r.summary["faults"]
    assert (f["cleared_t_s"], f["cleared_by"]) == (FAULT_T_S + CLEAR_AFTER_S, "duration")


def test_bench_alone_pairs_with_flight_software_started_by_hand(
    tmp_path: Path, runtime_dir: Path
) -> None:
    """`thruster-hil bench` waits for an external flight-software process and runs with it."""
    bus = unique_bus()
    out = tmp_path / "run"
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir))
    bench = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "bench.operator.entry",
            "bench",
            str(QUICKSTART),
            "--bus",
            bus,
            "--duration",
            SHORT_S,
            "--out",
            str(out),
        ],
        cwd=REPO,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert bench.stderr is not None
    sel = selectors.DefaultSelector()
    sel.register(bench.stderr, selectors.EVENT_READ)
    assert sel.select(timeout=START_DEADLINE_S), "bench never said it was ready"
    line = bench.stderr.readline()
    assert "bench ready" in line, line
    cfg = Path(line.rsplit("its configuration: ", 1)[1].strip())
    fsw = subprocess.Popen(
        [sys.executable, "-m", "flight_sw", "--bus", bus, "--config", str(cfg)],
        cwd=REPO,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        _, stderr = bench.communicate(timeout=START_DEADLINE_S)
    finally:
        fsw.terminate()
        fsw.wait(timeout=10)
    assert bench.returncode in (0, 1), stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["frames"]["THR_CMD_0"]["received"] > 0
    assert s["deadline_misses"]["stalls"] == 0
