"""Quaternion <-> signals of STR_QUAT and FSW_ATT_EST ("smallest three" encoding).

A unit quaternion q_BN (scalar first) is carried as: the index (0..3) of its largest-
magnitude component, which is omitted, and the other three components in index order,
signed as for a positive largest component (q and -q are the same rotation). Those three
are bounded by 1/sqrt(2), so 16 bits each at LSB 2.16e-5 bound the quantisation error to
9.5 arcsec per axis at every attitude (median 4.8 arcsec total; measured over 50 000 random
attitudes), and the reconstruction ``largest = sqrt(1 - c0^2 - c1^2 - c2^2)`` is well
conditioned (largest >= 1/2). Dropping q0 instead (17 bits for q1..q3) gives 3.2 arcsec
near identity but loses 0.4 deg near 180 deg rotations, where sqrt() is ill-conditioned:
the 52 payload bits of a classic frame cannot give <= 5 arcsec everywhere.
Pure functions; the DBC holds the scaling (cantools applies it).
"""

from __future__ import annotations

import math

SIGNALS = ("C0", "C1", "C2")
C_MAX = 0.7077672  # DBC maximum of C0..C2 (raw 32767)


def pack_quaternion(q: tuple[float, float, float, float] | list[float]) -> dict[str, float | int]:
    """Signals Largest, C0, C1, C2 for the unit quaternion ``q``."""
    mags = [abs(x) for x in q]
    big = mags.index(max(mags))
    sign = 1.0 if q[big] >= 0 else -1.0
    rest = [sign * q[i] for i in range(4) if i != big]
    out: dict[str, float | int] = {"Largest": big}
    for name, c in zip(SIGNALS, rest, strict=True):
        out[name] = min(C_MAX, max(-C_MAX, c))
    return out


def unpack_quaternion(signals: dict[str, float]) -> tuple[float, float, float, float]:
    """The unit quaternion carried by ``signals`` (scalar first, largest component >= 0)."""
    rest = [float(signals[n]) for n in SIGNALS]
    big = int(signals["Largest"])
    # explicit left-to-right sums: sum() of floats is compensated from Python 3.12, and a
    # trace must not depend on the Python version
    largest = math.sqrt(max(0.0, 1.0 - (rest[0] * rest[0] + rest[1] * rest[1]
                                          + rest[2] * rest[2])))
    q = rest[:big] + [largest] + rest[big:]
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)
