"""Handing frames over and waiting for them in lockstep, on any python-can bus.

:func:`send_frames` hands frames of one instant to a bus together: one burst (one
datagram) on a bus that takes bursts (hilbus's ``send_burst``), else one ``send`` each, as
on SocketCAN or any adapter. Receivers see the same frames in the same order either way.

Lockstep waits (:func:`recv_spinning`, :func:`lockstep_spin_s`): in lockstep the bench and
the flight software hand the turn to each other about every half millisecond, one process
waiting while the other computes. A process that blocks in the kernel gives its CPU up, and
on a virtual machine the idle virtual CPU gives the physical core up too: each hand-over
then costs a wake-up of ~0.1 ms and the code after it runs on cold caches (measured here:
the flight software's cycle p99 2-4x its hot value). So each lockstep process first polls
the bus without blocking, yielding the CPU between polls (``sched_yield``: any other
runnable task goes first), for up to :data:`LOCKSTEP_SPIN_S`, and only then blocks. This
spends the waiting time of two CPUs on polling; it is on by default where the process may
run on at least :data:`LOCKSTEP_SPIN_MIN_CPUS` CPUs (:func:`available_cpus`), and
``THRUSTER_HIL_LOCKSTEP_SPIN_S`` sets it (``0`` blocks at once, as realtime mode always
does). Times are in seconds.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Mapping, Sequence

import can

from dbc.errors import ConfigError

LOCKSTEP_SPIN_ENV = "THRUSTER_HIL_LOCKSTEP_SPIN_S"
# Poll this long before blocking in a lockstep wait: longer than either process's usual
# turn (~0.2-1 ms), far below the bench's stall timeout (2 s).
LOCKSTEP_SPIN_S = 0.005
LOCKSTEP_SPIN_MIN_CPUS = 2  # one for each process of the pair


def send_frames(bus: can.BusABC, msgs: Sequence[can.Message]) -> None:
    """Send ``msgs`` in order: as one burst where ``bus`` has ``send_burst`` (hilbus), else
    one ``bus.send`` each. Nothing is sent for an empty sequence."""
    if not msgs:
        return
    burst = getattr(bus, "send_burst", None)
    if burst is not None and len(msgs) > 1:
        burst(msgs)
        return
    for msg in msgs:
        bus.send(msg)


def lockstep_spin_s(cpus: int, env: Mapping[str, str]) -> float:
    """How long a lockstep process polls before blocking in a receive [s] (module docstring).

    ``cpus``: how many CPUs the process may run on; ``env``: the environment, whose
    ``THRUSTER_HIL_LOCKSTEP_SPIN_S`` (seconds >= 0) wins. Raises ConfigError for a bad value.
    """
    text = env.get(LOCKSTEP_SPIN_ENV)
    if text is None:
        return LOCKSTEP_SPIN_S if cpus >= LOCKSTEP_SPIN_MIN_CPUS else 0.0
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0.0):
        raise ConfigError("environment", LOCKSTEP_SPIN_ENV, text, "seconds >= 0 (0: no polling)")
    return value


def available_cpus() -> int:
    """How many CPUs this process may run on (its affinity where the OS tells it)."""
    affinity = getattr(os, "sched_getaffinity", None)
    return len(affinity(0)) if affinity is not None else (os.cpu_count() or 1)


def recv_spinning(bus: can.BusABC, timeout_s: float, spin_s: float) -> can.Message | None:
    """``bus.recv(timeout_s)``, but first poll (``recv(0)``) for up to ``spin_s`` of the
    timeout, yielding the CPU between polls; then block for the rest of it."""
    if spin_s <= 0.0:
        return bus.recv(timeout=timeout_s)
    start = time.monotonic()
    poll_end = start + min(spin_s, timeout_s)
    yield_cpu = getattr(os, "sched_yield", None)
    while True:
        msg = bus.recv(timeout=0.0)
        if msg is not None:
            return msg
        now = time.monotonic()
        if now >= poll_end:
            break
        if yield_cpu is not None:
            yield_cpu()
    return bus.recv(timeout=max(0.0, timeout_s - (now - start)))
