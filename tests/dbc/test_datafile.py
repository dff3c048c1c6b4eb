"""Tests of :mod:`dbc.datafile`: size, encoding, nesting and digits refused as ConfigErrors."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from dbc.datafile import (
    MAX_DEPTH,
    MAX_FILE_BYTES,
    NESTING_KEY,
    SYNTAX_KEY,
    nesting_depth,
    parse_json,
    parse_toml,
    read_text,
)
from dbc.errors import ConfigError

DEEP = 100_000  # the nesting the issue reported as a RecursionError


@pytest.mark.parametrize("text", [
    "a = " + "[" * DEEP + "]" * DEEP,
    "a = " + "{b=" * DEEP + "1" + "}" * DEEP,
    "a" + ".a" * DEEP + " = 1",
    "[" + "a." * DEEP + "a]",
    '"a"' + '."a"' * DEEP + " = 1",
    "a" + " . a" * (MAX_DEPTH + 1) + " = 1",
])
def test_deep_toml_is_refused_before_parsing(text: str) -> None:
    """Arrays, inline tables, dotted keys and headers nested past MAX_DEPTH: a ConfigError."""
    with pytest.raises(ConfigError) as info:
        parse_toml(text, "f.toml")
    assert info.value.key == NESTING_KEY and f"at most {MAX_DEPTH} deep" in str(info.value)


def test_nesting_at_the_limit_and_brackets_in_strings_are_accepted() -> None:
    """MAX_DEPTH levels parse; brackets inside strings and comments are not nesting."""
    brackets = "[" * (2 * MAX_DEPTH)
    data = parse_toml("a" + ".a" * (MAX_DEPTH - 1) + f' = 1\ns = "{brackets}" # {brackets}\n',
                      "f.toml")
    assert nesting_depth(data) == MAX_DEPTH and data["s"] == brackets


def test_too_many_digits_is_a_config_error() -> None:
    """An integer longer than Python converts: a ConfigError naming the limit, in both formats."""
    digits = sys.get_int_max_str_digits() + 1
    for parse, text in ((parse_toml, "a = 1" + "0" * digits), (parse_json, "1" + "0" * digits)):
        with pytest.raises(ConfigError) as info:
            parse(text, "f")
        assert info.value.key == SYNTAX_KEY and "digits" in str(info.value)


def test_deep_json_is_refused() -> None:
    """JSON nested 100 000 deep: a ConfigError, not a RecursionError."""
    with pytest.raises(ConfigError) as info:
        parse_json("[" * DEEP + "]" * DEEP, "c.json")
    assert info.value.key == NESTING_KEY


def test_large_and_binary_files_are_refused(tmp_path: Path) -> None:
    """A file over MAX_FILE_BYTES, and one that is not UTF-8: ConfigErrors naming the file."""
    big = tmp_path / "big.toml"
    big.write_bytes(b"#" * (MAX_FILE_BYTES + 1))
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"a = 1\n\xff\xfe")
    for path, says in ((big, f"at most {MAX_FILE_BYTES} bytes"), (binary, "byte 6 is not UTF-8")):
        with pytest.raises(ConfigError) as info:
            read_text(path)
        assert info.value.source == str(path) and says in str(info.value)
