"""docs/icd.md's frame table agrees with the DBC (IDs, names, senders, cycle times)."""

from __future__ import annotations

import re
from pathlib import Path

from dbc.database import load_database

DOC = Path(__file__).resolve().parents[2] / "docs" / "icd.md"
ROW = re.compile(r"^\| 0x([0-9A-F]{3}) \| (\w+) \| (\w+) → [^|]+\| (\d+ ms|event) \|")


def test_doc_table_matches_dbc() -> None:
    """Every DBC message has a row with its ID, sender and cycle time, and nothing else does."""
    rows = {m.group(2): m for m in map(ROW.match, DOC.read_text().splitlines()) if m}
    db = load_database()
    assert set(rows) == {m.name for m in db.messages}
    for m in db.messages:
        r = rows[m.name]
        assert int(r.group(1), 16) == m.frame_id
        assert r.group(3) == m.senders[0]
        assert r.group(4) == (f"{m.cycle_time} ms" if m.cycle_time else "event")
