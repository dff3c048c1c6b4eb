"""The project's error tree: one module, shared by bench, flight software, transport, tools.

    ThrusterHilError              base of every error this project raises on purpose
    ├── ConfigError (ValueError)  a scenario or configuration value is wrong (file, key, value)
    │   └── RefusedConfigError    another process refused its configuration or a command
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
None. A value is shown by :func:`brief`: its ``repr`` when that is short, else its type,
its length and a short prefix (a 5-million-element array or a 100 000-deep nesting makes a
one-line message, not megabytes or a RecursionError).

Frame-level problems on receipt are *not* exceptions: they are counted by cause
(see :mod:`dbc.codec`), because a bad frame must never crash a receiver.
"""

from __future__ import annotations

import reprlib

import can

# Longest value text in a message: a short repr is shown whole, a longer one is cut.
BRIEF_CHARS = 80
BRIEF_ITEMS = 6  # items of a container shown before "..."
BRIEF_LEVELS = 3  # nesting levels shown before "..."
_ELLIPSIS = "..."


def _brief_repr() -> reprlib.Repr:
    """A reprlib that cuts every container, string and number to a few characters."""
    r = reprlib.Repr()
    r.maxlevel = BRIEF_LEVELS
    r.maxtuple = r.maxlist = r.maxarray = r.maxdict = BRIEF_ITEMS
    r.maxset = r.maxfrozenset = r.maxdeque = BRIEF_ITEMS
    r.maxstring = r.maxother = BRIEF_CHARS
    r.maxlong = BRIEF_CHARS
    return r


_BRIEF = _brief_repr()


def brief(value: object) -> str:
    """``repr(value)`` for messages, at most about :data:`BRIEF_CHARS` characters.

    A value whose repr would be longer (or nested deeper than :data:`BRIEF_LEVELS`) is
    shown as its type, its length where it has one, and a cut repr:
    ``list of 5000000 items: [0, 0, 0, 0, 0, 0, ...]``. Never raises, never recurses
    deeper than :data:`BRIEF_LEVELS`, and never builds the whole repr of a large value.
    """
    try:
        if isinstance(value, int) and not isinstance(value, bool):
            digits = value.bit_length() * 0.30103  # log10(2): decimal digits, roughly
            if digits > BRIEF_CHARS:
                return f"int of about {int(digits) + 1} digits"
        text = _BRIEF.repr(value)
    except Exception:  # a value whose repr fails is still named by its type
        return f"<{type(value).__name__}>"
    cut = len(value) > BRIEF_CHARS if isinstance(value, (str, bytes)) else _ELLIPSIS in text
    if len(text) > BRIEF_CHARS:
        text, cut = text[:BRIEF_CHARS] + _ELLIPSIS, True
    if not cut:
        return text
    kind = type(value).__name__
    try:
        size = len(value)  # type: ignore[arg-type]
    except TypeError:
        return f"{kind}: {text}"
    unit = "char" if isinstance(value, (str, bytes)) else "item"
    return f"{kind} of {size} {unit}{'' if size == 1 else 's'}: {text}"


class ThrusterHilError(Exception):
    """Base class of every error raised on purpose by thruster-hil."""


class ConfigError(ThrusterHilError, ValueError):
    """A configuration value is invalid; the message names where it came from."""

    def __init__(self, source: str, key: str, value: object, expected: str) -> None:
        self.source = source
        self.key = key
        self.value = value
        self.expected = expected
        super().__init__(f"{source}: {key} = {brief(value)}: expected {expected}")


class RefusedConfigError(ConfigError):
    """A process refused its configuration (the flight software, saying why) or a command
    (the bench, a live FAULT_CMD: the bus carries only the refusal).

    ``message`` is the process's own error line, which names the file, key and value.
    """

    def __init__(self, who: str, message: str, what: str = "its configuration") -> None:
        """``what`` was refused (default: its configuration; a live fault command's
        refusal names the command)."""
        self.source, self.key, self.value, self.expected = who, "", None, message
        ValueError.__init__(self, f"{who} refused {what}: {message}")


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
