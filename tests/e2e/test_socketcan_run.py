"""The quickstart in lockstep over real SocketCAN (vcan0), bench and flight software apart."""

from __future__ import annotations

from pathlib import Path

import can
import pytest

from bench.results.record import run_file
from dbc.database import load_database
from tests.e2e.conftest import QUICKSTART, run_cli

pytestmark = pytest.mark.socketcan

VCAN = Path("/sys/class/net/vcan0")
SHORT_S = "4"


@pytest.mark.skipif(not VCAN.exists(), reason="no SocketCAN interface vcan0 on this kernel")
def test_lockstep_quickstart_over_vcan(tmp_path: Path, runtime_dir: Path) -> None:
    """Every frame sent is received and checked, and the trace decodes with the DBC."""
    r = run_cli(
        ["run", str(QUICKSTART), "--bus", "socketcan:vcan0", "--duration", SHORT_S],
        tmp_path / "run",
        runtime_dir,
    )
    s = r.summary
    assert "error" not in s, s.get("error")
    assert s["bus"] == "socketcan:vcan0"
    for name, f in s["frames"].items():
        if f["sent"] is not None:
            assert f["received"] == f["sent"] and f["rejected"] == {}, name
    db = load_database()
    n = 0
    for msg in can.LogReader(str(run_file(r.out, "trace.asc"))):
        db.decode_message(msg.arbitration_id, msg.data)
        n += 1
    assert n == sum(f["sent"] for f in s["frames"].values() if f["sent"])
    assert s["latency_us"]["sensor_to_command"]["n"] > 0
