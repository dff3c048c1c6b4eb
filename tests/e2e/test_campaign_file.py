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
POLL_S = 0.05  # polling the campaign folder for its first finished case

pytestmark = pytest.mark.slow


def _campaign_file(path: Path, body: str) -> Path:
    """A campaign file on the quickstart: ``[campaign]``'s scenario line, then ``body``."""
    path.write_text(f'[campaign]\nscenario = "{QUICKSTART}"\n' + body, encoding="utf-8")
    return path


def _hil(args: list[str], runtime: Path) -> subprocess.CompletedProcess[str]:
    import os

    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime))
    return subprocess.run([sys.executable, "-m", "bench.operator.entry", *args], env=env,
                          capture_output=True, text=True, timeout=RUN_TIMEOUT_S, check=False)


def test_small_monte_carlo_reruns_and_resumes(tmp_path: Path, runtime: Path) -> None:
    """3 cases: rows, report links, statistics; rerun identical; a lost case rerun alone."""
    f = _campaign_file(
        tmp_path / "mc.toml",
        f'cases = {CASES}\nseed = 11\n'
        'set = ["scenario.duration_s=3.0", "expectations.steady_state_window_s=1.0"]\n'
        '[[dispersions]]\nname = "thrust_scale"\ndist = "normal"\nmean = 1.0\nsigma = 0.05\n'
        '[[dispersions]]\nname = "latency"\ndist = "uniform"\nlow = 0.0005\nhigh = 0.003\n')
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
    import pyarrow.parquet as pq

    table = pq.read_table(out / "campaign.parquet")
    assert table.column_names == list(rows[0]) and table.num_rows == CASES
    assert table.column("trace_sha256").to_pylist() == [r["trace_sha256"] for r in rows]
    assert "value:thrusters.actual_thrust_scale[7]" in rows[0]
    html = (out / "campaign.html").read_text(encoding="utf-8")
    assert "href='cases/0000/run/report.html'" in html  # 3 cases: each among the 5 worst

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

    f.write_text(f.read_text(encoding="utf-8").replace(f"cases = {CASES}",
                                                       f"cases = {CASES + 1}"), encoding="utf-8")
    more = _hil(["campaign", str(f), "--out", str(out)], runtime)  # extended by one case
    assert more.returncode in (0, 1), more.stderr[-3000:]
    assert f"resuming: {CASES} of {CASES + 1} cases" in more.stdout and "1 cases run" in more.stdout
    grown = json.loads((out / "campaign.json").read_text(encoding="utf-8"))["cases"]
    assert [r["trace_sha256"] for r in grown[:CASES]] == [r["trace_sha256"] for r in before]


def test_minimal_failure_names_the_dispersion_that_fails(tmp_path: Path, runtime: Path) -> None:
    """A 90 ms valve opening delay fails the 12 s quickstart, a 0.1 deg/s initial rate does
    not: the minimal failure keeps the delay alone, the rate back at nominal."""
    f = _campaign_file(
        tmp_path / "f.toml",
        'study = "factorial"\n'
        'set = ["scenario.duration_s=12.0", "expectations.steady_state_window_s=4.0"]\n'
        '[[dispersions]]\nname = "initial_rate"\ndist = "sweep"\nvalues = [0.1]\n'
        '[[dispersions]]\nname = "open_delay"\ndist = "sweep"\nvalues = [0.09]\n')
    out = tmp_path / "out"
    run = _hil(["campaign", str(f), "--out", str(out)], runtime)
    assert run.returncode == 1, run.stdout[-2000:] + run.stderr[-2000:]  # the one case fails
    m = _hil(["campaign", "minimize", str(out), "0000", "--out", str(tmp_path / "m")], runtime)
    assert m.returncode == 0, m.stderr[-2000:]
    r = json.loads((tmp_path / "m" / "minimal.json").read_text(encoding="utf-8"))
    assert r["minimal"] == {"thrusters.open_delay_s": 0.09}, r
    # as drawn (fails), at nominal (passes), without the rates (fails); without the delay
    # is the nominal case again: not rerun
    assert [t["passed"] for t in r["trials"]] == [False, True, False]


def test_an_interrupted_campaign_resumes(tmp_path: Path, runtime: Path) -> None:
    """Ctrl-C after the first case (SIGINT to the whole process group, as a terminal sends
    it): the campaign stops without a traceback (no case folder half-written); the same
    command again runs only the cases missing and ends with every case once."""
    import os
    import signal
    import time

    cases = 6
    f = _campaign_file(
        tmp_path / "mc.toml",
        f'cases = {cases}\nseed = 3\n'
        'set = ["scenario.duration_s=6.0", "expectations.steady_state_window_s=2.0"]\n'
        '[[dispersions]]\nname = "latency"\ndist = "uniform"\nlow = 0.0005\nhigh = 0.003\n')
    out = tmp_path / "out"
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime))
    p = subprocess.Popen([sys.executable, "-m", "bench.operator.entry", "campaign", str(f),
                          "--out", str(out)], env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.monotonic() + RUN_TIMEOUT_S
    finished = out / "cases"
    while not (finished.exists() and list(finished.glob("*/result.json"))):
        assert p.poll() is None and time.monotonic() < deadline, "no case finished"
        time.sleep(POLL_S)
    os.killpg(p.pid, signal.SIGINT)
    _, err = p.communicate(timeout=RUN_TIMEOUT_S)
    assert "Traceback" not in err, err[-3000:]
    done_before = {d.name for d in (out / "cases").glob("*") if (d / "result.json").exists()}
    assert p.returncode != 0 and 1 <= len(done_before) < cases
    assert not (out / "campaign.json").exists()
    again = _hil(["campaign", str(f), "--out", str(out)], runtime)
    assert again.returncode in (0, 1), again.stderr[-3000:]
    rows = json.loads((out / "campaign.json").read_text(encoding="utf-8"))["cases"]
    assert [r["name"] for r in rows] == [f"{i:04d}" for i in range(cases)]
    assert all(r["status"] == "ok" for r in rows)
    assert not [d for d in (out / "cases").iterdir() if ".attempt-" in d.name]


def test_a_hung_case_is_retried_once_then_recorded_as_an_error(tmp_path: Path,
                                                               runtime: Path) -> None:
    """case_timeout_s = 1 s on one-hour cases: each case is stopped, retried, then listed as
    an error (exit 3), none dropped, no run left behind."""
    # An hour simulated: no run finishes in 1 s (that would take 3600x real time). 30 s cases
    # did: a warm case of the quickstart at ~40x real time ended within the timeout in CI.
    f = _campaign_file(
        tmp_path / "hang.toml",
        'cases = 2\ncase_timeout_s = 1.0\n'
        'set = ["scenario.duration_s=3600.0"]\n'
        '[[dispersions]]\nname = "latency"\ndist = "sweep"\nvalues = [0.001]\n')
    out = tmp_path / "out"
    run = _hil(["campaign", str(f), "--out", str(out)], runtime)
    assert run.returncode == 3, run.stdout[-2000:] + run.stderr[-2000:]
    rows = json.loads((out / "campaign.json").read_text(encoding="utf-8"))["cases"]
    assert [(r["name"], r["status"]) for r in rows] == [("0000", "error"), ("0001", "error")]
    assert all("still running after 1 s" in r["error"] and r["attempts"] == 2 for r in rows)
    assert run.stderr.count("retrying") == 2
    assert "ERROR 0000" in run.stdout and not list((out / "cases").iterdir())
