"""hilbus under threads: senders in several threads while a can.Notifier receives.

A send that waits for a full receiver must never touch what a receiving thread waits on
(python-can allows ``send`` from several threads and ``recv`` from one, e.g. a Notifier's,
at the same time). Waits are bounded by deadlines on real events.
"""

from __future__ import annotations

import threading
import time
from collections import defaultdict

import can
import pytest

from tests.transport.helpers import DEADLINE_S
from transport.hilbus import HilBus

SENDER_THREADS = 4  # on member A, whose Notifier thread is blocked receiving meanwhile
COMPETING_MEMBERS = 3  # other members sending to the same slow reader
FRAMES_PER_SENDER = 100
# how long the slow reader takes per frame: the stimulus that keeps its queue full, so
# that senders wait for room and compete for each slot it frees
READ_DELAY_S = 0.001
SEQ_BYTES = 2
RECV_WAIT_S = 0.5  # a reader's wait for the next frame before it checks the senders


class _Recorder(can.Listener):
    """A Notifier listener that keeps what arrives and every error of the receive thread."""

    def __init__(self) -> None:
        self.errors: list[BaseException] = []
        self.received = 0

    def on_message_received(self, msg: can.Message) -> None:
        self.received += 1

    def on_error(self, exc: Exception) -> None:
        self.errors.append(exc)


@pytest.mark.slow
def test_senders_in_threads_beside_a_notifier_lose_nothing_and_raise_nothing(
    channel: str,
) -> None:
    """Several threads send on A while A's Notifier receives and other members compete for
    a slow reader B: no send or receive raises, and B gets every frame of every sender in
    its order."""
    errors: list[BaseException] = []
    recorder = _Recorder()
    with HilBus(channel) as a, HilBus(channel) as b:
        others = [HilBus(channel) for _ in range(COMPETING_MEMBERS)]
        notifier = can.Notifier(a, [recorder], timeout=0.05)
        try:

            def send_all(bus: HilBus, ident: int) -> None:
                try:
                    for i in range(FRAMES_PER_SENDER):
                        data = i.to_bytes(SEQ_BYTES, "little")
                        bus.send(can.Message(arbitration_id=ident, data=data), timeout=DEADLINE_S)
                except BaseException as exc:  # inspected below
                    errors.append(exc)

            senders = [(a, k) for k in range(SENDER_THREADS)]
            senders += [(o, SENDER_THREADS + j) for j, o in enumerate(others)]
            threads = [
                threading.Thread(target=send_all, args=sender, daemon=True) for sender in senders
            ]
            for t in threads:
                t.start()
            got = _read_slowly(b, len(senders) * FRAMES_PER_SENDER, threads)
            for t in threads:
                t.join(DEADLINE_S)
                assert not t.is_alive(), "a sender thread is still blocked"
            assert b.recv(timeout=0) is None
        finally:
            notifier.stop()
            for o in others:
                o.shutdown()
    assert not errors, f"{len(errors)} sends raised, e.g. {errors[0]!r}"
    assert not recorder.errors, f"the Notifier's receive raised {recorder.errors[0]!r}"
    per_sender: dict[int, list[int]] = defaultdict(list)
    for m in got:
        per_sender[m.arbitration_id].append(int.from_bytes(m.data, "little"))
    assert per_sender == {ident: list(range(FRAMES_PER_SENDER)) for _b, ident in senders}


def _read_slowly(bus: HilBus, n: int, senders: list[threading.Thread]) -> list[can.Message]:
    """Up to n frames, READ_DELAY_S after each; stops early once every sender has ended
    and nothing more arrives (a sender that raised sent less)."""
    got: list[can.Message] = []
    deadline = time.monotonic() + DEADLINE_S
    while len(got) < n and time.monotonic() < deadline:
        m = bus.recv(timeout=RECV_WAIT_S)
        if m is not None:
            got.append(m)
            time.sleep(READ_DELAY_S)  # the slow reader (see READ_DELAY_S)
        elif not any(t.is_alive() for t in senders):
            break
    return got
