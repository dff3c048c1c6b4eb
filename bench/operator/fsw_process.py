"""The flight-software process as the bench runs it: its command line, start, stop, report.

The bench starts the flight software by command (``--fsw-cmd``, ours by default), exactly
as a real bench starts someone else's flight-software binary, so the bench never imports
it. Placeholders in the command (plain names only): ``{bus}``, ``{mode}``, ``{config}``
(the configuration file, dbc.contract.FswConfig), ``{stats}`` (where it may write its
statistics or its refusal, dbc.contract), ``{rx_log}`` (realtime: when it received each
frame) and ``{run_dir}``. On Linux the child is asked to get SIGTERM when the bench
process dies (even by SIGKILL). At the end it gets SIGTERM and ``FSW_TERM_TIMEOUT_S`` to
write its statistics before it is killed. docs/icd.md states the rules for another team.
"""

from __future__ import annotations

import json
import os
import selectors
import shlex
import signal
import string
import subprocess
import sys
from pathlib import Path
from typing import Any, Protocol

from bench.operator.analysis.reception import RX_LOG_FILE
from bench.operator.fsw_prestart import DEFAULT_FSW_MODULE, FSW_TERM_TIMEOUT_S
from dbc.contract import REFUSAL_SCHEMA, FswRefusal
from dbc.errors import ConfigError

DEFAULT_FSW_CMD = (
    f"{shlex.quote(sys.executable)} -m {DEFAULT_FSW_MODULE} --bus {{bus}} --mode {{mode}} "
    "--config {config} --stats {stats} --rx-log {rx_log}"
)
LOG_TAIL_LINES = 5


PLACEHOLDERS = ("bus", "mode", "config", "stats", "run_dir", "rx_log")


def fsw_argv(template: str, bus: str, mode: str, out: Path, config: Path, stats: Path
             ) -> list[str]:
    """The flight software's command line: ``template`` split as a shell would, with its
    placeholders (plain names of :data:`PLACEHOLDERS` only: no attribute, index, format
    or conversion) replaced."""
    values = {"bus": bus, "mode": mode, "config": str(config), "stats": str(stats),
              "run_dir": str(out), "rx_log": str(out / RX_LOG_FILE)}
    allowed = " ".join(f"{{{p}}}" for p in PLACEHOLDERS)
    try:
        args = shlex.split(template)
    except ValueError as exc:
        raise ConfigError("command line", "--fsw-cmd", template,
                          f"a command line a shell can split ({exc})") from exc
    argv: list[str] = []
    for a in args:
        parts: list[str] = []
        try:
            parsed = list(string.Formatter().parse(a))
        except ValueError as exc:
            raise ConfigError("command line", "--fsw-cmd", template,
                              f"placeholders among {allowed} ({exc}; write {{{{ for a brace)"
                              ) from exc
        for literal, name, spec, conv in parsed:
            parts.append(literal)
            if name is None:
                continue
            if name not in values or spec or conv:
                raise ConfigError("command line", "--fsw-cmd", template,
                                  f"placeholders among {allowed}, as plain names (found "
                                  f"{{{name}{'!' + conv if conv else ''}"
                                  f"{':' + spec if spec else ''}}})")
            parts.append(values[name])
        argv.append("".join(parts))
    return argv



class FswProcess(Protocol):
    """The flight-software child as the bench holds it: a ``subprocess.Popen`` (started by
    its command), a bench.operator.warm_start.ForkedProcess (started warm) or a
    bench.operator.fsw_prestart.PrestartedProcess (started in the console's prestart)."""

    @property
    def pid(self) -> int: ...

    @property
    def returncode(self) -> int | None: ...

    def poll(self) -> int | None: ...

    def wait(self, timeout: float | None = None) -> int: ...

    def send_signal(self, sig: int) -> None: ...

    def kill(self) -> None: ...


def stop(proc: FswProcess) -> int | None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(FSW_TERM_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.returncode



def log_tail(log: Path, lines: int = LOG_TAIL_LINES) -> list[str]:
    if not log.exists():
        return []
    return log.read_text(encoding="utf-8", errors="replace").splitlines()[-lines:]


def fsw_report(stats: Path, rc: int | None, out: Path) -> dict[str, Any]:
    """The flight software's part of summary.json: its exit code, its statistics or its
    refusal (dbc.contract records), and its log's tail when it failed."""
    rep: dict[str, Any] = {"exit_code": rc}
    if stats.exists():
        try:
            data = json.loads(stats.read_text(encoding="utf-8"))
            if isinstance(data, dict) and data.get("schema") == REFUSAL_SCHEMA:
                refusal = FswRefusal.from_json(data, str(stats))
                rep.update(refused=refusal.message, refusal=refusal.to_json())
            elif isinstance(data, dict):
                rep.update(data)
            else:
                rep["stats_error"] = f"{stats}: not a JSON object"
        except (OSError, json.JSONDecodeError, ConfigError) as exc:
            rep["stats_error"] = str(exc)
    else:
        rep["stats_error"] = "flight software wrote no statistics"
    if rc not in (0, None):
        rep["log_tail"] = log_tail(out / "fsw.log")
    return rep


def wait_for_exit(out: Path) -> None:
    """After the bench died: give its flight-software child time to write its statistics."""
    try:
        pid = int((out / "fsw.pid").read_text(encoding="utf-8"))
        fd = os.pidfd_open(pid)
    except (OSError, ValueError, AttributeError):
        return
    try:
        sel = selectors.DefaultSelector()
        sel.register(fd, selectors.EVENT_READ)  # readable when the process has exited
        sel.select(timeout=FSW_TERM_TIMEOUT_S)
        sel.close()
    finally:
        os.close(fd)


