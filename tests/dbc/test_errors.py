"""Tests of :mod:`dbc.errors`: the documented tree is the real one, bus errors are python-can's."""

from __future__ import annotations

import builtins
import re

import can
import pytest

import dbc.errors as errors
from dbc.errors import (
    BusArgumentError,
    BusError,
    BusInitError,
    BusOperationError,
    BusTimeoutError,
    ThrusterHilError,
)

TREE_LINE = re.compile(r"^(?P<indent>[ │]*)(?P<branch>[├└]── )?(?P<name>[A-Z]\w+)(?P<rest>.*)$")
INDENT_PER_LEVEL = 4


def _documented_tree() -> list[tuple[int, str, str]]:
    """(depth, class name, rest of the line) of each class in the module docstring's tree."""
    assert errors.__doc__ is not None
    out = []
    for line in errors.__doc__.splitlines():
        if not line.startswith(" " * INDENT_PER_LEVEL):
            continue
        m = TREE_LINE.match(line[INDENT_PER_LEVEL:])
        if m and hasattr(errors, m["name"]):
            depth = len(m["indent"]) // INDENT_PER_LEVEL + (1 if m["branch"] else 0)
            out.append((depth, m["name"], m["rest"]))
    return out


def test_the_documented_tree_is_the_class_tree() -> None:
    """Each class in the docstring's tree derives from the class one level above it, and
    from the python-can or built-in class named in parentheses on its line."""
    tree = _documented_tree()
    assert tree[0][:2] == (0, "ThrusterHilError")
    names = {name for _depth, name, _rest in tree}
    assert {"BusInitError", "BusArgumentError", "BusOperationError", "BusTimeoutError"} <= names
    parents: list[str] = []
    for depth, name, rest in tree:
        parents = parents[:depth]
        cls = getattr(errors, name)
        if parents:
            assert issubclass(cls, getattr(errors, parents[-1])), (name, parents[-1])
        for module, base in re.findall(r"\((?:also )?(can\.)?(\w+Error)\)", rest):
            expected = getattr(can if module else builtins, base)
            assert issubclass(cls, expected), (name, base)
        parents.append(name)


@pytest.mark.parametrize(
    ("cls", "python_can", "also"),
    [
        (BusInitError, can.CanInitializationError, ()),
        (BusArgumentError, can.CanInitializationError, (ValueError,)),
        (BusOperationError, can.CanOperationError, ()),
        (BusTimeoutError, can.CanOperationError, (can.CanTimeoutError, TimeoutError)),
    ],
)
def test_bus_errors_are_python_can_errors_and_the_projects(
    cls: type[BusError], python_can: type[can.CanError], also: tuple[type[Exception], ...]
) -> None:
    """A bus error is caught by ``except can.CanError``, its python-can class, and the
    project's BusError; its message and python-can's error_code (None) are kept."""
    exc = cls("hilbus: what failed")
    for base in (can.CanError, python_can, BusError, ThrusterHilError, *also):
        assert isinstance(exc, base), base
    assert str(exc) == "hilbus: what failed" and exc.error_code is None


def test_a_malformed_spec_is_a_bus_error_but_no_python_can_error() -> None:
    """BusError itself is the project's (a malformed bus spec), not a python-can error."""
    assert not issubclass(BusError, can.CanError)


def test_a_huge_value_is_shown_briefly() -> None:
    """A 5-million-element value: the message names its type and length and stays short."""
    big = [0] * 5_000_000
    text = str(errors.ConfigError("f.toml", "vehicle.mass_kg", big, "a number"))
    assert "list of 5000000 items: [0, 0, 0, 0, 0, 0, ...]" in text
    assert len(text) < 2 * errors.BRIEF_CHARS


def test_deep_and_long_values_are_shown_briefly() -> None:
    """A 100 000-deep list, a long string and a 5000-digit integer: short, no RecursionError."""
    deep: list[object] = []
    inner = deep
    for _ in range(100_000):
        nxt: list[object] = []
        inner.append(nxt)
        inner = nxt
    assert errors.brief(deep) == "list of 1 item: [[[[...]]]]"
    assert errors.brief("x" * 1000).startswith("str of 1000 chars: 'xxx")
    assert errors.brief(10**5000) == "int of about 5001 digits"
    assert errors.brief([1.5, -1]) == "[1.5, -1]"
