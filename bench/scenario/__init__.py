"""Scenarios: TOML files -> a validated, frozen :class:`Scenario` (see bench.scenario.spec).

``spec`` holds the records (pure data, read by every room of the bench), ``parse`` the
validation of TOML data, ``load`` the file reading and ``--set`` overrides. The names
below are imported on first use, so that importing ``bench.scenario.spec`` (as the pure
station does) loads no file-reading module.
"""

from __future__ import annotations

import importlib
from typing import Any

_WHERE = {
    "Scenario": "spec", "CaptureSpec": "spec", "ThrusterSpec": "spec", "ValveSpec": "spec",
    "MassSpec": "spec", "override_source": "spec",
    "parse_scenario": "parse", "quat_from_euler_zyx": "parse",
    "load_scenario": "load", "apply_overrides": "load",
}
__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_WHERE[name]}"), name)
