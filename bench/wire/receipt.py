"""The fate of a frame on receipt: one path for lockstep and realtime.

In: a frame read from the bus, the time it was read on the bench's clock [ns] (wall
clock: it decides whether a message's alive-counter stream is still live, which a
restarted sender's is not), and in lockstep the control cycle whose commands are awaited.
Out: one :class:`Arrival` per copy of the frame that reaches the bench, each either taken
(its decoded signals) or rejected with its cause; nothing else changes for a rejected frame.

Order (the same in both modes):
1. Bus faults injected on the flight software's and the operator's frames
   (bench.wire.fate): ``drop`` (the frame never arrives), ``corrupt`` (one payload bit
   flipped: the CRC check must reject it), ``duplicate`` (two copies: the second repeats
   the alive counter), ``delay`` and ``link_error`` (lockstep: later delivery on the wire).
2. The ICD's checks (dbc.codec.FrameChecker): error frame, extended ID, unknown ID, one
   of the bench's own messages (``unexpected``), remote frame, DLC, CRC, alive counter
   (repeat; ``sequence``: 1..3 behind the live stream), signal ranges.
3. Freshness of valve commands: in lockstep a THR_CMD must answer the awaited cycle
   (else ``stale``); in realtime its cycle must be newer than the last one taken for that
   frame (else ``stale``). A second, different valid frame of the same command for the same
   cycle is ``second_sender`` (the genuine flight software sends one per cycle).
A rejected frame never moves an alive counter, never takes a cycle's slot or a command,
and never raises. Frames that another node sends as the bench's own messages
(``unexpected``), ``sequence`` regressions and ``second_sender`` frames are evidence of a
second sender on the bus: counted per message in :attr:`Receipt.second_sender`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import can
import numpy as np

from bench.station.faults import FaultSpec
from bench.wire.fate import NO_FATE, Fate, flip, frame_fate
from dbc.codec import Decoded, FrameChecker, Reject
from dbc.icd import BENCH, Icd

EVIDENCE = frozenset({Reject.UNEXPECTED, Reject.SEQUENCE, Reject.SECOND_SENDER})


@dataclass
class Arrival:
    """One copy of a received frame, as it reached the bench."""

    msg: can.Message
    name: str | None  # the ICD message of its (11-bit) ID, None for an unknown ID
    decoded: Decoded | None  # taken: its signals; None: rejected (or dropped)
    passed_checks: bool  # the ICD's checks passed (even if then rejected as stale)
    fate: Fate
    injected_loss: bool  # an injected bus fault (drop, corrupt) kept it from the bench
    cause: Reject | None = None  # why it was rejected


class Receipt:
    """The bench's receive path (see the module docstring)."""

    def __init__(self, icd: Icd, checker: FrameChecker, rng: np.random.Generator,
                 fault_counts: dict[str, int],
                 active_faults: Callable[[], list[FaultSpec]]) -> None:
        self.icd = icd
        self.checker = checker
        self.rng = rng
        self.fault_counts = fault_counts
        self.active_faults = active_faults
        self._command_index = {n: i for i, n in enumerate(icd.command_frames)}
        self._modulus = icd.command_cycle_modulus
        self._last_command: dict[str, tuple[int, bytes]] = {}  # name -> (cycle, payload)
        #: evidence of a second sender, per message name
        self.second_sender: dict[str, int] = {}

    def command_index(self, name: str) -> int | None:
        """The command frame's index (0 for THR_CMD_0 ...), None for another message."""
        return self._command_index.get(name)

    def forget_commands(self) -> None:
        """A new flight software (a restart): its command cycles start again."""
        self._last_command.clear()

    def receive(self, msg: can.Message, t_ns: int, cycle: int | None) -> list[Arrival]:
        """The copies of ``msg`` that reach the bench (see the module docstring).

        ``cycle``: lockstep, the cycle whose commands are awaited; None in realtime.
        """
        icd = self.icd
        name = None if msg.is_extended_id else icd.name_by_id.get(msg.arbitration_id)
        sender = icd.sender[name] if name is not None else ""
        specs = self.active_faults()
        fate = (frame_fate(specs, name, sender, self.rng)
                if specs and name is not None and sender != BENCH else NO_FATE)
        counts = self.fault_counts
        if fate is not NO_FATE:
            if fate.drop:
                counts["dropped"] += 1
                return [Arrival(msg, name, None, False, fate, True)]
            counts["delayed"] += bool(fate.delay_ns)
            counts["failed_attempts"] += fate.failed_attempts
            if fate.corrupt_bit is not None:
                counts["corrupted"] += 1
                flip(msg, fate.corrupt_bit)
            counts["duplicated"] += fate.duplicate
        out = []
        for copy in range(2 if fate.duplicate else 1):
            out.append(self._take(msg, name, t_ns, cycle, fate, copy == 0))
        return out

    def _take(self, msg: can.Message, name: str | None, t_ns: int, cycle: int | None,
              fate: Fate, first_copy: bool) -> Arrival:
        checker = self.checker
        d = checker.inspect(msg, t_ns)
        if d is None:
            cause = checker.last_cause
            if cause in EVIDENCE and name is not None:
                self.second_sender[name] = self.second_sender.get(name, 0) + 1
            lost = first_copy and fate.corrupt_bit is not None
            return Arrival(msg, name, None, False, fate, lost, cause)
        cause = self._freshness(d, bytes(msg.data), cycle)
        if cause is not None:
            checker.reject(d.name, cause)
            if cause in EVIDENCE:
                self.second_sender[d.name] = self.second_sender.get(d.name, 0) + 1
            return Arrival(msg, name, None, True, fate, False, cause)
        checker.accept(d)
        return Arrival(msg, name, d, True, fate, False)

    def _freshness(self, d: Decoded, payload: bytes, cycle: int | None) -> Reject | None:
        """Why a valve command that passed the checks is not taken (None: it is)."""
        if d.name not in self._command_index:
            return None
        c = int(d.signals["Cycle"])
        last = self._last_command.get(d.name)
        if cycle is not None:  # lockstep: the answer to SYNC(cycle), once
            if c != cycle % self._modulus:
                return Reject.STALE
            if last is not None and last[0] == cycle:
                return Reject.SECOND_SENDER
            self._last_command[d.name] = (cycle, payload)
            return None
        if last is not None:  # realtime: newer than the last one taken
            ahead = (c - last[0]) % self._modulus
            if ahead == 0:
                return Reject.SECOND_SENDER
            if ahead > self._modulus // 2:
                return Reject.STALE
        self._last_command[d.name] = (c, payload)
        return None
