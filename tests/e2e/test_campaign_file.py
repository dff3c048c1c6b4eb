"""A campaign file end to end (slow): a small Monte Carlo on a local Dask cluster, its
files, a case rerun byte for byte, and a resumed campaign that runs only what is missing."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.e2e.conftest import RUN_TIMEOUT_S

REPO = Path(__file__).resolve().parents[2]
QUICKSTART = REPO / "scenarios" / "quickstart.toml"
CASES = 3

pytestmark = pytest.mark.slow


def _hil(args: list[str], runtime: Path) -> subprocess.CompletedProcess[str]:
    import os

    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime))
    return subprocess.run([sys.executable, "-m", "bench.operator.cli", *args], env=env,
                          capture_output=True, text=True, timeout=RUN_TIMEOUT_S, check=False)


def test_small_monte_carlo_reruns_and_resumes(tmp_path: Path, runtime: Path) -> None:
    """3 cases: rows, report links, statistics; rerun identical; a lost case rerun alone."""
    f = tmp_path / "mc.toml"
    f.write_text(
        f'[campaign]\nscenario = "{QUICKSTART}"\ncases = {CASES}\nseed = 11\n'
        'set = ["scenario.duration_s=3.0", "expectations.steady_state_window_s=1.0"]\n'
        '[[dispersions]]\nname = "thrust_scale"\ndist = "normal"\nmean = 1.0\nsigma = 0.05\n'
        '[[dispersions]]\nname = "latency"\ndist = "uniform"\nlow = 0.0005\nhigh = 0.003\n',
        encoding="utf-8")
    out = tmp_path / "out"
    first = _hil(["campaign", str(f), "--out", str(out)], runtime)
    assert first.returncode in (0, 1), first.stderr[-3000:]
    assert "95 % interval" in first.stdout and "per minute" in first.stdout
    with open(out / "campaign.csv", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["name"] for r in rows] == [f"{i:04d}" for i in range(CASES)]
    assert all(r["status"] == "ok" and len(r["trace_sha256"]) == 64 for r in rows)
    data = json.loads((out / "campaign.json").read_text(encoding="utf-8"))
    assert data["statistics"]["pass_rates"]["passed"]["cases"] == CASES
    assert "value:thrusters.actual_thrust_scale[7]" in rows[0]
    html = (out / "campaign.html").read_text(encoding="utf-8")
    assert "href='cases/0000/run/'" in html  # 3 cases: each among the 5 worst, linked

    rerun = _hil(["campaign", "rerun", str(out), "0001"], runtime)
    assert rerun.returncode == 0, rerun.stdout[-2000:] + rerun.stderr[-2000:]
    assert "identical" in rerun.stdout

    kept = (out / "cases" / "0000" / "result.json").stat().st_mtime_ns
    shutil.rmtree(out / "cases" / "0002")
    again = _hil(["campaign", str(f), "--out", str(out)], runtime)
    assert again.returncode == first.returncode, again.stderr[-3000:]
    assert (out / "cases" / "0000" / "result.json").stat().st_mtime_ns == kept
    after = json.loads((out / "campaign.json").read_text(encoding="utf-8"))["cases"]
    before = data["cases"]
    assert [(r["name"], r["trace_sha256"], r["figures"]) for r in after] == \
        [(r["name"], r["trace_sha256"], r["figures"]) for r in before]
