"""Runs one scenario: the bench in this process, the flight software as a child process.

The flight software is started by command (``--fsw-cmd``, ours by default), exactly as a
real bench starts someone else's flight-software binary, so the bench never imports it.
Placeholders in the command: ``{bus}``, ``{mode}``, ``{config}`` (the flight-software
configuration JSON written into the run folder), ``{stats}`` (where it may write its
statistics JSON), ``{rx_log}`` (where it may log when each frame arrived, realtime:
``fsw_rx.csv``, see :mod:`bench.operator.analysis.reception`) and ``{run_dir}``. The run folder
always ends up with ``summary.json``, ``trace.asc``, ``telemetry.csv``,
``valve_pulses.csv``, ``events.jsonl``, ``fsw.log`` and the PNG plots, even when the flight
software dies (the trace and the tables with ``.gz`` added at the default ``--record
standard``: bench.results.record).
"""

from __future__ import annotations

import gc
import json
import os
import shutil
import signal
import subprocess
import sys
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bench.node import BenchNode
from bench.operator.fsw_process import (
    DEFAULT_FSW_CMD,
    die_with_parent,
    fsw_argv,
    fsw_report,
    log_tail,
    stop,
)
from bench.operator.lifecycle import DiskReserve, Stopped, stop_on_signals, supervise
from bench.operator.partial import partial_summary, plot_folder
from bench.operator.run_warnings import (
    bus_warnings,
    compromised,
    duration_warnings,
    overrun_warning,
    scenario_warnings,
)
from bench.operator.shared_bus import probe
from bench.operator.verdict import abnormal, verdict
from bench.results.counts import merge_counts, zero_unheard
from bench.results.record import RECORD_STANDARD, check_record
from bench.results.writers import write_summary
from bench.scenario.spec import Scenario
from dbc.codec import cycle_time_ns
from dbc.contract import EXIT_REFUSED
from dbc.database import load_database
from dbc.errors import ConfigError, RefusedConfigError, RunError
from dbc.records import write_record
from transport.hilbus import MEMBER_STALL_S
from transport.lockstep import available_cpus, lockstep_spin_s
from transport.spec import mode_options, open_bus

EXIT_CHILD_OK, EXIT_CHILD_RUN_ERROR, EXIT_CHILD_CRASH, EXIT_CHILD_BAD_INPUT = 0, 3, 4, 5
EXIT_CHILD_STOPPED = 6  # a stop signal: the run folder is complete, the parent re-raises it


@dataclass(frozen=True)
class RunOptions:
    """How to run a scenario."""

    mode: str
    bus: str
    seed: int
    out: Path
    duration_s: float
    fsw_cmd: str | None = DEFAULT_FSW_CMD  # None: bench alone (external flight software)
    bus_shared: bool = False  # a bus the user named: another run may be on it (probed)
    record: str = RECORD_STANDARD  # bench.results.record: compressed or plain files

    def __post_init__(self) -> None:
        if self.mode not in ("lockstep", "realtime"):
            raise ConfigError("command line", "--mode", self.mode, "lockstep or realtime")
        check_record(self.record)
        period_s = cycle_time_ns(load_database(), "THR_CMD_0") / 1e9
        if not self.duration_s >= period_s:  # also rejects NaN
            raise ConfigError("command line", "--duration", self.duration_s,
                              f"at least one control period ({period_s} s)")



