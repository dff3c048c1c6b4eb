"""Hostile-input generator: floods a bus with malformed frames, counted by the cause they carry.

``python -m bench.operator.flood --bus SPEC --frames 100000 --rate-hz 7400`` sends, at a steady
rate,
frames each built to fail exactly one receive check of the ICD: unknown IDs, error frames,
and, for one message consumed by each side (IMU_ACCEL by the flight software, FSW_ATT_EST
by the bench), wrong DLC, bad CRC or remote frames. It prints a JSON object with how many
frames it sent per target and cause, so a test can compare them with the receivers'
reject counters. Seeded, so the same seed gives the same flood. Rate: a 1 Mbit/s bus
carries about 7400 8-byte frames per second.
"""

from __future__ import annotations

import argparse
import json
import time

import can
import numpy as np

from dbc.codec import Encoder
from dbc.database import load_database
from transport.spec import open_bus

CAUSES = ("unknown_id", "error_frame", "crc", "dlc", "remote_frame")
TARGETS = {"FSW": "IMU_ACCEL", "BENCH": "FSW_ATT_EST"}  # a message each side consumes
UNKNOWN_ID_RANGE = (0x100, 0x7DF)
BAD_DLC = 5
CRC_SPOIL = 0x5A
DEFAULT_RATE_HZ = 7400.0


def build_flood(n: int, seed: int) -> tuple[list[can.Message], dict[str, dict[str, int]]]:
    """``n`` malformed frames and the count sent per receiver and cause."""
    db = load_database()
    enc = Encoder(db)
    known = {m.frame_id for m in db.messages}
    rng = np.random.default_rng(seed)
    counts: dict[str, dict[str, int]] = {r: dict.fromkeys(CAUSES, 0) for r in (*TARGETS, "ALL")}
    frames = []
    for _ in range(n):
        cause = CAUSES[int(rng.integers(len(CAUSES)))]
        if cause == "unknown_id":
            can_id = int(rng.integers(*UNKNOWN_ID_RANGE))
            while can_id in known:
                can_id = int(rng.integers(*UNKNOWN_ID_RANGE))
            frames.append(can.Message(arbitration_id=can_id, is_extended_id=False,
                                      data=rng.bytes(8)))
            counts["ALL"][cause] += 1
            continue
        if cause == "error_frame":
            frames.append(can.Message(arbitration_id=0, is_error_frame=True, is_extended_id=False))
            counts["ALL"][cause] += 1
            continue
        target = "FSW" if rng.random() < 0.5 else "BENCH"
        m = db.get_message_by_name(TARGETS[target])
        if cause == "remote_frame":
            msg = can.Message(arbitration_id=m.frame_id, is_extended_id=False,
                              is_remote_frame=True, dlc=m.length)
        else:
            payload = enc.encode(m.name, {s.name: 0 for s in m.signals
                                          if s.name not in ("CRC", "AliveCounter")}, counter=0)
            payload[0] ^= CRC_SPOIL  # the CRC is made wrong on purpose
            data = payload if cause == "crc" else payload[:BAD_DLC]
            msg = can.Message(arbitration_id=m.frame_id, is_extended_id=False, data=bytes(data))
        frames.append(msg)
        counts[target][cause] += 1
    return frames, counts


def send_flood(bus: can.BusABC, frames: list[can.Message], rate_hz: float) -> float:
    """Send ``frames`` at ``rate_hz`` (paced by the monotonic clock); returns seconds taken.

    Between frames the flooder reads and discards what the bus delivers to it, as any CAN
    controller receives the whole bus: on the portable bus, whose senders wait for room in
    each member's queue rather than lose frames, a member that never read would stall the
    bench and the flight software once its queue filled, which is not the hostile input
    under test. The wait for the next slot is that receive (``recv`` with the time left).
    """
    period = 1.0 / rate_hz
    t0 = time.monotonic()
    for i, msg in enumerate(frames):
        while bus.recv(timeout=0.0) is not None:
            pass
        while (lag := t0 + i * period - time.monotonic()) > 0:
            bus.recv(timeout=lag)
        bus.send(msg)
    return time.monotonic() - t0


def main(argv: list[str] | None = None) -> None:
    """Command line: flood a bus and print what was sent as JSON."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bus", required=True, help="bus spec of the run to flood")
    p.add_argument("--frames", type=int, default=100_000,
                   help="how many frames to send (default 100000)")
    p.add_argument("--rate-hz", type=float, default=DEFAULT_RATE_HZ,
                   help=f"frames per second (default {DEFAULT_RATE_HZ:g})")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the flood (the same seed gives the same frames; default 0)")
    args = p.parse_args(argv)
    frames, counts = build_flood(args.frames, args.seed)
    with open_bus(args.bus) as bus:
        took = send_flood(bus, frames, args.rate_hz)
    print(json.dumps({"frames": args.frames, "seconds": round(took, 3), "sent": counts}))


if __name__ == "__main__":
    main()
