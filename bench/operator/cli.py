"""``thruster-hil``: the bench operator's console.

Subcommands: ``run SCENARIO`` (bench + flight software as two processes, lockstep or
realtime), ``bench SCENARIO`` (the bench alone, for external flight software or hardware
on the same bus), ``report RUN_DIR`` (redraw plots, print the summary), ``export RUN_DIR``
(decoded signals: MF4, CSV or Parquet), ``replay RUN_DIR`` (a recorded run into a new flight
software, compared), ``timing RUN_DIR``
(per-message timing, chains, bus load, worst-case bounds; ``timing --live --bus SPEC``
measures a running bus). Exit codes: 0 pass, 1 the run's expectations failed (``timing
--strict``: a measured latency above its bound, or a message sent but never received), 2
bad input (scenario, options, a bus in use by another run), 3 run error (a process died,
the disk filled up), 128 + N stopped by signal N (130 SIGINT, 143 SIGTERM, 129 SIGHUP):
the run folder is complete in every case (bench.operator.lifecycle).
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import json
import sys
from pathlib import Path
from typing import Any

from bench.operator import export, monitor, replay
from bench.operator.console import print_summary, progress_printer
from bench.operator.fsw_prestart import FswPrestart
from bench.operator.junit import write_junit
from bench.operator.lifecycle import Stopped
from bench.results.record import RECORD_CHOICES, RECORD_STANDARD
from dbc import options as opt
from dbc.datafile import parse_json, read_text
from dbc.errors import BusError, ConfigError, IcdError, RunError
from dbc.options import StrictParser
from transport.spec import BusSpec, check_bus_spec, default_bus_spec, private_bus_spec

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT, EXIT_RUN_ERROR = 0, 1, 2, 3
EXIT_INTERRUPTED = 130  # 128 + SIGINT, as shells report it
MAX_SUMMARY_BYTES = 64 << 20  # a summary.json of a long run with many faults: a few MB


def _cmd_run(args: argparse.Namespace, alone: bool, prestart: FswPrestart | None) -> int:
    from bench.operator import alerts
    from bench.operator.fsw_process import DEFAULT_FSW_CMD
    from bench.operator.orchestrator import RunOptions, run_scenario
    from bench.operator.run_folder import default_run_folder, prepare_run_folder
    from bench.operator.run_warnings import scenario_warnings
    from bench.scenario.load import load_scenario

    junit = _junit_path(args.junit)  # before any folder is made
    sc = load_scenario(args.scenario, args.overrides)
    for w in scenario_warnings(sc):  # said before the run too, not only in its summary
        print(f"thruster-hil: warning: {w}", file=sys.stderr)
    bus = args.bus or private_bus_spec()
    spec = BusSpec.parse(bus)
    if args.bus is None or args.out is None:
        where = "" if args.bus is not None else (
            f" (a channel of its own; watch it: python -m can.logger -i {spec.interface} "
            f"-c {spec.channel})")
        print(f"thruster-hil: bus {bus}{where}", file=sys.stderr, flush=True)
    opts = RunOptions(  # checks the options before any folder is made
        mode=args.mode,
        bus=bus,
        seed=sc.seed if args.seed is None else args.seed,
        out=Path(args.out or "."),
        duration_s=args.duration if args.duration is not None else sc.duration_s,
        fsw_cmd=None if alone else (args.fsw_cmd or DEFAULT_FSW_CMD),
        bus_shared=args.bus is not None,
        record=args.record,
        plots=not args.no_plots,
        monitor=args.monitor,
    )
    opts = dataclasses.replace(opts, out=prepare_run_folder(Path(args.out), args.replace)
                               if args.out else default_run_folder(sc.name))

    def ready(config: Path) -> None:
        print(
            f"bench ready on {bus}, mode {opts.mode}: waiting up to "
            f"{sc.bus.startup_timeout_s} s for flight software (FSW_STATUS heartbeat), e.g. "
            f"`python -m flight_sw --bus {bus} --mode {opts.mode} --config {config}`; "
            f"its configuration: {config}",
            file=sys.stderr,
            flush=True,
        )

    printed: list[bool] = []

    def show(summary: dict[str, Any]) -> None:  # the verdict first, then the plots are drawn
        if sys.stderr.isatty():
            sys.stderr.write("\n")
        print_summary(summary, opts.out)
        sys.stdout.flush()
        printed.append(True)

    # no progress bar or alert lines under the monitor's screen: its event log shows them
    on_screen = not (opts.monitor and sys.stdout.isatty())
    try:
        summary = run_scenario(sc, opts, progress_printer() if on_screen else None, ready
                               if alone else None, alerts.printer() if on_screen else None,
                               show, prestart)
    except BaseException as exc:  # a failed or stopped run is a CI result too
        if junit is not None:
            write_junit(junit, opts.out, sc.name, f"{type(exc).__name__}: {exc}")
        raise
    if junit is not None:
        write_junit(junit, opts.out, sc.name)
    if not printed:
        show(summary)
    return EXIT_OK if summary["passed"] else EXIT_FAILED


def _junit_path(value: str | None) -> Path | None:
    """``--junit FILE``: a file path whose folder exists or can be made (as pytest's
    --junitxml does), checked before the run."""
    if value is None:
        return None
    path = Path(value)
    if path.is_dir():
        raise ConfigError("command line", "--junit", value, "a file path, not a folder")
    existed = path.exists()
    try:  # made and written once here, so a path that cannot take the file fails now
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path, "ab"):
            pass
    except OSError as exc:
        raise ConfigError("command line", "--junit", value,
                          f"a file this user can write ({exc.strerror or exc})") from exc
    if not existed:
        path.unlink()
    return path


def _cmd_report(args: argparse.Namespace) -> int:
    from bench.operator.plots import plot_run
    from bench.operator.report_html import event_marks, read_events, write_report

    run_dir = Path(args.run_dir)
    path = run_dir / "summary.json"
    if not path.exists():
        raise ConfigError(str(run_dir), "summary.json", None, "a run folder (no summary.json)")
    s = parse_json(read_text(path, "summary.json", MAX_SUMMARY_BYTES), str(path))
    if not isinstance(s, dict):
        raise ConfigError(str(path), "<root>", s, "a summary.json written by thruster-hil")
    junit = _junit_path(args.junit)
    try:
        marks = event_marks(read_events(run_dir))
        for p in plot_run(run_dir, s.get("settling_band_deg"), marks):
            print(f"wrote {p}")
        if junit is not None:
            write_junit(junit, run_dir)
            print(f"wrote {junit}")
        print_summary(s, run_dir)  # a summary.json it cannot print stops here (exit 2)
        print(f"wrote {write_report(run_dir)}")
    except KeyError as exc:
        raise ConfigError(str(path), str(exc.args[0]), None, "a summary.json written by "
                          "thruster-hil (this key is missing)") from exc
    except (TypeError, ValueError, AttributeError) as exc:
        raise ConfigError(str(path), "<content>", str(exc), "a summary.json written by "
                          "thruster-hil") from exc
    return EXIT_OK if s.get("passed") else EXIT_FAILED


def _cmd_timing(args: argparse.Namespace) -> int:
    from bench.operator.analysis.defaults import (
        DEFAULT_FIRST_FRAME_TIMEOUT_S,
        DEFAULT_LIVE_DURATION_S,
    )
    from bench.operator.analysis.live import LiveOptions, live_timing
    from bench.operator.analysis.records import TimingOptions
    from bench.operator.analysis.report import format_report, write_histograms, write_json
    from bench.operator.analysis.timing import RunTiming

    if args.live == (args.run_dir is not None):
        raise ConfigError("timing", "RUN_DIR/--live", args.run_dir, "a run folder or --live")
    for dest in LIVE_ONLY if not args.live else ():
        if getattr(args, dest) is not None:
            opt.refuse("--" + dest.replace("_", "-"), getattr(args, dest),
                       "absent without --live (a run folder has its own bus and duration)")
    options = TimingOptions(
        window_ms=args.window_ms,
        cycle_abs_tolerance_ms=None if args.abs_tol_ms < 0 else args.abs_tol_ms,
        cycle_rel_tolerance_pct=None if args.rel_tol_pct < 0 else args.rel_tol_pct,
    )
    if args.live:
        bus = args.bus or default_bus_spec()
        BusSpec.parse(bus)
        live = LiveOptions(
            DEFAULT_LIVE_DURATION_S if args.duration is None else args.duration,
            DEFAULT_FIRST_FRAME_TIMEOUT_S if args.first_frame_timeout is None
            else args.first_frame_timeout,
            args.bitrate)

        def listening() -> None:
            print(
                f"listening on {bus}: {live.duration_s:g} s from the first frame "
                f"(waiting up to {live.first_frame_timeout_s:g} s for it)",
                file=sys.stderr,
                flush=True,
            )

        rt, cap = live_timing(bus, live, options, listening=listening)
        extra = {"bus": bus, "error_frames": cap.error_frames, "fd_frames": cap.fd_frames}
        if args.json:
            print(json.dumps({**rt.to_dict(), **extra}, indent=2))
        else:
            print(format_report(rt))
            print(
                f"bus {bus}: {len(cap.frames)} frames, {cap.error_frames} error frames, "
                f"{cap.fd_frames} CAN FD frames (not timed)"
            )
    else:
        run_dir = Path(args.run_dir)
        if not (run_dir / "summary.json").exists():  # bad input, as for `report`
            raise ConfigError(str(run_dir), "summary.json", None, "a run folder (no summary.json)")
        rt = RunTiming.load(run_dir, options)
        written = [write_json(rt, run_dir), *write_histograms(rt, run_dir)]
        if args.json:
            print(json.dumps(rt.to_dict(), indent=2))
        else:
            print(format_report(rt))
            for p in written:
                print(f"wrote {p}")
    return EXIT_FAILED if args.strict and (rt.flagged() or rt.unheard()) else EXIT_OK


MODES = ("lockstep", "realtime")
SCENARIO_HELP = "scenario TOML file"
# --live: a CAN classic bitrate (ISO 11898-1: at most 1 Mbit/s; 5 kbit/s is the lowest that
# CAN controllers commonly configure)
LIVE_BITRATE_BPS = (5_000, 1_000_000)
# timing: bus-load window (10 us, ten bit times at 1 Mbit/s, to an hour) and tolerances
WINDOW_MS = (0.01, 3_600_000.0)
MAX_TOLERANCE_MS = 1e6
MAX_TOLERANCE_PCT = 100.0
LIVE_ONLY = ("bus", "duration", "first_frame_timeout", "bitrate")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``thruster-hil`` (every option checked: :mod:`dbc.options`)."""
    from bench.scenario.limits import MAX_DURATION_S, SEED_MAX

    p = StrictParser(prog="thruster-hil", description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, help_ in (
        ("run", "run a scenario: bench + flight software"),
        ("bench", "run the bench alone; pair it with external flight software"),
    ):
        r = sub.add_parser(name, help=help_)
        r.add_argument("scenario", type=opt.text("SCENARIO", "a scenario file"),
                       help=SCENARIO_HELP)
        r.add_argument("--mode", type=opt.choice("--mode", MODES), default="lockstep",
                       metavar="{lockstep,realtime}",
                       help="lockstep: the bench is the time master, one SYNC per control "
                       "cycle, deterministic; realtime: paced by the wall clock, measured "
                       "latency (default lockstep)")
        r.add_argument("--bus", type=_bus_option("--bus"),
                       help="bus spec INTERFACE:CHANNEL, e.g. socketcan:vcan0 or hilbus:lab "
                       "(default: a portable-bus channel of this run's own, printed at the "
                       "start; on a named bus another run is detected and refused)")
        r.add_argument("--seed", type=opt.integer("--seed", 0, SEED_MAX),
                       help=f"random seed, 0..{SEED_MAX} (default: the scenario's)")
        r.add_argument("--out", type=opt.text("--out", "a folder path"),
                       help="run folder, new or empty (default: runs/<scenario>-<time>-<hex>, "
                       "a new folder)")
        r.add_argument("--record", type=opt.choice("--record", RECORD_CHOICES),
                       default=RECORD_STANDARD, metavar="{standard,full,lean}",
                       help="standard: the CAN trace and the CSV tables gzip-compressed "
                       "(trace.asc.gz, telemetry.csv.gz, ...: about a fifth of the size); "
                       "full: the same files as plain text; lean (a campaign's cases): "
                       "telemetry at 10 Hz and the trace as trace.blf only, no tables "
                       "(default standard); every level writes trace.blf")
        r.add_argument("--no-plots", action="store_true",
                       help="leave out the PNG plots (~0.3 s sooner: no matplotlib, no "
                       "drawing); `thruster-hil report RUN_DIR` draws them later")
        r.add_argument("--monitor", action="store_true",
                       help="show the live monitor (`thruster-hil monitor`) on the run's own "
                       "bus while it runs; q closes it, the run goes on. Without a terminal "
                       "its last picture is printed")
        r.add_argument("--replace", action="store_true",
                       help="let --out name a folder holding an earlier run, which is deleted")
        r.add_argument("--junit", type=opt.text("--junit", "a file path"), metavar="FILE",
                       help="also write the run's checks as JUnit XML (one test case per "
                       "expectation, with its requirement ID) for a CI server; written "
                       "whatever way the run ends")
        r.add_argument("--duration", type=opt.number("--duration", control_period_s,
                                                     MAX_DURATION_S, unit="s"),
                       help="override the scenario duration [s] (one control period to "
                       f"{MAX_DURATION_S:g})")
        r.add_argument("--set", dest="overrides", action="append", default=[],
                       metavar="KEY=VALUE",
                       help="override a scenario value, e.g. --set bus.bitrate_bps=125000 "
                       "(repeatable; TOML values)")
        if name == "run":
            r.add_argument(
                "--fsw-cmd", type=opt.text("--fsw-cmd", "a command line"),
                help="flight-software command; placeholders {bus} {mode} "
                "{config} {stats} {rx_log} {run_dir}",
            )
    rp = sub.add_parser("report", help="redraw the plots and report.html of a run folder and "
                        "print its summary")
    rp.add_argument("run_dir", metavar="RUN_DIR", type=opt.text("RUN_DIR", "a run folder"),
                    help="a run folder (with summary.json), as `run --out` names it")
    rp.add_argument("--junit", type=opt.text("--junit", "a file path"), metavar="FILE",
                    help="also write the run's checks as JUnit XML (as `run --junit`)")
    _add_timing_parser(sub)
    export.add_parser(sub)
    replay.add_parser(sub)
    monitor.add_parser(sub)
    inj = sub.add_parser("inject", help="inject or clear a fault live on a running bench "
                         "(a FAULT_CMD frame, acknowledged by the bench)")
    inj.add_argument("kind", type=opt.text("KIND", "a fault kind"),
                     help="fault kind, e.g. stuck_open, degraded, drop, bus_off, outage")
    inj.add_argument("--bus", type=_bus_option("--bus"),
                     help="bus spec of the running bench (default as for run)")
    inj.add_argument("--target", type=opt.integer("--target"), required=True,
                     help="thruster index, sensor index (0 gyro, 1 accelerometer, 2 star "
                     "tracker), message CAN ID (e.g. 0x40) or node index (0 BENCH, 1 FSW)")
    inj.add_argument("--duration", type=opt.number("--duration"), default=0.0,
                     help="seconds of the bench's time (simulated in lockstep, wall clock in "
                     "realtime); 0 = until cleared")
    inj.add_argument("--param", type=opt.number("--param"), default=0.0,
                     help="the kind's parameter (factor, probability, delay s, ...)")
    inj.add_argument("--clear", action="store_true", help="clear the fault instead")
    inj.add_argument("--print-frame", type=opt.integer("--print-frame"), metavar="COUNTER",
                     help="only print the frame for cansend, with this alive counter")
    campaign_help = ("a campaign file's Monte Carlo / sweep on Dask, or every single-thruster "
                     "failure of a scenario; `campaign rerun DIR CASE` reruns one case, "
                     "`campaign minimize DIR CASE` finds a failure's minimal dispersions, "
                     "`campaign margin SCENARIO --key K --toward V` finds a requirement's "
                     "margin (each has its own --help; docs/campaigns.md)")
    cp = sub.add_parser("campaign", help=campaign_help, description=campaign_help)
    from bench.operator.campaign import add_arguments

    add_arguments(cp, default_jobs=1)
    return p


def control_period_s() -> float:
    """The control period [s]: the DBC cycle time of the command frame (THR_CMD_0)."""
    from bench.scenario.limits import NS_PER_S, PERIOD_MESSAGE
    from dbc.codec import cycle_time_ns
    from dbc.database import load_database

    return cycle_time_ns(load_database(), PERIOD_MESSAGE) / NS_PER_S


def _bus_option(option: str) -> Any:
    """An argparse converter: a bus spec other processes can share (transport.spec)."""
    return opt.checked(option, check_bus_spec)


def _cmd_inject(args: argparse.Namespace) -> int:
    from bench.operator.inject import FaultCommand, cansend_string, inject

    cmd = FaultCommand(args.kind, args.target, args.duration, args.param, args.clear)
    if args.print_frame is not None and args.bus is not None:
        opt.refuse("--bus", args.bus, "absent with --print-frame (the frame is printed, "
                   "not sent)")
    if args.print_frame is not None:
        print(cansend_string(cmd, args.print_frame))
        return EXIT_OK
    bus = args.bus or default_bus_spec()
    counter = inject(bus, cmd)
    print(f"{'cleared' if args.clear else 'injected'} {args.kind} target {args.target} on {bus} "
          f"(acknowledged, counter {counter})")
    return EXIT_OK


def _add_timing_parser(sub: Any) -> None:
    from bench.operator.analysis.defaults import (
        DEFAULT_CYCLE_ABS_TOLERANCE_MS,
        DEFAULT_CYCLE_REL_TOLERANCE_PCT,
        DEFAULT_FIRST_FRAME_TIMEOUT_S,
        DEFAULT_LIVE_DURATION_S,
        DEFAULT_WINDOW_MS,
    )
    from bench.scenario.limits import MAX_DURATION_S

    t = sub.add_parser(
        "timing",
        help="timing of a run folder (table, timing.json, histograms) or of a live bus",
        description="Per message: count, period mean and jitter, latency p50/p99/max, "
        "worst-case bound, missed cycles, cycle-time violations; the IMU->command->valve "
        "chain; bus load per window and per node.",
    )
    t.add_argument("run_dir", nargs="?", metavar="RUN_DIR",
                   type=opt.text("RUN_DIR", "a run folder"),
                   help="run folder (omit with --live)")
    t.add_argument(
        "--window-ms",
        type=opt.number("--window-ms", *WINDOW_MS, unit="ms"),
        default=DEFAULT_WINDOW_MS,
        help=f"bus-load window [ms], {WINDOW_MS[0]:g}..{WINDOW_MS[1]:g} "
        f"(default {DEFAULT_WINDOW_MS:g})",
    )
    t.add_argument(
        "--abs-tol-ms",
        type=opt.number("--abs-tol-ms", hi=MAX_TOLERANCE_MS, unit="ms"),
        default=DEFAULT_CYCLE_ABS_TOLERANCE_MS,
        help="absolute cycle-time window, ± ms around GenMsgCycleTime; negative: "
        f"off (default {DEFAULT_CYCLE_ABS_TOLERANCE_MS:g})",
    )
    t.add_argument(
        "--rel-tol-pct",
        type=opt.number("--rel-tol-pct", hi=MAX_TOLERANCE_PCT, hi_open=True, unit="%"),
        default=DEFAULT_CYCLE_REL_TOLERANCE_PCT,
        help="relative cycle-time window, ± %% of GenMsgCycleTime, below 100; negative: off "
        f"(default {DEFAULT_CYCLE_REL_TOLERANCE_PCT:g})",
    )
    t.add_argument("--json", action="store_true", help="print JSON instead of the table")
    t.add_argument(
        "--strict",
        action="store_true",
        help="exit 1 if a measured latency is above its worst-case bound, or a message "
        "its sender sent never reached the trace",
    )
    t.add_argument("--live", action="store_true", help="listen to a running bus instead")
    t.add_argument("--bus", type=_bus_option("--bus"),
                   help="--live: bus spec INTERFACE:CHANNEL (default as for run)")
    t.add_argument(
        "--duration",
        type=opt.number("--duration", 0.0, MAX_DURATION_S, lo_open=True, unit="s"),
        help="--live: seconds to listen from the first frame "
        f"(default {DEFAULT_LIVE_DURATION_S:g})",
    )
    t.add_argument(
        "--first-frame-timeout",
        type=opt.number("--first-frame-timeout", 0.0, MAX_DURATION_S, lo_open=True,
                        unit="s"),
        help="--live: seconds to wait for the first frame "
        f"(default {DEFAULT_FIRST_FRAME_TIMEOUT_S:g})",
    )
    t.add_argument(
        "--bitrate",
        type=opt.integer("--bitrate", *LIVE_BITRATE_BPS),
        help="--live: bitrate for the load estimate [bit/s], "
        f"{LIVE_BITRATE_BPS[0]}..{LIVE_BITRATE_BPS[1]} (default: the DBC's)",
    )


def main(argv: list[str] | None = None, prestart: FswPrestart | None = None) -> int:
    """The console (bench.operator.entry starts it); ``prestart``: where a ``run`` starts
    its flight software, if it can (bench.operator.fsw_prestart)."""
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["campaign"] and argv[1:2] in (["rerun"], ["margin"], ["minimize"]):
        from bench.campaign.tools import main as campaign_tool

        return campaign_tool(argv[1:])
    args = opt.parse_or_exit_code(build_parser(), argv)
    if isinstance(args, int):
        return args
    try:
        return _dispatch(args, prestart)
    finally:
        # What was loaded (matplotlib's heap, the bench's tables) is never collected again:
        # the interpreter's last collection would walk all of it on exit (~0.1 s)
        gc.freeze()


def _dispatch(args: argparse.Namespace, prestart: FswPrestart | None = None) -> int:
    """Run the chosen subcommand; errors become exit codes (module docstring)."""
    try:
        if args.command == "report":
            return _cmd_report(args)
        if args.command == "timing":
            return _cmd_timing(args)
        if args.command == "inject":
            return _cmd_inject(args)
        if args.command == "export":
            return export.run(args)
        if args.command == "replay":
            return replay.run(args)
        if args.command == "monitor":
            return monitor.run(args)
        if args.command == "campaign":
            from bench.operator.campaign import from_namespace

            return from_namespace(args)
        return _cmd_run(args, args.command == "bench", prestart)
    except (ConfigError, BusError, IcdError) as exc:
        print(f"thruster-hil: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RunError as exc:
        print(f"thruster-hil: run error: {exc}", file=sys.stderr)
        return EXIT_RUN_ERROR
    except Stopped as exc:
        if exc.summary is not None and exc.out is not None:
            print_summary(exc.summary, exc.out)
        print(f"\nthruster-hil: stopped by {exc.name} (the run folder was completed with "
              "what ran)", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("\nthruster-hil: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
