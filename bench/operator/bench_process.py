"""The bench process of a run: opens the bus, starts the flight software, runs, summarises.

Forked by the supervisor (bench.operator.orchestrator), which imports this module only
after the fork: the flight software is started first, so its start-up (interpreter,
imports, design-time set-up: ~0.3 s) overlaps the bench's own (the bench node and its
imports), and the bus is open before its first heartbeat; with the console script's
prestart (bench.operator.fsw_prestart) its imports are done by then. Writes ``summary.json``
(whatever happened: the flight software dying, a stop signal, an error); the supervisor
draws the plots afterwards (bench.operator.partial.plot_folder).
"""

from __future__ import annotations

import gc
import io
import os
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bench.node import BenchNode
from bench.operator.fsw_prestart import FswPrestart
from bench.operator.fsw_process import (
    FswProcess,
    fsw_argv,
    fsw_report,
    log_tail,
    stop,
)
from bench.operator.lifecycle import DiskReserve, Stopped
from bench.operator.run_warnings import (
    bus_warnings,
    compromised,
    duration_warnings,
    overrun_warning,
    scenario_warnings,
)
from bench.operator.verdict import abnormal, verdict
from bench.operator.warm_start import die_with_parent, fork_program, run_module, warm_module
from bench.results.counts import merge_counts, zero_unheard
from bench.results.writers import write_summary
from bench.scenario.spec import Scenario
from dbc.contract import EXIT_REFUSED
from dbc.database import load_database
from dbc.errors import RefusedConfigError, RunError
from transport.hilbus import MEMBER_STALL_S
from transport.spec import mode_options, open_bus

if TYPE_CHECKING:
    from bench.operator.orchestrator import RunOptions


def _start_fsw(opts: RunOptions, config: Path, stats: Path, prestart: FswPrestart | None
               ) -> tuple[FswProcess, str]:
    """The flight-software child, its output in ``fsw.log``, its pid in ``fsw.pid``: started
    warm (forked, bench.operator.warm_start) where this process may and can, else in the
    console's prestart (bench.operator.fsw_prestart) if it serves this command, else by its
    command line. With how it started: ``forked``, ``prestart`` or ``command``
    (summary.json ``fsw.start``)."""
    out = opts.out
    assert opts.fsw_cmd is not None
    argv = fsw_argv(opts.fsw_cmd, opts.bus, opts.mode, out, config, stats)
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    module = warm_module(argv, env)
    with open(out / "fsw.log", "wb") as log:  # the child keeps its own copy
        proc: FswProcess | None = None
        how = "forked"
        if module is not None:
            proc = fork_program(run_module(module, argv[3:]), log.fileno(), log.fileno(),
                                in_child=_unbuffered_fsw)
        elif prestart is not None:
            proc, how = prestart.run(argv, env, os.getcwd(), str(out / "fsw.log")), "prestart"
        if proc is None:
            proc, how = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, env=env,
                                         preexec_fn=die_with_parent), "command"
    (out / "fsw.pid").write_text(f"{proc.pid}\n", encoding="utf-8")
    return proc, how


def _unbuffered_fsw() -> None:  # pragma: no cover - runs in the warm child
    """The warm child as PYTHONUNBUFFERED makes a cold one: each write reaches fsw.log."""
    die_with_parent()
    for f in (sys.stdout, sys.stderr):
        if isinstance(f, io.TextIOWrapper):
            f.reconfigure(line_buffering=True, write_through=True)


def run_bench(
    sc: Scenario,
    opts: RunOptions,
    progress: Callable[[float, float], None] | None,
    ready: Callable[[Path], None] | None,
    config: Path,
    spin_s: float = 0.0,
    reserve: DiskReserve | None = None,
    alert: Callable[[int, str, dict[str, Any]], None] | None = None,
    prestart: FswPrestart | None = None,
) -> dict[str, Any]:
    """The bench process: run, then write summary.json (whatever happened).

    ``prestart``: the console's prestart, where the flight software starts if it serves
    its command (bench.operator.fsw_prestart).

    ``spin_s``: lockstep, how long to poll for the flight software's answer before blocking
    (transport.lockstep.lockstep_spin_s; our flight software works its own out the same way).
    """
    out = opts.out
    stats = out / "fsw_stats.json"
    supervisor_pid = os.getppid()  # the command; a SIGTERM after it died is its death's
    bus = open_bus(opts.bus, **mode_options(opts.bus, opts.mode))
    proc: FswProcess | None = None
    fsw_start: str | None = None
    try:
        if opts.fsw_cmd is not None:  # first: it boots while the bench node is built
            proc, fsw_start = _start_fsw(opts, config, stats, prestart)
        node = BenchNode(sc, load_database(), bus, out, opts.mode, opts.seed, opts.bus,
                         progress, record=opts.record)
    except BaseException:
        if proc is not None:
            stop(proc)
            (out / "fsw.pid").unlink(missing_ok=True)
        bus.shutdown()
        raise
    node.trace.listener = alert
    node.lockstep_spin_s = spin_s
    if ready is not None:
        ready(config)
    error: BaseException | None = None
    try:
        if proc is not None:
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
    orphaned = isinstance(error, Stopped) and os.getppid() != supervisor_pid
    if isinstance(error, Stopped):
        node.trace.event(node.plant.t_ns, "run_interrupted", by=error.name,
                         **({"supervisor_died": True} if orphaned else {}))
    if reserve is not None:
        reserve.release()  # the summary and the last of the files get the space kept back
    summary = node.close(opts.duration_s if error is None else node.plant.t_ns / 1e9)
    summary["ended"] = ("completed" if error is None
                        else error.name if isinstance(error, Stopped) else "error")
    if orphaned:  # SIGTERM from Linux (PR_SET_PDEATHSIG), not from a user: say whose death
        summary["supervisor_died"] = True
    summary["fsw"] = fsw_report(stats, fsw_rc, out)
    if fsw_start is not None:
        summary["fsw"]["start"] = fsw_start
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
    if error is not None and not isinstance(error, Stopped):  # a stop is no error: `ended`
        summary["error"] = f"{type(error).__name__}: {error}"
        if "first frame" in str(error):
            summary["fsw"]["log_tail"] = log_tail(out / "fsw.log")
            # a refusal is a record in the statistics file (dbc.contract.FswRefusal)
            if fsw_rc == EXIT_REFUSED and summary["fsw"].get("refused"):
                summary["error"] = f"the flight software refused its configuration: " \
                                   f"{summary['fsw']['refused']}"
                error = RefusedConfigError("the flight software", summary["fsw"]["refused"])
    if error is not None:
        summary["passed"] = False
    summary["verdict"], summary["abnormal"] = verdict(summary), abnormal(summary)
    write_summary(out / "summary.json", summary)
    if error is not None and not isinstance(error, Exception):
        raise error  # KeyboardInterrupt and friends, after the folder is complete
    if isinstance(error, RefusedConfigError):
        raise error
    if error is not None:
        tail = "".join(f"\n  fsw.log: {x}" for x in summary["fsw"].get("log_tail", []))
        raise RunError(f"run failed ({summary['error']}); run folder: {out}{tail}") from error
    return summary
