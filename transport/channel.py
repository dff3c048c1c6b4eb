"""hilbus's channels on the file system: directories, member socket files, their owners.

Layout: ``<runtime>/thruster-hil-<uid>/<channel>/<pid>-<random hex>.sock``, one
``AF_UNIX``/``SOCK_DGRAM`` socket file per member (per open ``HilBus``), where
``<runtime>`` is ``$XDG_RUNTIME_DIR`` if set and writable, else the system temporary
directory (:func:`runtime_dir`).

Permissions: only the owning user can see or join a bus. Both directories are created
with mode 0o700 and, when they already exist, must be real directories (not symlinks)
owned by the current uid with no group/other permission bits, else
:class:`~dbc.errors.BusInitError` names the path (someone else pre-creating
``/tmp/thruster-hil-<uid>`` cannot hijack it, only block it). Socket files are mode 0o600.
Channel names are restricted to ``[A-Za-z0-9_.-]+`` (and not ``.``/``..``) so they cannot
escape the directory (else :class:`~dbc.errors.BusArgumentError`). The socket path must
fit ``sun_path`` (107 bytes on Linux, 103 elsewhere; else BusArgumentError).

Lifetime: a channel directory exists while the channel has members. A member joining
creates it (:func:`join`); the last member leaving removes it (:func:`leave`: ``rmdir``,
which only succeeds on an empty directory, so a member that joined meanwhile keeps it).
A member that joins while the last one leaves may find its directory gone between
creating it and binding its socket in it: it creates it again and retries. Once its
socket is bound the directory is not empty, so nobody can remove it under a member.
Members of processes that died without leaving, and channel directories left empty by
them, are removed by :func:`sweep`, which every joining member runs over the user's
channels: a socket file goes when the process in its name is dead *and* nothing is bound
to it (a connection is refused), a directory when it is then empty. Files that are not
member sockets are never touched.

In: channel names, member socket names. Out: paths, a bound member socket
(:func:`join`), the pid in a member's name and whether it is alive, the channels that have
live members (:func:`live_channels`). Assumes one host and one user.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import socket
import sys
import tempfile
from pathlib import Path

from dbc.errors import BusArgumentError, BusInitError

DEFAULT_CHANNEL = "default"
CHANNEL_RE = re.compile(r"[A-Za-z0-9_.-]+")
DIR_PREFIX = "thruster-hil-"
SOCKET_SUFFIX = ".sock"
MEMBER_RE = re.compile(r"([0-9]+)-[0-9a-f]+\.sock")
MEMBER_TOKEN_BYTES = 4
DIR_MODE = 0o700
SOCKET_MODE = 0o600
PERMISSION_BITS = 0o7777
GROUP_OTHER_BITS = 0o077
SUN_PATH_MAX_LINUX_B = 107
SUN_PATH_MAX_OTHER_B = 103
#: times a joining member recreates a channel directory that a leaving member removed
#: between its creation and the bind (each retry needs another member to leave meanwhile)
JOIN_ATTEMPTS = 16

#: errors of a member socket whose process is gone (or never was there)
STALE_ERRNOS = frozenset(
    {
        errno.ECONNREFUSED,
        errno.ECONNRESET,
        errno.ENOENT,
        errno.ENOTCONN,
        errno.ENOTSOCK,
        errno.EPIPE,
    }
)


def runtime_dir() -> Path:
    """``$XDG_RUNTIME_DIR`` if set and writable, else the system temporary directory."""
    xdg = os.environ.get("XDG_RUNTIME_DIR")
    if xdg and os.path.isdir(xdg) and os.access(xdg, os.W_OK | os.X_OK):
        return Path(xdg)
    return Path(tempfile.gettempdir())


def bus_root() -> Path:
    """The per-user directory holding one directory per channel."""
    return runtime_dir() / f"{DIR_PREFIX}{os.getuid()}"


def is_channel_name(name: str) -> bool:
    """True for a valid channel name (letters, digits, ``_.-``; not ``.`` or ``..``)."""
    return CHANNEL_RE.fullmatch(name) is not None and name not in (".", "..")


def check_channel(channel: object) -> str:
    """Return ``channel`` as a valid channel name; raises BusArgumentError naming a bad
    value."""
    name = str(channel) if isinstance(channel, int) and not isinstance(channel, bool) else channel
    if not isinstance(name, str) or not is_channel_name(name):
        raise BusArgumentError(
            f"hilbus channel {channel!r}: expected a name of letters, digits, '_', '.', '-' "
            "(not '.' or '..')"
        )
    return name


def channel_dir(channel: str) -> Path:
    """The directory of ``channel``'s member sockets (not created)."""
    return bus_root() / check_channel(channel)


def new_member_path(directory: Path) -> Path:
    """A fresh member socket path in ``directory``: ``<pid>-<random hex>.sock``; raises
    BusArgumentError if it is longer than the OS allows for a socket path."""
    token = os.urandom(MEMBER_TOKEN_BYTES).hex()
    path = directory / f"{os.getpid()}-{token}{SOCKET_SUFFIX}"
    limit_b = sun_path_max_b()
    if len(os.fsencode(path)) > limit_b:
        raise BusArgumentError(
            f"hilbus channel {directory.name!r}: socket path {path} is longer than the OS "
            f"allows ({limit_b} bytes); use a shorter channel name or a shorter "
            "$XDG_RUNTIME_DIR"
        )
    return path


