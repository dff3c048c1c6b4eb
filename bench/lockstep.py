"""The lockstep loop of the bench node (DESIGN §5): the bench is the time master.

Per control cycle k: the samples of (t_{k-1}, t_k] and SYNC(k) go out together; while the
flight software computes, the station integrates up to the earliest moment its answer can
arrive and the wire writes what it has resolved; every frame read goes through the
receive path (bench.wire.receipt, with the awaited cycle); the commands taken are
delivered to the valves at their modelled arrival (response delay, arbitration, exact
frame length); the station integrates to t_{k+1}. The wall time of each part (before
SYNC, meanwhile, the wait, after the commands) goes into summary.json's
``lockstep_wall_us``. A missing answer within
``stall_timeout_s`` of wall time is a counted stall (its event names the missing frames);
after ``SILENT_AFTER_STALLS`` in a row the flight software is declared silent and the
bench stops waiting for it (never hangs). Deterministic: the same scenario and seed give
the same trace, whatever the wall-clock speed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bench.results.record import FLUSH_PERIOD_NS
from bench.station.fault_book import Event
from bench.station.plant import STEP_NS
from bench.station.station import Pulse
from bench.wire.receipt import Arrival
from dbc.icd import BENCH
from transport.lockstep import recv_spinning

if TYPE_CHECKING:
    from bench.node import BenchNode

NS_PER_S = 1_000_000_000
PROGRESS_EVERY_CYCLES = 5  # the progress line is updated this often
SILENT_AFTER_STALLS = 3


class Lockstep:
    """One lockstep run of a bench node."""

    def __init__(self, node: BenchNode) -> None:
        self.node = node
        #: cycles between two flushes of the run files (FLUSH_PERIOD_NS, at least one)
        self.flush_every = max(1, FLUSH_PERIOD_NS // node.period_ns)
        self.consecutive_stalls = 0
        # wall-clock marks of the current cycle [ns, the node's clock]: SYNC handed over,
        # the wait for the answer ended (the per-cycle split in summary.json)
        self.synced_ns = 0
        self.answered_ns = 0

    def run(self, duration_s: float) -> None:
        """Lockstep run of ``duration_s`` simulated seconds."""
        n = self.node
        period = n.period_ns
        n_cycles = round(duration_s * NS_PER_S / period)
        n.last_sync_ns = (n_cycles - 1) * period
        delay_ns = round(n.sc.bus.fsw_response_delay_s * NS_PER_S)
        n.wait_for_fsw()
        n.started = True
        n.trace.event(0, "run_started", mode=n.mode, seed=n.seed, cycles=n_cycles)
        clock, wire, results = n.clock, n.wire, n.results
        results.lockstep_spin_s = n.lockstep_spin_s
        wall0 = clock.now_ns()
        try:  # the loop's wall time, also of a run a signal stops
            n._start()
            for k in range(n_cycles):
                t_k = k * period
                cycle_wall0 = clock.now_ns()
                n._emit_samples(t_k)
                # SYNC closes the samples of (t_{k-1}, t_k]: it is queued once they are through,
                # and the flight software's cycle starts when SYNC has arrived.
                wire.flush()
                n._send("SYNC", {"Cycle": k, "SimTime": t_k / NS_PER_S},
                        max(t_k, wire.last_rx_ns))
                wire.release()
                wire.flush()
                self.synced_ns = clock.now_ns()
                self._collect(k, wire.last_rx_ns + delay_ns, duration_s)
                n.integrate_to(t_k + period)
                cycle_wall1 = clock.now_ns()
                results.cycle_wall_ns.add(cycle_wall1 - cycle_wall0)
                results.before_sync_ns.add(self.synced_ns - cycle_wall0)
                results.after_commands_ns.add(cycle_wall1 - self.answered_ns)
            wire.release()
            wire.flush()
            n._samples.clear()
        finally:
            results.wall_s = (clock.now_ns() - wall0) / NS_PER_S
        n.trace.event(n.station.t_ns, "run_finished", stalls=results.stalls)

    def _collect(self, k: int, ready_ns: int, duration_s: float) -> None:
        """Receive cycle k's commands and deliver them at their modelled arrival."""
        n = self.node
        st, wire, results = n.station, n.wire, n.results
        # While the flight software computes: integrate the steps that end before its
        # frames can arrive, and record the bench's own frames already on the wire.
        n.integrate_to(max(st.t_ns, ready_ns // STEP_NS * STEP_NS))
        wire.flush(ready_ns)
        wire.babble(k * n.period_ns, (k + 1) * n.period_ns)
        wire.release()  # delayed frames released meanwhile
        n.trace.write_pending()
        results.write_pending()
        if k % self.flush_every == 0:
            n.trace.flush()
            results.flush()
        if k % PROGRESS_EVERY_CYCLES == 0 and n.progress is not None:
            n.progress(k * n.period_ns / NS_PER_S, duration_s)
        n.check_fsw_alive()  # here, not after the cycle: its poll is off the critical path
        got: list[tuple[int, int, dict[str, float], int]] = []  # (frame, seq, signals, delay)
        lost = 0  # command frames that injected faults kept from the bench this cycle
        fsw_dead = n.fsw_exit_ns is not None
        timeout_ns = (0 if (st.fsw_silent or fsw_dead)
                      else round(n.sc.bus.stall_timeout_s * NS_PER_S))
        wait0 = n.clock.now_ns()
        results.meanwhile_ns.add(wait0 - self.synced_ns)
        deadline = wait0 + timeout_ns
        imu_counter: int | None = None
        want = len(n.cmd_frames)
        events: list[Event] = []
        while len(got) + lost < want:
            left_s = max(0.0, (deadline - n.clock.now_ns()) / NS_PER_S)
            msg = recv_spinning(n.bus, left_s, n.lockstep_spin_s)
            if msg is None:
                break
            arrivals = n.receipt.receive(msg, n.clock.now_ns(), k)
            n.note_rejects(arrivals, events)
            for a in arrivals:
                is_cmd = a.name is not None and n.receipt.command_index(a.name) is not None
                if a.fate.drop:
                    lost += is_cmd
                    continue
                seq = self._onto_wire(a, ready_ns)
                lost += is_cmd and a.injected_loss
                d = a.decoded
                if d is None:
                    continue
                index = n.receipt.command_index(d.name)
                if index is not None:
                    got.append((index, seq, d.signals, a.fate.delay_ns))
                    imu_counter = int(d.signals["ImuCounter"])
                else:
                    n._take(d, events)
            if events:
                n._events(events)
                events = []
        n._second_sender()
        self.answered_ns = n.clock.now_ns()
        results.fsw_wait_ns.add(self.answered_ns - wait0)
        rx = wire.flush(ready_ns + n.period_ns)
        if any(g[1] not in rx for g in got):  # a congested wire: resolve what is left
            rx.update(wire.flush())
        self._stall_bookkeeping(k, len(got) + lost < want, got)
        if not got:
            return
        t_last = 0
        t_fire: int | None = None
        pulses: list[Pulse] = []
        for index, seq, s, delay_ns in sorted(got, key=lambda g: (g[0], g[1])):
            t_rx = rx[seq] + delay_ns
            t_last = max(t_last, t_rx)
            if st.command(index, s, t_rx, pulses) and (t_fire is None or t_rx < t_fire):
                t_fire = t_rx
        results.add_pulses(pulses)
        st.commanded(t_last, events)
        n._events(events)
        if imu_counter is not None:
            results.chain(k, imu_counter, t_last, t_fire)

    def _onto_wire(self, a: Arrival, ready_ns: int) -> int:
        """Lockstep: a received copy goes onto the modelled wire (a frame that passed the
        checks, or one an injected bus fault spoiled; -1 otherwise: trace only, so garbage
        on the bus cannot shift a lockstep run)."""
        n = self.node
        faulted = a.fate.corrupt_bit is not None or a.fate.duplicate
        sender = n.icd.sender[a.name] if a.name is not None else ""
        if a.name is not None and sender != BENCH and (a.passed_checks or faulted):
            return n.wire.received(a.msg, ready_ns, sender, a.fate)
        n.wire.received_off_wire(a.msg, ready_ns)
        return -1

    def _stall_bookkeeping(self, k: int, stalled: bool,
                           got: list[tuple[int, int, dict[str, float], int]]) -> None:
        """Count a stall (naming the missing frames), declare the flight software silent
        after ``SILENT_AFTER_STALLS`` in a row, and back when it answers again."""
        n = self.node
        st, results = n.station, n.results
        t_ns = k * n.period_ns
        if stalled:
            results.stalls += 1
            self.consecutive_stalls += 1
            if not st.fsw_silent:
                have = {g[0] for g in got}
                missing = [name for i, name in enumerate(n.cmd_frames) if i not in have]
                n.trace.event(t_ns, "stall", cycle=k, frames=len(got), missing=missing)
            if self.consecutive_stalls >= SILENT_AFTER_STALLS and not st.fsw_silent:
                st.fsw_silent = True
                n.trace.event(t_ns, "fsw_silent", cycle=k)
        else:
            if st.fsw_silent:
                n.trace.event(t_ns, "fsw_back", cycle=k)
            self.consecutive_stalls = 0
            st.fsw_silent = False

