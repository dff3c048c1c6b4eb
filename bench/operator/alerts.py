"""The console's live alerts: what is abnormal, said the moment it happens.

In: the run's events as the bench writes them (``events.jsonl``; bench.wire.trace hands
each to a listener). Out: one line on stderr for each event an operator must not miss
(:data:`FORMATS`): a second sender on the bus, frames of another node rejected (the first
of each message and cause), the flight software going silent, coming back, restarting,
exiting or changing mode (SAFE), the valve watchdog closing the valves, a stall, a live
fault command applied or refused. Every line starts with the simulated time. The same
events are in ``events.jsonl`` and their totals in ``summary.json``.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any, TextIO

NS_PER_S = 1e9
Fields = dict[str, Any]


def _join(x: Any) -> str:
    return ", ".join(str(v) for v in x) if isinstance(x, (list, tuple, dict)) else str(x)


FORMATS: dict[str, Callable[[Fields], str]] = {
    "second_sender": lambda f: "second sender: another node sends "
    f"{_join(f.get('messages', {}))} on this bus (the run is compromised)",
    "frames_rejected": lambda f: f"{f['message']} rejected: {f['cause']} "
    "(the first; the count is in summary.json)",
    "fsw_silent": lambda f: f"flight software silent since cycle {f.get('cycle')} "
    "(3 cycles without its commands): the bench no longer waits for it",
    "fsw_back": lambda f: f"flight software answering again at cycle {f.get('cycle')}",
    "fsw_restart": lambda f: f"flight software restarted (restart {f.get('count')})",
    "fsw_restart_refused": lambda f: "a BOOT status while the flight software was live: "
    "not taken as a restart (replayed or forged frames?)",
    "fsw_exited": lambda f: "the flight-software process has exited",
    "fsw_mode": lambda f: f"flight software mode {f['mode']} (was {f['previous']}; flags: "
    f"{_join(f.get('fdir_flags')) or 'none'})",
    "valve_watchdog": lambda f: "valve watchdog: every valve closed (no valid command since "
    f"{f.get('last_command_s', 0.0):.3f} s)",
    "stall": lambda f: f"stall at cycle {f.get('cycle')}: missing {_join(f.get('missing', []))}",
    "fault_cmd_rejected": lambda f: f"live fault command refused: {f.get('why')}",
}
LIVE_SOURCE = "FAULT_CMD"


def describe(what: str, fields: Fields) -> str | None:
    """The console line for event ``what``, or None if it is not an alert."""
    if what == "fault_injected" and fields.get("source") == LIVE_SOURCE:
        return f"live fault injected: {fields.get('kind')} ({_fields_text(fields)})"
    fmt = FORMATS.get(what)
    return None if fmt is None else fmt(fields)


def _fields_text(fields: Fields) -> str:
    return ", ".join(f"{k}={v}" for k, v in fields.items() if k not in ("kind", "source"))


def printer(stream: TextIO | None = None) -> Callable[[int, str, Fields], None]:
    """A listener that prints each alert as one line to ``stream`` (default: the process's
    stderr at the time), after a newline if a progress bar is drawn on a terminal."""
    stream = stream if stream is not None else sys.stderr
    tty = stream.isatty()

    def alert(t_ns: int, what: str, fields: Fields) -> None:
        line = describe(what, fields)
        if line is not None:
            stream.write(f"{chr(10) if tty else ''}thruster-hil: [t={t_ns / NS_PER_S:.3f} s] "
                         f"{line}\n")
            stream.flush()

    return alert
