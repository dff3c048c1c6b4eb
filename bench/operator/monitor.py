"""``thruster-hil monitor --bus SPEC``: a live, decoded view of a bus in the terminal (textual).

In: every frame on any python-can bus (a run's channel, SocketCAN, an adapter on real
hardware), read by a thread of its own into bench.operator.monitor_state, which checks and
decodes it with the DBC; the bus itself is read by a relay process (transport.relay), so
that the terminal's redraws never hold up the reading (a thread beside them would get the
interpreter too seldom to keep up with a realtime run). Times are seconds since the
monitor started. Out: a terminal console redrawn every ``--refresh`` seconds: the
vehicle (flight-software mode, FDIR flags, failed thruster, estimated attitude, rates,
position, the bench's time, health and faults), the bus load, a message table (ID, name,
count, period, jitter, rejects by cause, last decoded signals), the thrusters (commanded and
actual valve state, openings) and an event log. The reader never waits for the screen: a
slow terminal skips redraws, never frames (the bus is read as fast as it delivers).
``--duration`` ends it (also for scripts); without a terminal it runs headless and prints
the last picture as text. ``thruster-hil run --monitor`` shows it on the run's own bus while
the run goes (:func:`watch_run`; one more listener on the bus). Textual (terminal UI
library, its own test driver in tests/); q quits.
"""

from __future__ import annotations

import os
import select
import threading
import time
from collections.abc import Callable
from typing import Any, ClassVar

import can
from cantools.database.can import Database

from bench.operator.monitor_state import MonitorState
from dbc.errors import ConfigError
from transport.relay import RelayBus

RECV_POLL_S = 0.1  # the reader's longest wait, so that it sees a stop request
DEFAULT_REFRESH_S = 0.25
SIGNALS_SHOWN = 4  # decoded signals of a message in its row (the E2E ones left out)
E2E_SIGNALS = ("CRC", "AliveCounter")


class BusReader:
    """A thread that feeds every frame of ``bus`` into a :class:`MonitorState`."""

    def __init__(self, bus: can.BusABC, state: MonitorState) -> None:
        self.bus, self.state = bus, state
        self.t0_ns = time.monotonic_ns()  # the monitor's times count from here
        self.lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="monitor-reader", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()

    def _run(self) -> None:
        while not self._stop.is_set():
            msg = self.bus.recv(RECV_POLL_S)
            if msg is not None:
                # the edge's clock: when the relay read it, else now
                t_ns = getattr(self.bus, "last_rx_monotonic_ns", 0) or time.monotonic_ns()
                with self.lock:
                    self.state.feed(msg, t_ns - self.t0_ns)

    def snapshot(self) -> dict[str, Any]:
        with self.lock:
            return self.state.snapshot()


def _fmt(x: Any, spec: str = ".3g") -> str:
    return "-" if x is None else format(x, spec)


def vehicle_text(s: dict[str, Any]) -> str:
    """The vehicle and bus lines of a snapshot."""
    v = s["vehicle"]
    q = v.get("q_est")
    lines = [
        f"mode {v.get('mode', '-')}  FDIR {v.get('fdir', '-')}  failed thruster "
        f"{v.get('failed_thruster', 'none')}  cycle {v.get('cycle', '-')}",
        "q_est " + (" ".join(f"{c:+.5f}" for c in q) if q else "-")
        + "   rates [deg/s] " + " ".join(_fmt(r, "+.4f") for r in v.get("rate_deg_s", ())),
        "position [m] " + (" ".join(_fmt(p, "+.3f") for p in v["pos_m"]) if "pos_m" in v
                           else "-")
        + f"   bench t {_fmt(v.get('sim_time_s'), '.2f')} s  health {v.get('health', '-')}"
        f"  faults {v.get('active_faults', '-')}",
        f"bus load {100.0 * s['bus_load']:.1f} % of the last wall-clock second (a lockstep "
        f"run goes faster than real time: more than its modelled load)   frames {s['frames']}",
    ]
    return "\n".join(lines)


def thruster_text(s: dict[str, Any]) -> str:
    """One cell per thruster: commanded/actual valve, openings."""
    cells = [f"T{t['thruster']:02d} {'C' if t['commanded'] else '.'}"
             f"{'O' if t['open'] else '.'} {t['openings']:5d}" for t in s["thrusters"]]
    return "thrusters (C commanded, O open, openings)\n" + "\n".join(
        "   ".join(cells[i:i + 4]) for i in range(0, len(cells), 4))


def message_rows(s: dict[str, Any]) -> list[tuple[str, ...]]:
    """The message table's rows (the UI's and the text picture's)."""
    rows: list[tuple[str, ...]] = []
    for m in s["messages"]:
        sig = ", ".join(f"{k}={v:.4g}" for k, v in m["last"].items()
                        if k not in E2E_SIGNALS)
        rows.append((f"0x{m['id']:03X}", m["name"], str(m["count"]), _fmt(m["period_ms"]),
                     _fmt(m["jitter_ms"]),
                     ", ".join(f"{c}={n}" for c, n in m["rejected"].items()) or "-",
                     sig[:80]))
    return rows


COLUMNS = ("ID", "message", "count", "period ms", "jitter ms", "rejected", "last signals")


