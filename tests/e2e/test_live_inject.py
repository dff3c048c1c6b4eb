"""Live injection: a FAULT_CMD sent by another process reaches a running bench and is recorded."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bench.operator.inject import FaultCommand, cansend_string, inject
from dbc.codec import FrameChecker
from dbc.database import load_database
from dbc.errors import RefusedConfigError
from tests.e2e.conftest import QUICKSTART, running, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

RUN_S = "8"
STUCK = 5
MISSING_THRUSTER = 12  # the quickstart vehicle has 8
DEADLINE_S = 60.0


def test_inject_reaches_running_bench(
    tmp_path: Path, runtime_dir: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """inject(stuck_open) during a realtime run: acknowledged, applied, in events and summary;
    one for a thruster the vehicle lacks: refused (exit 2 from the CLI) and recorded so."""
    bus, out = unique_bus(), tmp_path / "run"
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(runtime_dir))
    args = ["run", str(QUICKSTART), "--bus", bus, "--mode", "realtime", "--duration", RUN_S]
    with running(args, out, runtime_dir):
        counter = inject(bus, FaultCommand("stuck_open", STUCK))
        with pytest.raises(RefusedConfigError,
                           match=r"refused the fault command: stuck_open --target 12 .*"
                                 r"not applicable to this bench"):
            inject(bus, FaultCommand("stuck_open", MISSING_THRUSTER))
    s = json.loads((out / "summary.json").read_text())
    live = [f for f in s["faults"] if f.get("source") == "FAULT_CMD"]
    assert live and live[0]["kind"] == "stuck_open" and live[0]["thruster"] == STUCK
    refused = [f for f in live if f.get("applied") is False]
    assert len(refused) == 1 and f"Target = {MISSING_THRUSTER}" in refused[0]["why"]
    assert refused[0]["kind"] == "stuck_open"  # named in the summary's fault line
    assert 0 <= counter < 15
    assert "thruster-hil fault_injected" in run_text(out, "trace.asc")


def test_cansend_string_is_a_valid_protected_frame() -> None:
    """The printed cansend frame decodes with the DBC and passes the E2E check."""
    text = cansend_string(FaultCommand("drop", 0x040, duration_s=1.0, param=0.25), counter=3)
    can_id, data = text.split("#")
    import can

    msg = can.Message(
        arbitration_id=int(can_id, 16), is_extended_id=False, data=bytes.fromhex(data)
    )
    d = FrameChecker(load_database()).check(msg)
    assert d is not None and d.name == "FAULT_CMD" and d.counter == 3
    assert d.signals["Target"] == 0x040 and d.signals["Param"] == pytest.approx(0.25)
