"""Start the flight software's interpreter while the console is still starting (prestart).

A ``thruster-hil run`` spends ~0.25 s importing its console and parsing the scenario before
its bench process starts the flight software, whose fresh interpreter then spends ~0.3 s
importing numpy, python-can and its own stack before its first cycle: on 2 cores the two
can overlap. With the default flight-software command (``python -m flight_sw``, this
interpreter) the console script (bench.operator.entry) starts, before its own imports,
``python -m bench.operator.fsw_prestart MODULE``: a process that imports
``MODULE.__main__`` (nothing of the bench), then waits on its stdin for the one run it
serves. Results are the same as a cold start's, byte for byte (tested).

Protocol, one JSON object a line
    - stdin, from the bench process (forked from the console, it inherits the pipe): one
      request ``{"argv", "env", "cwd", "log"}``: the flight software's whole command line
      (``[python, -m, MODULE, ARGS...]``), its environment, working folder and log file.
    - stdout: ``{"pid": N}`` once the child is forked (bench.operator.warm_start: reset to a
      fresh interpreter's state, ``env`` as its environment, stdin /dev/null, stdout and
      stderr appended to ``log``, SIGTERM if the prestart dies), ``{"exit": CODE}`` when it
      ends (negative: killed by that signal); or ``{"error": TEXT}`` instead of the pid
      (its imports failed): the bench then starts it by its command, which fails the same
      way in its log.

Ends (nothing outlives it)
    Its stdin's end of file, once the bench and the console have both let go of the pipe
    (the run is over, or the bench died): before a request it exits at once; after one,
    a child still running gets SIGTERM (what ``PR_SET_PDEATHSIG`` gives a cold child whose
    bench dies) and SIGKILL after ``FSW_TERM_TIMEOUT_S``. The child is reaped only after
    its exit code is answered, and the bench signals it through a pidfd opened when it
    hears the pid, so a reused pid is never signalled. SIGTERM or
    SIGHUP to the prestart end it the same way: the console sends SIGTERM at its own end to
    a prestart still there (one a refused command never used may still be importing). A
    bench that waits ``START_TIMEOUT_S`` for the pid kills it and starts the command. A
    terminal's Ctrl-C (SIGINT to the whole process group) is the run's to handle: the
    prestart ignores it through a Python handler, so its child starts with the
    interpreter's own, as a cold one does.

Linux only (``os.pidfd_open``); ``THRUSTER_HIL_PRESTART=0`` turns it off (cold start).
"""

from __future__ import annotations

import contextlib
import importlib
import io
import json
import os
import select
import signal
import subprocess
import sys
from typing import IO, Any

from bench.operator.warm_start import (
    WARM_ENV,
    die_with_parent,
    fork_program,
    parse_request,
    run_module,
)

DEFAULT_FSW_MODULE = "flight_sw"
"""The module of the default flight-software command (``python -m flight_sw``)."""
PRESTART_ENV = "THRUSTER_HIL_PRESTART"
"""``0``: the console starts no prestart (the flight software starts cold)."""
REQUEST_KEYS = ("argv", "env", "cwd", "log")
FSW_TERM_TIMEOUT_S = 5.0  # a flight software's time to write its statistics after SIGTERM
CLOSE_TIMEOUT_S = FSW_TERM_TIMEOUT_S + 5.0  # the console waits this long for it to end
START_TIMEOUT_S = 60.0  # its imports (or a fork) on a loaded machine, as the zygote's
STARTUP_PREFIX = "PYTHON"  # the interpreter reads these as it starts
END_SIGNALS = (signal.SIGTERM, signal.SIGHUP)


def startup_env(env: dict[str, str] | os._Environ[str]) -> dict[str, str]:
    """The variables an interpreter reads as it starts (PYTHONPATH, PYTHONHASHSEED...),
    but PYTHONUNBUFFERED, which the child applies itself: a request whose environment
    sets the others otherwise than the prestart's is started cold."""
    return {k: v for k, v in env.items()
            if k.startswith(STARTUP_PREFIX) and k != "PYTHONUNBUFFERED"}


# --- the client: the console starts it, the bench uses it ------------------------------

