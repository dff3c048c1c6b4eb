"""Runs one scenario: the bench in this process, the flight software as a child process.

The flight software is started by command (``--fsw-cmd``, ours by default), exactly as a
real bench starts someone else's flight-software binary, so the bench never imports it.
Placeholders in the command: ``{bus}``, ``{mode}``, ``{config}`` (the flight-software
configuration JSON written into the run folder), ``{stats}`` (where it may write its
statistics JSON) and ``{run_dir}``. The run folder always ends up with ``summary.json``,
``trace.asc``, ``telemetry.csv``, ``valve_pulses.csv``, ``events.jsonl``, ``fsw.log`` and
the PNG plots, even when the flight software dies.
"""

from __future__ import annotations

import ctypes
import json
import os
import shlex
import shutil
import signal
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bench.node import BenchNode, merge_counts
from bench.plots import plot_run
from bench.scenario import Scenario
from dbc import load_database
from dbc.bus import open_bus
from dbc.errors import RunError

DEFAULT_FSW_CMD = (
    f"{shlex.quote(sys.executable)} -m flight_sw --bus {{bus}} --mode {{mode}} "
    "--config {config} --stats {stats}"
)
FSW_TERM_TIMEOUT_S = 5.0
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


@dataclass(frozen=True)
class RunOptions:
    """How to run a scenario."""

    mode: str
    bus: str
    seed: int
    out: Path
    duration_s: float
    fsw_cmd: str | None = DEFAULT_FSW_CMD  # None: bench alone (external flight software)

    def __post_init__(self) -> None:
        if self.mode not in ("lockstep", "realtime"):
            raise RunError(f"--mode {self.mode!r}: expected lockstep or realtime")
        if not self.duration_s > 0:
            raise RunError(f"--duration {self.duration_s!r}: expected a positive number of seconds")


def _fsw_argv(template: str, opts: RunOptions, config: Path, stats: Path) -> list[str]:
    try:
        return [
            a.format(bus=opts.bus, mode=opts.mode, config=config, stats=stats, run_dir=opts.out)
            for a in shlex.split(template)
        ]
    except (KeyError, IndexError, ValueError) as exc:
        raise RunError(f"--fsw-cmd {template!r}: bad placeholder ({exc})") from exc


def _die_with_parent() -> None:
    """In the child: ask Linux for SIGTERM when the bench process dies (even by SIGKILL).

    Elsewhere (macOS) this is a no-op; the flight software then notices the silence itself.
    """
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def _stop(proc: subprocess.Popen[bytes]) -> int | None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(FSW_TERM_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.returncode


def run_scenario(
    sc: Scenario,
    opts: RunOptions,
    progress: Callable[[float, float], None] | None = None,
    ready: Callable[[Path], None] | None = None,
) -> dict[str, Any]:
    """Run ``sc``; returns the summary (also written to ``opts.out/summary.json``)."""
    out = opts.out
    out.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(sc.path, out / "scenario.toml")
    config = out / "fsw_config.json"
    config.write_text(json.dumps(sc.fsw_config(), indent=2) + "\n", encoding="utf-8")
    stats = out / "fsw_stats.json"
    db = load_database()
    bus = open_bus(opts.bus)
    proc: subprocess.Popen[bytes] | None = None
    node = BenchNode(sc, db, bus, out, opts.mode, opts.seed, opts.bus, progress)
    if ready is not None:
        ready(config)
    error: BaseException | None = None
    try:
        if opts.fsw_cmd is not None:
            log = open(out / "fsw.log", "wb")  # noqa: SIM115 - handed to the child
            env = dict(os.environ, PYTHONUNBUFFERED="1")
            proc = subprocess.Popen(
                _fsw_argv(opts.fsw_cmd, opts, config, stats),
                stdout=log,
                stderr=subprocess.STDOUT,
                env=env,
                preexec_fn=_die_with_parent,
            )
            log.close()
            node.fsw_alive = lambda: proc is not None and proc.poll() is None
        if opts.mode == "lockstep":
            node.run_lockstep(opts.duration_s)
        else:
            node.run_realtime(opts.duration_s)
    except BaseException as exc:  # keep the run folder whatever happened
        error = exc
    finally:
        fsw_rc = _stop(proc) if proc is not None else None
        bus.shutdown()
    summary = node.close(opts.duration_s if error is None else node.plant.t_ns / 1e9)
    summary["fsw"] = _fsw_report(stats, fsw_rc, out)
    merge_counts(summary["frames"], summary["rejected_other"], "FSW",
                 summary["fsw"].get("sent", {}), summary["fsw"].get("received", {}))
    if isinstance(summary["deadline_misses"], dict):
        summary["deadline_misses"]["fsw_overruns"] = max(
            summary["deadline_misses"]["fsw_overruns"], summary["fsw"].get("overruns", 0)
        )
        summary["deadline_misses"]["total"] = sum(
            v for k, v in summary["deadline_misses"].items() if k in ("bench_late", "fsw_overruns")
        )
    if error is not None:
        summary["error"] = f"{type(error).__name__}: {error}"
        summary["passed"] = False
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    plot_run(out, sc.expectations.settling_band_deg)
    if error is not None and not isinstance(error, Exception):
        raise error  # KeyboardInterrupt and friends, after the folder is complete
    if error is not None:
        raise RunError(f"run failed ({summary['error']}); run folder: {out}") from error
    return summary


def _fsw_report(stats: Path, rc: int | None, out: Path) -> dict[str, Any]:
    rep: dict[str, Any] = {"exit_code": rc}
    if stats.exists():
        try:
            rep.update(json.loads(stats.read_text(encoding="utf-8")))
        except (OSError, json.JSONDecodeError) as exc:
            rep["stats_error"] = str(exc)
    else:
        rep["stats_error"] = "flight software wrote no statistics"
    if rc not in (0, None):
        log = out / "fsw.log"
        tail = (
            log.read_text(encoding="utf-8", errors="replace").splitlines()[-5:]
            if log.exists()
            else []
        )
        rep["log_tail"] = tail
    return rep
