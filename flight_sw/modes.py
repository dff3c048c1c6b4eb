"""Flight-software modes and FDIR bits, as carried by FSW_STATUS and FSW_FDIR (see the DBC).

``FdirFlag`` bits 0-2 are the DBC's (IMU lost, star tracker lost, safe mode latched); bits
3-7 are added by the FDIR of issue 4 (to be documented in the DBC comment of
FSW_STATUS.FdirFlags): navigation lost (a 6-DoF controller fell back to attitude-only
control), thruster fault detected (a detection is pending or a thruster was isolated),
thruster isolated (the allocator runs with a reduced availability mask), sensor data
rejected as frozen, bench restart seen. ``SensorFlag`` is FSW_FDIR.SensorFlags (4 bits,
as the DBC comment defines them).
"""

from __future__ import annotations

from enum import IntEnum


class Mode(IntEnum):
    """FSW_STATUS.Mode values."""

    BOOT = 0
    NOMINAL = 1
    SAFE = 2


class FdirFlag(IntEnum):
    """FSW_STATUS.FdirFlags bits."""

    IMU_LOST = 0x01
    STR_LOST = 0x02
    SAFE_LATCHED = 0x04
    NAV_LOST = 0x08
    THRUSTER_FAULT_DETECTED = 0x10
    THRUSTER_ISOLATED = 0x20
    SENSOR_FROZEN = 0x40
    BENCH_RESTART = 0x80


class SensorFlag(IntEnum):
    """FSW_FDIR.SensorFlags bits."""

    STR_DEGRADED = 0x1  # star tracker lost or frozen: attitude propagated on the gyro only
    IMU_FROZEN = 0x2
    STR_FROZEN = 0x4
    BENCH_RESTART = 0x8
