"""Stepped replay of a recorded lockstep run into a new flight-software process, compared.

In: a run folder (its CAN trace, ``trace.asc`` or ``.asc.gz``, and ``fsw_config.json``,
or another configuration: a changed gain), a bus spec (default: a portable-bus channel of
its own) and the flight-software command (``--fsw-cmd``, ours by default, with the same
placeholders as ``run``). Out: a :class:`ReplayResult`: cycles replayed, frames compared,
and the first divergent frame (cycle, message, recorded and received bytes, the signals
that differ), printed by ``thruster-hil replay`` (exit 0: every command frame as
recorded; 1: a divergence).

How: the bench's side of the trace (the frames it sent: sensors, SYNC, valve status,
bench status) is sent again in the lockstep schedule the bench kept, cycle by cycle:
``SYNC(k)``; then the flight software's frames the trace holds for cycle k (until
``SYNC(k+1)``) are awaited and compared, byte for byte, in the order the trace has them per
message; then the bench's frames recorded in that cycle (the samples of the next one)
go out, and ``SYNC(k+1)``. Frames before the first SYNC (the boot heartbeat) are not
compared; the new process's first frame is awaited instead. Each wait is bounded by
:data:`ANSWER_TIMEOUT_S` of wall time; a missing answer is a divergence, never a hang.

Timed (not stepped) replay of any trace onto any bus is python-can's
``python -m can.player``; this module adds what it cannot: the lockstep hand-shake and the
comparison.
"""

from __future__ import annotations

import subprocess
import tempfile
from collections import defaultdict, deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can
from cantools.database.can import Database

from bench.operator.fsw_process import DEFAULT_FSW_CMD, fsw_argv, stop
from bench.operator.warm_start import die_with_parent
from bench.results.record import trace_file
from dbc.errors import ConfigError
from dbc.icd import FSW, Icd
from transport.spec import mode_options, open_bus

ANSWER_TIMEOUT_S = 5.0  # wall time to wait for one awaited frame of the flight software
SYNC = "SYNC"


@dataclass
class Divergence:
    """The first frame that differs from the recording (or did not come)."""

    cycle: int
    t_s: float  # the cycle's SYNC in the recording [s, run time]
    message: str
    recorded: str  # hex bytes
    received: str | None  # hex bytes; None: nothing came within ANSWER_TIMEOUT_S
    signals: dict[str, tuple[Any, Any]] = field(default_factory=dict)  # name: (rec, got)


@dataclass
class ReplayResult:
    """What a replay found."""

    cycles: int = 0
    frames_sent: int = 0
    frames_compared: int = 0
    divergence: Divergence | None = None


@dataclass
class _Cycle:
    """One cycle of the recording: SYNC, the flight software's answers, the bench's frames
    that followed (the next cycle's samples), in trace order."""

    sync: can.Message
    answers: list[can.Message] = field(default_factory=list)
    after: list[can.Message] = field(default_factory=list)


def split_cycles(run_dir: Path, db: Database) -> tuple[list[can.Message], list[_Cycle]]:
    """The bench's frames before the first SYNC, and the recording cycle by cycle."""
    path = trace_file(run_dir)
    if not path.exists():
        raise ConfigError(str(run_dir), "trace.asc", None, "a run folder with its CAN trace "
                          "(a campaign keeps it for failing and worst cases only: `thruster-hil "
                          "campaign rerun DIR CASE` makes the run again, trace included)")
    icd = Icd.from_database(db)
    names = {m.frame_id: m.name for m in db.messages}
    before: list[can.Message] = []
    cycles: list[_Cycle] = []
    for msg in can.LogReader(str(path)):
        name = names.get(msg.arbitration_id)
        if msg.is_error_frame or msg.is_remote_frame or name is None:
            continue
        from_fsw = icd.sender.get(name) == FSW
        if name == SYNC:
            cycles.append(_Cycle(msg))
        elif not cycles:
            if not from_fsw:
                before.append(msg)
        elif from_fsw:
            cycles[-1].answers.append(msg)
        else:
            cycles[-1].after.append(msg)
    if not cycles:
        raise ConfigError(str(path), "SYNC", None, "a lockstep run's trace (no SYNC frame)")
    return before, cycles


def _frame(msg: can.Message) -> can.Message:
    """The recorded frame as a new one to send (no timestamp or direction of the trace)."""
    return can.Message(arbitration_id=msg.arbitration_id, data=bytes(msg.data),
                       is_extended_id=msg.is_extended_id, dlc=msg.dlc)


def _divergence(db: Database, cycle: int, t_s: float, rec: can.Message,
                got: can.Message | None) -> Divergence:
    spec = db.get_message_by_frame_id(rec.arbitration_id)
    out = Divergence(cycle, t_s, spec.name, bytes(rec.data).hex(" "),
                     None if got is None else bytes(got.data).hex(" "))
    if got is not None:
        try:
            a = spec.decode(bytes(rec.data), decode_choices=False)
            b = spec.decode(bytes(got.data), decode_choices=False)
            if isinstance(a, dict) and isinstance(b, dict):
                out.signals = {k: (a[k], b.get(k)) for k in a if a[k] != b.get(k)}
        except Exception:  # a received frame that does not decode: the bytes say it
            pass
    return out


