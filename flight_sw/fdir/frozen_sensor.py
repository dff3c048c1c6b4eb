"""Frozen-sensor detection: a sensor repeating exactly the same payload while its frames advance.

What it does: for each watched message (IMU_RATE, STR_QUAT) it compares the decoded
payload values of every accepted frame with the previous one. The receiver's frame
checker has already rejected repeated alive counters, so an accepted frame is a new
transmission; ``N`` consecutive accepted frames with identical values (N = the message's
``*_samples`` setting) declare the sensor frozen. From then on identical samples are
rejected (the caller ignores them: the estimator does not use them and the sensor
watchdog does not count them as seen, so a frozen IMU ends as a lost IMU, i.e. safe mode,
and a frozen star tracker as a star-tracker outage, i.e. gyro-only propagation). The
first sample whose values differ clears the flag and is accepted.

Inputs: ``check(name, values)`` per accepted frame, ``values`` the tuple of its payload
signals (physical values as decoded; identical raw payloads decode identically).
Outputs: True if the sample is to be ignored; ``frozen(name)``.

Assumptions: a live sensor's output changes within N samples: its noise spans several
LSBs (the quickstart gyro: σ ≈ 1.5 LSB per axis, so three axes repeat by chance with
probability below 1e-2 per sample and 20 in a row essentially never; the star tracker's
25 arcsec about-boresight noise is ≈ 3 LSB of the quaternion encoding). A noise-free
simulated sensor at constant truth looks frozen, as it would to any such monitor.

Sources: "stuck-at" / frozen-value sensor checks of on-board monitoring
(ECSS-E-ST-70-11C; Isermann 2006, "Fault-Diagnosis Systems", Springer (limit and trend
checks); the persistence count is the usual guard against chance repeats.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from dbc import validation as check

_SOURCE = "FrozenSensorParams"
# Fewer than two identical samples cannot show a frozen sensor.
MIN_IDENTICAL_SAMPLES = 2


@dataclass(frozen=True)
class FrozenSensorParams:
    """Identical consecutive samples that declare a sensor frozen.

    Attributes:
        imu_rate_samples: for IMU_RATE (100 Hz), ≥ 2.
        str_quat_samples: for STR_QUAT (10 Hz), ≥ 2.
    """

    imu_rate_samples: int = 20
    str_quat_samples: int = 10

    def __post_init__(self) -> None:
        for key in ("imu_rate_samples", "str_quat_samples"):
            check.integer(_SOURCE, key, getattr(self, key), MIN_IDENTICAL_SAMPLES)

    def by_message(self) -> dict[str, int]:
        """Counts by message name."""
        return {"IMU_RATE": self.imu_rate_samples, "STR_QUAT": self.str_quat_samples}


class FrozenSensorMonitor:
    """Per-message identical-payload counter (see the module docstring)."""

    def __init__(self, samples_by_message: Mapping[str, int]) -> None:
        self._n = dict(samples_by_message)
        self.reset()

    def reset(self) -> None:
        """Forget every sample."""
        self._last: dict[str, tuple[float, ...]] = {}
        self._repeats: dict[str, int] = {}
        self._frozen: dict[str, bool] = {}

    def check(self, name: str, values: tuple[float, ...]) -> bool:
        """Take one accepted sample of ``name``; True if it is frozen data to ignore."""
        n = self._n.get(name)
        if n is None:
            return False
        if self._last.get(name) == values:
            self._repeats[name] = self._repeats.get(name, 0) + 1
        else:
            self._repeats[name] = 0
            self._frozen[name] = False
        self._last[name] = values
        if self._repeats[name] + 1 >= n:
            self._frozen[name] = True
        return self._frozen.get(name, False)

    def frozen(self, name: str) -> bool:
        """True while ``name`` is declared frozen."""
        return self._frozen.get(name, False)