def run_scenario(
    sc: Scenario,
    opts: RunOptions,
    progress: Callable[[float, float], None] | None = None,
    ready: Callable[[Path], None] | None = None,
    alert: Callable[[int, str, dict[str, Any]], None] | None = None,
) -> dict[str, Any]:
    """Run ``sc``; returns the summary (also written to ``opts.out/summary.json``).

    ``alert`` hears every event of the run as it happens (bench.operator.alerts).

    The bench runs in a forked child process and this process supervises it, so that the
    run folder is completed (from the files written so far) even if the bench is killed.
    """
    out = opts.out
    if opts.fsw_cmd is not None:
        # a bad placeholder: exit 2 before anything runs
        fsw_argv(opts.fsw_cmd, opts.bus, opts.mode, out, out, out)
    check_bus(opts.bus)
    if opts.bus_shared:
        heard = probe(opts.bus)
        if heard:
            refusal = ConfigError("command line", "--bus", opts.bus,
                                  f"a bus no other run uses (heard {', '.join(heard)} from a "
                                  "running bench or flight software; leave out --bus for a "
                                  "channel of this run's own)")
            _write_refusal(sc, opts, refusal, heard)
            raise refusal
    spin_s = lockstep_spin_s(available_cpus(), os.environ) if opts.mode == "lockstep" else 0.0
    try:
        out.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(sc.path, out / "scenario.toml")
        config = out / "fsw_config.json"
        write_record(config, sc.fsw_config())
    except OSError as exc:
        raise ConfigError("command line", "--out", str(out),
                          f"a folder this user can create and write ({exc.strerror or exc})"
                          ) from exc
    reserve = DiskReserve(out)
    if not hasattr(os, "fork"):  # pragma: no cover - no supervisor where fork is missing
        return _run_bench(sc, opts, progress, ready, config, spin_s, reserve, alert)
    pid = os.fork()
    if pid == 0:  # the bench process
        code = EXIT_CHILD_OK
        try:
            die_with_parent()
            stop_on_signals()
            (out / "bench.pid").write_text(f"{os.getpid()}\n", encoding="utf-8")
            _run_bench(sc, opts, progress, ready, config, spin_s, reserve, alert)
        except ConfigError as exc:
            code = EXIT_CHILD_BAD_INPUT
            if not (out / "summary.json").exists():  # refused before the run: say why
                reserve.release()
                partial_summary(sc, opts, f"bad input: {exc}", refused=str(exc))
        except RunError:
            code = EXIT_CHILD_RUN_ERROR
        except (Stopped, KeyboardInterrupt):
            code = EXIT_CHILD_STOPPED
        except BaseException:
            code = EXIT_CHILD_CRASH
            if not (out / "summary.json").exists():
                traceback.print_exc()  # nothing else will say what happened
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
    status, stop_signal = supervise(pid)
    reserve.release()
    (out / "bench.pid").unlink(missing_ok=True)  # a pid file names a running process only
    if os.WIFSIGNALED(status):
        summary = partial_summary(sc, opts, f"bench process killed by signal {os.WTERMSIG(status)}")
        raise RunError(f"run failed ({summary['error']}); partial run folder: {out}")
    if not (out / "summary.json").exists():  # it failed before its run folder was set up
        summary = partial_summary(
            sc, opts, f"bench process exited with code {os.WEXITSTATUS(status)} before "
            "writing summary.json (see its traceback above)")
        raise RunError(f"run failed ({summary['error']}); partial run folder: {out}")
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    if os.WEXITSTATUS(status) == EXIT_CHILD_STOPPED or stop_signal is not None:
        # after the bench completed the folder
        raise Stopped(stop_signal or signal.SIGINT, summary, out)
    if os.WEXITSTATUS(status) == EXIT_CHILD_BAD_INPUT:
        if summary.get("refused"):
            raise RefusedConfigError("the bench", summary["refused"])
        raise RefusedConfigError("the flight software", summary["fsw"]["refused"])
    if os.WEXITSTATUS(status) != EXIT_CHILD_OK:
        tail = "".join(f"\n  fsw.log: {x}" for x in (summary.get("fsw") or {}).get("log_tail", []))
        raise RunError(f"run failed ({summary.get('error')}); run folder: {out}{tail}")
    return summary