def text_picture(s: dict[str, Any]) -> str:
    """A snapshot as plain text (headless runs, scripts)."""
    widths = [max(len(c), *(len(r[i]) for r in message_rows(s))) if s["messages"] else len(c)
              for i, c in enumerate(COLUMNS)]
    table = [" | ".join(c.ljust(w) for c, w in zip(COLUMNS, widths, strict=True))]
    table += [" | ".join(c.ljust(w) for c, w in zip(r, widths, strict=True))
              for r in message_rows(s)]
    return "\n".join([vehicle_text(s), *table, thruster_text(s), "events:", *s["events"]])


def make_app(reader: BusReader, title: str, refresh_s: float,
             duration_s: float | None, stop_when: Callable[[], bool] | None = None) -> Any:
    """The textual application over ``reader`` (imported here: only the monitor needs it);
    it ends after ``duration_s``, on q, or at the first redraw where ``stop_when()``."""
    from textual.app import App, ComposeResult
    from textual.css.query import NoMatches
    from textual.widgets import DataTable, Footer, Header, Log, Static

    class MonitorApp(App[None]):
        CSS = "#vehicle {height: 5;} #thrusters {height: 6;} #events {height: 8;}"
        BINDINGS: ClassVar = [("q", "quit", "Quit")]
        TITLE = title

        def compose(self) -> ComposeResult:
            yield Header()
            yield Static(id="vehicle")
            yield DataTable(id="messages")
            yield Static(id="thrusters")
            yield Log(id="events")
            yield Footer()

        def on_mount(self) -> None:
            self.query_one("#messages", DataTable).add_columns(*COLUMNS)
            self.logged = 0
            self.set_interval(refresh_s, self.redraw)
            if duration_s is not None:
                self.set_timer(duration_s, self.exit)

        def redraw(self) -> None:
            try:
                vehicle = self.query_one("#vehicle", Static)
            except NoMatches:  # a last timer tick while the app closes: its screen is gone
                return
            done = stop_when is not None and stop_when()
            s = reader.snapshot()
            self.picture = s
            vehicle.update(vehicle_text(s))
            self.query_one("#thrusters", Static).update(thruster_text(s))
            table = self.query_one("#messages", DataTable)
            table.clear()
            table.add_rows(message_rows(s))
            log = self.query_one("#events", Log)
            for line in s["events"][self.logged:]:
                log.write_line(line)
            self.logged = len(s["events"])
            if done:  # the last picture drawn, with every frame read before the end
                self.exit()

    return MonitorApp()


def process_ended(pid: int) -> Callable[[], bool]:
    """A check that is true once process ``pid`` (a child of ours) has ended, without
    reaping it (its parent still waits for it): a pidfd turns readable at its end."""
    fd = os.pidfd_open(pid)

    def ended() -> bool:
        return bool(select.select([fd], [], [], 0.0)[0])

    return ended


def watch_run(bus: RelayBus, pid: int, before_app: Callable[[], None] | None = None,
              refresh_s: float = DEFAULT_REFRESH_S, db: Database | None = None) -> None:
    """``thruster-hil run --monitor``: the monitor on a run's bus until the run's process
    ``pid`` ends (or q: the run goes on), then ``bus`` shut down. ``bus`` is on the run's
    bus before its bench starts (a relay already joined sees the run's first frame).
    ``before_app`` runs once the bus is being read (the supervisor's own preparations).
    Without a terminal it prints the last picture."""
    import sys

    from dbc.database import load_database

    reader = BusReader(bus, MonitorState(db or load_database()))
    reader.start()
    try:
        if before_app is not None:
            before_app()
        app = make_app(reader, f"thruster-hil run --monitor {bus.spec}", refresh_s, None,
                       process_ended(pid))
        app.run(headless=not sys.stdout.isatty())
        if not sys.stdout.isatty():
            print(text_picture(reader.snapshot()), flush=True)
    finally:
        reader.stop()
        bus.shutdown()


def add_parser(sub: Any) -> None:
    """The ``monitor`` subcommand of ``thruster-hil``."""
    from dbc import options as opt

    mp = sub.add_parser("monitor", help="watch a bus live, every frame decoded with the DBC "
                        "and checked (a run's channel, SocketCAN, real hardware)")
    mp.add_argument("--bus", type=opt.text("--bus", "a bus spec"), required=True,
                    help="bus spec, e.g. hilbus:run-1a2b3c4d (printed by `run`) or "
                    "socketcan:vcan0")
    mp.add_argument("--duration", type=opt.number("--duration", 0.1, 1e6, unit="s"),
                    help="stop after this many seconds (default: until q)")
    mp.add_argument("--refresh", type=opt.number("--refresh", 0.05, 10.0, unit="s"),
                    default=DEFAULT_REFRESH_S, help="seconds between redraws (default 0.25)")


def run(args: Any, db: Database | None = None) -> int:
    """``thruster-hil monitor``: open the bus, read it, show it (module docstring)."""
    import sys

    from dbc.database import load_database
    from transport.spec import check_bus_spec

    check_bus_spec(args.bus)
    if not sys.stdout.isatty() and args.duration is None:
        raise ConfigError("command line", "--duration", None, "a duration when the output "
                          "is not a terminal (the monitor then prints its last picture)")
    db = db or load_database()
    bus = RelayBus(spec=args.bus)
    reader = BusReader(bus, MonitorState(db))
    reader.start()
    print(f"thruster-hil monitor: listening on {args.bus}", file=sys.stderr, flush=True)
    try:
        app = make_app(reader, f"thruster-hil monitor {args.bus}", args.refresh,
                       args.duration)
        app.run(headless=not sys.stdout.isatty())
        if not sys.stdout.isatty():
            print(text_picture(reader.snapshot()))
    finally:
        reader.stop()
        bus.shutdown()
    return 0