class _Inbox:
    """The flight software's frames as they arrive, kept per ID until awaited."""

    def __init__(self, bus: can.BusABC, db: Database) -> None:
        self.bus = bus
        icd = Icd.from_database(db)
        self.fsw_ids = {m.frame_id for m in db.messages if icd.sender.get(m.name) == FSW}
        self.queues: dict[int, deque[can.Message]] = defaultdict(deque)

    def next_any(self, timeout_s: float) -> can.Message | None:
        """The next frame of the flight software (any ID), None after ``timeout_s``."""
        msg = self.bus.recv(timeout_s)
        while msg is not None and msg.arbitration_id not in self.fsw_ids:
            msg = self.bus.recv(timeout_s)
        return msg

    def next_of(self, frame_id: int, timeout_s: float) -> can.Message | None:
        """The flight software's next frame with ``frame_id`` (others are kept)."""
        while not self.queues[frame_id]:
            msg = self.next_any(timeout_s)
            if msg is None:
                return None
            self.queues[msg.arbitration_id].append(msg)
        return self.queues[frame_id].popleft()


def replay(run_dir: Path, db: Database, bus_spec: str, config: Path,
           fsw_cmd: str | None = DEFAULT_FSW_CMD, work: Path | None = None) -> ReplayResult:
    """Replay ``run_dir`` into a new flight software (module docstring); ``fsw_cmd`` None:
    one already listening on ``bus_spec``; ``work``: where its log and statistics go."""
    before, cycles = split_cycles(run_dir, db)
    result = ReplayResult()
    work = work or Path(tempfile.mkdtemp(prefix="thil-replay-"))
    bus = open_bus(bus_spec, **mode_options(bus_spec, "lockstep"))
    proc: subprocess.Popen[bytes] | None = None
    try:
        if fsw_cmd is not None:
            with open(work / "fsw.log", "wb") as log:
                proc = subprocess.Popen(
                    fsw_argv(fsw_cmd, bus_spec, "lockstep", work, config,
                             work / "fsw_stats.json"),
                    stdout=log, stderr=subprocess.STDOUT, preexec_fn=die_with_parent)
        inbox = _Inbox(bus, db)
        first = inbox.next_any(ANSWER_TIMEOUT_S)  # its boot heartbeat: it is listening
        if first is None:
            raise ConfigError("command line", "--bus", bus_spec, "a flight software that "
                              f"answers within {ANSWER_TIMEOUT_S:g} s (see {work / 'fsw.log'})")
        for msg in before:
            bus.send(_frame(msg))
            result.frames_sent += 1
        for k, cyc in enumerate(cycles):
            bus.send(_frame(cyc.sync))
            result.frames_sent += 1
            for rec in cyc.answers:
                got = inbox.next_of(rec.arbitration_id, ANSWER_TIMEOUT_S)
                result.frames_compared += 1
                if got is None or bytes(got.data) != bytes(rec.data):
                    result.divergence = _divergence(db, k, cyc.sync.timestamp, rec, got)
                    result.cycles = k + 1
                    return result
            for msg in cyc.after:
                bus.send(_frame(msg))
                result.frames_sent += 1
            result.cycles = k + 1
        return result
    finally:
        if proc is not None:
            stop(proc)
        bus.shutdown()


def add_parser(sub: Any) -> None:
    """The ``replay`` subcommand of ``thruster-hil`` (its options, each checked)."""
    from bench.operator.fsw_process import PLACEHOLDERS
    from dbc import options as opt

    rp = sub.add_parser("replay", help="replay a recorded lockstep run's bench frames into a "
                        "new flight software, cycle by cycle, and compare its commands with "
                        "the recorded ones (exit 1 at the first divergence)")
    rp.add_argument("run_dir", metavar="RUN_DIR", type=opt.text("RUN_DIR", "a run folder"),
                    help="a lockstep run folder (its trace and fsw_config.json)")
    rp.add_argument("--config", type=opt.text("--config", "a file path"),
                    help="the flight software's configuration (default: the run's "
                    "fsw_config.json; e.g. a copy with a changed gain)")
    rp.add_argument("--fsw-cmd", type=opt.text("--fsw-cmd", "a command line"),
                    help="flight-software command, placeholders "
                    + " ".join(f"{{{p}}}" for p in PLACEHOLDERS) + " (default: ours)")
    rp.add_argument("--external", action="store_true",
                    help="start no flight software: one is already on --bus (a board)")
    rp.add_argument("--bus", type=opt.text("--bus", "a bus spec"),
                    help="bus spec (default: a portable-bus channel of its own; required "
                    "with --external)")


def run(args: Any) -> int:
    """``thruster-hil replay``: replay, then say where it diverged (exit 1) or that every
    compared frame was as recorded (exit 0)."""
    from dbc.database import load_database
    from transport.spec import check_bus_spec, private_bus_spec

    run_dir = Path(args.run_dir)
    if not run_dir.is_dir():
        raise ConfigError("command line", "RUN_DIR", str(run_dir), "an existing run folder")
    if args.external and args.bus is None:
        raise ConfigError("command line", "--bus", None, "the bus of the flight software "
                          "already running (--external)")
    config = Path(args.config) if args.config else run_dir / "fsw_config.json"
    if not config.is_file():
        raise ConfigError("command line", "--config", str(config), "a configuration file")
    bus = args.bus or private_bus_spec()
    check_bus_spec(bus)
    fsw_cmd = None if args.external else (args.fsw_cmd or DEFAULT_FSW_CMD)
    with tempfile.TemporaryDirectory(prefix="thil-replay-") as work:
        r = replay(run_dir, load_database(), bus, config, fsw_cmd, Path(work))
    print(f"replayed {r.cycles} cycles of {run_dir} on {bus}: {r.frames_sent} bench frames "
          f"sent, {r.frames_compared} flight-software frames compared")
    d = r.divergence
    if d is None:
        print("every compared frame as recorded")
        return 0
    got = "nothing" if d.received is None else d.received
    print(f"first divergence: cycle {d.cycle} (SYNC at {d.t_s:.3f} s), {d.message}: "
          f"recorded {d.recorded}, received {got}")
    for name, (a, b) in d.signals.items():
        print(f"  {name}: recorded {a}, received {b}")
    return 1
