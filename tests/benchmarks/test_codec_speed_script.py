"""A small version of the codec benchmark: every DBC message timed, figures positive."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from dbc.database import load_database

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "benchmarks" / "codec_speed.py"
TIMEOUT_S = 120.0  # a hang guard


def test_codec_speed_times_every_message() -> None:
    """One JSON object naming every message of the DBC, each figure a positive time."""
    done = subprocess.run([sys.executable, str(SCRIPT), "--batches", "2", "--frames", "50"],
                          cwd=REPO, capture_output=True, text=True, timeout=TIMEOUT_S)
    assert done.returncode == 0, done.stderr[-3000:]
    out = json.loads(done.stdout)
    assert set(out["messages"]) == {m.name for m in load_database().messages}
    for figures in out["messages"].values():
        assert figures["encode_us"] > 0.0 and figures["message_us"] > 0.0
        assert figures["inspect_accept_us"] > 0.0
