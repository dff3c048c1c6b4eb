"""The realtime loop of the bench node: the plant paced to the wall clock.

The station is stepped to the clock; the sensors go out when due (traced at the measured
time); each frame read goes through the same receive path as in lockstep
(bench.wire.receipt, with no awaited cycle: a command must be newer than the last one
taken) and a valve command is applied when it arrives. A bench slower than the wall clock
still ends at the run's duration: each pass steps the plant to the clock, then reads at
most ``RT_FRAMES_PER_PASS`` frames, so neither catching up nor a stream of frames can keep
it from sending sensors or from ending. Every pass, and every command, that finds the
plant more than a control period behind the clock is counted (``bench_late``), and the
largest lag is reported: such a run's timing figures are not real time.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import can
from mypy_extensions import mypyc_attr

from bench.results.record import FLUSH_PERIOD_NS
from bench.station.fault_book import Event
from bench.station.plant import STEP_NS
from bench.station.station import Pulse
from bench.wire.timing.classic import frame_bits

if TYPE_CHECKING:
    from bench.node import BenchNode, Clock

NS_PER_S = 1_000_000_000
NS_PER_MS = 1e6
RT_FRAMES_PER_PASS = 64  # realtime: frames read between two steps toward the wall clock
PROGRESS_EVERY_CYCLES = 5  # liveness check and progress line this often


@mypyc_attr(allow_interpreted_subclasses=True)  # tests count the frames it handles
class Realtime:
    """One realtime run of a bench node, paced by ``clock``."""

    def __init__(self, node: BenchNode, clock: Clock) -> None:
        self.node = node
        self.clock = clock
        self.end_ns = 0
        self.fire_ns: int | None = None  # receipt of this cycle's first firing command

    def run(self, duration_s: float) -> None:
        """Wall-clock-paced run of ``duration_s`` seconds (module docstring)."""
        n = self.node
        n.wait_for_fsw()
        # t = 0 is now: the flight software's start-up (0.3 s and more) is no lag of the
        # plant's (it counted as a late step, and the valve watchdog tripped, every run)
        self.clock.restart()
        n.started = True
        n.trace.event(0, "run_started", mode=n.mode, seed=n.seed)
        clock = self.clock
        st, results = n.station, n.results
        results.wall_origin_s = clock.wall0_s
        end_ns = round(duration_s * NS_PER_S)
        self.end_ns = end_ns
        n._realtime_clock = clock
        n._start()
        n._emit_samples(0)
        next_progress = next_flush = 0
        try:  # the run's wall time, also of a run a signal stops
            while st.t_ns < end_ns:
                results.note_lag(clock.now_ns() - st.t_ns, n.period_ns)
                n.integrate_to(min(clock.now_ns(), end_ns) // STEP_NS * STEP_NS)
                wait_s = max(0.0, (st.t_ns + STEP_NS - clock.now_ns()) / NS_PER_S)
                msg = n.bus.recv(timeout=wait_s)
                n_read = 0
                while msg is not None:
                    self.frame(msg)
                    n_read += 1
                    if n_read >= RT_FRAMES_PER_PASS or st.t_ns >= end_ns:
                        break  # back to stepping; the rest stays queued for the next pass
                    msg = n.bus.recv(timeout=0.0)
                if st.t_ns >= next_flush:
                    n.trace.flush()
                    results.flush()
                    next_flush += FLUSH_PERIOD_NS
                if st.t_ns >= next_progress:
                    n.check_fsw_alive()
                    if n.progress is not None:
                        n.progress(st.t_ns / NS_PER_S, duration_s)
                    next_progress += PROGRESS_EVERY_CYCLES * n.period_ns
        finally:
            results.wall_s = clock.now_ns() / NS_PER_S
        n._realtime_clock = None
        n.trace.event(st.t_ns, "run_finished", late_steps=results.late_steps,
                      max_lag_ms=results.max_lag_ns / NS_PER_MS)

    def frame(self, msg: can.Message) -> None:
        """A frame read in realtime: the receive path, then the trace and its effect."""
        n, clock = self.node, self.clock
        st = n.station
        events: list[Event] = []
        arrivals = n.receipt.receive(msg, clock.now_ns(), None)
        n.note_rejects(arrivals, events)
        for a in arrivals:
            if a.fate.drop:
                continue
            t_ns = clock.now_ns()
            tx_wall = getattr(a.msg, "tx_timestamp", None)  # the portable bus: sender's time
            n.trace.frame(
                a.msg, t_ns, tx=False,
                t_ready_ns=float("nan") if tx_wall is None else clock.from_wall_ns(tx_wall),
                t_rx_ns=clock.from_wall_ns(a.msg.timestamp) if a.msg.timestamp > 0 else t_ns,
                bits=frame_bits(a.msg.arbitration_id, bytes(a.msg.data)))
            d = a.decoded
            if d is None:
                continue
            index = n.receipt.command_index(d.name)
            if index is None:
                n._take(d, events)
                continue
            n.results.note_lag(t_ns - st.t_ns, n.period_ns)
            n.integrate_to(min(self.end_ns, max(st.t_ns, t_ns // STEP_NS * STEP_NS)))
            t_apply = max(t_ns, st.t_ns)
            pulses: list[Pulse] = []
            if st.command(index, d.signals, t_apply, pulses):
                self.fire_ns = t_apply if self.fire_ns is None else self.fire_ns
            n.results.add_pulses(pulses)
            st.commanded(t_apply, events)
            st.fsw_silent = False
            n._fsw_heard_wall_ns = clock.now_ns()
            if index == len(n.cmd_frames) - 1:
                n.results.chain(int(d.signals["Cycle"]), int(d.signals["ImuCounter"]), t_ns,
                                self.fire_ns)
                self.fire_ns = None
        n._events(events)
        n._second_sender()

