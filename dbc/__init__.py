"""thruster-hil's interface contract: the DBC, its facts, the codec, end-to-end protection.

Modules: ``database`` (the DBC file and its loader), ``icd`` (the facts both sides read
from it: IDs, periods, command layout, value tables), ``codec`` and ``layout`` (frames to
physical values and back, the receive checks), ``e2e`` (CRC-8 and alive counter),
``quaternion`` (the smallest-three encoding), ``schema`` (strict reading of configuration
tables), ``errors`` (the project's error tree). ``load_database`` and ``DBC_PATH`` are
importable from here too; they are loaded on first use, so that a pure module importing
``dbc.icd`` pulls in no file-reading code.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["DBC_PATH", "load_database"]


def __getattr__(name: str) -> Any:
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module("dbc.database"), name)
