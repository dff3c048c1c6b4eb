"""The wire's record of the bus: the CAN trace (Vector ASC and BLF), per-frame timing, events.

File names are those of a full record; a standard one (the default) adds ``.gz`` to the
trace and to ``frames.csv``; a lean one (a campaign's cases) writes ``trace.blf`` and
``events.jsonl`` only (bench.results.record).

* ``trace.asc`` — every frame the bench sent or received, in wire order, with its
  modelled (lockstep) or measured (realtime) time of reception; Tx = sent by the bench.
  Written through python-can's ``ASCWriter`` so python-can, Vector tools and SavvyCAN
  read it; flushed every ``FLUSH_PERIOD_NS`` of run time (bench.results.record), so a killed
  bench loses at most that much.
* ``trace.blf`` (every run, at either record level) — the same frames and events in
  Vector's binary logging format (python-can's ``BLFWriter``: zlib-compressed containers;
  CANoe and CANalyzer open it natively), with the same run-time timestamps (the
  measurement start is 0: no date; ``trace.asc`` has it) at 1 ns resolution. Written in
  containers as they fill and completed when the run ends, however it ends but SIGKILL;
  ``trace.asc`` is the trace that survives a kill. About 5.3 kB per simulated second for
  the quickstart (its ASC, gzip: 5.1 kB; plain: 28 kB); ~2 µs of the bench's time per
  frame, spent while the flight software computes (deferred writing).
* ``frames.csv`` — one row per frame of the trace, same order: when it was queued for
  transmission (``t_ready_s``), when it won arbitration (``t_start_s``), when it was received
  (``t_rx_s``), ID, DLC, bits on the wire, ``tx`` (1 = sent by the bench) and alive counter.
  Lockstep: modelled times; realtime: measured (``nan`` where the bench cannot know, e.g.
  when the flight software received a bench frame, or a sender's time on SocketCAN).
* ``events.jsonl`` — one JSON object per event (faults, watchdog, stalls), flushed per line;
  the events of :data:`TRACE_EVENTS` also go into the trace as ASC event lines.

``trace_sha256`` (summary.json, every record level): the SHA-256 of the trace's content in
trace order, each frame as ``<q I B B`` (time [ns], ID, flags: 1 sent by the bench, 2
extended ID, 4 remote, 8 error frame; DLC) and its data bytes, each trace event as its time
and text: what a rerun is compared on (bench.campaign), independent of the file formats,
their compression and the wall-clock date.

Deferred writing (``deferred=True``, the lockstep bench): frames and trace lines are kept as
values and formatted into the files by :meth:`TraceRecorder.write_pending` (also called by
``flush`` and ``close``), so that a bench can do the text formatting while the flight
software computes its cycle instead of between its frames. The files' content is the same
either way; ``events.jsonl`` is always written and flushed at once.

No clock is read here: every timestamp is passed in (the trace's start date too).
"""

from __future__ import annotations

import hashlib
import json
import struct
from collections.abc import Callable
from datetime import datetime
from pathlib import Path
from typing import IO, Any

import can

from bench.results.record import RECORD_FULL, file_name, open_writer, writes_tables
from bench.results.writers import TelemetryWriter

NS_PER_S = 1e9
BLF_NAME = "trace.blf"
US_PER_MS = 1000
NAN = float("nan")
# events also written into trace.asc (python-can's ASC reader skips such lines)
TRACE_EVENTS = frozenset({"fault_injected", "fault_cleared", "valve_watchdog",
                          "valve_watchdog_cleared", "fsw_silent", "fsw_back", "fsw_restart"})
COUNTER_MASK = 0x0F
FRAME_COLUMNS = ["t_ready_s", "t_start_s", "t_rx_s", "id", "dlc", "bits", "tx", "counter"]
PENDING_FRAME, PENDING_ERROR, PENDING_EVENT = 0, 1, 2  # kinds of a deferred trace line
DIGEST_FRAME = struct.Struct("<qIBB")  # time [ns], ID, flags, DLC (module docstring)
DIGEST_EVENT = struct.Struct("<q")  # time [ns], then the event's text
FLAG_TX, FLAG_EXTENDED, FLAG_REMOTE, FLAG_ERROR = 1, 2, 4, 8


