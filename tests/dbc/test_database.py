"""The DBC loader: parsed once per process while the file is unchanged, clear errors."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from dbc.database import DBC_PATH, load_database
from dbc.errors import IcdError


def test_the_icd_is_parsed_once_per_process() -> None:
    """Two loads of the unchanged ICD give the same parsed database."""
    assert load_database() is load_database(DBC_PATH)


def test_a_changed_file_is_parsed_again(tmp_path: Path) -> None:
    """Editing a DBC (new size and time) gives a new database with the edit in it."""
    path = tmp_path / "copy.dbc"
    text = DBC_PATH.read_text(encoding="utf-8")
    path.write_text(text, encoding="utf-8")
    first = load_database(path)
    assert load_database(path) is first
    renamed = text.replace("BENCH_STATUS", "BENCH_STATE")
    path.write_text(renamed, encoding="utf-8")
    later_ns = path.stat().st_mtime_ns + 1  # a new time even on a coarse clock
    os.utime(path, ns=(later_ns, later_ns))
    second = load_database(path)
    assert second is not first
    assert second.get_message_by_name("BENCH_STATE").frame_id == \
        first.get_message_by_name("BENCH_STATUS").frame_id


def test_a_missing_file_names_the_path(tmp_path: Path) -> None:
    """A DBC that is not there is an IcdError naming its path."""
    missing = tmp_path / "none.dbc"
    with pytest.raises(IcdError, match=r"none\.dbc: cannot load DBC"):
        load_database(missing)
