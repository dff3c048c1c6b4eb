"""Bus specs -> python-can buses, for both processes and every tool.

A bus spec is ``INTERFACE:CHANNEL`` with optional ``?key=value&...`` keyword arguments
passed to :class:`can.Bus`, e.g. ``socketcan:vcan0``, ``virtual:test``, ``hilbus:default``
(the portable cross-process bus of :mod:`dbc.hilbus`), ``pcan:PCAN_USBBUS1?bitrate=1000000``.
The default is ``socketcan:vcan0`` where the kernel has that interface, else
``hilbus:default``.

SocketCAN buses get a large receive buffer (:data:`SOCKETCAN_RCVBUF_BYTES`): the kernel
default (``net.core.rmem_default``, ~212 kB) holds only about 280 frames, and a socket
whose buffer is full drops frames silently, so a bench or flight-software process that is
briefly descheduled during a burst (a flood, a trace replay, a slow emulated CPU) would
lose frames. ``SO_RCVBUFFORCE`` is used where the process may (CAP_NET_ADMIN), else
``SO_RCVBUF``, which the kernel caps at ``net.core.rmem_max``.

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
run on at least :data:`LOCKSTEP_SPIN_MIN_CPUS` CPUs, and ``THRUSTER_HIL_LOCKSTEP_SPIN_S``
sets it (``0`` blocks at once, as realtime mode always does).
"""

from __future__ import annotations

import errno
import math
import os
import socket
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import parse_qsl

import can

from dbc.errors import BusError, ConfigError

DEFAULT_SOCKETCAN_CHANNEL = "vcan0"
PORTABLE_INTERFACE = "hilbus"
PORTABLE_DEFAULT_CHANNEL = "default"
# Realtime on the portable bus: a member whose queue stays full this long (a paused bus
# monitor) loses frames instead of holding the sender; half a 20 ms control period, below
# the flight software's IMU loss (3 x 10 ms) and the valve watchdog (3 x 20 ms). A real
# CAN bus never waits for a receiver. Lockstep keeps hilbus's own 1 s (lossless for slow
# members; the wait is wall-clock time only).
REALTIME_MEMBER_STALL_S = 0.010
MEMBER_STALL_OPTION = "member_stall_s"
SYS_NET = Path("/sys/class/net")
SOCKETCAN_RCVBUF_BYTES = 8 * 1024 * 1024  # ~10 000 queued frames (kernel skb accounting)
SO_RCVBUFFORCE = getattr(socket, "SO_RCVBUFFORCE", 33)  # Linux value; missing on some builds
LOCKSTEP_SPIN_ENV = "THRUSTER_HIL_LOCKSTEP_SPIN_S"
# Poll this long before blocking in a lockstep wait: longer than either process's usual
# turn (~0.2-1 ms), far below the bench's stall timeout (2 s).
LOCKSTEP_SPIN_S = 0.005
LOCKSTEP_SPIN_MIN_CPUS = 2  # one for each process of the pair


@dataclass(frozen=True)
class BusSpec:
    """A parsed bus spec."""

    interface: str
    channel: str
    options: tuple[tuple[str, str], ...] = ()

    def __post_init__(self) -> None:
        if not self.interface or not self.channel:
            raise BusError(f"bus spec {self}: interface and channel must both be given")

    @classmethod
    def parse(cls, spec: str) -> BusSpec:
        """Parse ``INTERFACE:CHANNEL[?k=v&...]``; raises BusError naming the spec."""
        head, _, query = spec.partition("?")
        interface, sep, channel = head.partition(":")
        if not sep or not interface or not channel:
            raise BusError(
                f"bus spec {spec!r}: expected INTERFACE:CHANNEL, e.g. socketcan:vcan0 "
                f"or {PORTABLE_INTERFACE}:{PORTABLE_DEFAULT_CHANNEL}"
            )
        try:
            options = tuple(parse_qsl(query, strict_parsing=bool(query)))
        except ValueError as exc:
            raise BusError(f"bus spec {spec!r}: malformed options {query!r}: {exc}") from None
        return cls(interface, channel, options)

    def __str__(self) -> str:
        q = "&".join(f"{k}={v}" for k, v in self.options)
        return f"{self.interface}:{self.channel}" + (f"?{q}" if q else "")

    @property
    def is_portable(self) -> bool:
        """True for the project's own cross-process bus."""
        return self.interface == PORTABLE_INTERFACE


def mode_options(spec: str, mode: str) -> dict[str, object]:
    """Extra ``open_bus`` options a run mode needs on ``spec`` (an option in the spec wins).

    Realtime on the portable bus: ``member_stall_s = REALTIME_MEMBER_STALL_S``.
    """
    bs = BusSpec.parse(spec)
    if mode != "realtime" or not bs.is_portable or any(k == MEMBER_STALL_OPTION
                                                       for k, _ in bs.options):
        return {}
    return {MEMBER_STALL_OPTION: REALTIME_MEMBER_STALL_S}


def _coerce(value: str) -> object:
    for conv in (int, float):
        try:
            return conv(value)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(value.lower(), value)


def default_bus_spec(sys_net: Path = SYS_NET) -> str:
    """``socketcan:vcan0`` if the kernel has it, else the portable bus."""
    if (sys_net / DEFAULT_SOCKETCAN_CHANNEL).exists():
        return f"socketcan:{DEFAULT_SOCKETCAN_CHANNEL}"
    return f"{PORTABLE_INTERFACE}:{PORTABLE_DEFAULT_CHANNEL}"


def open_bus(spec: str | BusSpec, **kwargs: object) -> can.BusABC:
    """Open the python-can bus named by ``spec``; raises BusError with the spec on failure."""
    bs = spec if isinstance(spec, BusSpec) else BusSpec.parse(spec)
    options = {k: _coerce(v) for k, v in bs.options}
    options.update(kwargs)
    try:
        bus = can.Bus(interface=bs.interface, channel=bs.channel, **options)  # type: ignore[arg-type]
    except (can.CanError, OSError, ValueError, ImportError, NotImplementedError) as exc:
        hint = ""
        if bs.interface == "socketcan" and getattr(exc, "errno", None) == errno.EAFNOSUPPORT:
            hint = " (this kernel has no SocketCAN: use the portable bus, e.g. --bus hilbus:NAME)"
        raise BusError(f"cannot open bus {bs}: {exc}{hint}") from exc
    sock = getattr(bus, "socket", None)
    if bs.interface == "socketcan" and isinstance(sock, socket.socket):
        enlarge_receive_buffer(sock)
    return bus


def enlarge_receive_buffer(sock: socket.socket, size_bytes: int = SOCKETCAN_RCVBUF_BYTES) -> int:
    """Ask for a ``size_bytes`` receive buffer on ``sock``; returns what the kernel granted.

    Tries ``SO_RCVBUFFORCE`` (needs CAP_NET_ADMIN), then ``SO_RCVBUF`` (capped by
    ``net.core.rmem_max``); never raises for a refused size.
    """
    for option in (SO_RCVBUFFORCE, socket.SO_RCVBUF):
        try:
            sock.setsockopt(socket.SOL_SOCKET, option, size_bytes)
            break
        except OSError:
            continue
    return int(sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF))


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
