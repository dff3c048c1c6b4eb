"""Tests of :mod:`tests.transport.python_can_suite`: python-can's test files, fetched for the
installed version, or a failure that says how to get them (never a silent skip)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.transport.python_can_suite import (
    CACHE_ENV,
    COMPLETE_MARK,
    fetch,
    installed_version,
    load_back2back,
)

FETCH_AHEAD = "python -m tests.transport.python_can_suite"


def test_the_suite_is_the_installed_python_cans() -> None:
    """The cached files come from the installed version's sdist and hold Back2BackTestCase."""
    directory = fetch()
    assert (directory / COMPLETE_MARK).read_text().startswith(
        f"python_can-{installed_version()}.tar.gz sha256 ")
    assert {"__init__.py", "back2back_test.py", "config.py"} <= {
        p.name for p in directory.iterdir()}
    assert hasattr(load_back2back(), "Back2BackTestCase")


def test_a_suite_that_cannot_be_fetched_fails_saying_how(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """No index to fetch from: RuntimeError naming pip's failure and how to fetch ahead,
    and nothing half-fetched left in the cache."""
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    monkeypatch.setenv("PIP_NO_INDEX", "1")  # pip finds nothing, without any network
    with pytest.raises(RuntimeError, match=re.escape(FETCH_AHEAD)) as info:
        fetch()
    assert "pip download" in str(info.value)
    assert list(tmp_path.iterdir()) == []
