"""Start a Python program by fork from a process that has already imported it ("warm").

A fresh interpreter spends ~0.3 CPU-s importing numpy, python-can, cantools and the
project before a run's first cycle; a campaign pays that for every case, three processes a
case. A *warm* start forks a process that has those modules imported instead (the
campaign's zygote, bench.campaign.zygote, and the bench process it forks) and runs the
program's entry in the child, as a fresh interpreter would run it: the same argv, its own
process, pid, session or process group, file descriptors 0-2 and exit code. Everything
else the child inherited from its parent is put back first (:func:`reset_child`):

* signal handlers the parent set in Python go back to the interpreter's start-up ones
  (SIGINT: KeyboardInterrupt; others: the default action); an ignored signal stays ignored,
  as it would across exec; the signal mask is cleared and the wakeup fd unset;
* every file descriptor but those kept is closed (the parent's bus sockets, pipes and
  files), after ``gc.freeze()``, so that no inherited Python object is ever collected
  (and closes a descriptor number the child has reused) in the child;
* ``sys.stdout`` and ``sys.stderr`` are new streams over descriptors 1 and 2;
* at the end the exit handlers run and stdio is flushed, then ``os._exit`` (the parent's
  objects are never finalised in the child).

Only code the caller names runs warm: a ``python -m MODULE`` command whose
``MODULE.__main__`` is already imported here (:func:`warm_module`), or a function. Linux
only (``os.pidfd_open``); elsewhere callers start programs cold.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import gc
import io
import json
import os
import runpy
import select
import signal
import subprocess
import sys
import traceback
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, NoReturn

from bench.operator.lifecycle import exit_now

WARM_ENV = "THRUSTER_HIL_WARM_START"
"""``1``: a bench process starts its flight-software command warm where it can
(:func:`warm_module`); set by the campaign's zygote in the runs it starts."""
EXIT_UNCAUGHT = 1  # what the interpreter exits with after an uncaught exception
FD_DIR = Path("/proc/self/fd")
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
STDIO_FDS = (0, 1, 2)


def warm_module(argv: list[str], env: dict[str, str] | os._Environ[str]) -> str | None:
    """The module a command ``[this python, -m, MODULE, ...]`` runs, if it can be started
    warm here: ``env`` asks for it (:data:`WARM_ENV`), ``MODULE.__main__`` is imported in
    this process and this is Linux; else None (start it cold)."""
    if env.get(WARM_ENV) != "1" or not hasattr(os, "pidfd_open"):
        return None
    if len(argv) < 3 or argv[1] != "-m" or os.path.realpath(argv[0]) != os.path.realpath(
            sys.executable):
        return None
    module = argv[2]
    return module if f"{module}.__main__" in sys.modules else None


def die_with_parent() -> None:
    """In the child: ask Linux for SIGTERM when its parent process dies (even by SIGKILL).

    Elsewhere (macOS) this is a no-op; the flight software then notices the silence itself.
    """
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def parse_request(line: bytes, keys: tuple[str, ...]) -> dict[str, Any]:
    """A warm starter's request (bench.campaign.zygote, bench.operator.fsw_prestart): one
    JSON object holding ``keys`` (ValueError otherwise)."""
    req = json.loads(line)
    if not isinstance(req, dict) or any(k not in req for k in keys):
        raise ValueError(f"a request has {', '.join(keys)}")
    return req


def _open_fds() -> list[int]:
    try:
        return [int(n) for n in os.listdir(FD_DIR)]
    except OSError:  # pragma: no cover - no /proc
        return list(range(3, os.sysconf("SC_OPEN_MAX")))


def reset_child(keep: tuple[int, ...] = STDIO_FDS) -> None:
    """In a freshly forked child: back to what a fresh interpreter has (module docstring)."""
    gc.freeze()
    for s in signal.valid_signals():
        with contextlib.suppress(OSError, ValueError, RuntimeError):
            h = signal.getsignal(s)
            if callable(h) and h is not signal.default_int_handler:
                signal.signal(s, signal.default_int_handler if s == signal.SIGINT
                              else signal.SIG_DFL)
    with contextlib.suppress(ValueError):
        signal.set_wakeup_fd(-1)
    for fd in _open_fds():
        if fd not in keep:
            with contextlib.suppress(OSError):
                os.close(fd)
    signal.pthread_sigmask(signal.SIG_SETMASK, set())
    _fresh_stdio()


def _fresh_stdio() -> None:
    """sys.stdout and sys.stderr over descriptors 1 and 2, as a fresh interpreter has them
    (the parent's may be other objects: a test runner's capture, a closed descriptor)."""
    sys.stdout = io.TextIOWrapper(open(1, "wb", closefd=False), encoding="utf-8",  # noqa: SIM115
                                  line_buffering=os.isatty(1))
    sys.stderr = io.TextIOWrapper(open(2, "wb", closefd=False), encoding="utf-8",  # noqa: SIM115
                                  errors="backslashreplace", line_buffering=True)