class FswPrestart:
    """A prestart process for ``module`` and the pipe to it (module docstring). Started by
    the console (the constructor); the bench process (a fork of the console) sends the one
    request (:meth:`run`); the console lets go of its ends once it has forked the bench
    (:meth:`release`) and reaps it at the end (:meth:`close`)."""

    def __init__(self, module: str) -> None:
        self.module = module
        self._startup = startup_env(os.environ)
        self._proc = subprocess.Popen(
            [sys.executable, "-m", __name__, module], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)

    @classmethod
    def wanted(cls) -> bool:
        """Whether this process may start one: Linux (pidfd), not turned off, not in a
        warm-started run (its bench forks the flight software from itself)."""
        return (hasattr(os, "pidfd_open") and os.environ.get(PRESTART_ENV) != "0"
                and os.environ.get(WARM_ENV) != "1")

    def serves(self, argv: list[str], env: dict[str, str]) -> bool:
        """Whether ``argv`` is this prestart's command (``python -m MODULE ...`` with this
        interpreter) and ``env`` starts an interpreter as the prestart's did."""
        return (len(argv) >= 3 and argv[1:3] == ["-m", self.module]
                and os.path.realpath(argv[0]) == os.path.realpath(sys.executable)
                and startup_env(env) == self._startup and self._proc.stdin is not None
                and not self._proc.stdin.closed)

    def run(self, argv: list[str], env: dict[str, str], cwd: str, log: str
            ) -> PrestartedProcess | None:
        """Start the flight software ``argv`` in the prestart; None if it cannot (not its
        command, its imports failed, it is gone, or it did not answer within
        ``START_TIMEOUT_S``: then it is killed): start it by its command then."""
        if not self.serves(argv, env):
            return None
        assert self._proc.stdin is not None and self._proc.stdout is not None
        request = {"argv": argv, "env": env, "cwd": cwd, "log": log}
        try:
            self._proc.stdin.write(json.dumps(request).encode() + b"\n")
            self._proc.stdin.flush()
        except OSError:
            return None
        reader = _Lines(self._proc.stdout)
        first = reader.record(START_TIMEOUT_S)
        if first is None:  # hung: it must not start a second flight software later
            with contextlib.suppress(ProcessLookupError):
                os.kill(self._proc.pid, signal.SIGKILL)
        if first is None or "pid" not in first:
            return None
        return PrestartedProcess(int(first["pid"]), reader, self._proc.stdin)

    def release(self) -> None:
        """In the console, once it has forked the bench: close its ends of the pipe (the
        bench holds its own), so that the prestart ends with the bench."""
        for f in (self._proc.stdin, self._proc.stdout):
            if f is not None:
                with contextlib.suppress(OSError):
                    f.close()

    def close(self) -> None:
        """At the end of the command (its run is over, its flight software stopped): let go
        of it and reap it. One still running (a command that ended before its run, as a
        refused one does: the prestart may still be importing) gets SIGTERM, and SIGKILL
        after ``CLOSE_TIMEOUT_S``."""
        self.release()
        if self._proc.poll() is None:
            self._proc.terminate()
        try:
            self._proc.wait(CLOSE_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait()


class PrestartedProcess:
    """The flight software forked by the prestart, as the bench holds it
    (bench.operator.fsw_process.FswProcess: pid, returncode, poll, wait, send_signal,
    kill). Its exit code comes over the pipe; once it is known the request pipe is closed,
    which lets the prestart reap it and end."""

    def __init__(self, pid: int, reader: _Lines, request: IO[bytes]) -> None:
        self.pid = pid
        self.returncode: int | None = None
        self._reader = reader
        self._request = request
        try:  # it is unreaped until its exit is answered: this is that process
            self._pidfd = os.pidfd_open(pid)
        except ProcessLookupError:  # already gone: its exit record is in the pipe
            self._pidfd = -1

    def poll(self) -> int | None:
        """Its exit code if it has ended, else None."""
        if self.returncode is None:
            self._ended(self._reader.record(0.0))
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        """Wait for its end (``subprocess.TimeoutExpired`` after ``timeout`` seconds)."""
        if self.returncode is None:
            self._ended(self._reader.record(timeout))
            if self.returncode is None:
                raise subprocess.TimeoutExpired(str(self.pid), timeout or 0.0)
        return self.returncode

    def _ended(self, record: dict[str, Any] | None) -> None:
        if record is None:
            return
        # an exit record, or the prestart gone without one (killed): it killed its child
        self.returncode = int(record.get("exit", -signal.SIGKILL))
        if self._pidfd >= 0:
            os.close(self._pidfd)
            self._pidfd = -1
        with contextlib.suppress(OSError):
            self._request.close()

    def send_signal(self, sig: int) -> None:
        """Signal it (through its pidfd: never another process), unless it has ended."""
        if self.poll() is None and self._pidfd >= 0:
            with contextlib.suppress(ProcessLookupError):
                signal.pidfd_send_signal(self._pidfd, sig)

    def terminate(self) -> None:
        """SIGTERM."""
        self.send_signal(signal.SIGTERM)

    def kill(self) -> None:
        """SIGKILL."""
        self.send_signal(signal.SIGKILL)


class _Lines:
    """JSON records, one a line, from a pipe; ``{"exit": ...}``-less end of file gives
    ``{}`` (the prestart is gone)."""

    def __init__(self, pipe: IO[bytes]) -> None:
        self._fd = pipe.fileno()
        self._buf = b""

    def record(self, timeout_s: float | None) -> dict[str, Any] | None:
        """The next record; None if none came within ``timeout_s`` (None: wait)."""
        while b"\n" not in self._buf:
            ready, _, _ = select.select([self._fd], [], [], timeout_s)
            if not ready:
                return None
            chunk = os.read(self._fd, 65536)
            if not chunk:
                return {}
            self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        rec = json.loads(line)
        return rec if isinstance(rec, dict) else {}


# --- the prestart process --------------------------------------------------------------

def _ignore(signum: int, frame: object) -> None:
    """SIGINT is the run's (module docstring)."""


def _end(signum: int, frame: object) -> None:
    for s in END_SIGNALS:  # once: the clean-up it starts (the child's stop) runs to the end
        signal.signal(s, signal.SIG_IGN)
    raise SystemExit(0)


def _read_request() -> dict[str, Any] | None:
    buf = b""
    while not buf.endswith(b"\n"):
        chunk = os.read(0, 65536)
        if not chunk:
            return None
        buf += chunk
    return parse_request(buf, REQUEST_KEYS)


def _send(record: dict[str, Any]) -> None:
    with contextlib.suppress(OSError):
        os.write(1, json.dumps(record).encode() + b"\n")


def _fork(module: str, req: dict[str, Any]) -> int:
    """Fork the flight software of ``req``; its pid."""
    args = [str(a) for a in req["argv"]][3:]
    env = {str(k): str(v) for k, v in req["env"].items()}
    cwd = str(req["cwd"])

    def in_child() -> None:  # pragma: no cover - runs in the child
        die_with_parent()
        os.chdir(cwd)
        os.environ.clear()
        os.environ.update(env)
        if env.get("PYTHONUNBUFFERED"):
            for f in (sys.stdout, sys.stderr):
                if isinstance(f, io.TextIOWrapper):
                    f.reconfigure(line_buffering=True, write_through=True)

    log = os.open(str(req["log"]), os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_CLOEXEC, 0o644)
    null = os.open(os.devnull, os.O_RDWR | os.O_CLOEXEC)
    try:
        return fork_program(run_module(module, args), log, log, in_child, stdin_fd=null).detach()
    finally:
        os.close(log)
        os.close(null)


def _exit_code(pid: int) -> int:
    """The ended child's exit code, leaving it unreaped (negative: killed by a signal)."""
    info = os.waitid(os.P_PID, pid, os.WEXITED | os.WNOWAIT)
    assert info is not None
    return info.si_status if info.si_code == os.CLD_EXITED else -info.si_status


def _watch(pid: int, answered: list[bool]) -> None:
    """Answer the child's exit code when it ends (``answered`` then holds True); return
    at stdin's end of file."""
    pidfd = os.pidfd_open(pid)
    try:
        watched = [0, pidfd]
        while True:
            ready, _, _ = select.select(watched, [], [])
            if pidfd in ready:
                _send({"exit": _exit_code(pid)})
                answered.append(True)
                watched = [0]
            if 0 in ready and not os.read(0, 4096):
                return
    finally:
        os.close(pidfd)


def _stop(pid: int, answered: list[bool]) -> None:
    """SIGTERM to a child still running, SIGKILL after FSW_TERM_TIMEOUT_S; its exit code
    answered (if it was not yet) while it is still unreaped, then reap it."""
    pidfd = os.pidfd_open(pid)
    try:
        if not select.select([pidfd], [], [], 0.0)[0]:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGTERM)
            if not select.select([pidfd], [], [], FSW_TERM_TIMEOUT_S)[0]:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
                select.select([pidfd], [], [])
    finally:
        os.close(pidfd)
    if not answered:
        _send({"exit": _exit_code(pid)})
    os.waitpid(pid, 0)


