"""report.html of a real fault run (slow: real processes): every event marked, no network."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from bench.operator.report_html import FIGURES
from tests.e2e.conftest import QUICKSTART, run_cli, unique_bus

pytestmark = pytest.mark.slow


def test_fault_run_report_marks_every_event(tmp_path: Path, runtime_dir: Path) -> None:
    """A stuck-open valve at 10 s: report.html holds a marker of each events.jsonl event on
    each figure, fetches nothing, and names the fault."""
    run = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", "20",
                   "--set", 'faults=[{t_s=10.0, kind="stuck_open", thruster=2}]'],
                  tmp_path / "run", runtime_dir)
    assert run.returncode in (0, 1), run.stderr
    text = (run.out / "report.html").read_text(encoding="utf-8")
    events = [json.loads(x) for x in (run.out / "events.jsonl").read_text().splitlines()]
    assert any(e["event"] == "fault_injected" for e in events)
    for i in range(len(events)):
        for name, _ in FIGURES:
            assert f"id='{name}-event-{i}'" in text, (name, i, events[i])
    assert "<script" not in text and not re.search(r"(src|href)=['\"]https?:", text)
    assert "stuck_open" in text