def exit_code(code: object) -> int:
    """The exit status ``sys.exit(code)`` gives (None: 0; an int: itself; else 1, printed)."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code
    print(code, file=sys.stderr)
    return EXIT_UNCAUGHT


def run_and_exit(entry: Callable[[], object]) -> NoReturn:
    """In the child: run ``entry`` as a program (its return value or SystemExit is the exit
    code; an uncaught exception prints its traceback and exits 1), then exit."""
    code = EXIT_UNCAUGHT
    try:
        code = exit_code(entry())
    except SystemExit as exc:
        code = exit_code(exc.code)
    except BaseException:
        traceback.print_exc()
    finally:
        with contextlib.suppress(BaseException):
            atexit._run_exitfuncs()
        while True:  # a stop's handler may raise on the way into exit_now (it fires once)
            try:  # noqa: SIM105 - no context manager: its __enter__ could take that raise
                exit_now(code, (sys.stdout, sys.stderr))
            except BaseException:
                pass


def run_module(module: str, args: list[str]) -> Callable[[], object]:
    """The entry that runs ``python -m module *args``."""

    def entry() -> object:
        sys.argv = [module, *args]
        # imported only for its imports: runpy runs it afresh as __main__ (and warns if
        # the imported copy is still registered)
        sys.modules.pop(f"{module}.__main__", None)
        runpy.run_module(module, run_name="__main__", alter_sys=True)
        return None

    return entry


@contextlib.contextmanager
def signals_blocked() -> Iterator[None]:
    """Hold every signal while forking (the child unblocks them once its handlers are
    reset: a stop signal cannot reach the parent's handler in the child)."""
    old = signal.pthread_sigmask(signal.SIG_BLOCK, signal.valid_signals())
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


class ForkedProcess:
    """A warm-started child, with the part of ``subprocess.Popen``'s interface the bench
    uses (pid, returncode, poll, wait, send_signal, terminate, kill)."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.returncode: int | None = None
        self._pidfd = os.pidfd_open(pid)

    def poll(self) -> int | None:
        """Its exit code if it has ended (reaped), else None."""
        if self.returncode is None:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid:
                self._ended(status)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        """Wait for its end (``subprocess.TimeoutExpired`` after ``timeout`` seconds)."""
        if self.returncode is None:
            ready, _, _ = select.select([self._pidfd], [], [], timeout)
            if not ready:
                raise subprocess.TimeoutExpired(str(self.pid), timeout or 0.0)
            self._ended(os.waitpid(self.pid, 0)[1])
        assert self.returncode is not None
        return self.returncode

    def _ended(self, status: int) -> None:
        self.returncode = os.waitstatus_to_exitcode(status)
        self.detach()

    def detach(self) -> int:
        """Stop following it (its pidfd closed: a parent that reaps its children itself,
        the zygote, keeps none); its pid."""
        if self._pidfd >= 0:
            os.close(self._pidfd)
            self._pidfd = -1
        return self.pid

    def send_signal(self, sig: int) -> None:
        """Signal it, unless it has been reaped already."""
        if self.returncode is None:
            os.kill(self.pid, sig)

    def terminate(self) -> None:
        """SIGTERM."""
        self.send_signal(signal.SIGTERM)

    def kill(self) -> None:
        """SIGKILL."""
        self.send_signal(signal.SIGKILL)


def fork_program(entry: Callable[[], object], stdout_fd: int, stderr_fd: int,
                 in_child: Callable[[], None] | None = None,
                 stdin_fd: int | None = None) -> ForkedProcess:
    """Fork a child that runs ``entry`` as a program with its stdout and stderr (and
    stdin, if given; else this process's) on the given descriptors (``in_child`` first:
    e.g. a parent-death signal, a new session)."""
    for f in (sys.stdout, sys.stderr):  # nothing buffered here is written twice
        f.flush()
    child: ForkedProcess | None = None
    try:
        with signals_blocked():
            pid = os.fork()
            if pid == 0:  # pragma: no cover - the child (its effects are tested)
                try:
                    if stdin_fd is not None:
                        os.dup2(stdin_fd, 0)
                    os.dup2(stdout_fd, 1)
                    os.dup2(stderr_fd, 2)
                    reset_child()
                    if in_child is not None:
                        in_child()
                except BaseException:
                    with contextlib.suppress(BaseException):
                        traceback.print_exc()
                    os._exit(EXIT_UNCAUGHT)
                run_and_exit(entry)
            child = ForkedProcess(pid)
    except BaseException:  # a stop signal held while forking: the child goes with us
        if child is not None:
            child.kill()
            child.wait()
        raise
    return child
