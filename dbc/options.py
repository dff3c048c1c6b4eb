"""Command-line options checked at the edge, the same way by every tool of both sides.

What it does: :class:`StrictParser` is an ``argparse.ArgumentParser`` whose every error is
one line on stderr and exit code 2 (no usage block, no traceback, a long value cut); the
converters below are argparse ``type=`` functions that turn an option's text into a
checked value or refuse it with the words of :class:`dbc.errors.ConfigError`
(``command line: --seed = '-1': expected an integer in [0, 9223372036854775807]``):

- :func:`number`: a finite real number in an interval (``inf``, ``nan``, ``1e400`` and
  words are refused);
- :func:`integer`: an integer in an interval, decimal or with a base prefix (``0x40``);
- :func:`choice`: one of a fixed set of words;
- :func:`text`: a non-empty string (a path, a command).

Bounds may be given as zero-argument callables, evaluated only when the option is given
(a bound read from the DBC costs nothing for ``--help``). Used by ``thruster-hil`` (every
subcommand), ``thruster-hil campaign`` and the flight software's ``python -m flight_sw``;
bus specs are checked by :func:`transport.spec.check_bus_spec`.

Inputs: the option's text. Outputs: float, int or str. Units: those of the option (in
its help text and in ``unit``). Source: project convention (issue 19, strict input).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Iterable
from typing import NoReturn

from dbc import validation as check
from dbc.errors import BRIEF_CHARS, ConfigError

SOURCE = "command line"
EXIT_BAD_INPUT = 2
# An argparse message longer than this is cut (it may quote a 100 kB argument).
MAX_MESSAGE_CHARS = 4 * BRIEF_CHARS

Bound = float | Callable[[], float]
IntBound = int | Callable[[], int] | None


class StrictParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line (``PREFIX: error: ...``) and exit 2.

    ``error_prefix``: the word before ``error:`` (default: the first word of ``prog``, so
    a subcommand's errors read like the tool's own).
    """

    def __init__(self, *args: object, error_prefix: str | None = None,
                 **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.error_prefix = error_prefix

    def error(self, message: str) -> NoReturn:
        """Print ``message`` as one line and exit 2 (argparse calls this on bad input)."""
        head, _, rest = message.partition(": ")
        if head.startswith("argument ") and rest.startswith(f"{SOURCE}: "):
            message = rest  # a converter's message: it names the option, its value is brief
        else:  # argparse's own (it may quote a whole argument): one line, cut
            message = " ".join(message.split())
            if len(message) > MAX_MESSAGE_CHARS:
                message = message[:MAX_MESSAGE_CHARS] + "..."
        prefix = self.error_prefix or self.prog.split()[0]
        self.exit(EXIT_BAD_INPUT, f"{prefix}: error: {message}\n")


def parse_or_exit_code(parser: argparse.ArgumentParser,
                       argv: list[str] | None) -> argparse.Namespace | int:
    """``parser.parse_args(argv)``, or the exit code argparse chose (2 after a one-line
    error, 0 after ``--help``), so that a ``main(argv)`` returns it instead of raising."""
    try:
        return parser.parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT


def _value(bound: Bound | IntBound) -> float | int | None:
    return bound() if callable(bound) else bound


def _refuse(option: str, text: str, expected: str) -> NoReturn:
    raise argparse.ArgumentTypeError(str(ConfigError(SOURCE, option, text, expected)))


def number(option: str, lo: Bound = -math.inf, hi: Bound = math.inf, *,
           lo_open: bool = False, hi_open: bool = False,
           unit: str = "") -> Callable[[str], float]:
    """A converter: a finite real number in [lo, hi] (a bound excluded with ``*_open``)."""

    def convert(text: str) -> float:
        low, high = float(_value(lo) or 0.0), float(_value(hi) or 0.0)
        try:
            x = float(text)
        except ValueError:
            x = math.nan
        try:
            return check.number(SOURCE, option, x, low, high, lo_open=lo_open,
                                hi_open=hi_open, unit=unit)
        except ConfigError as exc:
            _refuse(option, text, exc.expected)

    convert.__name__ = option
    return convert


def integer(option: str, lo: IntBound = None, hi: IntBound = None) -> Callable[[str], int]:
    """A converter: an integer in [lo, hi], decimal (``007`` too) or ``0x``/``0o``/``0b``."""

    def convert(text: str) -> int:
        low, high = _value(lo), _value(hi)
        expected = check.integer_range(None if low is None else int(low),
                                       None if high is None else int(high))
        n: int | None = None
        for base in (10, 0):
            try:
                n = int(text, base)
                break
            except ValueError:  # also an integer of more digits than Python converts
                continue
        if n is None or (low is not None and n < low) or (high is not None and n > high):
            _refuse(option, text, expected)
        return n

    convert.__name__ = option
    return convert


def choice(option: str, choices: Iterable[str]) -> Callable[[str], str]:
    """A converter: one of ``choices``."""
    allowed = tuple(choices)

    def convert(text: str) -> str:
        if text not in allowed:
            _refuse(option, text, "one of " + ", ".join(allowed))
        return text

    convert.__name__ = option
    return convert


def text(option: str, what: str = "a non-empty value") -> Callable[[str], str]:
    """A converter: a non-empty string (``what`` says what it is, for the message)."""

    def convert(value: str) -> str:
        if not value.strip():
            _refuse(option, value, what)
        return value

    convert.__name__ = option
    return convert


def refuse(option: str, value: object, expected: str) -> NoReturn:
    """Raise the ConfigError of an option whose value is wrong in context (after parsing)."""
    raise ConfigError(SOURCE, option, value, expected)


def checked(option: str, check_text: Callable[[str], object]) -> Callable[[str], str]:
    """A converter from a check that raises ConfigError: the text, or the check's refusal."""

    def convert(value: str) -> str:
        try:
            check_text(value)
        except ConfigError as exc:
            _refuse(option, value, exc.expected)
        return value

    convert.__name__ = option
    return convert
