"""The DBC file and its loader: ``thruster_hil.dbc`` read with cantools (strict).

``thruster_hil.dbc`` beside this file is the single source of truth for every frame
exchanged between flight software and bench: IDs, lengths, signals, scaling, ranges,
senders and cycle times (``GenMsgCycleTime``). Both sides encode and decode only through
:mod:`dbc.codec`, and read the other facts through :mod:`dbc.icd`.
"""

from __future__ import annotations

from pathlib import Path

import cantools
from cantools.database.can import Database

from dbc.errors import IcdError

DBC_PATH = Path(__file__).with_name("thruster_hil.dbc")


def load_database(path: Path | str = DBC_PATH) -> Database:
    """Load and return the CAN database at ``path`` (the project's ICD by default)."""
    try:
        db = cantools.database.load_file(str(path), strict=True)
    except (OSError, cantools.database.UnsupportedDatabaseFormatError) as exc:
        raise IcdError(f"{path}: cannot load DBC: {exc}") from exc
    if not isinstance(db, Database):
        raise IcdError(f"{path}: not a CAN database")
    return db