def _run_bench(
    sc: Scenario,
    opts: RunOptions,
    progress: Callable[[float, float], None] | None,
    ready: Callable[[Path], None] | None,
    config: Path,
    spin_s: float = 0.0,
    reserve: DiskReserve | None = None,
    alert: Callable[[int, str, dict[str, Any]], None] | None = None,
) -> dict[str, Any]:
    """The bench process: run, then write summary.json and plots (whatever happened).

    ``spin_s``: lockstep, how long to poll for the flight software's answer before blocking
    (transport.lockstep.lockstep_spin_s; our flight software works its own out the same way).
    """
    out = opts.out
    stats = out / "fsw_stats.json"
    db = load_database()
    bus = open_bus(opts.bus, **mode_options(opts.bus, opts.mode))
    proc: subprocess.Popen[bytes] | None = None
    node = BenchNode(sc, db, bus, out, opts.mode, opts.seed, opts.bus, progress,
                     record=opts.record)
    node.trace.listener = alert
    node.lockstep_spin_s = spin_s
    if ready is not None:
        ready(config)
    error: BaseException | None = None
    try:
        if opts.fsw_cmd is not None:
            log = open(out / "fsw.log", "wb")  # noqa: SIM115 - handed to the child
            env = dict(os.environ, PYTHONUNBUFFERED="1")
            proc = subprocess.Popen(
                fsw_argv(opts.fsw_cmd, opts.bus, opts.mode, out, config, stats),
                stdout=log,
                stderr=subprocess.STDOUT,
                env=env,
                preexec_fn=die_with_parent,
            )
            log.close()
            (out / "fsw.pid").write_text(f"{proc.pid}\n", encoding="utf-8")
            node.fsw_alive = lambda: proc is not None and proc.poll() is None
        # Everything built so far lives for the whole run: keep it out of the cyclic
        # garbage collector's passes. Without this, a full collection over it stops the
        # bench for ~100 ms a few seconds in, which in realtime trips the flight software's
        # sensor watchdog (safe mode) every run.
        gc.collect()
        gc.freeze()
        if opts.mode == "lockstep":
            node.run_lockstep(opts.duration_s)
        else:
            node.run_realtime(opts.duration_s)
    except BaseException as exc:  # keep the run folder whatever happened
        error = exc
    finally:
        fsw_rc = stop(proc) if proc is not None else None
        (out / "fsw.pid").unlink(missing_ok=True)
        bus.shutdown()
    if isinstance(error, KeyboardInterrupt):
        error = Stopped(signal.SIGINT)
    if isinstance(error, Stopped):
        node.trace.event(node.plant.t_ns, "run_interrupted", by=error.name)
    if reserve is not None:
        reserve.release()  # the summary and the last of the files get the space kept back
    summary = node.close(opts.duration_s if error is None else node.plant.t_ns / 1e9)
    summary["ended"] = ("completed" if error is None
                        else error.name if isinstance(error, Stopped) else "error")
    summary["fsw"] = fsw_report(stats, fsw_rc, out)
    merge_counts(summary["frames"], summary["rejected_other"], "FSW",
                 summary["fsw"].get("sent", {}), summary["fsw"].get("received", {}))
    fsw_heard = {"FSW"} if "received" in summary["fsw"] else set()
    zero_unheard(summary["frames"], {"BENCH"} | fsw_heard)
    if isinstance(summary["deadline_misses"], dict):
        summary["deadline_misses"]["fsw_overruns"] = max(
            summary["deadline_misses"]["fsw_overruns"], summary["fsw"].get("overruns", 0)
        )
        summary["deadline_misses"]["total"] = sum(
            v for k, v in summary["deadline_misses"].items() if k in ("bench_late", "fsw_overruns")
        )
    summary["compromised"] = compromised(summary)
    summary["warnings"] = (bus_warnings(summary) + duration_warnings(sc, opts.duration_s)
                           + scenario_warnings(sc)
                           + [f"flight software: {w}" for w in summary["fsw"].get("warnings", [])
                              if isinstance(w, str)])
    if error is None and not (summary.get("valve_openings") or {}).get("total"):
        summary["warnings"].append(
            "no valve opened in the whole run: if the vehicle was to move, check the thrust "
            "levels against its inertia and the modulator's thresholds (an on-time too short "
            "for min_on_s or a Schmitt trigger's u_on is never commanded)")
    # hilbus: frames the bench and the flight software could not deliver to a member that
    # stopped reading (each process counts its own)
    bench_drops = getattr(bus, "overrun_drops", 0)
    fsw_drops = int(summary["fsw"].get("bus_overrun_drops", 0) or 0)
    summary["bus_overrun_drops"] = bench_drops + fsw_drops
    if bench_drops + fsw_drops:
        fsw_by_pid = {int(k): int(v) for k, v in
                      (summary["fsw"].get("bus_overrun_drops_by_pid") or {}).items()}
        summary["warnings"].append(overrun_warning(
            getattr(bus, "overrun_drops_by_pid", {}), fsw_by_pid, os.getpid(),
            None if proc is None else proc.pid,
            float(getattr(bus, "member_stall_s", None) or MEMBER_STALL_S)))
    if summary["compromised"] is not None:
        summary["passed"] = False
    if error is not None:
        summary["error"] = f"{type(error).__name__}: {error}"
        if "first frame" in str(error):
            summary["fsw"]["log_tail"] = log_tail(out / "fsw.log")
            # a refusal is a record in the statistics file (dbc.contract.FswRefusal)
            if fsw_rc == EXIT_REFUSED and summary["fsw"].get("refused"):
                summary["error"] = f"the flight software refused its configuration: " \
                                   f"{summary['fsw']['refused']}"
                error = RefusedConfigError("the flight software", summary["fsw"]["refused"])
        summary["passed"] = False
    summary["verdict"], summary["abnormal"] = verdict(summary), abnormal(summary)
    write_summary(out / "summary.json", summary)
    plot_folder(out, sc)
    if error is not None and not isinstance(error, Exception):
        raise error  # KeyboardInterrupt and friends, after the folder is complete
    if isinstance(error, RefusedConfigError):
        raise error
    if error is not None:
        tail = "".join(f"\n  fsw.log: {x}" for x in summary["fsw"].get("log_tail", []))
        raise RunError(f"run failed ({summary['error']}); run folder: {out}{tail}") from error
    return summary


def _write_refusal(sc: Scenario, opts: RunOptions, refusal: ConfigError,
                   heard: list[str]) -> None:
    """summary.json of a run refused before it started (a shared bus): what it heard."""
    summary: dict[str, Any] = {
        "scenario": sc.name, "scenario_file": sc.path, "mode": opts.mode, "seed": opts.seed,
        "bus": opts.bus, "sim_time_s": 0.0, "ended": "refused", "passed": False,
        "refused": str(refusal), "second_sender_heard": heard,
    }
    summary["verdict"], summary["abnormal"] = verdict(summary), abnormal(summary)
    try:
        opts.out.mkdir(parents=True, exist_ok=True)
        write_summary(opts.out / "summary.json", summary)
    except OSError:
        pass  # a folder that cannot be written: the refusal is still said on the console


def check_bus(spec: str) -> None:
    """Open and close ``spec`` once: a bus that cannot be opened fails here, with its reason.

    Raises :class:`~dbc.errors.BusError` (exit 2 from the CLI) instead of letting the forked
    bench fail where only its exit code is seen.
    """
    open_bus(spec).shutdown()


