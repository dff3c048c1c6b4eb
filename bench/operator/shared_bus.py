"""A named bus another run may already use: listen before starting, and say so if it does.

A run without ``--bus`` gets a channel of its own (transport.spec.private_bus_spec) and
meets nobody. On a bus the user names (``socketcan:vcan0``, ``hilbus:lab``) another bench
or flight software may be running. Before starting, :func:`probe` listens for
``PROBE_S``: a running bench sends a sensor frame every 10 ms and a flight software its
commands every cycle, so a well-formed frame of the ICD from either (a valid CRC) means
the bus is in use. Then the new run does not start (exit 2, naming what it heard) and
first announces itself with one BENCH_STATUS flagged ``second_sender``: the running bench
hears its own message from another node and reports a second sender on its console and in
its summary, so both operators learn of it within the probe's time.
"""

from __future__ import annotations

import time

import can

from dbc.codec import Encoder, FrameChecker
from dbc.database import load_database
from dbc.icd import BENCH, FSW, Icd
from transport.spec import open_bus

PROBE_S = 0.25  # longer than 20 sensor periods of a running bench


def probe(spec: str, window_s: float = PROBE_S) -> list[str]:
    """The messages of a bench or flight software heard on ``spec`` within ``window_s``;
    if any, the bus is announced to them as shared (module docstring)."""
    db = load_database()
    icd = Icd.from_database(db)
    names = icd.sent_by(BENCH) | icd.sent_by(FSW)
    checker = FrameChecker(db, accept=names)
    heard: set[str] = set()
    bus = open_bus(spec)
    try:
        deadline = time.monotonic() + window_s
        while (left := deadline - time.monotonic()) > 0:
            msg = bus.recv(timeout=left)
            if msg is None:
                continue
            d = checker.check(msg)
            if d is not None:
                heard.add(d.name)
        if heard:
            _announce(bus, icd)
    finally:
        bus.shutdown()
    return sorted(heard)


def _announce(bus: can.BusABC, icd: Icd) -> None:
    """One BENCH_STATUS flagged second_sender: the running bench hears a second bench."""
    signals: dict[str, float | int] = {
        "SimTime": 0.0, "ActiveFaults": 0, "Health": icd.health_flags["second_sender"],
        "FaultCmdCounter": icd.fault_cmd_counter_none, "FaultCmdRejected": 0}
    bus.send(Encoder(load_database()).message("BENCH_STATUS", signals))
