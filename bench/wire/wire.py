"""The wire: what happens to the bench's frames between encoding and the bus, and the trace.

In: frames the bench sends (message name, physical signals, the time they are queued
[ns]), frames received from other nodes that belong on the modelled wire, the active bus
faults (read from the station's fault book through ``active_faults``). Out: frames on the
python-can bus (held and handed over together in lockstep, one burst per instant, or sent
at once in realtime), and the trace (``trace.asc``, ``frames.csv``) in wire order.

Lockstep (``modelled=True``): every frame is submitted to the bus arbitration model
(bench.wire.timing: arbitration by ID, bit-exact stuffed length at the scenario's
bitrate, error frames and retransmission, bus-off windows); :meth:`Wire.flush` resolves it
up to a time and writes the trace with the modelled times, returning each frame's
reception time (end of EOF). Bus faults on the bench's own frames: ``drop`` (encoded, so
the alive counter advances, never sent), ``delay`` (held until its release time, see
:meth:`Wire.next_release_ns`), ``corrupt`` (one payload bit flipped after E2E protection),
``duplicate`` (sent twice), ``link_error`` (failed attempts before success), and the
frames of babbling nodes (:meth:`Wire.babble`). Realtime (``modelled=False``): frames are
sent at once and traced at the measured time; only drop, corrupt and duplicate apply.

Counts: frames sent per message (``sent``) and the bus faults' effects (``fault_counts``).
The random generator for fault fates is the wire's own, seeded from the run seed.
"""

from __future__ import annotations

from collections.abc import Callable

import can
import numpy as np

from bench.station.faults import FaultSpec
from bench.wire.fate import NO_FATE, Fate, flip, frame_fate
from bench.wire.timing.arbiter import BusArbiter, Delivery
from bench.wire.timing.classic import INTERMISSION_BITS, frame_bits, wire_time_ns
from bench.wire.trace import NAN, TraceRecorder
from dbc.codec import Encoder
from dbc.faults import BABBLING
from dbc.icd import BENCH, Icd
from transport.lockstep import send_frames

NS_PER_S = 1_000_000_000
BABBLE_DLC = 8
FAULT_EFFECTS = ("dropped", "delayed", "corrupted", "duplicated", "babbled", "failed_attempts")


