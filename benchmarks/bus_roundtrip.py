"""Bus round-trip latency and one-way throughput; prints one JSON object to stdout.

For each bus (``hilbus``, python-can ``virtual`` as the in-process baseline, and
``socketcan:vcan0`` when the kernel has it):

* round trip: this process sends a frame, an echo peer sends it back, N times (default
  5000) per run, R runs (default 3) after a warm-up; p50 (the run's median), p99, max and
  mean in µs of the run with the median p50 (the host is shared and noisy: the 1-minute
  load average is reported too). The peer is a second OS process, except for ``virtual``
  (python-can's virtual bus cannot cross processes), where it is a thread of this process.
  For scale, the round trip of bare datagrams between two Python processes over a Unix
  socketpair is measured first (the host's floor at that moment).
* throughput: this process sends M frames (default 100 000) back to back; the peer counts
  them (checking their sequence numbers) and reports when it has seen the last one.
  Frames/s over that span, plus frames lost or out of order; once one frame per send, once
  8 per ``transport.lockstep.send_frames`` call (one datagram on hilbus).

Usage: ``python benchmarks/bus_roundtrip.py [--rtt-n 5000] [--rtt-runs 3]
[--throughput-n 100000]`` (about 7 s here with the defaults, well under 30 s).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

import can

from transport.lockstep import send_frames
from transport.spec import open_bus

PING_ID = 0x100
PONG_ID = 0x101
SINK_ID = 0x200
REPORT_ID = 0x7F1
REPORTED_ID = 0x7F2
READY_ID = 0x7F0
STOP_ID = 0x7FF
SEQ = struct.Struct("<I")
REPORT = struct.Struct("<II")

RTT_N_DEFAULT = 5000
RTT_RUNS_DEFAULT = 3
THROUGHPUT_N_DEFAULT = 100_000
WARMUP_S = 1.5  # > transport.hilbus.MTIME_SETTLE_S: membership caches have settled
STARTUP_TIMEOUT_S = 20.0
REPLY_TIMEOUT_S = 10.0
SYS_NET = Path("/sys/class/net")
RAW_RECORD_B = 23  # a hilbus record of a 8-byte frame
BURST_FRAMES = 8  # about a lockstep instant's frames


@dataclass(frozen=True)
class Config:
    """What to measure."""

    rtt_n: int
    rtt_runs: int
    throughput_n: int


def echo(spec: str) -> None:
    """The peer: echo pings, count sink frames, report counts, until told to stop."""
    with open_bus(spec) as bus:
        bus.send(can.Message(arbitration_id=READY_ID, is_extended_id=False))
        count = 0
        out_of_order = 0
        while True:
            msg = bus.recv(timeout=1.0)
            if msg is None:
                continue
            ident = msg.arbitration_id
            if ident == SINK_ID:
                if SEQ.unpack_from(msg.data)[0] != count:
                    out_of_order += 1
                count += 1
            elif ident == PING_ID:
                bus.send(can.Message(arbitration_id=PONG_ID, is_extended_id=False, data=msg.data))
            elif ident == REPORT_ID:
                bus.send(
                    can.Message(
                        arbitration_id=REPORTED_ID,
                        is_extended_id=False,
                        data=REPORT.pack(count, out_of_order),
                    )
                )
                count = out_of_order = 0
            elif ident == STOP_ID:
                return


def _wait_for(bus: can.BusABC, ident: int, data: bytes | None = None) -> can.Message:
    deadline = time.monotonic() + REPLY_TIMEOUT_S
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError(f"no frame 0x{ident:X} within {REPLY_TIMEOUT_S} s")
        msg = bus.recv(timeout=left)
        if (
            msg is not None
            and msg.arbitration_id == ident
            and (data is None or bytes(msg.data) == data)
        ):
            return msg


def _ping(bus: can.BusABC, seq: int) -> float:
    """One round trip; seconds."""
    data = SEQ.pack(seq)
    t0 = time.perf_counter()
    bus.send(can.Message(arbitration_id=PING_ID, is_extended_id=False, data=data))
    _wait_for(bus, PONG_ID, data)
    return time.perf_counter() - t0


def _rtt_stats(rtts_us: list[float]) -> dict[str, float]:
    rtts_us = sorted(rtts_us)
    n = len(rtts_us)
    return {
        "p50": round(statistics.median(rtts_us), 1),
        "p99": round(rtts_us[min(n - 1, int(0.99 * n))], 1),
        "max": round(rtts_us[-1], 1),
        "mean": round(statistics.fmean(rtts_us), 1),
    }


def measure(bus: can.BusABC, cfg: Config) -> dict[str, object]:
    """Warm up, then round trips and throughput against a peer that is already READY."""
    seq = 0
    warm_until = time.monotonic() + WARMUP_S
    while time.monotonic() < warm_until:
        _ping(bus, seq)
        seq += 1
    runs = []
    for _ in range(cfg.rtt_runs):
        rtts_us = []
        for _ in range(cfg.rtt_n):
            rtts_us.append(_ping(bus, seq) * 1e6)
            seq += 1
        runs.append(_rtt_stats(rtts_us))
    median_run = sorted(runs, key=lambda r: r["p50"])[len(runs) // 2]

    return {
        "rtt_us": {
            "n": cfg.rtt_n,
            "runs": cfg.rtt_runs,
            **median_run,
            "p50_of_each_run": [r["p50"] for r in runs],
        },
        "throughput": _throughput(bus, cfg.throughput_n, 1),
        # frames of one instant handed over together (transport.lockstep.send_frames: one
        # datagram on hilbus, one send each elsewhere), as a lockstep bench does with its samples
        f"throughput_in_bursts_of_{BURST_FRAMES}": _throughput(bus, cfg.throughput_n,
                                                               BURST_FRAMES),
    }


def _throughput(bus: can.BusABC, n: int, burst: int) -> dict[str, object]:
    """Send n frames back to back, ``burst`` at a time; the peer counts them."""
    frames = [can.Message(arbitration_id=SINK_ID, is_extended_id=False,
                          data=SEQ.pack(i) + b"\0" * 4) for i in range(n)]
    t0 = time.perf_counter()
    for i in range(0, n, burst):
        send_frames(bus, frames[i:i + burst])
    bus.send(can.Message(arbitration_id=REPORT_ID, is_extended_id=False))
    reply = _wait_for(bus, REPORTED_ID)
    elapsed_s = time.perf_counter() - t0
    count, out_of_order = REPORT.unpack_from(reply.data)
    return {"frames": n, "frames_per_s": round(n / elapsed_s), "lost": n - count,
            "out_of_order": out_of_order}


def run_process_peer(spec: str, cfg: Config) -> dict[str, object]:
    """Measure against an echo peer in a second OS process."""
    with open_bus(spec) as bus:
        peer = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--echo", spec])
        try:
            deadline = time.monotonic() + STARTUP_TIMEOUT_S
            while True:
                msg = bus.recv(timeout=0.5)
                if msg is not None and msg.arbitration_id == READY_ID:
                    break
                if peer.poll() is not None:
                    raise RuntimeError(f"echo process for {spec} exited {peer.returncode}")
                if time.monotonic() > deadline:
                    raise TimeoutError(f"echo process for {spec} not ready")
            result = measure(bus, cfg)
            bus.send(can.Message(arbitration_id=STOP_ID, is_extended_id=False))
            peer.wait(timeout=REPLY_TIMEOUT_S)
        finally:
            if peer.poll() is None:
                peer.kill()
                peer.wait()
    return {"peer": "second OS process", **result}


def run_thread_peer(spec: str, cfg: Config) -> dict[str, object]:
    """Measure against an echo peer in a thread of this process."""
    with open_bus(spec) as bus:
        peer = threading.Thread(target=echo, args=(spec,), daemon=True)
        peer.start()
        _wait_for(bus, READY_ID)
        result = measure(bus, cfg)
        bus.send(can.Message(arbitration_id=STOP_ID, is_extended_id=False))
        peer.join(timeout=REPLY_TIMEOUT_S)
    return {"peer": "thread of the same process", **result}


def raw_unix_rtt_us(n: int) -> float:
    """p50 round trip of bare datagrams over a socketpair to a forked child: the host's floor.

    Wake-up latency on a shared VM varies several-fold over minutes; this puts the bus
    figures beside what the kernel and Python alone achieve at the same moment.
    """
    mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_DGRAM)
    with mine, theirs:
        pid = os.fork()
        if pid == 0:  # child: echo until an empty datagram
            mine.close()
            while d := theirs.recv(RAW_RECORD_B):
                theirs.send(d)
            os._exit(0)
        rtts_us = []
        record = bytes(RAW_RECORD_B)
        for _ in range(n):
            t0 = time.perf_counter()
            mine.send(record)
            mine.recv(RAW_RECORD_B)
            rtts_us.append((time.perf_counter() - t0) * 1e6)
        mine.send(b"")
        os.waitpid(pid, 0)
    return round(statistics.median(rtts_us), 1)


def main(argv: list[str] | None = None) -> None:
    """Entry point: run every bus available here and print the JSON figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rtt-n", type=int, default=RTT_N_DEFAULT, help="round trips per run")
    parser.add_argument(
        "--rtt-runs", type=int, default=RTT_RUNS_DEFAULT, help="runs (the median run is shown)"
    )
    parser.add_argument(
        "--throughput-n", type=int, default=THROUGHPUT_N_DEFAULT, help="frames one way"
    )
    parser.add_argument("--echo", metavar="SPEC", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.echo:
        echo(args.echo)
        return
    cfg = Config(args.rtt_n, args.rtt_runs, args.throughput_n)

    load_before = os.getloadavg()[0]
    raw_before = raw_unix_rtt_us(cfg.rtt_n)  # before any thread exists (fork)
    tag = f"bench-{os.getpid()}-{uuid.uuid4().hex[:6]}"
    results: dict[str, object] = {}
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="thb-bench-") as runtime:
        # a private hilbus runtime dir (inherited by the echo process): nothing left behind
        os.environ["XDG_RUNTIME_DIR"] = runtime
        results[f"hilbus:{tag}"] = run_process_peer(f"hilbus:{tag}", cfg)
    results[f"virtual:{tag}"] = run_thread_peer(f"virtual:{tag}", cfg)
    if (SYS_NET / "vcan0").exists():
        results["socketcan:vcan0"] = run_process_peer("socketcan:vcan0", cfg)
    report = {
        "benchmark": "bus_roundtrip",
        "python": platform.python_version(),
        "python_can": can.__version__,
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "load_avg_1min_before": round(load_before, 2),
        "raw_unix_socketpair_rtt_p50_us_before": raw_before,
        "results": results,
        "wall_s": round(time.perf_counter() - started, 1),
    }
    json.dump(report, sys.stdout, indent=2)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
