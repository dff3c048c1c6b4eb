"""Replay (slow: real processes): a recorded lockstep run into a new flight software gives
the recorded commands frame for frame; a changed gain is caught at its first frame."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.e2e.conftest import QUICKSTART, REPO, run_cli, unique_bus

pytestmark = pytest.mark.slow

SHORT_S = "4"
GAIN_FACTOR = 1.05
TIMEOUT_S = 300.0  # a hang guard


def _replay(run_dir: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "bench.operator.entry", "replay", str(run_dir),
                           *extra], cwd=REPO, capture_output=True, text=True,
                          timeout=TIMEOUT_S, check=False)


def test_replay_reproduces_the_run_and_finds_a_changed_gain(tmp_path: Path,
                                                            runtime_dir: Path) -> None:
    """Exit 0 and every frame as recorded; with the controller's natural frequency 5 %
    higher, exit 1 naming the cycle and message of the first divergent frame."""
    run = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", SHORT_S,
                   "--no-plots"], tmp_path / "run", runtime_dir)
    assert run.returncode in (0, 1), run.stderr
    same = _replay(run.out)
    assert same.returncode == 0, same.stdout + same.stderr
    assert "every compared frame as recorded" in same.stdout
    cycles = round(float(SHORT_S) / 0.02)
    assert f"replayed {cycles} cycles" in same.stdout
    cfg = json.loads((run.out / "fsw_config.json").read_text(encoding="utf-8"))
    cfg["flight_sw"]["controller"]["natural_frequency_rad_s"] *= GAIN_FACTOR
    changed = tmp_path / "changed.json"
    changed.write_text(json.dumps(cfg), encoding="utf-8")
    diff = _replay(run.out, "--config", str(changed))
    assert diff.returncode == 1, diff.stdout + diff.stderr
    assert "first divergence: cycle " in diff.stdout and "recorded" in diff.stdout
