"""A hostile second node: attack frames of every category, each counted, against a live run.

``python -m bench.operator.hostile --bus SPEC --frames 100000 [--forgeries]`` joins a bus
where a bench and a flight software run, and sends frames built to exercise each receive
check of the ICD, at up to ``--rate-hz`` (a hilbus sender is also paced by its slowest
reader). It reads the bus all along, as any CAN controller receives the whole bus: that
keeps it from stalling the portable bus, and gives it the frames it replays and the cycle
it forges commands for. It prints a JSON object with how many frames it sent per category.

Categories
    Noise (no valid E2E protection; no receiver can take them for a frame of the ICD):
    ``unknown_id`` (an 11-bit ID the DBC does not have), ``error_frame``, ``extended_id``
    (a 29-bit frame numbered like a valve command), ``remote_frame``, ``dlc`` (5 bytes),
    ``crc`` (a spoiled CRC), each on a message of either side.
    Forgeries (``--forgeries``: a valid CRC, so the sender speaks the ICD's E2E protection):
    ``range`` (a value outside its DBC range), ``counter`` (the invalid alive counter 15),
    ``stale_command`` (a valve command for an old cycle), ``forged_command`` (a valve
    command for the cycle just SYNCed, every valve full on), ``replayed_sync`` and
    ``replayed_status`` (an old SYNC or BENCH_STATUS heard on the bus, sent again as is).

What the receivers should do: count every one by cause (each frame is heard by the bench
and by the flight software, and each counts it once), crash on none, restart nothing; noise
changes nothing else; forgeries mark the run compromised, naming their messages.
Seeded: the same seed gives the same sequence of categories.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import dataclass

import can
import numpy as np

from dbc.codec import Encoder, data_id
from dbc.database import load_database
from dbc.e2e import COUNTER_MODULUS, frame_crc
from dbc.icd import Icd
from dbc.layout import FrameLayout
from transport.spec import open_bus

NOISE = ("unknown_id", "error_frame", "extended_id", "remote_frame", "dlc", "crc")
FORGERIES = ("range", "counter", "stale_command", "forged_command", "replayed_sync",
             "replayed_status")
UNKNOWN_ID_RANGE = (0x100, 0x7DF)
BAD_DLC = 5
CRC_SPOIL = 0x5A
STALE_CYCLES = 3  # a stale command answers this many cycles back
DEFAULT_RATE_HZ = 20_000.0
DEFAULT_FRAMES = 100_000
# (message, signal) whose largest raw value lies outside its DBC range, per side's input
OUT_OF_RANGE = {"THR_CMD_0": "ImuCounter", "IMU_RATE": "RateX"}
COUNTER_BYTE = 1


def _set_raw(data: bytearray, start: int, length: int, raw: int) -> None:
    """Write the unsigned bit pattern ``raw`` into a little-endian signal's bits."""
    for i in range(length):
        byte, bit = divmod(start + i, 8)
        data[byte] = (data[byte] & ~(1 << bit)) | (((raw >> i) & 1) << bit)


@dataclass
class Sniffer:
    """What the hostile node learnt from the bus: the last SYNC's cycle, frames to replay."""

    sync_id: int
    status_id: int
    sync_layout: FrameLayout
    cycle: int | None = None
    sync: can.Message | None = None
    status: can.Message | None = None
    heard: int = 0

    def hear(self, msg: can.Message) -> None:
        """Take note of one frame read from the bus."""
        self.heard += 1
        if msg.is_extended_id or msg.is_error_frame or msg.is_remote_frame:
            return
        if msg.arbitration_id == self.sync_id and len(msg.data) == self.sync_layout.length:
            self.cycle = int(self.sync_layout.unpack(bytes(msg.data))["Cycle"])
            self.sync = self.sync or msg  # the first one: the oldest
        elif msg.arbitration_id == self.status_id and self.status is None:
            self.status = msg


