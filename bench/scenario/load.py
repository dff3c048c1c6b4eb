"""Scenario files: read the TOML, apply ``--set KEY=VALUE`` overrides, validate.

:func:`load_scenario` reads a file (errors name it: unreadable, too large, not UTF-8, not
TOML, nested too deep: :mod:`dbc.datafile`), applies the
overrides (:func:`apply_overrides`; an error names the override) and hands the data to
:func:`bench.scenario.parse.parse_scenario`. A validation error caused by an override is
reported against the override, not the file.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path
from typing import Any

from bench.scenario.parse import parse_scenario
from bench.scenario.spec import Scenario, override_source
from dbc.datafile import SYNTAX_KEY, check_nesting, parse_toml, read_text
from dbc.errors import ConfigError


def apply_overrides(data: dict[str, Any], overrides: list[str], source: str) -> None:
    """Apply ``KEY=VALUE`` overrides (dotted keys, TOML values) to parsed scenario data in place.

    ``bus.bitrate_bps=125000``, ``flight_sw.modulator.km=10.0``, ``manoeuvre.t_start_s=2``;
    an element of an array of tables by its index: ``thrusters.list[0].max_thrust_N=5.0``,
    ``faults[1].t_s=30``. A value that is not valid TOML is taken as a string. Errors name
    the override.
    """
    for item in overrides:
        cli = f"command line (--set on {source})"  # the blame: not the file's
        key, sep, text = item.partition("=")
        if not sep or not key:
            raise ConfigError(cli, "--set", item, "KEY=VALUE with a dotted KEY")
        try:
            value = parse_toml(f"v = {text}", source)["v"]
        except ConfigError as exc:
            if exc.key != SYNTAX_KEY:  # too deep, too many digits: not a string either
                raise ConfigError(cli, "--set", item, exc.expected) from exc
            value = text
        table = data
        parts = [_override_part(cli, key, p) for p in key.split(".")]
        for name, index in parts[:-1]:
            nxt = table.setdefault(name, {} if index is None else [])
            if index is not None:
                if not isinstance(nxt, list) or not 0 <= index < len(nxt):
                    size = len(nxt) if isinstance(nxt, list) else 0
                    raise ConfigError(cli, key, item, f"{name!r} to be an array of tables "
                                      f"with an element {index} (it has {size})")
                nxt = nxt[index]
            if not isinstance(nxt, dict):
                raise ConfigError(cli, key, item, f"{name!r} to be a table")
            table = nxt
        name, index = parts[-1]
        if index is not None:
            raise ConfigError(cli, key, item, "a key inside the element (e.g. "
                              f"{name}[{index}].t_s), or the whole array: {name}=[...]")
        table[name] = value


_OVERRIDE_PART = re.compile(r"([A-Za-z0-9_-]+)(?:\[(\d+)\])?")


def _override_part(source: str, key: str, part: str) -> tuple[str, int | None]:
    """``name`` or ``name[i]`` of a dotted override key."""
    m = _OVERRIDE_PART.fullmatch(part)
    if m is None:
        raise ConfigError(source, "--set", key, "a dotted KEY of names, each optionally "
                          "indexed as name[i]")
    return m.group(1), None if m.group(2) is None else int(m.group(2))


def load_scenario(path: str | Path, overrides: list[str] | None = None) -> Scenario:
    """Read and validate the scenario file at ``path``, after ``KEY=VALUE`` overrides."""
    p = Path(path)
    data = parse_toml(read_text(p, "scenario file"), str(p))
    apply_overrides(data, overrides or [], str(p))
    check_nesting(data, override_source(str(p), list(overrides or [])))
    try:
        sc = parse_scenario(data, str(p))
    except ConfigError as exc:
        item = override_of(exc.key, overrides or [])
        if item is None:
            raise
        raise ConfigError(override_source(str(p), [item]), exc.key, exc.value,
                          exc.expected) from exc
    return dataclasses.replace(sc, overrides=tuple(overrides or ()))


def override_of(key: str, overrides: list[str]) -> str | None:
    """The ``--set`` item that wrote ``key`` (or a table above or below it), if any."""
    for item in reversed(overrides):  # the last one wins, as applied
        k = item.partition("=")[0]
        if key == k or key.startswith(k + ".") or k.startswith(key + "."):
            return item
    return None
