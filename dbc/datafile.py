"""Reading configuration files safely: size, encoding, nesting, then TOML or JSON.

What it does: the one way both sides read a data file they are handed (the bench its
scenario TOML and ``--set`` values, the flight software its configuration JSON), so that
no input, however made, ends in a traceback, a RecursionError or an exhausted memory
instead of :class:`dbc.errors.ConfigError` ``(file, key, value, expected)``:

- :func:`read_text`: at most :data:`MAX_FILE_BYTES` (a scenario is a few kB; a larger file
  is refused before it is read whole, so ``/dev/zero`` is refused too), UTF-8;
- :func:`parse_toml` / :func:`parse_json`: nesting (tables, arrays, dotted-key parts) at most
  :data:`MAX_DEPTH` deep, checked on the text before the parser sees it (Python's
  ``tomllib`` recurses per nested array or inline table, and spends memory quadratic in
  the parts of one dotted key: 100 000 parts take tens of GB) and on the result after;
  integers of more digits than Python converts (``sys.get_int_max_str_digits``) and
  syntax errors are ConfigErrors naming the file.

Inputs: a path or text and the name to report (``source``). Outputs: the text, or the
parsed ``dict``. Units: bytes and nesting levels. Assumptions: TOML 1.0 and JSON as
Python's parsers read them; no state.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import Any

from dbc.errors import ConfigError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

# Largest configuration file read: the shipped scenarios are 2-6 kB.
MAX_FILE_BYTES = 1 << 20
# Deepest nesting of tables and arrays (the shipped scenarios reach 4: a 3x3 matrix in a
# table of an array of tables): far below the parsers' recursion limits.
MAX_DEPTH = 32
FILE_KEY, SYNTAX_KEY, NESTING_KEY = "<file>", "<syntax>", "<nesting>"

# What a TOML text's structure is made of, strings and comments skipped: an opening or
# closing bracket or brace, or a dotted key of MAX_DEPTH + 1 or more parts (bare or quoted).
_STRINGS = r'"""(?:\\.|[^\\])*?"""|\'\'\'.*?\'\'\'|"(?:\\.|[^"\\\n])*"|\'[^\'\n]*\'|#[^\n]*'
_TOML_TOKEN = re.compile(rf"({_STRINGS})|([\[{{])|([\]}}])", re.S)
_KEY_PART = r'(?:[A-Za-z0-9_-]+|"(?:\\.|[^"\\\n])*"|\'[^\'\n]*\')'
_LONG_DOTTED_KEY = re.compile(rf"(?:{_KEY_PART}[ \t]*\.[ \t]*){{{MAX_DEPTH},}}{_KEY_PART}")


def read_text(path: str | Path, what: str = "configuration file",
              max_bytes: int = MAX_FILE_BYTES) -> str:
    """The UTF-8 text of the file at ``path``, refused if longer than ``max_bytes``."""
    p = Path(path)
    try:
        with open(p, "rb") as f:
            data = f.read(max_bytes + 1)
    except OSError as exc:
        raise ConfigError(str(p), FILE_KEY, str(p),
                          f"a readable {what} ({exc.strerror or exc})") from exc
    if len(data) > max_bytes:
        raise ConfigError(str(p), FILE_KEY, str(p),
                          f"a {what} of at most {max_bytes} bytes (this one is larger)")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(str(p), FILE_KEY, str(p),
                          f"a UTF-8 text file (byte {exc.start} is not UTF-8)") from exc


def _nesting_error(source: str, key: str) -> ConfigError:
    return ConfigError(source, key, f"more than {MAX_DEPTH} levels",
                       f"tables, arrays and dotted keys nested at most {MAX_DEPTH} deep")


def _prescan_toml(text: str, source: str, key: str) -> None:
    """Refuse nesting deeper than MAX_DEPTH in TOML ``text`` before parsing it."""
    depth = 0
    skeleton: list[str] = []  # the text with its strings and comments blanked
    last = 0
    for m in _TOML_TOKEN.finditer(text):
        if m.group(1) is not None:
            skeleton.append(text[last:m.start()])
            skeleton.append('""' if m.group(1)[0] in "\"'" else "")
            last = m.end()
        elif m.group(2) is not None:
            depth += 1
            if depth > MAX_DEPTH:
                raise _nesting_error(source, key)
        else:
            depth = max(0, depth - 1)
    skeleton.append(text[last:])
    if _LONG_DOTTED_KEY.search("".join(skeleton)):
        raise _nesting_error(source, key)


def nesting_depth(data: Any) -> int:
    """Levels of dicts and lists in ``data`` (0 for a scalar), without recursion."""
    deepest = 0
    stack: list[tuple[Any, int]] = [(data, 0)]
    while stack:
        node, level = stack.pop()
        if isinstance(node, dict):
            children: Any = node.values()
        elif isinstance(node, list):
            children = node
        else:
            continue
        deepest = max(deepest, level + 1)
        if level + 1 > MAX_DEPTH:
            return deepest
        stack.extend((c, level + 1) for c in children)
    return deepest


def check_nesting(data: Any, source: str, key: str = NESTING_KEY) -> None:
    """ConfigError if ``data`` nests deeper than MAX_DEPTH."""
    if nesting_depth(data) > MAX_DEPTH:
        raise _nesting_error(source, key)


def _digits_error(source: str, key: str, language: str) -> ConfigError:
    limit = sys.get_int_max_str_digits()
    return ConfigError(source, key, f"an integer of more than {limit} digits",
                       f"valid {language} with integers of at most {limit} digits")


def parse_toml(text: str, source: str, key: str | None = None) -> dict[str, Any]:
    """TOML ``text`` as a dict; every failure a ConfigError naming ``source`` and ``key``
    (default ``<syntax>``, or ``<nesting>`` for too deep a nesting)."""
    _prescan_toml(text, source, key or NESTING_KEY)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(source, key or SYNTAX_KEY, str(exc), "valid TOML") from exc
    except RecursionError as exc:  # pragma: no cover - the prescan refuses such depths
        raise _nesting_error(source, key or NESTING_KEY) from exc
    except ValueError as exc:  # an integer of more digits than Python converts
        raise _digits_error(source, key or SYNTAX_KEY, "TOML") from exc
    check_nesting(data, source, key or NESTING_KEY)
    return data


def parse_json(text: str, source: str, key: str | None = None) -> Any:
    """JSON ``text`` (any JSON value); every failure a ConfigError, as :func:`parse_toml`."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ConfigError(source, key or SYNTAX_KEY, str(exc), "valid JSON") from exc
    except RecursionError as exc:
        raise _nesting_error(source, key or NESTING_KEY) from exc
    except ValueError as exc:  # an integer of more digits than Python converts
        raise _digits_error(source, key or SYNTAX_KEY, "JSON") from exc
    check_nesting(data, source, key or NESTING_KEY)
    return data
