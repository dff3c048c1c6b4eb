"""Scenario keys with element indices, read and written on scenario data (a TOML dict).

A key is the ``--set`` language of ``thruster-hil run`` (dotted names, an array of tables
indexed as ``faults[0].t_s``) plus indices into the leaf's own array, possibly nested:
``vehicle.inertia_B_kgm2[1][1]``, ``initial.omega_BN_B_deg_s[2]``; ``[*]`` stands for every
index (``thrusters.actual_thrust_scale[*]``: one value per thruster).

- :func:`parse_key` splits a key into parts (errors name the campaign file and key);
- :func:`expand` turns ``[*]`` into the indices the data has;
- :func:`get_value` / :func:`set_value` read and write one concrete path;
- :func:`leaf_key` is the ``--set`` key that carries the whole leaf of a path (and
  :func:`leaf_path` that leaf's path)
  (``initial.omega_BN_B_deg_s`` for ``initial.omega_BN_B_deg_s[2]``);
- :func:`toml_value` writes a value back as TOML (floats by ``repr``: read back exactly).
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

from dbc.errors import ConfigError

STAR = -1
"""An index that stands for every element (``[*]``)."""

Part = tuple[str, tuple[int, ...]]
"""A dotted name and the indices after it."""

_PART = re.compile(r"([A-Za-z0-9_-]+)((?:\[(?:\d+|\*)\])*)")
_INDEX = re.compile(r"\[(\d+|\*)\]")


def parse_key(source: str, where: str, key: object) -> tuple[Part, ...]:
    """The parts of ``key``; ``where`` is the campaign file's key that holds it."""
    if not isinstance(key, str) or not key:
        raise ConfigError(source, where, key, "a scenario key such as vehicle.mass_kg")
    parts = []
    for text in key.split("."):
        m = _PART.fullmatch(text)
        if m is None:
            raise ConfigError(source, where, key, "dotted names, each optionally indexed "
                              "as name[i] or name[*] (e.g. thrusters.actual_thrust_scale[*])")
        idx = tuple(STAR if i == "*" else int(i) for i in _INDEX.findall(m.group(2)))
        parts.append((m.group(1), idx))
    for name, idx in parts[:-1]:
        if len(idx) > 1:
            raise ConfigError(source, where, key, f"one index on {name!r} (an array of tables)")
    return tuple(parts)


def _child(node: Any, name: str, idx: tuple[int, ...], path: str) -> Any:
    if not isinstance(node, dict) or name not in node:
        raise KeyError(f"{path}: no key {name!r}")
    node = node[name]
    for i in idx:
        if not isinstance(node, list) or not 0 <= i < len(node):
            raise KeyError(f"{path}: no element [{i}] of {name!r}")
        node = node[i]
    return node


def expand(data: dict[str, Any], parts: tuple[Part, ...]) -> list[tuple[Part, ...]]:
    """Every concrete path ``parts`` names in ``data`` (``[*]`` → each index present), in
    order; KeyError (a message naming the missing piece) if a name or index is missing."""
    out: list[tuple[Part, ...]] = [()]
    for name, idx in parts:
        nxt: list[tuple[Part, ...]] = []
        for prefix in out:
            node = get_value(data, prefix) if prefix else data
            for done in _expand_indices(node, name, idx, leaf_key(prefix + ((name, ()),))):
                nxt.append(prefix + ((name, done),))
        out = nxt
    return out


def _expand_indices(node: Any, name: str, idx: tuple[int, ...], path: str) -> list[tuple[int, ...]]:
    if not isinstance(node, dict) or name not in node:
        raise KeyError(f"{path}: not in the scenario")
    results: list[tuple[int, ...]] = [()]
    for i in idx:
        nxt: list[tuple[int, ...]] = []
        for done in results:
            arr = _child(node, name, done, path)
            if not isinstance(arr, list):
                raise KeyError(f"{path}: not an array")
            if i == STAR:
                nxt.extend(done + (j,) for j in range(len(arr)))
            elif i < len(arr):
                nxt.append(done + (i,))
            else:
                raise KeyError(f"{path}: no element [{i}] (it has {len(arr)})")
        results = nxt
    return results


def get_value(data: dict[str, Any], path: tuple[Part, ...]) -> Any:
    """The value at a concrete ``path``."""
    node: Any = data
    for name, idx in path:
        node = _child(node, name, idx, leaf_key(path))
    return node


def set_value(data: dict[str, Any], path: tuple[Part, ...], value: Any) -> None:
    """Write ``value`` at a concrete ``path`` (its container must exist)."""
    node: Any = data
    for name, idx in path[:-1]:
        node = _child(node, name, idx, leaf_key(path))
    name, idx = path[-1]
    if not idx:
        node[name] = value
        return
    arr = _child(node, name, idx[:-1], leaf_key(path))
    arr[idx[-1]] = value


def leaf_key(path: tuple[Part, ...]) -> str:
    """The ``--set`` key of the whole leaf: indices kept on the tables, dropped on the leaf."""
    names = [f"{n}{''.join(f'[{i}]' for i in idx)}" for n, idx in path[:-1]]
    return ".".join([*names, path[-1][0]]) if path else ""


def leaf_path(path: tuple[Part, ...]) -> tuple[Part, ...]:
    """The path of the whole leaf (its element indices dropped): what :func:`leaf_key` names."""
    return (*path[:-1], (path[-1][0], ()))


def path_text(path: tuple[Part, ...]) -> str:
    """A concrete path written as a key (``thrusters.actual_thrust_scale[3]``)."""
    return ".".join(f"{n}{''.join(f'[{i}]' for i in idx)}" for n, idx in path)


def toml_value(v: Any) -> str:
    """``v`` as a TOML value (inline tables and arrays nested); floats by ``repr``."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"not a finite number: {v!r}")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML form for {type(v).__name__}: {v!r}")
