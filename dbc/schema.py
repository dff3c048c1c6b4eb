"""Typed, strict reading of config tables: a bad value raises ConfigError(file, key, value, ...).

Shared by the bench (scenario files) and the flight software (its configuration file), so
both report bad values the same way. A :class:`Table` wraps one TOML table with its
file name and dotted path, hands out typed values, and at the end :meth:`Table.done`
rejects any key nobody asked for (so a misspelt key is an error, not a silent default).
Nothing is ever evaluated: values are data only.
"""

from __future__ import annotations

import difflib
import math
from typing import Any

from dbc.errors import ConfigError

_MISSING = object()
NEAR_MISS_CUTOFF = 0.75  # difflib similarity above which a present key is suggested


class Table:
    """One TOML table, read strictly."""

    def __init__(self, data: Any, source: str, path: str = "") -> None:
        if not isinstance(data, dict):
            raise ConfigError(source, path or "<root>", data, "a table")
        self._data = data
        self._source = source
        self._path = path
        self._used: set[str] = set()

    def _key(self, key: str) -> str:
        return f"{self._path}.{key}" if self._path else key

    def error(self, key: str, value: object, expected: str) -> ConfigError:
        """A ConfigError for ``key`` of this table."""
        return ConfigError(self._source, self._key(key), value, expected)

    def has(self, key: str) -> bool:
        """True if ``key`` is present."""
        return key in self._data

    def raw(self, key: str, default: Any = _MISSING) -> Any:
        """The raw value of ``key`` (required unless ``default`` is given)."""
        self._used.add(key)
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
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise self.error(key, v, "a finite number")
        if lo is not None and (v < lo or (lo_open and v == lo)):
            raise self.error(key, v, f"a number {'>' if lo_open else '>='} {lo}")
        if hi is not None and v > hi:
            raise self.error(key, v, f"a number <= {hi}")
        return float(v)

    def integer(self, key: str, default: Any = _MISSING, *, lo: int | None = None) -> int:
        """An integer >= lo."""
        v = self.raw(key, default)
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(key, v, "an integer")
        if lo is not None and v < lo:
            raise self.error(key, v, f"an integer >= {lo}")
        return v

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
    ) -> tuple[float, ...]:
        """A list of ``n`` finite numbers, each in [lo, hi] when those are given."""
        v = self.raw(key, default)
        if (
            not isinstance(v, list)
            or len(v) != n
            or not all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                for x in v
            )
        ):
            raise self.error(key, v, f"a list of {n} finite numbers")
        if (lo is not None and min(v) < lo) or (hi is not None and max(v) > hi):
            raise self.error(key, v, f"a list of {n} numbers in [{lo}, {hi}]")
        return tuple(float(x) for x in v)

    def vector3(self, key: str, default: Any = _MISSING) -> tuple[float, float, float]:
        """A list of 3 finite numbers."""
        x, y, z = self.vector(key, 3, default)
        return (x, y, z)

    def vector4(self, key: str, default: Any = _MISSING) -> tuple[float, float, float, float]:
        """A list of 4 finite numbers."""
        a, b, c, d = self.vector(key, 4, default)
        return (a, b, c, d)

    def matrix3(self, key: str) -> tuple[tuple[float, float, float], ...]:
        """A 3x3 list of lists of finite numbers."""
        v = self.raw(key)
        if not isinstance(v, list) or len(v) != 3:
            raise self.error(key, v, "a 3x3 matrix (list of three lists of three numbers)")
        rows = []
        for i, row in enumerate(v):
            if (
                not isinstance(row, list)
                or len(row) != 3
                or not all(
                    isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                    for x in row
                )
            ):
                raise self.error(f"{key}[{i}]", row, "a list of 3 finite numbers")
            rows.append((float(row[0]), float(row[1]), float(row[2])))
        return tuple(rows)

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
            near = difflib.get_close_matches(str(key), sorted(self._used), n=1,
                                             cutoff=NEAR_MISS_CUTOFF)
            hint = f"did you mean {near[0]!r}? " if near else ""
            known = ", ".join(sorted(self._used)) or "no keys"
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
