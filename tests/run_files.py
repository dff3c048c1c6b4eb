"""Run-folder files for tests, whichever record level wrote them (bench.results.record)."""

from __future__ import annotations

from pathlib import Path

from bench.results.record import read_lines, run_file


def run_text(run_dir: Path, base: str) -> str:
    """The text of ``base`` (e.g. ``telemetry.csv``) in ``run_dir``, plain or ``.gz``."""
    return "".join(read_lines(run_file(run_dir, base)))

