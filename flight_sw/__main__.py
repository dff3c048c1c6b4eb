"""Flight-software entry point: ``python -m flight_sw`` / ``thruster-hil-fsw``.

Opens the bus, builds the flight computer from ``--config`` and runs it in lockstep (one
cycle per SYNC) or realtime (own timer) until SIGTERM/SIGINT/SIGHUP. ``--check`` only validates
the configuration. ``--rx-log`` (realtime) logs when each frame arrived
(:mod:`flight_sw.rx_log`). Exit codes: 0 ok, 2 bad configuration, bus or log path (and
the reason, as a ``thruster-hil/fsw-refusal`` record of dbc.contract, in the ``--stats``
file).
"""

from __future__ import annotations

# First, before anything imports numpy: OpenBLAS reads its settings when it loads.
import flight_sw.blas_env  # noqa: F401

# isort: split
import contextlib
import gc
import os
import sys
from pathlib import Path

from dbc import options as opt
from dbc.codec import cycle_time_ns
from dbc.contract import EXIT_REFUSED, FswRefusal
from dbc.database import load_database
from dbc.errors import BusError, ConfigError
from dbc.options import StrictParser
from dbc.records import write_record
from flight_sw.config import build_computer, load_config
from flight_sw.node import FlightNode
from flight_sw.rx_log import ReceiveLog
from transport.lockstep import available_cpus, lockstep_spin_s
from transport.spec import check_bus_spec, default_bus_spec, mode_options, open_bus

MODES = ("lockstep", "realtime")


def _write_refusal(stats: str | None, refusal: FswRefusal) -> None:
    """The refusal record (dbc.contract) as the statistics file: the bench reports it."""
    if stats:
        with contextlib.suppress(OSError):  # the message is on stderr as well
            write_record(Path(stats), refusal.to_json())


def _check_writable(option: str, path: Path) -> None:
    """ConfigError unless ``path`` can be written: not a folder, in a writable folder."""
    folder = path.parent
    if path.is_dir() or not folder.is_dir() or not os.access(folder, os.W_OK | os.X_OK):
        raise ConfigError("command line", option, str(path),
                          "a file path in an existing folder this user can write")


def main(argv: list[str] | None = None) -> int:
    """Run the flight software."""
    p = StrictParser(prog="thruster-hil-fsw", description=__doc__.split("\n")[0],
                     error_prefix="flight_sw")
    p.add_argument("--config", required=True, type=opt.text("--config", "a file path"),
                   help="flight-software configuration JSON (thruster-hil/fsw-config)")
    p.add_argument(
        "--bus", type=opt.checked("--bus", check_bus_spec),
        help="bus spec (default: socketcan:vcan0 if present, else hilbus:default); an "
        "interface other processes share",
    )
    p.add_argument("--mode", type=opt.choice("--mode", MODES), default="lockstep",
                   metavar="{lockstep,realtime}",
                   help="lockstep: one cycle per SYNC from the bench; realtime: its own "
                   "timer (default lockstep)")
    p.add_argument("--stats", type=opt.text("--stats", "a file path"),
                   help="write frame and cycle statistics JSON here (its folder must exist)")
    p.add_argument(
        "--rx-log", type=opt.text("--rx-log", "a file path"),
        help="realtime: log every received frame's receive timestamp, ID and alive counter "
        "to this CSV file (the bench's timing analysis turns it into bench-frame latency)",
    )
    p.add_argument("--check", action="store_true", help="validate the configuration and exit")
    args = opt.parse_or_exit_code(p, argv)
    if isinstance(args, int):
        return args
    db = load_database()
    try:
        if args.stats:
            _check_writable("--stats", Path(args.stats))
        computer = build_computer(
            load_config(args.config),
            cycle_time_ns(db, "THR_CMD_0"),
            cycle_time_ns(db, "IMU_RATE"),
            {n: cycle_time_ns(db, n) for n in ("IMU_RATE", "STR_QUAT", "NAV_POS")},
        )
        for w in computer.warnings:
            print(f"flight_sw: warning: {w}", file=sys.stderr)
        if args.check:
            print(f"{args.config}: configuration ok")
            return 0
        spin_s = lockstep_spin_s(available_cpus(), os.environ) if args.mode == "lockstep" else 0.0
        spec = args.bus or default_bus_spec()
        bus = open_bus(spec, **mode_options(spec, args.mode))
    except ConfigError as exc:
        print(f"flight_sw: error: {exc}", file=sys.stderr)
        _write_refusal(args.stats, FswRefusal.of(exc))
        return EXIT_REFUSED
    except BusError as exc:
        print(f"flight_sw: error: {exc}", file=sys.stderr)
        _write_refusal(args.stats, FswRefusal("command line", "--bus", args.bus, str(exc)))
        return EXIT_REFUSED
    try:
        rx_log = ReceiveLog(Path(args.rx_log)) if args.rx_log and args.mode == "realtime" else None
    except OSError as exc:
        print(f"flight_sw: error: --rx-log {args.rx_log}: {exc}", file=sys.stderr)
        _write_refusal(args.stats, FswRefusal("command line", "--rx-log", args.rx_log,
                                              f"a writable file ({exc.strerror or exc})"))
        bus.shutdown()
        return EXIT_REFUSED
    node = FlightNode(db, bus, computer, Path(args.stats) if args.stats else None, rx_log)
    node.lockstep_spin_s = spin_s
    node.install_signal_handlers()
    # Everything built so far (the DBC, the strategies) lives for the whole run: keep it out
    # of the cyclic garbage collector's passes, which otherwise walk it inside cycles.
    gc.collect()
    gc.freeze()
    try:
        node.run(args.mode)
    finally:
        bus.shutdown()
        if rx_log is not None:
            rx_log.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
