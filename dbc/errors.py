"""The project's error tree: one module, shared by bench, flight software, transport, tools.

    ThrusterHilError              base of every error this project raises on purpose
    ├── ConfigError (ValueError)  a scenario or configuration value is wrong (file, key, value)
    │   └── RefusedConfigError    another process refused its configuration (its own message)
    ├── IcdError                  the DBC is unusable or a frame cannot be encoded from it
    ├── BusError                  a bus spec is malformed; base of the bus errors below
    │   ├── BusInitError          a bus cannot be opened      (can.CanInitializationError)
    │   │   └── BusArgumentError  ... an argument is out of range (also ValueError)
    │   └── BusOperationError     a send or receive failed, or the bus refused a frame or a
    │       │                     setting                     (can.CanOperationError)
    │       └── BusTimeoutError   a send did not complete in its timeout (can.CanTimeoutError)
    └── RunError                  a run could not start or complete (a process failed, a stall)

The bus errors are python-can errors too (the classes in parentheses, whose documented
meaning they have: python-can's ``exceptions.py``), so code written for any python-can bus
catches hilbus's failures with ``except can.CanError`` (or the specific class), while the
project's command-line tools catch ``BusError`` and exit 2 naming the bus. python-can asks
for ValueError where a constructor argument is out of range, hence BusArgumentError.
Messages carry the cause and the bus or path concerned; python-can's ``error_code`` is
None.

Frame-level problems on receipt are *not* exceptions: they are counted by cause
(see :mod:`dbc.codec`), because a bad frame must never crash a receiver.
"""

from __future__ import annotations

import can


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
    """A bus spec is malformed; the base class of every bus error of the project."""


class BusInitError(BusError, can.CanInitializationError):
    """A bus cannot be opened (a directory, a socket, a driver); names the bus or path."""


class BusArgumentError(BusInitError, ValueError):
    """A bus cannot be opened because an argument is out of range (a channel name, a
    stall time); names the argument and its value."""


class BusOperationError(BusError, can.CanOperationError):
    """An operation on an open bus failed or was refused: a send or a receive (also after
    shutdown), a frame that cannot exist, a state the bus does not support."""


class BusTimeoutError(BusOperationError, can.CanTimeoutError):
    """A send did not complete within its timeout (a member is not reading); the frame may
    have reached some members."""


class RunError(ThrusterHilError):
    """A run could not be started or finished."""
