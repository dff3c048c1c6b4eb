"""Helpers for end-to-end tests: run the real CLI as a separate process on a private bus."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[2]
QUICKSTART = REPO / "scenarios" / "quickstart.toml"
RUN_TIMEOUT_S = 600


@dataclass
class Run:
    """A finished ``thruster-hil`` invocation."""

    returncode: int
    stdout: str
    stderr: str
    out: Path

    @property
    def summary(self) -> dict[str, Any]:
        """The run's summary.json."""
        return json.loads((self.out / "summary.json").read_text(encoding="utf-8"))


def run_cli(args: list[str], out: Path, runtime_dir: Path, timeout_s: float = RUN_TIMEOUT_S) -> Run:
    """Run ``thruster-hil ARGS --out OUT`` with a private hilbus runtime directory."""
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir))
    p = subprocess.run(
        [sys.executable, "-m", "bench.cli", *args, "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=timeout_s,
        env=env,
        cwd=REPO,
    )
    return Run(p.returncode, p.stdout, p.stderr, out)


@pytest.fixture
def runtime_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A private, owner-only runtime directory for the portable bus."""
    d = tmp_path_factory.mktemp("xdg")
    d.chmod(0o700)
    return d


def unique_bus() -> str:
    """A portable-bus spec no other test uses."""
    return f"hilbus:t{uuid.uuid4().hex[:10]}"
