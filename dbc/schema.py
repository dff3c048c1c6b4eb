"""Typed, strict reading of config tables: a bad value raises ConfigError(file, key, value, ...).

Shared by the bench (scenario files) and the flight software (its configuration file), so
both report bad values the same way. A :class:`Table` wraps one TOML table with its
file name and dotted path, hands out typed values, and at the end :meth:`Table.done`
rejects any key nobody asked for (so a misspelt key is an error, not a silent default).
Nothing is ever evaluated: values are data only. The checks of a value (finite, in its
range, the length of a vector) are those of :mod:`dbc.validation`, with the file as the
source and the dotted key as the key.
"""

from __future__ import annotations

import difflib
import math
from typing import Any

from dbc import validation as check
from dbc.errors import ConfigError

_MISSING = object()
MATRIX3_ROWS = 3
NEAR_MISS_CUTOFF = 0.75  # difflib similarity above which a present key is suggested
# The integers of a configuration table are counts (samples, cycles), indices, IDs and
# versions: at most this unless the key says otherwise (ten million 20 ms cycles: 55 h;
# a bitrate in bit/s reaches 1e6), so a count of 10**12 is refused, not allocated.
MAX_TABLE_INTEGER = 10**7


class Table:
    """One TOML table, read strictly."""

    def __init__(self, data: Any, source: str, path: str = "") -> None:
        if not isinstance(data, dict):
            raise ConfigError(source, path or "<root>", data, "a table")
        self._data = data
        self._source = source
        self._path = path
        self._used: set[str] = set()  # read: accepted by done()
        self._known: set[str] = set()  # asked for, read or not: what done() lists

    def _key(self, key: str) -> str:
        return f"{self._path}.{key}" if self._path else key

    def dotted(self, key: str) -> str:
        """The dotted key of ``key`` in this table, as errors name it (``vehicle.mass_kg``)."""
        return self._key(key)

    def error(self, key: str, value: object, expected: str) -> ConfigError:
        """A ConfigError for ``key`` of this table."""
        return ConfigError(self._source, self._key(key), value, expected)

    def has(self, key: str) -> bool:
        """True if ``key`` is present (an optional key: :meth:`done` lists it as one this
        table takes, and accepts it only if it is then read)."""
        self._known.add(key)
        return key in self._data

    def raw(self, key: str, default: Any = _MISSING) -> Any:
        """The raw value of ``key`` (required unless ``default`` is given)."""
        self._used.add(key)
        self._known.add(key)
        if key not in self._data:
            if default is _MISSING:
                # a near miss among the keys nobody has read yet (a read one is not a typo)
                spare = [str(k) for k in self._data if k not in self._used]
                near = difflib.get_close_matches(key, spare, n=1, cutoff=NEAR_MISS_CUTOFF)
                hint = f"; found {near[0]!r}: misspelt?" if near else ""
                raise self.error(key, None, f"a value (key is required{hint})")
            return default
        return self._data[key]

    def number(
        self,
        key: str,
        default: Any = _MISSING,
        *,
        lo: float | None = None,
        hi: float | None = None,
        lo_open: bool = False,
    ) -> float:
        """A finite real number in [lo, hi] (or (lo, hi] with ``lo_open``)."""
        v = self.raw(key, default)
        return check.number(self._source, self._key(key), v, _lo(lo), _hi(hi), lo_open=lo_open)

    def integer(self, key: str, default: Any = _MISSING, *, lo: int | None = None,
                hi: int = MAX_TABLE_INTEGER) -> int:
        """An integer in [lo, hi] (``hi``: :data:`MAX_TABLE_INTEGER` unless given)."""
        return check.integer(self._source, self._key(key), self.raw(key, default), lo, hi)

    def flag(self, key: str, default: Any = _MISSING) -> bool:
        """A bool (``true`` or ``false``)."""
        return check.flag(self._source, self._key(key), self.raw(key, default))

    def string(self, key: str, default: Any = _MISSING, *, choices: tuple[str, ...] = ()) -> str:
        """A string, one of ``choices`` if given."""
        v = self.raw(key, default)
        if not isinstance(v, str):
            raise self.error(key, v, "a string")
        if choices and v not in choices:
            raise self.error(key, v, "one of " + ", ".join(repr(c) for c in choices))
        return v

    def vector(
        self,
        key: str,
        n: int,
        default: Any = _MISSING,
        *,
        lo: float | None = None,
        hi: float | None = None,
        lo_open: bool = False,
    ) -> tuple[float, ...]:
        """A list of ``n`` finite numbers, each in [lo, hi] (or (lo, hi] with ``lo_open``)
        when those are given."""
        v = self.raw(key, default)
        return check.vector(self._source, self._key(key), v, n, _lo(lo), _hi(hi),
                            lo_open=lo_open)

    def unit_vector(self, key: str, n: int, default: Any = _MISSING) -> tuple[float, ...]:
        """A list of ``n`` finite numbers of Euclidean norm 1 (within
        :data:`dbc.validation.UNIT_NORM_TOL`; not renormalised)."""
        return check.unit_vector(self._source, self._key(key), self.raw(key, default), n)

    def vector3(self, key: str, default: Any = _MISSING) -> tuple[float, float, float]:
        """A list of 3 finite numbers."""
        x, y, z = self.vector(key, 3, default)
        return (x, y, z)

    def vector4(self, key: str, default: Any = _MISSING) -> tuple[float, float, float, float]:
        """A list of 4 finite numbers."""
        a, b, c, d = self.vector(key, 4, default)
        return (a, b, c, d)

    def matrix3(self, key: str) -> tuple[tuple[float, float, float], ...]:
        """A 3x3 list of lists of finite numbers (a bad row is named by its index)."""
        v = self.raw(key)
        if not isinstance(v, list) or len(v) != MATRIX3_ROWS:
            raise self.error(key, v, "a 3x3 matrix (list of three lists of three numbers)")
        return tuple(
            check.triple(self._source, f"{self._key(key)}[{i}]", row) for i, row in enumerate(v)
        )

    def table(self, key: str, default: Any = _MISSING) -> Table:
        """Sub-table ``key`` (an empty one if absent and ``default`` is given)."""
        v = self.raw(key, default)
        return Table({} if v is None else v, self._source, self._key(key))

    def tables(self, key: str) -> list[Table]:
        """Array of tables ``key`` (empty if absent)."""
        v = self.raw(key, [])
        if not isinstance(v, list):
            raise self.error(key, v, "an array of tables ([[...]])")
        return [Table(x, self._source, f"{self._key(key)}[{i}]") for i, x in enumerate(v)]

    def done(self) -> None:
        """Reject keys that were never read (misspelt or unsupported).

        The error lists the keys this table takes (those its reader asked for), so a key
        that belongs to another ``kind`` reads as such, and suggests a near miss.
        """
        extra = sorted(set(self._data) - self._used)
        if extra:
            key = extra[0]
            # the keys read, and the optional ones asked for that are absent (a key present
            # but left unread here is not one this table takes)
            takes = sorted(self._used | {k for k in self._known if k not in self._data})
            near = difflib.get_close_matches(str(key), takes, n=1, cutoff=NEAR_MISS_CUTOFF)
            hint = f"did you mean {near[0]!r}? " if near else ""
            known = ", ".join(takes) or "no keys"
            raise self.error(key, self._data[key], f"no such key here ({hint}this table "
                             f"takes: {known})")

    @property
    def source(self) -> str:
        """File this table came from."""
        return self._source

    @property
    def path(self) -> str:
        """Dotted path of this table."""
        return self._path


def _lo(lo: float | None) -> float:
    """A lower bound, None meaning none."""
    return -math.inf if lo is None else lo


def _hi(hi: float | None) -> float:
    """An upper bound, None meaning none."""
    return math.inf if hi is None else hi
