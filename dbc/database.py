"""The DBC file and its loader: ``thruster_hil.dbc`` read with cantools (strict).

``thruster_hil.dbc`` beside this file is the single source of truth for every frame
exchanged between flight software and bench: IDs, lengths, signals, scaling, ranges,
senders and cycle times (``GenMsgCycleTime``). Both sides encode and decode only through
:mod:`dbc.codec`, and read the other facts through :mod:`dbc.icd`.

A process parses a file once: :func:`load_database` keeps the parsed database per path,
size and modification time (a changed file is parsed again), and hands the same object to
every caller, so nothing may modify the database it gets (nothing does: the codec, the ICD
and the tools only read it). A run's supervisor asked for it four times before it started
the flight software (12 ms each), and the forked bench inherits it.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

import cantools
from cantools.database.can import Database

from dbc.errors import IcdError

DBC_PATH = Path(__file__).with_name("thruster_hil.dbc")


PARSED_KEEP = 8  # parsed databases kept per process (the ICD, and a test's own files)


def load_database(path: Path | str = DBC_PATH) -> Database:
    """The CAN database at ``path`` (the project's ICD by default), parsed once per
    process while the file is unchanged (module docstring: never modify it)."""
    try:
        st = os.stat(path)
    except OSError as exc:
        raise IcdError(f"{path}: cannot load DBC: {exc}") from exc
    return _parse(str(path), st.st_size, st.st_mtime_ns)


@functools.lru_cache(maxsize=PARSED_KEEP)
def _parse(path: str, _size: int, _mtime_ns: int) -> Database:
    """The database in the file ``path`` (its size and time are the cache's key)."""
    try:
        db = cantools.database.load_file(path, strict=True)
    except (OSError, cantools.database.UnsupportedDatabaseFormatError) as exc:
        raise IcdError(f"{path}: cannot load DBC: {exc}") from exc
    if not isinstance(db, Database):
        raise IcdError(f"{path}: not a CAN database")
    return db
