"""Live fault injection over the bus: one FAULT_CMD frame, acknowledged by the bench.

The operator side of ``thruster-hil inject``. It listens for BENCH_STATUS to learn the last
FAULT_CMD alive counter the bench accepted (``FaultCmdCounter``), sends FAULT_CMD with the
next counter (so the bench's E2E check accepts a new sender), and waits for a BENCH_STATUS
that acknowledges it (``FaultCmdRejected`` = 1: the bench refused it, e.g. a thruster it
does not have; exit 2). Any CAN tool can do the same: :func:`cansend_string` prints the frame
in can-utils ``cansend`` syntax. Frames in: BENCH_STATUS; out: FAULT_CMD.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import can

from dbc import e2e
from dbc.codec import Encoder, FrameChecker
from dbc.database import load_database
from dbc.errors import ConfigError, RefusedConfigError, RunError
from dbc.icd import Icd
from transport.spec import open_bus

INJECT_SOURCE = "thruster-hil inject"
DEFAULT_TIMEOUT_S = 5.0
ICD = Icd.from_database(load_database())
KIND_CODES = {kind: code for code, kind in ICD.fault_kinds.items()}


@dataclass(frozen=True)
class FaultCommand:
    """What to send (see FAULT_CMD's signal comments in the DBC)."""

    kind: str
    target: int
    duration_s: float = 0.0
    param: float = 0.0
    clear: bool = False

    def __post_init__(self) -> None:
        if self.kind not in KIND_CODES:
            raise ConfigError(INJECT_SOURCE, "kind", self.kind,
                              f"one of {', '.join(KIND_CODES)}")
        frame = load_database().get_message_by_name("FAULT_CMD")
        for option, signal, value in (("--target", "Target", self.target),
                                      ("--duration", "Duration", self.duration_s),
                                      ("--param", "Param", self.param)):
            s = frame.get_signal_by_name(signal)
            lo, hi = float(s.minimum or 0.0), float(s.maximum or 0.0)
            if not lo <= value <= hi:  # also rejects NaN
                raise ConfigError(INJECT_SOURCE, option, value,
                                  f"{s.minimum:g}..{s.maximum:g} (FAULT_CMD.{signal} in the DBC)")

    def signals(self) -> dict[str, float | int]:
        """FAULT_CMD signal values."""
        action = ICD.fault_actions["clear" if self.clear else "inject"]
        return {"Action": action, "FaultType": KIND_CODES[self.kind],
                "Target": self.target, "Duration": self.duration_s, "Param": self.param}


def cansend_string(cmd: FaultCommand, counter: int) -> str:
    """The FAULT_CMD frame as ``ID#HEXDATA`` for can-utils ``cansend``."""
    if not 0 <= counter < e2e.COUNTER_MODULUS:
        raise ConfigError(INJECT_SOURCE, "--print-frame", counter,
                          f"an alive counter 0..{e2e.COUNTER_MODULUS - 1}")
    db = load_database()
    data = Encoder(db).encode("FAULT_CMD", cmd.signals(), counter=counter)
    return f"{db.get_message_by_name('FAULT_CMD').frame_id:03X}#{bytes(data).hex().upper()}"


def inject(bus_spec: str, cmd: FaultCommand, timeout_s: float = DEFAULT_TIMEOUT_S) -> int:
    """Send ``cmd`` on ``bus_spec``, wait for the bench's acknowledgement; returns the counter."""
    db = load_database()
    checker = FrameChecker(db, accept=frozenset({"BENCH_STATUS"}))
    with open_bus(bus_spec) as bus:
        last, _ = _bench_status(bus, checker, timeout_s)
        counter = 0 if last == ICD.fault_cmd_counter_none else (last + 1) % e2e.COUNTER_MODULUS
        frame = db.get_message_by_name("FAULT_CMD")
        bus.send(can.Message(arbitration_id=frame.frame_id, is_extended_id=False,
                             data=Encoder(db).encode("FAULT_CMD", cmd.signals(), counter=counter)))
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            acked, rejected = _bench_status(bus, checker, deadline - time.monotonic())
            if acked == counter:
                if rejected:
                    raise RefusedConfigError(
                        "the bench", f"{cmd.kind} --target {cmd.target} --param "
                        f"{cmd.param:g} is not applicable to this bench; the bus carries "
                        "only the refusal (BENCH_STATUS.FaultCmdRejected): the bench's "
                        "console, events.jsonl and summary.json say why",
                        what="the fault command")
                return counter
    raise RunError(f"no acknowledgement of FAULT_CMD (counter {counter}) on {bus_spec} "
                   f"within {timeout_s} s")


def _bench_status(bus: can.BusABC, checker: FrameChecker, timeout_s: float) -> tuple[int, bool]:
    """(FaultCmdCounter, FaultCmdRejected) of the next BENCH_STATUS."""
    deadline = time.monotonic() + timeout_s
    while (left := deadline - time.monotonic()) > 0:
        msg = bus.recv(timeout=left)
        if msg is None:
            break
        d = checker.check(msg)
        if d is not None:
            return int(d.signals["FaultCmdCounter"]), bool(d.signals["FaultCmdRejected"])
    raise RunError(f"no BENCH_STATUS within {timeout_s:.1f} s: is a bench running on this bus? "
                   "(a lockstep bench sends it once its flight software is cycling)")