class TraceRecorder:
    """CAN trace in Vector ASC format, plus an events log."""

    def __init__(self, run_dir: Path, start_wall_s: float, deferred: bool = False,
                 record: str = RECORD_FULL) -> None:
        """``start_wall_s``: wall-clock time of the run's start (``time.time()`` seconds);
        ``deferred``: keep frames and events until :meth:`write_pending` (module docstring);
        ``record``: a level of bench.results.record (plain or compressed files)."""
        self.path = run_dir / file_name("trace.asc", record)
        self.deferred = deferred
        # (kind, t_ns, message or None, tx, event text): in trace order until written
        self._pending: list[tuple[int, int, can.Message | None, bool, str]] = []
        self._writer: can.ASCWriter | None = None
        self._frames: TelemetryWriter | None = None
        self._blf = can.BLFWriter(run_dir / BLF_NAME, channel=1)
        self._blf.start_timestamp = 0.0  # run time, as in the ASC trace (docstring)
        if writes_tables(record):
            self._writer = w = can.ASCWriter(open_writer(self.path), channel=1)
            # The trigger block is dated when the run started (metadata, as the file's
            # "date" line); frame times stay run time, relative to it. Left to python-can,
            # it is dated from the first frame's timestamp: 1 Jan 1970 for a run that
            # starts at t = 0.
            start = datetime.fromtimestamp(start_wall_s)
            date = start.strftime(w.FORMAT_DATE.format(start.microsecond // US_PER_MS))
            w.file.write(f"Begin Triggerblock {date}\n")
            w.header_written = True
            w.started = w.last_timestamp = 0.0
            w.log_event("Start of measurement")
            self._frames = TelemetryWriter(run_dir / file_name("frames.csv", record),
                                           FRAME_COLUMNS, deferred)
        self._events: IO[str] = open(run_dir / "events.jsonl", "w", encoding="utf-8")  # noqa: SIM115
        self.frames_written = 0
        self._digest = hashlib.sha256()
        #: called with (t_ns, event, fields) for every event (bench.operator.alerts)
        self.listener: Callable[[int, str, dict[str, Any]], None] | None = None

    def frame(
        self, msg: can.Message, t_ns: int, tx: bool, *, t_ready_ns: float = NAN,
        t_start_ns: float = NAN, t_rx_ns: float | None = None, bits: int = 0,
    ) -> None:
        """Record ``msg`` in the trace at ``t_ns`` (``tx`` = sent by the bench) and its timing row.

        ``t_rx_ns`` defaults to ``t_ns``; pass ``NAN`` when the reception time is unknown.
        An error frame goes into the trace only: it is no message, frames.csv times messages.
        """
        if msg.is_error_frame:
            self.error_frame(t_ns)
            return
        flags = ((FLAG_TX if tx else 0) | (FLAG_EXTENDED if msg.is_extended_id else 0)
                 | (FLAG_REMOTE if msg.is_remote_frame else 0))
        self._digest.update(DIGEST_FRAME.pack(t_ns, msg.arbitration_id, flags, msg.dlc))
        self._digest.update(bytes(msg.data))
        if self._frames is not None:
            data = msg.data
            counter = data[1] & COUNTER_MASK if len(data) > 1 else -1
            self._frames.row([t_ready_ns / NS_PER_S, t_start_ns / NS_PER_S,
                              (t_ns if t_rx_ns is None else t_rx_ns) / NS_PER_S,
                              msg.arbitration_id, msg.dlc, bits, int(tx), counter])
        self.frames_written += 1
        if self.deferred:
            self._pending.append((PENDING_FRAME, t_ns, msg, tx, ""))
        else:
            self._write_frame(t_ns, msg, tx)

    def _write_frame(self, t_ns: int, msg: can.Message, tx: bool) -> None:
        record = can.Message(
            timestamp=t_ns / NS_PER_S,
            arbitration_id=msg.arbitration_id,
            is_extended_id=msg.is_extended_id,
            is_remote_frame=msg.is_remote_frame,
            is_error_frame=msg.is_error_frame,
            dlc=msg.dlc,
            data=msg.data,
            is_rx=not tx,
            channel=0,
        )
        if self._writer is not None:
            self._writer.on_message_received(record)
        self._blf.on_message_received(record)

    def error_frame(self, t_ns: int) -> None:
        """An error frame on the bus at ``t_ns`` (ASC ``ErrorFrame`` line)."""
        self.frames_written += 1
        self._digest.update(DIGEST_FRAME.pack(t_ns, 0, FLAG_ERROR, 0))
        if self.deferred:
            self._pending.append((PENDING_ERROR, t_ns, None, False, ""))
        else:
            self._write_error(t_ns)

    def _write_error(self, t_ns: int) -> None:
        record = can.Message(timestamp=t_ns / NS_PER_S, is_error_frame=True, channel=0)
        if self._writer is not None:
            self._writer.on_message_received(record)
        self._blf.on_message_received(record)

    def _write_event(self, t_ns: int, line: str) -> None:
        if self._writer is not None:
            self._writer.log_event(line, t_ns / NS_PER_S)
        self._blf.log_event(line, t_ns / NS_PER_S)

    def event(self, t_ns: int, what: str, /, **fields: Any) -> None:
        """Append one event line (``what`` at ``t_ns`` with ``fields``) and flush it; the
        :attr:`listener`, if set, hears it too (the console's live alerts)."""
        self._events.write(json.dumps({"event": what, **fields, "t_s": t_ns / NS_PER_S}) + "\n")
        self._events.flush()
        if self.listener is not None:
            self.listener(t_ns, what, fields)
        if what in TRACE_EVENTS:  # also in the CAN trace, as an ASC event line
            text = " ".join(f"{k}={v}" for k, v in fields.items() if k != "t_s")
            line = f"thruster-hil {what} {text}".rstrip()
            self._digest.update(DIGEST_EVENT.pack(t_ns) + line.encode("utf-8"))
            if self.deferred:
                self._pending.append((PENDING_EVENT, t_ns, None, False, line))
            else:
                self._write_event(t_ns, line)

    def digest(self) -> str:
        """``trace_sha256`` of what was recorded so far (module docstring)."""
        return self._digest.hexdigest()

    def write_pending(self) -> None:
        """Format what deferred writing kept into the files (in trace order); not flushed."""
        for kind, t_ns, msg, tx, line in self._pending:
            if msg is not None:
                self._write_frame(t_ns, msg, tx)
            elif kind == PENDING_ERROR:
                self._write_error(t_ns)
            else:
                self._write_event(t_ns, line)
        self._pending.clear()
        if self._frames is not None:
            self._frames.write_pending()

    def flush(self) -> None:
        """Flush the trace and the frame timing to disk."""
        self.write_pending()
        if self._writer is not None:
            self._writer.file.flush()
        if self._frames is not None:
            self._frames.flush()

    def close(self) -> None:
        """Finish every file."""
        self.write_pending()
        if self._writer is not None:
            self._writer.stop()
        self._blf.stop()
        if self._frames is not None:
            self._frames.close()
        self._events.close()


