"""Bus specs -> python-can buses, for both processes and every tool.

In: a bus spec ``INTERFACE:CHANNEL`` with optional ``?key=value&...`` keyword arguments
passed to :class:`can.Bus`, e.g. ``socketcan:vcan0``, ``virtual:test``, ``hilbus:default``
(the portable cross-process bus of :mod:`transport.hilbus`),
``pcan:PCAN_USBBUS1?bitrate=1000000``. Option values are converted to int, float or bool
where they read as one. Out: an open :class:`can.BusABC` (:func:`open_bus`), the options a
run mode adds (:func:`mode_options`), the default spec of this host
(:func:`default_bus_spec`): ``socketcan:vcan0`` where the kernel has that interface, else
``hilbus:default``.

SocketCAN buses get a large receive buffer (:data:`SOCKETCAN_RCVBUF_BYTES`): the kernel
default (``net.core.rmem_default``, ~212 kB) holds only about 280 frames, and a socket
whose buffer is full drops frames silently, so a bench or flight-software process that is
briefly descheduled during a burst (a flood, a trace replay, a slow emulated CPU) would
lose frames. ``SO_RCVBUFFORCE`` is used where the process may (CAP_NET_ADMIN), else
``SO_RCVBUF``, which the kernel caps at ``net.core.rmem_max``.

Errors: a malformed spec raises :class:`~dbc.errors.BusError`; a bus that cannot be opened
raises :class:`~dbc.errors.BusInitError` (a :class:`can.CanInitializationError`); both name
the spec. :func:`check_bus_spec` is the command lines' check before anything starts: a
malformed spec, an interface python-can does not have (``can.interfaces.VALID_INTERFACES``,
plugins such as ``hilbus`` included) or one whose bus exists inside one process only
(python-can's ``virtual``: the bench, the flight software and the tools are separate
processes, so nothing would ever be heard on it) is a
:class:`~dbc.errors.ConfigError` naming the option.
"""

from __future__ import annotations

import errno
import secrets
import socket
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import parse_qsl

import can

from dbc.errors import BusError, BusInitError, ConfigError

DEFAULT_SOCKETCAN_CHANNEL = "vcan0"
PORTABLE_INTERFACE = "hilbus"
PORTABLE_DEFAULT_CHANNEL = "default"
PRIVATE_CHANNEL_PREFIX = "run-"  # a run's own channel when no bus is named
PRIVATE_TOKEN_BYTES = 4
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
# python-can interfaces whose bus lives inside one process (can.interfaces.virtual)
IN_PROCESS_INTERFACES = frozenset({"virtual"})
SPEC_FORM = "INTERFACE:CHANNEL[?key=value&...], e.g. socketcan:vcan0 or hilbus:default"


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


def check_bus_spec(spec: str, option: str = "--bus", source: str = "command line") -> BusSpec:
    """``spec`` parsed, with an interface python-can has that crosses processes.

    Raises ConfigError(source, option, spec, expected) otherwise; opens nothing.
    """
    try:
        bs = BusSpec.parse(spec)
    except BusError:
        raise ConfigError(source, option, spec, SPEC_FORM) from None
    if bs.interface not in can.interfaces.VALID_INTERFACES:
        known = ", ".join(sorted(can.interfaces.VALID_INTERFACES - IN_PROCESS_INTERFACES))
        raise ConfigError(source, option, spec, f"a python-can interface: one of {known}")
    if bs.interface in IN_PROCESS_INTERFACES:
        raise ConfigError(source, option, spec, "an interface that other processes share "
                          f"(a {bs.interface} bus exists inside one process: the bench, the "
                          "flight software and the tools are separate processes and would "
                          "never hear each other; use hilbus:NAME or socketcan:IFACE)")
    return bs


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


def private_bus_spec() -> str:
    """A portable-bus channel no other run uses: ``hilbus:run-<8 hex digits>``."""
    return f"{PORTABLE_INTERFACE}:{PRIVATE_CHANNEL_PREFIX}{secrets.token_hex(PRIVATE_TOKEN_BYTES)}"


def open_bus(spec: str | BusSpec, **kwargs: object) -> can.BusABC:
    """Open the python-can bus named by ``spec`` (``kwargs`` override its options).

    Raises BusError for a malformed spec, BusInitError if the bus cannot be opened; both
    name the spec.
    """
    bs = spec if isinstance(spec, BusSpec) else BusSpec.parse(spec)
    options = {k: _coerce(v) for k, v in bs.options}
    options.update(kwargs)
    try:
        bus = can.Bus(interface=bs.interface, channel=bs.channel, **options)  # type: ignore[arg-type]
    except (can.CanError, OSError, ValueError, ImportError, NotImplementedError) as exc:
        hint = ""
        if bs.interface == "socketcan" and getattr(exc, "errno", None) == errno.EAFNOSUPPORT:
            hint = " (this kernel has no SocketCAN: use the portable bus, e.g. --bus hilbus:NAME)"
        raise BusInitError(f"cannot open bus {bs}: {exc}{hint}") from exc
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
