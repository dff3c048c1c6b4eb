"""A second process attacks a live lockstep run with every category of hostile frame: nothing
crashes or restarts, every frame is counted by cause by both receivers, noise leaves the
telemetry identical to the clean run, and forgeries mark the run compromised by name."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import QUICKSTART, REPO, RUN_TIMEOUT_S, running, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

RUN_S = "300"  # of simulated time: longer than the attack takes at any speed-up seen here
ATTACK_FRAMES = 20_000
ATTACK_RATE_HZ = 10_000.0
SEED = "7"
START_PERCENT = 2.0  # the attack starts once the run is under way (BENCH_STATUS heard)


def _attack(bus: str, runtime_dir: Path, forgeries: bool) -> dict[str, Any]:
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir))
    args = [sys.executable, "-m", "bench.operator.hostile", "--bus", bus, "--frames",
            str(ATTACK_FRAMES), "--rate-hz", str(ATTACK_RATE_HZ)]
    done = subprocess.run([*args, *(["--forgeries"] if forgeries else [])], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=RUN_TIMEOUT_S, check=True)
    return dict(json.loads(done.stdout))


def _run(tmp_path: Path, runtime_dir: Path, name: str, attack: bool | None) -> dict[str, Any]:
    """The quickstart in lockstep; ``attack``: None none, False noise, True with forgeries."""
    bus, out = unique_bus(), tmp_path / name
    args = ["run", str(QUICKSTART), "--bus", bus, "--duration", RUN_S, "--seed", SEED]
    sent = None
    with running(args, out, runtime_dir, min_percent=START_PERCENT):
        if attack is not None:
            sent = _attack(bus, runtime_dir, attack)
    s = json.loads((out / "summary.json").read_text())
    s["_sent"], s["_telemetry"] = sent, run_text(out, "telemetry.csv").encode()
    return s


def _rejects(s: dict[str, Any], node: str) -> int:
    """Every frame ``node`` rejected: non-ICD frames, others' messages, its own from others."""
    total = sum((s["rejected_other"].get(node) or {}).values())
    for row in s["frames"].values():
        if row["sender"] == node:
            total += sum((row.get("at_sender") or {}).values())
        elif node == "BENCH" or row["sender"] == "BENCH":
            total += sum((row.get("rejected") or {}).values())
    return total


@pytest.fixture(scope="module")
def clean(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The run without an attacker."""
    runtime = tmp_path_factory.mktemp("xdg-clean")
    runtime.chmod(0o700)
    return _run(tmp_path_factory.mktemp("clean"), runtime, "clean", None)


def test_noise_is_counted_and_changes_nothing(clean: dict[str, Any], tmp_path: Path,
                                              runtime_dir: Path) -> None:
    """Frames without a valid E2E protection: each counted once by the bench and once by the
    flight software; identical telemetry; no restart; not compromised."""
    s = _run(tmp_path, runtime_dir, "noise", False)
    n = sum(s["_sent"]["sent"].values())
    assert n == ATTACK_FRAMES
    assert "error" not in s and s["fsw"]["exit_code"] == 0
    for node in ("BENCH", "FSW"):
        assert _rejects(s, node) - _rejects(clean, node) == n, node
    assert s["_telemetry"] == clean["_telemetry"]
    assert s["fsw_restarts"] == 0 and s["fsw"]["restarts"] == 0
    assert s["compromised"] is None and s["passed"] == clean["passed"]


def test_forgeries_are_counted_and_the_run_is_compromised(clean: dict[str, Any],
                                                          tmp_path: Path,
                                                          runtime_dir: Path) -> None:
    """With forged commands, replayed SYNC and BENCH_STATUS, out-of-range and invalid-counter
    frames: no crash, no restart, every frame counted by both sides, and the run reported
    compromised, naming the forged messages."""
    s = _run(tmp_path, runtime_dir, "forged", True)
    sent = s["_sent"]["sent"]
    n = sum(sent.values())
    assert n == ATTACK_FRAMES and all(sent[c] > 0 for c in sent), sent
    assert "error" not in s and s["fsw"]["exit_code"] == 0
    assert s["fsw_restarts"] == 0 and s["fsw"]["restarts"] == 0
    assert s["fsw"]["restarts_refused"] > 0  # the replayed SYNC(0)s and BENCH_STATUS
    # every attack frame is counted; a forged command taken in place of the genuine one
    # (it came first) moves on the alive counter, so the genuine one is rejected too
    for node in ("BENCH", "FSW"):
        assert _rejects(s, node) - _rejects(clean, node) >= n, node
    comp = s["compromised"]
    assert comp is not None and s["passed"] is False
    assert {"THR_CMD_0", "SYNC", "BENCH_STATUS", "IMU_RATE"} <= set(comp["messages"])
    assert any("run compromised" in w and "THR_CMD_0" in w for w in s["warnings"])