class Attacker:
    """Builds the frames of each category (see the module docstring)."""

    def __init__(self, seed: int, forgeries: bool) -> None:
        db = load_database()
        self.db = db
        self.icd = Icd.from_database(db)
        self.enc = Encoder(db)
        self.rng = np.random.default_rng(seed)
        self.categories = NOISE + (FORGERIES if forgeries else ())
        self.sniffer = Sniffer(self.icd.frame_id["SYNC"], self.icd.frame_id["BENCH_STATUS"],
                               FrameLayout(db.get_message_by_name("SYNC")))
        self.known = set(self.icd.name_by_id)

    def _target(self) -> str:
        """A message of either side: a valve command (the bench's input) or IMU_RATE."""
        return self.icd.command_frames[0] if self.rng.random() < 0.5 else "IMU_RATE"

    def _valid(self, name: str, counter: int | None = None,
               signals: dict[str, float | int] | None = None) -> bytearray:
        sig: dict[str, float | int] = dict.fromkeys(self.icd.payload[name], 0)
        sig.update(signals or {})
        return self.enc.encode(name, sig, counter)

    def _frame(self, name: str, data: bytes | bytearray) -> can.Message:
        return can.Message(arbitration_id=self.icd.frame_id[name], is_extended_id=False,
                           data=bytes(data))

    def _reprotect(self, name: str, data: bytearray) -> bytearray:
        data[0] = frame_crc(data_id(self.db.get_message_by_name(name)), data)
        return data

    def build(self, category: str) -> can.Message | None:
        """One frame of ``category``; None when the bus has not shown what it needs yet."""
        icd, rng, s = self.icd, self.rng, self.sniffer
        if category == "unknown_id":
            can_id = int(rng.integers(*UNKNOWN_ID_RANGE))
            while can_id in self.known:
                can_id = int(rng.integers(*UNKNOWN_ID_RANGE))
            return can.Message(arbitration_id=can_id, is_extended_id=False, data=rng.bytes(8))
        if category == "error_frame":
            return can.Message(arbitration_id=0, is_error_frame=True, is_extended_id=False)
        name = self._target()
        if category == "extended_id":
            return can.Message(arbitration_id=icd.frame_id[icd.command_frames[0]],
                               is_extended_id=True, data=bytes(self._valid(name)))
        if category == "remote_frame":
            return can.Message(arbitration_id=icd.frame_id[name], is_extended_id=False,
                               is_remote_frame=True, dlc=8)
        if category in ("dlc", "crc"):
            data = self._valid(name)
            data[0] ^= CRC_SPOIL
            return self._frame(name, data if category == "crc" else data[:BAD_DLC])
        if category == "range":
            data = self._valid(name)
            sig = self.db.get_message_by_name(name).get_signal_by_name(OUT_OF_RANGE[name])
            largest = (1 << (sig.length - 1)) - 1 if sig.is_signed else (1 << sig.length) - 1
            _set_raw(data, sig.start, sig.length, largest)
            return self._frame(name, self._reprotect(name, data))
        if category == "counter":
            data = self._valid(name)
            data[COUNTER_BYTE] |= COUNTER_MODULUS  # 15: never sent by a live sender
            return self._frame(name, self._reprotect(name, data))
        if category in ("stale_command", "forged_command"):
            if s.cycle is None:
                return None
            cmd = icd.command_frames[0]
            back = STALE_CYCLES if category == "stale_command" else 0
            full_on = {} if back else {
                sig: icd.signal_range[(cmd, sig)][1]
                for sig in icd.on_time_signals[:icd.thrusters_per_command]}
            cycle = (s.cycle - back) % icd.command_cycle_modulus
            return self._frame(cmd, self._valid(cmd, signals={"Cycle": cycle, **full_on}))
        replay = s.sync if category == "replayed_sync" else s.status
        return None if replay is None else can.Message(
            arbitration_id=replay.arbitration_id, is_extended_id=False, data=bytes(replay.data))

    def run(self, bus: can.BusABC, n_frames: int, rate_hz: float) -> dict[str, int]:
        """Send ``n_frames`` at up to ``rate_hz``, reading the bus between them."""
        sent = dict.fromkeys(self.categories, 0)
        period_s = 1.0 / rate_hz
        t0 = time.monotonic()
        i = 0
        while i < n_frames:
            while (msg := bus.recv(timeout=0.0)) is not None:
                self.sniffer.hear(msg)
            category = self.categories[int(self.rng.integers(len(self.categories)))]
            frame = self.build(category)
            if frame is None:  # nothing to replay or forge yet: wait for the bus
                msg = bus.recv(timeout=period_s)
                if msg is not None:
                    self.sniffer.hear(msg)
                continue
            while (lag := t0 + i * period_s - time.monotonic()) > 0:
                msg = bus.recv(timeout=lag)
                if msg is not None:
                    self.sniffer.hear(msg)
            bus.send(frame)
            sent[category] += 1
            i += 1
        return sent


def main(argv: list[str] | None = None) -> None:
    """Command line: attack a bus and print what was sent, per category, as JSON."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bus", required=True, help="bus spec of the run to attack")
    p.add_argument("--frames", type=int, default=DEFAULT_FRAMES, help="how many frames to send")
    p.add_argument("--rate-hz", type=float, default=DEFAULT_RATE_HZ,
                   help="the most frames per second (a hilbus sender is also paced by readers)")
    p.add_argument("--seed", type=int, default=0, help="seed of the category sequence")
    p.add_argument("--forgeries", action="store_true",
                   help="also send frames with a valid CRC (forgeries, replays)")
    args = p.parse_args(argv)
    attacker = Attacker(args.seed, args.forgeries)
    t0 = time.monotonic()
    with open_bus(args.bus) as bus:
        sent = attacker.run(bus, args.frames, args.rate_hz)
    print(json.dumps({"frames": args.frames, "seconds": round(time.monotonic() - t0, 3),
                      "sent": sent, "heard": attacker.sniffer.heard}))


if __name__ == "__main__":
    main()
