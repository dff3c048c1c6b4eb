"""A warm process that starts a campaign's runs by fork: the same runs without the imports.

A ``thruster-hil run`` process spends ~0.3 CPU-s on imports before it does anything, and so
does its flight software: on 2 cores that is a fifth of a quickstart case. A zygote
(``python -m bench.campaign.zygote SOCKET``, started by :class:`Zygote`) imports the
supervisor, the bench and the flight software's entry module once (``OPENBLAS_NUM_THREADS``
1, as the flight software sets it: one BLAS thread per process, two processes per case),
freezes what it has for the garbage collector, and serves requests on a Unix socket in a
private folder: each connection sends one JSON line ``{"argv", "env", "cwd", "console"}``;
the zygote forks a child that runs ``thruster-hil ARGV`` as the command line would
(bench.operator.warm_start: a session of its own, the environment ``env`` with
``THRUSTER_HIL_WARM_START=1`` so that its bench starts the flight software warm too, stdin
/dev/null, stdout and stderr to the file ``console``), answers ``{"pid": N}`` and,
when the child ends, ``{"exit": CODE}`` (a negative code: killed by that signal).

Ends, and nothing outlives it: a caller that hangs up before its run ended gets that run
stopped (SIGTERM to its session: the run's lifecycle still completes its folder); when the
process that started the zygote dies or closes it (its stdin reaches end of file), or a
SIGTERM or SIGHUP reaches it, the zygote stops every run it started, removes its folder
(socket and log), then exits (a caller still waiting gives the run
``STOP_GRACE_S`` to complete its folder, then RunError); a child also gets SIGTERM if the
zygote dies (``PR_SET_PDEATHSIG``). A run whose environment sets the interpreter's start-up
variables (``PYTHON*``) otherwise than the zygote's is started cold (exec). Results are the
same as a cold run's, byte for byte (tested).
"""

from __future__ import annotations

import contextlib
import json
import os
import selectors
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bench.operator.fsw_prestart import DEFAULT_FSW_MODULE
from bench.operator.warm_start import parse_request
from dbc.errors import RunError

READY = "ready"
REQUEST_KEYS = ("argv", "env", "cwd", "console")
REQUEST_TIMEOUT_S = 10.0  # a connection has this long to send its request line
MAX_REQUEST_BYTES = 1 << 20
START_TIMEOUT_S = 60.0  # the zygote's imports (or a fork) on a loaded machine
STOP_GRACE_S = 10.0  # after SIGTERM, as bench.campaign.case_run gives a run
LOG_TAIL_LINES = 5
STARTUP_PREFIX = "PYTHON"
SESSION_POLL_S = 0.02  # polling a stopped run's session for its end
END_SIGNALS = (signal.SIGTERM, signal.SIGHUP)
CLI_MODULE = "bench.operator.cli"


def preload() -> None:
    """Import what a run's three processes import (module docstring), then freeze it."""
    import gc
    import importlib

    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    importlib.import_module(f"{DEFAULT_FSW_MODULE}.__main__")
    for name in ("bench.operator.cli", "bench.operator.orchestrator",
                 "bench.operator.bench_process", "bench.node", "bench.lockstep",
                 "bench.realtime"):
        importlib.import_module(name)
    gc.collect()
    gc.freeze()


def _read_request(conn: socket.socket) -> dict[str, Any]:
    conn.settimeout(REQUEST_TIMEOUT_S)
    buf = b""
    while not buf.endswith(b"\n"):
        chunk = conn.recv(65536)
        if not chunk or len(buf) > MAX_REQUEST_BYTES:
            raise ValueError("no complete request line")
        buf += chunk
    return parse_request(buf, REQUEST_KEYS)


