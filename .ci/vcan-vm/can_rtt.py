#!/usr/bin/env python3
"""Round trips over SocketCAN vcan0 between two processes with python-can (VM self-check).

Usage: python can_rtt.py [N]   (inside the guest, after vcan0 is up; see guest_test.sh)
Latency in the emulated guest is not meaningful; this checks behaviour and prints figures.
"""

from __future__ import annotations

import multiprocessing as mp
import statistics
import sys
import time
from multiprocessing.synchronize import Event

import can

CH = "vcan0"
REQ_ID = 0x100
REPLY_ID = 0x101


def _bus(can_id: int) -> can.BusABC:
    return can.Bus(
        interface="socketcan",
        channel=CH,
        can_filters=[{"can_id": can_id, "can_mask": 0x7FF, "extended": False}],
    )


def echo(n: int, ready: Event) -> None:
    """Child process: answer every request with the same payload."""
    with _bus(REQ_ID) as bus:
        ready.set()
        for _ in range(n):
            m = bus.recv(timeout=30)
            if m is None:
                print("echo: timeout", file=sys.stderr)
                sys.exit(2)
            bus.send(can.Message(arbitration_id=REPLY_ID, data=m.data, is_extended_id=False))


def main() -> int:
    """Run N round trips; 0 if all payloads came back unchanged."""
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    ready = mp.Event()
    p = mp.Process(target=echo, args=(n, ready))
    p.start()
    if not ready.wait(60):
        print("echo process did not start", file=sys.stderr)
        p.kill()
        return 5
    rtts = []
    with _bus(REPLY_ID) as bus:
        for i in range(n):
            payload = i.to_bytes(4, "little") + b"\xaa\x55\x00\xff"
            t0 = time.perf_counter()
            bus.send(can.Message(arbitration_id=REQ_ID, data=payload, is_extended_id=False))
            r = bus.recv(timeout=30)
            t1 = time.perf_counter()
            if r is None or bytes(r.data) != payload:
                print(f"mismatch/timeout at {i}: {r}", file=sys.stderr)
                p.kill()
                return 3
            rtts.append((t1 - t0) * 1e6)
    p.join(60)
    q = statistics.quantiles(rtts, n=100)
    print(
        f"python-can {can.__version__}: {n} round trips OK over {CH}; RTT us "
        f"p50={q[49]:.0f} p99={q[98]:.0f} min={min(rtts):.0f} max={max(rtts):.0f}"
    )
    return 0 if p.exitcode == 0 else 4


if __name__ == "__main__":
    sys.exit(main())