def _stdin_closed() -> bool:
    """Whether stdin is at its end of file now (the bench gone after its request)."""
    return bool(select.select([0], [], [], 0.0)[0]) and not os.read(0, 4096)


def serve(module: str) -> int:
    """The prestart process (module docstring)."""
    signal.signal(signal.SIGINT, _ignore)
    for s in END_SIGNALS:
        signal.signal(s, _end)
    error: str | None = None
    try:
        importlib.import_module(f"{module}.__main__")
        import gc

        gc.collect()
        gc.freeze()
    except Exception as exc:  # said in the answer; the bench then starts it cold
        error = f"{type(exc).__name__}: {exc}"
    req = _read_request()
    if req is None:
        return 0
    if error is not None:
        _send({"error": error})
        return 0
    if _stdin_closed():  # the bench went while this imported: its run is over
        return 0
    answered: list[bool] = []
    pid = _fork(module, req)
    try:
        _send({"pid": pid})
        _watch(pid, answered)
    finally:  # also on SIGTERM (a whole process group stopped): the bench hears the end
        _stop(pid, answered)
    return 0


def main(argv: list[str] | None = None) -> int:
    """``python -m bench.operator.fsw_prestart MODULE``."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m bench.operator.fsw_prestart MODULE", file=sys.stderr)
        return 2
    return serve(args[0])


if __name__ == "__main__":
    sys.exit(main())
