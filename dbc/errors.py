"""The project's error tree: one module, shared by bench, flight software and tools.

    ThrusterHilError            base of every error this project raises on purpose
    ├── ConfigError             a scenario or configuration value is wrong (file, key, value)
    │   └── RefusedConfigError  another process refused its configuration (its own message)
    ├── IcdError                the DBC is unusable or a frame cannot be encoded from it
    ├── BusError                a bus spec is wrong or a bus cannot be opened / used
    └── RunError                a run could not start or complete (a process failed, a stall)

Frame-level problems on receipt are *not* exceptions: they are counted by cause
(see :mod:`dbc.codec`), because a bad frame must never crash a receiver.
"""

from __future__ import annotations


class ThrusterHilError(Exception):
    """Base class of every error raised on purpose by thruster-hil."""


class ConfigError(ThrusterHilError, ValueError):
    """A configuration value is invalid; the message names where it came from."""

    def __init__(self, source: str, key: str, value: object, expected: str) -> None:
        self.source = source
        self.key = key
        self.value = value
        self.expected = expected
        super().__init__(f"{source}: {key} = {value!r}: expected {expected}")


class RefusedConfigError(ConfigError):
    """A child process (the flight software) refused its configuration and said why.

    ``message`` is the process's own error line, which names the file, key and value.
    """

    def __init__(self, who: str, message: str) -> None:
        self.source, self.key, self.value, self.expected = who, "", None, message
        ValueError.__init__(self, f"{who} refused its configuration: {message}")


class IcdError(ThrusterHilError):
    """The interface control document (DBC) is missing, malformed, or misused."""


class BusError(ThrusterHilError):
    """A bus spec is malformed or the bus cannot be opened."""


class RunError(ThrusterHilError):
    """A run could not be started or finished."""
