"""Flight-software modes and FDIR flag bits, as carried by FSW_STATUS (see the DBC's VAL_ table)."""

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