class Wire:
    """The bench's side of the bus (see the module docstring)."""

    def __init__(self, bus: can.BusABC, icd: Icd, encoder: Encoder, trace: TraceRecorder,
                 bitrate_bps: int, rng: np.random.Generator, *, modelled: bool,
                 active_faults: Callable[[], list[FaultSpec]]) -> None:
        self.bus = bus
        self.icd = icd
        self.encoder = encoder
        self.trace = trace
        self.modelled = modelled
        self.rng = rng
        self.active_faults = active_faults
        self.arbiter = BusArbiter(bitrate_bps)
        self._intermission_ns = wire_time_ns(INTERMISSION_BITS, bitrate_bps)
        self._pending: dict[int, tuple[can.Message, bool, int]] = {}  # seq -> (msg, tx, bits)
        self._delayed: list[tuple[int, can.Message, str]] = []  # (release time, msg, name)
        self._held: list[can.Message] = []  # lockstep: released together (one burst)
        self.sent: dict[str, int] = {}
        self.fault_counts = dict.fromkeys(FAULT_EFFECTS, 0)
        self.last_rx_ns = 0  # latest reception on the modelled wire

    # -- the bench's frames ---------------------------------------------------------
    def send(self, name: str, signals: dict[str, float | int], ready_ns: int,
             now_ns: int | None = None) -> can.Message:
        """Encode ``name`` and put it on the bus as the bus faults say; returns the frame.

        ``ready_ns``: modelled time it is queued (lockstep); ``now_ns``: realtime, the
        clock's reading (traced at once). A dropped or delayed frame is still encoded.
        """
        msg = self.encoder.message(name, signals)
        specs = self.active_faults()
        fate = frame_fate(specs, name, BENCH, self.rng) if specs else NO_FATE
        if fate is not NO_FATE:
            counts = self.fault_counts
            if fate.drop:
                counts["dropped"] += 1
                return msg
            if fate.delay_ns and now_ns is None:
                counts["delayed"] += 1
                self._delayed.append((ready_ns + fate.delay_ns, msg, name))
                return msg
            if fate.corrupt_bit is not None:
                counts["corrupted"] += 1
                flip(msg, fate.corrupt_bit)
            if fate.duplicate:
                counts["duplicated"] += 1
            counts["failed_attempts"] += fate.failed_attempts
        for _ in range(2 if fate.duplicate else 1):
            self._put(msg, name, ready_ns, now_ns, fate.failed_attempts)
        return msg

    def _put(self, msg: can.Message, name: str, ready_ns: int, now_ns: int | None,
             failed_attempts: int = 0) -> None:
        if self.modelled:
            self._held.append(msg)
        else:
            self.bus.send(msg)
        self.sent[name] = self.sent.get(name, 0) + 1
        bits = frame_bits(msg.arbitration_id, bytes(msg.data))
        if now_ns is not None:
            self.trace.frame(msg, now_ns, tx=True, t_ready_ns=now_ns, t_rx_ns=NAN, bits=bits)
        else:
            seq = self.arbiter.submit(ready_ns, msg.arbitration_id, bits, node=BENCH,
                                      failed_attempts=failed_attempts)
            self._pending[seq] = (msg, True, bits)

    def next_release_ns(self) -> int | None:
        """When the next delayed frame is due (None: none waits)."""
        return min(d[0] for d in self._delayed) if self._delayed else None

    def release_delayed(self, t_ns: int) -> None:
        """Put the delayed frames whose time has come on the bus (in time, then ID order)."""
        if not self._delayed:
            return
        due = [d for d in self._delayed if d[0] <= t_ns]
        for item in sorted(due, key=lambda d: (d[0], d[1].arbitration_id)):
            self._delayed.remove(item)
            self._put(item[1], item[2], item[0], None)

    def babble(self, t0_ns: int, t1_ns: int) -> None:
        """Frames of the active babbling nodes for [t0, t1): on the bus and on the model."""
        for f in self.active_faults():
            if f.kind != BABBLING:
                continue
            step = round(NS_PER_S / f.params["rate_hz"])
            t = -(-t0_ns // step) * step
            while t < t1_ns:
                data = bytes(self.rng.integers(0, 256, BABBLE_DLC, dtype=np.uint8))
                msg = can.Message(arbitration_id=int(f.params["can_id"]), is_extended_id=False,
                                  data=data)
                if self.modelled:
                    self._held.append(msg)
                else:
                    self.bus.send(msg)
                self.fault_counts["babbled"] += 1
                bits = frame_bits(msg.arbitration_id, data)
                seq = self.arbiter.submit(t, msg.arbitration_id, bits, node=str(f.node))
                self._pending[seq] = (msg, True, bits)
                t += step

    def bus_off(self, node: str, from_ns: int, to_ns: int) -> None:
        """Hold ``node``'s frames on the modelled wire in [from_ns, to_ns)."""
        self.arbiter.bus_off(node, from_ns, to_ns)

    def release(self) -> None:
        """Hand the held frames to the bus, in order, together (transport.lockstep.send_frames)."""
        if self._held:
            send_frames(self.bus, self._held)
            self._held = []

    # -- frames of other nodes ------------------------------------------------------
    def received(self, msg: can.Message, ready_ns: int, node: str, fate: Fate) -> int:
        """A received frame that belongs on the modelled wire; returns its sequence number."""
        bits = frame_bits(msg.arbitration_id, bytes(msg.data))
        seq = self.arbiter.submit(ready_ns, msg.arbitration_id, bits, node=node,
                                  failed_attempts=fate.failed_attempts)
        self._pending[seq] = (msg, False, bits)
        return seq

    def received_off_wire(self, msg: can.Message, t_ns: int) -> None:
        """A received frame with no place on the modelled wire: in the trace only."""
        self.trace.frame(msg, t_ns, tx=False, t_rx_ns=NAN,
                         bits=frame_bits(msg.arbitration_id, bytes(msg.data)))

    # -- resolution -----------------------------------------------------------------
    def flush(self, until_ns: int | None = None) -> dict[int, int]:
        """Resolve arbitration up to ``until_ns``; trace frames in wire order.

        Returns sequence number -> reception time. A frame's failed attempts (link_error)
        go into the trace as error frames, stamped at their end, in time order with the
        frames delivered meanwhile.
        """
        rx: dict[int, int] = {}
        entries: list[tuple[int, int, Delivery | None]] = []  # (time, 0 error / 1 frame, ...)
        errors = False
        for d in self.arbiter.resolve(until_ns):
            if d.failed_ns:
                errors = True
                entries.extend((end - self._intermission_ns, 0, None) for _s, end in d.failed_ns)
            t_rx = d.end_ns - self._intermission_ns  # received at the end of EOF
            entries.append((t_rx, 1, d))
            rx[d.seq] = t_rx
            self.last_rx_ns = max(self.last_rx_ns, t_rx)
        if errors:
            entries.sort(key=lambda e: (e[0], e[1]))  # stable: frames keep their wire order
        for t, _kind, frame in entries:
            if frame is None:
                self.trace.error_frame(t)
                continue
            msg, tx, bits = self._pending.pop(frame.seq)
            self.trace.frame(msg, t, tx=tx, t_ready_ns=frame.ready_ns,
                             t_start_ns=frame.start_ns, bits=bits)
        return rx
