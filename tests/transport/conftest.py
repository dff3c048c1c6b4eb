"""Fixtures of the transport tests: a private channel and a pair of hilbus members on it."""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

from transport.hilbus import HilBus


@pytest.fixture
def channel(runtime: Path) -> str:
    """A channel name unique to the test, in the test's private runtime directory."""
    return f"t-{uuid.uuid4().hex[:8]}"


@pytest.fixture
def pair(channel: str) -> Iterator[tuple[HilBus, HilBus]]:
    """Two members A and B of one channel."""
    with HilBus(channel) as a, HilBus(channel) as b:
        yield a, b