def sun_path_max_b() -> int:
    """The longest socket path the OS takes [bytes]."""
    return SUN_PATH_MAX_LINUX_B if sys.platform.startswith("linux") else SUN_PATH_MAX_OTHER_B


def secure_dir(path: Path) -> None:
    """Create ``path`` with mode 0o700, or check an existing one is ours and private.

    Raises BusInitError naming the path if it cannot be created or is not private, and
    FileNotFoundError if it (or its parent) was removed meanwhile (the caller retries).
    """
    try:
        os.mkdir(path, DIR_MODE)
    except FileExistsError:
        pass
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise BusInitError(f"hilbus: cannot create directory {path}: {exc.strerror}") from exc
    else:
        os.chmod(path, DIR_MODE)  # the umask may have taken bits away
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise BusInitError(f"hilbus: cannot inspect directory {path}: {exc.strerror}") from exc
    if not is_private_dir(st):
        raise BusInitError(
            f"hilbus: refusing directory {path}: it must be a directory (not a symlink) "
            f"owned by uid {os.getuid()} with mode 0700 (found uid {st.st_uid}, "
            f"mode {st.st_mode & PERMISSION_BITS:o}, type {'dir' if _isdir(st) else 'other'})"
        )


def _isdir(st: os.stat_result) -> bool:
    return (st.st_mode & 0o170000) == 0o040000


def is_private_dir(st: os.stat_result) -> bool:
    """True for a directory (not a symlink) of ours without group/other permissions."""
    return _isdir(st) and st.st_uid == os.getuid() and (st.st_mode & GROUP_OTHER_BITS) == 0


def join(sock: socket.socket, path: Path) -> None:
    """Create the channel's directories if needed and bind ``sock`` at ``path`` (mode
    0o600), creating the channel directory again if the last member removed it meanwhile.
    Raises BusInitError naming the path if either fails."""
    for _attempt in range(JOIN_ATTEMPTS):
        try:
            secure_dir(path.parent.parent)
            secure_dir(path.parent)
            sock.bind(os.fspath(path))
        except FileNotFoundError:
            continue  # the last member left and removed the directory: create it again
        except BusInitError:
            raise
        except OSError as exc:
            remove_if_empty(path.parent)  # checked private and ours: if we made it, unmake it
            raise BusInitError(f"hilbus: cannot bind {path}: {exc}") from exc
        try:
            os.chmod(path, SOCKET_MODE)
        except OSError as exc:
            leave(path)
            raise BusInitError(f"hilbus: cannot restrict {path} to its owner: {exc}") from exc
        return
    raise BusInitError(
        f"hilbus: cannot join {path.parent}: it was removed {JOIN_ATTEMPTS} times while "
        "joining (members leaving as fast as this one joins)"
    )


def leave(path: Path) -> None:
    """Unlink member socket ``path``, then its channel directory if that is now empty."""
    with contextlib.suppress(FileNotFoundError):
        os.unlink(path)
    remove_if_empty(path.parent)


def remove_if_empty(directory: Path) -> None:
    """``rmdir`` ``directory``: removed if empty, left alone otherwise (or if gone)."""
    with contextlib.suppress(OSError):  # ENOTEMPTY: a member is (or joined) there
        os.rmdir(directory)


def member_pid(name: str) -> int | None:
    """The process id in a member socket's name, None for other names."""
    m = MEMBER_RE.fullmatch(name)
    return int(m.group(1)) if m else None


def pid_alive(pid: int) -> bool:
    """True if a process ``pid`` exists (whoever owns it)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_if_dead(directory: Path, name: str) -> None:
    """Unlink member socket ``name`` if the process in its name is no longer alive."""
    pid = member_pid(name)
    if pid is not None and not pid_alive(pid):
        with contextlib.suppress(FileNotFoundError):
            os.unlink(directory / name)


def _refuses(path: Path) -> bool:
    """True if nothing is bound to socket file ``path`` (or it is gone, or no socket)."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(os.fspath(path))
        except OSError as exc:
            return exc.errno in STALE_ERRNOS
    return False


def sweep(root: Path) -> None:
    """Remove what dead processes left in ``root`` (the user's bus directory): member
    sockets whose process is dead and that nobody is bound to, then channel directories
    that are empty. Skips anything that is not a private directory of ours; never raises."""
    try:
        channels = os.listdir(root)
    except OSError:
        return
    for ch in channels:
        directory = root / ch
        try:
            if not is_channel_name(ch) or not is_private_dir(os.lstat(directory)):
                continue
            names = os.listdir(directory)
        except OSError:
            continue
        for name in names:
            pid = member_pid(name)
            if pid is not None and not pid_alive(pid) and _refuses(directory / name):
                with contextlib.suppress(OSError):
                    os.unlink(directory / name)
        remove_if_empty(directory)


def live_channels() -> list[str]:
    """This user's channels that have at least one member whose process is alive."""
    root = bus_root()
    try:
        if not is_private_dir(os.lstat(root)):
            return []
        channels = sorted(os.listdir(root))
    except OSError:
        return []
    found = []
    for ch in channels:
        if not is_channel_name(ch):
            continue
        try:
            members = os.listdir(root / ch)
        except OSError:
            continue
        pids = (member_pid(n) for n in members)
        if any(pid is not None and pid_alive(pid) for pid in pids):
            found.append(ch)
    return found
