"""Micro-benchmark of the frame codec both processes run on every frame (dbc.codec).

Prints JSON: per message of the DBC, microseconds per ``Encoder.encode`` (payload, alive
counter and CRC), per ``Encoder.message`` (the same as a ``can.Message``) and per
``FrameChecker.inspect`` + ``accept`` of a valid frame (every receive check and the
decoding), medians over ``--batches`` batches of ``--frames`` calls each. The signal
values are each signal's DBC minimum (every signal in range). No process, bus or file:
the codec alone, as compiled by ``pip install`` (setup.py).

Usage: ``python benchmarks/codec_speed.py [--batches N] [--frames M]``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from collections.abc import Callable

from cantools.database.can import Database, Message

from dbc.codec import Encoder, FrameChecker
from dbc.database import load_database

US_PER_S = 1e6
E2E_SIGNALS = ("CRC", "AliveCounter")
FRAME_SPACING_NS = 10_000_000  # receive times of consecutive frames in the inspect batch


def _per_call_us(batches: int, frames: int, call: Callable[[int], object]) -> float:
    """Median over batches of the mean wall time of one ``call(i)`` [µs]."""
    times = []
    for b in range(batches):
        t0 = time.perf_counter()
        for i in range(b * frames, (b + 1) * frames):
            call(i)
        times.append((time.perf_counter() - t0) / frames * US_PER_S)
    return round(statistics.median(times), 3)


def time_message(db: Database, m: Message, batches: int, frames: int) -> dict[str, object]:
    """The figures of one message (module docstring)."""
    signals = {s.name: s.minimum or 0 for s in m.signals if s.name not in E2E_SIGNALS}
    enc = Encoder(db)
    encode_us = _per_call_us(batches, frames, lambda _i: enc.encode(m.name, signals))
    message_us = _per_call_us(batches, frames, lambda _i: enc.message(m.name, signals))
    sent = [enc.message(m.name, signals) for _ in range(batches * frames)]
    checker = FrameChecker(db)

    def receive(i: int) -> None:
        d = checker.inspect(sent[i], i * FRAME_SPACING_NS)
        if d is None:
            raise RuntimeError(f"{m.name}: a valid frame was rejected ({checker.last_cause})")
        checker.accept(d)

    return {"signals": len(m.signals), "encode_us": encode_us, "message_us": message_us,
            "inspect_accept_us": _per_call_us(batches, frames, receive)}


def main() -> None:
    """Time every message, print JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batches", type=int, default=7, help="batches per figure (7)")
    parser.add_argument("--frames", type=int, default=5000, help="calls per batch (5000)")
    args = parser.parse_args()
    db = load_database()
    out = {"benchmark": "codec_speed", "python": platform.python_version(),
           "batches": args.batches, "frames": args.frames,
           "messages": {m.name: time_message(db, m, args.batches, args.frames)
                        for m in db.messages}}
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
