"""Runs one scenario: this process supervises, the bench runs in a forked child, the
flight software is the bench's child process (or, with the console script's prestart,
the prestart's: bench.operator.fsw_prestart; the bench holds it the same way).

The flight software is started by command (``--fsw-cmd``, ours by default), exactly as a
real bench starts someone else's flight-software binary, so the bench never imports it.
Placeholders in the command: ``{bus}``, ``{mode}``, ``{config}`` (the flight-software
configuration JSON written into the run folder), ``{stats}`` (where it may write its
statistics JSON), ``{rx_log}`` (where it may log when each frame arrived, realtime:
``fsw_rx.csv``, see :mod:`bench.operator.analysis.reception`) and ``{run_dir}``. The run folder
always ends up with ``summary.json``, ``trace.asc``, ``telemetry.csv``,
``valve_pulses.csv``, ``events.jsonl``, ``fsw.log`` and the PNG plots, even when the flight
software dies (the trace and the tables with ``.gz`` added at the default ``--record
standard``: bench.results.record). The bench's side is bench.operator.bench_process,
imported only in the forked child; this process loads matplotlib while the run goes and
draws the plots once the bench has written ``summary.json``.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import sys
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bench.operator.fsw_prestart import FswPrestart
from bench.operator.fsw_process import DEFAULT_FSW_CMD, fsw_argv
from bench.operator.lifecycle import (
    DiskReserve,
    Stopped,
    exit_now,
    held_stop_signals,
    stop_on_signals,
    supervise,
)
from bench.operator.partial import partial_summary, plot_folder, preload_plots
from bench.operator.shared_bus import probe
from bench.operator.verdict import abnormal, verdict
from bench.operator.warm_start import die_with_parent
from bench.results.record import RECORD_STANDARD, check_record
from bench.results.writers import write_summary
from bench.scenario.spec import Scenario
from dbc.codec import cycle_time_ns
from dbc.database import load_database
from dbc.errors import ConfigError, RefusedConfigError, RunError
from dbc.records import write_record
from transport.lockstep import available_cpus, lockstep_spin_s
from transport.relay import RelayBus
from transport.spec import open_bus

EXIT_CHILD_OK, EXIT_CHILD_RUN_ERROR, EXIT_CHILD_CRASH, EXIT_CHILD_BAD_INPUT = 0, 3, 4, 5
EXIT_CHILD_STOPPED_BASE = 64  # + the signal's number: stopped by it, the parent re-raises it


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
    plots: bool = True  # the PNG plots (bench.operator.plots), drawn after the summary
    monitor: bool = False  # the live monitor on the run's bus (bench.operator.monitor)

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
    summary_ready: Callable[[dict[str, Any]], None] | None = None,
    prestart: FswPrestart | None = None,
) -> dict[str, Any]:
    """Run ``sc``; returns the summary (also written to ``opts.out/summary.json``).

    ``prestart``: where the bench starts the flight software if it can
    (bench.operator.fsw_prestart); this process lets go of it once the bench is forked.

    ``alert`` hears every event of the run as it happens (bench.operator.alerts);
    ``summary_ready`` gets the summary of a run that completed as soon as it is written,
    before the plots are drawn.

    The bench runs in a forked child process and this process supervises it, so that the
    run folder is completed (from the files written so far) even if the bench is killed.
    """
    # from here (the run folder exists) a stop signal waits until the bench is supervised
    # (then forwarded to it), or completes the folder without a bench; after the run, one
    # still held here stops the command as the others do
    with held_stop_signals() as early:
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
        spin_s = (lockstep_spin_s(available_cpus(), os.environ) if opts.mode == "lockstep"
                  else 0.0)
        return _fork_and_supervise(sc, opts, progress, ready, alert, summary_ready, prestart,
                                   spin_s, early)


def _fork_and_supervise(
    sc: Scenario,
    opts: RunOptions,
    progress: Callable[[float, float], None] | None,
    ready: Callable[[Path], None] | None,
    alert: Callable[[int, str, dict[str, Any]], None] | None,
    summary_ready: Callable[[dict[str, Any]], None] | None,
    prestart: FswPrestart | None,
    spin_s: float,
    early: list[int],
) -> dict[str, Any]:
    """:func:`run_scenario` from the run folder's files on: fork the bench and supervise
    it; ``early``: the stop signals held so far (the list goes on filling until the bench
    is supervised, which forwards them)."""
    out = opts.out
    # the monitor's relay joins the bus before the bench starts: it sees the first frame
    watcher = RelayBus(spec=opts.bus) if opts.monitor else None
    try:
        out.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(sc.path, out / "scenario.toml")
        config = out / "fsw_config.json"
        write_record(config, sc.fsw_config())
    except OSError as exc:
        if watcher is not None:
            watcher.shutdown()
        raise ConfigError("command line", "--out", str(out),
                          f"a folder this user can create and write ({exc.strerror or exc})"
                          ) from exc
    reserve = DiskReserve(out)
    if early:  # stopped before the bench: the folder says so
        if watcher is not None:
            watcher.shutdown()
        name = signal.Signals(early[0]).name
        reserve.release()
        summary = partial_summary(sc, opts, "before the bench process started", stopped=name)
        raise Stopped(early[0], summary, out)
    if not hasattr(os, "fork"):  # pragma: no cover - no supervisor where fork is missing
        from bench.operator.bench_process import run_bench

        try:
            return run_bench(sc, opts, progress, ready, config, spin_s, reserve, alert,
                             prestart)
        finally:
            _plots(opts, sc)
    pid = os.fork()
    if pid == 0:  # the bench process
        code = EXIT_CHILD_OK
        try:
            die_with_parent()
            stop_on_signals()
            if early:  # one came between the fork and the line above (this copy's list)
                raise Stopped(early[0])
            (out / "bench.pid").write_text(f"{os.getpid()}\n", encoding="utf-8")
            # imported here, after the fork: the supervisor never loads the bench's models,
            # and the flight software starts before they load (bench.operator.bench_process)
            from bench.operator.bench_process import run_bench

            run_bench(sc, opts, progress, ready, config, spin_s, reserve, alert, prestart)
        except ConfigError as exc:
            code = EXIT_CHILD_BAD_INPUT
            if not (out / "summary.json").exists():  # refused before the run: say why
                reserve.release()
                partial_summary(sc, opts, f"bad input: {exc}", refused=str(exc))
        except RunError:
            code = EXIT_CHILD_RUN_ERROR
        except Stopped as exc:
            code = EXIT_CHILD_STOPPED_BASE + exc.signum
        except KeyboardInterrupt:
            code = EXIT_CHILD_STOPPED_BASE + signal.SIGINT
        except BaseException:
            code = EXIT_CHILD_CRASH
            if not (out / "summary.json").exists():
                traceback.print_exc()  # nothing else will say what happened
        finally:
            while True:  # a stop's handler may raise on the way into exit_now (it fires once)
                try:  # noqa: SIM105 - no context manager: its __enter__ could take that raise
                    exit_now(code, (sys.stdout, sys.stderr))
                except BaseException:
                    pass
    if prestart is not None:  # the bench holds it now: it ends with the bench
        prestart.release()
    # matplotlib loads while the flight software boots and the run goes (on the core the
    # bench leaves idle while it waits); the plots are drawn here once the bench is done
    prepare = preload_plots if opts.plots else None
    if watcher is not None:
        from bench.operator.monitor import watch_run

        def meanwhile() -> None:
            assert watcher is not None
            watch_run(watcher, pid, prepare)

        status, stop_signal = supervise(pid, meanwhile, early)
    else:
        status, stop_signal = supervise(pid, prepare, early)
    # the bench's own stop (a signal to it alone has its number in the exit code)
    code = os.WEXITSTATUS(status) if os.WIFEXITED(status) else -1
    bench_stop = (code - EXIT_CHILD_STOPPED_BASE
                  if EXIT_CHILD_STOPPED_BASE < code < EXIT_CHILD_STOPPED_BASE + signal.NSIG
                  else None)
    late = len(early)  # held from here on by run_scenario's block: read at the end
    # a stop signal from here on waits for the folder to be complete (the plots too)
    with held_stop_signals() as held:
        reserve.release()
        (out / "bench.pid").unlink(missing_ok=True)  # a pid file names a running process only
        if os.WIFSIGNALED(status):
            summary = partial_summary(sc, opts,
                                      f"bench process killed by signal {os.WTERMSIG(status)}")
            _plots(opts, sc)
            raise RunError(f"run failed ({summary['error']}); partial run folder: {out}")
        stopped = stop_signal or (held[0] if held else None) or bench_stop
        if stopped is not None and not (out / "summary.json").exists():
            summary = partial_summary(sc, opts, "before the bench wrote summary.json",
                                      stopped=signal.Signals(stopped).name)
            _plots(opts, sc)
            raise Stopped(stopped, summary, out)
        if not (out / "summary.json").exists():  # it failed before its run folder was set up
            summary = partial_summary(
                sc, opts, f"bench process exited with code {os.WEXITSTATUS(status)} before "
                "writing summary.json (see its traceback above)")
            _plots(opts, sc)
            raise RunError(f"run failed ({summary['error']}); partial run folder: {out}")
        summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
        if summary_ready is not None and stop_signal is None and not held and \
                os.WEXITSTATUS(status) == EXIT_CHILD_OK:
            summary_ready(summary)
        _plots(opts, sc)
    stop_signal = (stop_signal or (held[0] if held else None)
                   or (early[late] if len(early) > late else None) or bench_stop)
    if stop_signal is not None:  # after the bench completed the folder
        raise Stopped(stop_signal, summary, out)
    if os.WEXITSTATUS(status) == EXIT_CHILD_BAD_INPUT:
        if summary.get("refused"):
            raise RefusedConfigError("the bench", summary["refused"])
        raise RefusedConfigError("the flight software", summary["fsw"]["refused"])
    if os.WEXITSTATUS(status) != EXIT_CHILD_OK:
        tail = "".join(f"\n  fsw.log: {x}" for x in (summary.get("fsw") or {}).get("log_tail", []))
        raise RunError(f"run failed ({summary.get('error')}); run folder: {out}{tail}")
    return summary


def _plots(opts: RunOptions, sc: Scenario) -> None:
    """The run folder's PNG plots and report.html (without figures at ``--no-plots``)."""
    if opts.plots:
        plot_folder(opts.out, sc)
    else:
        from bench.operator.report_html import write_report

        write_report(opts.out)


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


