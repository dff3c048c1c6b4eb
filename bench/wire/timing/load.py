"""Bus load from deliveries: busy time and busy fraction per window, per node, mean and peak.

In: :class:`~bench.wire.timing.arbiter.Delivery` records (every interval each frame, its
failed attempts and error frames held the bus), a window length and an interval [t0, t1).
Out: (window start, busy ns) or (window start, busy fraction 0..1) per window tiling the
interval, the same per transmitting node, or (mean, peak) load.

Units. Times in integer nanoseconds; loads are fractions 0..1 of a window's own length
(the last window may be shorter).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from bench.wire.timing.arbiter import Delivery


def _window_starts(window_ns: int, t0_ns: int, t1_ns: int) -> range:
    if window_ns <= 0:
        raise ValueError(f"window_ns={window_ns}: must be positive")
    if t1_ns <= t0_ns:
        raise ValueError(f"[{t0_ns}, {t1_ns}): empty interval")
    return range(t0_ns, t1_ns, window_ns)


def busy_ns_per_window(
    deliveries: Iterable[Delivery], window_ns: int, t0_ns: int, t1_ns: int
) -> list[tuple[int, int]]:
    """(window start, ns the bus was held) for windows of ``window_ns`` tiling [t0, t1).

    Busy = every interval of :meth:`Delivery.busy_intervals` (failed attempts and error
    frames included), clipped to the window; the last window ends at ``t1_ns``.
    """
    starts = _window_starts(window_ns, t0_ns, t1_ns)
    busy = [0] * len(starts)
    for d in deliveries:
        for a, b in d.busy_intervals():
            a, b = max(a, t0_ns), min(b, t1_ns)
            k = (a - t0_ns) // window_ns
            while a < b:
                seg_end = min(b, t0_ns + (k + 1) * window_ns)
                busy[k] += seg_end - a
                a, k = seg_end, k + 1
    return list(zip(starts, busy, strict=True))


def load_per_window(
    deliveries: Iterable[Delivery], window_ns: int, t0_ns: int, t1_ns: int
) -> list[tuple[int, float]]:
    """(window start, busy fraction 0..1) for windows of ``window_ns`` tiling [t0, t1).

    The fraction of a last, shorter window is relative to its own length.
    """
    return [
        (start, busy / (min(start + window_ns, t1_ns) - start))
        for start, busy in busy_ns_per_window(deliveries, window_ns, t0_ns, t1_ns)
    ]


def load_per_window_by_node(
    deliveries: Iterable[Delivery],
    window_ns: int,
    t0_ns: int,
    t1_ns: int,
    node_of: Mapping[int, str] | None = None,
) -> dict[str, list[tuple[int, float]]]:
    """:func:`load_per_window` per transmitting node.

    The node of a delivery is ``node_of[seq]`` if given, else ``Delivery.node``. A frame's
    failed attempts and error frames count for its transmitter.
    """
    by_node: dict[str, list[Delivery]] = {}
    for d in deliveries:
        name = node_of[d.seq] if node_of is not None else d.node
        by_node.setdefault(name, []).append(d)
    return {name: load_per_window(ds, window_ns, t0_ns, t1_ns) for name, ds in by_node.items()}


def mean_peak_load(
    deliveries: Iterable[Delivery], window_ns: int, t0_ns: int, t1_ns: int
) -> tuple[float, float]:
    """(mean load over [t0, t1), peak load of a ``window_ns`` window)."""
    windows = busy_ns_per_window(deliveries, window_ns, t0_ns, t1_ns)
    mean = sum(busy for _, busy in windows) / (t1_ns - t0_ns)
    peak = max(busy / (min(start + window_ns, t1_ns) - start) for start, busy in windows)
    return mean, peak