def _start(req: dict[str, Any]) -> int:
    """Fork the run of ``req``; its pid."""
    from bench.operator.cli import main
    from bench.operator.warm_start import WARM_ENV, die_with_parent, fork_program

    argv = [str(a) for a in req["argv"]]
    env = {str(k): str(v) for k, v in req["env"].items()} | {WARM_ENV: "1"}
    cwd = str(req["cwd"])

    def in_child() -> None:  # pragma: no cover - runs in the child
        os.setsid()
        die_with_parent()
        os.chdir(cwd)
        os.environ.clear()
        os.environ.update(env)
        sys.argv = ["thruster-hil", *argv]

    def entry() -> int:  # pragma: no cover - runs in the child
        if _startup_env(env) != _startup_env(os.environ):  # the interpreter reads these
            os.execve(sys.executable, [sys.executable, "-m", CLI_MODULE, *argv], env)
        return main(argv)

    out = os.open(req["console"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_CLOEXEC, 0o644)
    null = os.open(os.devnull, os.O_RDWR | os.O_CLOEXEC)
    try:
        child = fork_program(entry, out, out, in_child, stdin_fd=null)
    finally:
        os.close(out)
        os.close(null)
    return child.detach()  # reaped by the loop (SIGCHLD), not followed by a pidfd


def _startup_env(env: dict[str, str] | os._Environ[str]) -> dict[str, str]:
    """The variables a Python interpreter reads as it starts (PYTHONHASHSEED, PYTHONPATH,
    PYTHONWARNINGS...): a run whose environment sets them otherwise than the zygote's is
    started cold (exec), as its command would be."""
    return {k: v for k, v in env.items() if k.startswith(STARTUP_PREFIX)}


def _send(conn: socket.socket, record: dict[str, Any]) -> None:
    with contextlib.suppress(OSError):
        conn.sendall(json.dumps(record).encode() + b"\n")


def _stop_session(pid: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pid, signal.SIGTERM)


def _wait_session(pid: int, within_s: float) -> bool:
    """Whether the session ``pid`` leads has no process left, waiting up to ``within_s``
    (another process's children: polled, there is no wait call for them)."""
    deadline = time.monotonic() + within_s
    while True:
        try:
            os.killpg(pid, 0)
        except ProcessLookupError:
            return True
        except PermissionError:
            return False
        if time.monotonic() >= deadline:
            return False
        time.sleep(SESSION_POLL_S)


def serve(path: Path) -> int:
    """The zygote's loop (module docstring), listening on ``path``."""
    preload()
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(str(path))
    listener.listen()
    wake_r, wake_w = socket.socketpair()
    wake_r.setblocking(False)
    wake_w.setblocking(False)
    signal.signal(signal.SIGCHLD, lambda *_: None)  # wakes the selector (wakeup fd)
    signal.set_wakeup_fd(wake_w.fileno())
    sel = selectors.DefaultSelector()
    sel.register(listener, selectors.EVENT_READ, "listen")
    sel.register(wake_r, selectors.EVENT_READ, "child")
    sel.register(sys.stdin, selectors.EVENT_READ, "parent")
    runs: dict[int, socket.socket] = {}  # pid -> the connection that asked for it
    for s in END_SIGNALS:  # ends as its parent's end of file does: runs stopped, folder gone
        signal.signal(s, _end)
    try:
        print(READY, flush=True)
        _loop(listener, wake_r, sel, runs)
    finally:
        for pid in runs:
            _stop_session(pid)
        listener.close()
        shutil.rmtree(path.parent, ignore_errors=True)  # its socket and log: nothing left
    return 0


def _end(signum: int, frame: object) -> None:
    raise SystemExit(0)


def _loop(listener: socket.socket, wake_r: socket.socket, sel: selectors.BaseSelector,
          runs: dict[int, socket.socket]) -> None:
    """Serve until the parent's end of file (module docstring)."""
    while True:
        for key, _ in sel.select():
            if key.data == "listen":
                conn, _ = listener.accept()
                try:
                    pid = _start(_read_request(conn))
                except Exception as exc:  # a bad request is answered, never fatal
                    _send(conn, {"error": f"{type(exc).__name__}: {exc}"})
                    conn.close()
                    continue
                conn.setblocking(True)
                _send(conn, {"pid": pid})
                runs[pid] = conn
                sel.register(conn, selectors.EVENT_READ, pid)
            elif key.data == "child":
                with contextlib.suppress(BlockingIOError):
                    while wake_r.recv(4096):
                        pass
                _reap(runs, sel)
            elif key.data == "parent":
                if not os.read(0, 4096):  # its parent is gone (or closed it)
                    return
            else:  # a caller hung up (or sent more): its run is stopped
                with contextlib.suppress(OSError):
                    if not key.fileobj.recv(4096):  # type: ignore[union-attr]
                        sel.unregister(key.fileobj)
                        _stop_session(key.data)


def _reap(runs: dict[int, socket.socket], sel: selectors.BaseSelector) -> None:
    """Answer each ended child's exit code to its caller."""
    while True:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        conn = runs.pop(pid, None)
        if conn is None:
            continue
        _send(conn, {"exit": os.waitstatus_to_exitcode(status)})
        with contextlib.suppress(KeyError, ValueError):
            sel.unregister(conn)
        conn.close()

class Zygote:
    """A zygote process of this user's, started here, and the way to run commands in it
    (module docstring). :meth:`close` (or leaving a ``with`` block) ends it."""

    def __init__(self) -> None:
        self._dir = Path(tempfile.mkdtemp(prefix="thruster-hil-zygote-"))  # mode 0700
        self.path = self._dir / "zygote.sock"
        with open(self._dir / "zygote.log", "wb") as log:
            self._proc = subprocess.Popen([sys.executable, "-m", __name__, str(self.path)],
                                          stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                          stderr=log)
        assert self._proc.stdout is not None
        sel = selectors.DefaultSelector()
        sel.register(self._proc.stdout, selectors.EVENT_READ)
        line = self._proc.stdout.readline() if sel.select(START_TIMEOUT_S) else b""
        sel.close()
        if line.strip() != READY.encode():
            self.close()
            raise RunError(f"the campaign's zygote did not start within {START_TIMEOUT_S:g} s"
                           f" ({self._log_tail()})")

    def _log_tail(self) -> str:
        try:
            text = (self._dir / "zygote.log").read_text(encoding="utf-8", errors="replace")
        except OSError:
            return "no log"
        return " | ".join(text.strip().splitlines()[-LOG_TAIL_LINES:]) or "no output"

    def alive(self) -> bool:
        """Whether the zygote process is still running."""
        return self._proc.poll() is None

    def run(self, argv: list[str], env: dict[str, str], console: Path,
            timeout_s: float) -> int:
        """Run ``thruster-hil ARGV`` in a child of the zygote (environment ``env``, the
        working folder this process's, stdout and stderr into the file ``console``); its exit
        code
        (negative: killed by that signal). After ``timeout_s`` it is stopped (SIGTERM to its
        session, SIGKILL after ``STOP_GRACE_S``) and ``subprocess.TimeoutExpired`` raised;
        so it is on any exception here (Ctrl-C)."""
        conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        with conn:
            conn.connect(str(self.path))
            request = {"argv": argv, "env": env, "cwd": os.getcwd(), "console": str(console)}
            conn.sendall(json.dumps(request).encode() + b"\n")
            reader = _Lines(conn)
            try:
                first = reader.record(START_TIMEOUT_S)
            except EOFError:
                first = None
            if first is None or "pid" not in first:
                raise RunError("the campaign's zygote did not start the run "
                               f"({(first or {}).get('error', self._log_tail())})")
            pid = int(first["pid"])
            try:
                last = reader.record(timeout_s)
            except EOFError:  # the zygote ended first: it stopped the run (SIGTERM)
                _wait_session(pid, STOP_GRACE_S)
                raise RunError("the campaign's zygote ended during the run (stopped; "
                               f"{self._log_tail()})") from None
            except BaseException:
                self._stop(pid, reader)
                raise
            if last is None:
                self._stop(pid, reader)
                raise subprocess.TimeoutExpired(argv, timeout_s)
            if "exit" not in last:
                raise RunError(f"the campaign's zygote lost the run ({self._log_tail()})")
            return int(last["exit"])

    @staticmethod
    def _stop(pid: int, reader: _Lines) -> None:
        """SIGTERM to the run's session; SIGKILL if it has not ended (its exit answered)
        within STOP_GRACE_S."""
        _stop_session(pid)
        with contextlib.suppress(OSError, ValueError, EOFError):
            if reader.record(STOP_GRACE_S) is not None:
                return
        if _wait_session(pid, 0.0):
            return
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(pid, signal.SIGKILL)
        with contextlib.suppress(OSError, ValueError, EOFError):
            reader.record(STOP_GRACE_S)

    def close(self) -> None:
        """End the zygote (and any run it still has) and remove its folder."""
        if self._proc.stdin is not None and not self._proc.stdin.closed:
            self._proc.stdin.close()
        try:
            self._proc.wait(STOP_GRACE_S)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait()
        if self._proc.stdout is not None:
            self._proc.stdout.close()
        shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self) -> Zygote:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class _Lines:
    """JSON records, one a line, read from a socket with a timeout per record."""

    def __init__(self, conn: socket.socket) -> None:
        self.conn = conn
        self.buf = b""

    def record(self, timeout_s: float) -> dict[str, Any] | None:
        """The next record; None after ``timeout_s``; EOFError at the end of the stream (the
        zygote gone)."""
        deadline = time.monotonic() + timeout_s
        while b"\n" not in self.buf:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self.conn.settimeout(left)
            try:
                chunk = self.conn.recv(65536)
            except TimeoutError:
                return None
            if not chunk:
                raise EOFError("the zygote closed the connection")
            self.buf += chunk
        line, self.buf = self.buf.split(b"\n", 1)
        rec = json.loads(line)
        return rec if isinstance(rec, dict) else None


def main(argv: list[str] | None = None) -> int:
    """``python -m bench.campaign.zygote SOCKET``."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m bench.campaign.zygote SOCKET", file=sys.stderr)
        return 2
    return serve(Path(args[0]))


if __name__ == "__main__":
    sys.exit(main())
