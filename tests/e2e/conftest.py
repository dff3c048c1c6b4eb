"""Helpers for end-to-end tests: run the real CLI as a separate process on a private bus."""

from __future__ import annotations

import contextlib
import json
import os
import selectors
import signal
import subprocess
import sys
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from tests.run_files import run_text

REPO = Path(__file__).resolve().parents[2]
QUICKSTART = REPO / "scenarios" / "quickstart.toml"
# Wall-clock limit of one run: a hang guard, not a measurement. The emulated CI guest
# (Python ~7x slower, matplotlib's font cache built on first use) raises it.
RUN_TIMEOUT_S = float(os.environ.get("THIL_TEST_RUN_TIMEOUT_S", "600"))


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


def trace_lines(trace: Path) -> list[str]:
    """An ASC trace's content without its wall-clock header (date line); ``trace`` named as
    in a full record (``.../trace.asc``), read whichever record level wrote it."""
    return [
        ln
        for ln in run_text(trace.parent, trace.name).splitlines()
        if not ln.startswith(("date", "Begin Triggerblock"))
    ]


def run_cli(args: list[str], out: Path, runtime_dir: Path, timeout_s: float = RUN_TIMEOUT_S,
            extra_env: dict[str, str] | None = None, drop_env: tuple[str, ...] = ()) -> Run:
    """Run ``thruster-hil ARGS --out OUT`` with a private hilbus runtime directory (with
    ``extra_env`` added to the environment and the variables ``drop_env`` removed)."""
    env = {k: v for k, v in os.environ.items() if k not in drop_env}
    env.update(XDG_RUNTIME_DIR=str(runtime_dir), **(extra_env or {}))
    p = subprocess.run(
        [sys.executable, "-m", "bench.operator.entry", *args, "--out", str(out)],
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


PROGRESS_DEADLINE_S = 120.0


def _default_sigint() -> None:
    """In the child before exec: SIGINT back to its default (Python then raises on it)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@contextlib.contextmanager
def running(
    args: list[str], out: Path, runtime_dir: Path, min_percent: float = 0.0,
    own_group: bool = False, env_extra: dict[str, str] | None = None,
) -> Iterator[subprocess.Popen[str]]:
    """``thruster-hil ARGS --out OUT`` in the background, entered once its progress passes
    ``min_percent``; on exit it is waited for (and killed if a test failed meanwhile).

    ``own_group``: in a process group of its own (its pid), as a terminal's foreground job,
    so that a signal can go to all its processes at once (``os.killpg``), and with SIGINT
    at its default disposition as a terminal gives it (a background job of a
    non-interactive shell, such as a CI runner's, inherits it ignored)."""
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir), **(env_extra or {}))
    p = subprocess.Popen(
        [sys.executable, "-m", "bench.operator.entry", *args, "--out", str(out)],
        cwd=REPO,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=own_group,
        preexec_fn=_default_sigint if own_group else None,
    )
    try:
        assert p.stderr is not None
        sel = selectors.DefaultSelector()
        sel.register(p.stderr, selectors.EVENT_READ)
        while True:  # real progress lines, read as they come
            assert sel.select(timeout=PROGRESS_DEADLINE_S), "no progress from the run"
            line = p.stderr.readline()
            assert line, "the run ended before it made progress"
            if line.startswith("progress") and float(line.split()[1]) > min_percent:
                break
        sel.close()
        yield p
        p.communicate(timeout=RUN_TIMEOUT_S)
    finally:
        if p.poll() is None:
            p.kill()
        p.communicate()


def flood(bus: str, runtime_dir: Path, frames: int, rate_hz: float) -> dict[str, Any]:
    """Run the hostile-input generator to completion; what it sent, per receiver and cause."""
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir))
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "bench.operator.flood",
            "--bus",
            bus,
            "--frames",
            str(frames),
            "--rate-hz",
            str(rate_hz),
        ],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
        check=True,
    )
    return dict(json.loads(done.stdout))


def processes_with(mark: str) -> list[int]:
    """Pids of the processes whose environment holds ``mark`` (a run's own: its console,
    bench, prestart and flight software inherit it, whatever their command lines)."""
    found = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            with contextlib.suppress(OSError):
                if mark.encode() in (d / "environ").read_bytes():
                    found.append(int(d.name))
    return found
