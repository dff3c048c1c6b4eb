"""docs/icd.md's frame table agrees with the DBC (IDs, names, senders, cycle times and how
each is sent)."""

from __future__ import annotations

import re
from pathlib import Path

from dbc.database import load_database

DOC = Path(__file__).resolve().parents[2] / "docs" / "icd.md"
ROW = re.compile(
    r"^\| 0x([0-9A-F]{3}) \| (\w+) \| (\w+) → [^|]+\| (\d+ ms(?: and on change)?|event) \|")
# GenMsgSendType -> how the doc's cycle column says it ("{} ms": the cycle time)
CYCLE_TEXT = {"Cyclic": "{} ms", "CyclicAndSpontanX": "{} ms and on change", "Event": "event"}


def test_doc_table_matches_dbc() -> None:
    """Every DBC message has a row with its ID, sender, cycle time and send type, and
    nothing else does."""
    rows = {m.group(2): m for m in map(ROW.match, DOC.read_text().splitlines()) if m}
    db = load_database()
    assert set(rows) == {m.name for m in db.messages}
    for m in db.messages:
        r = rows[m.name]
        assert int(r.group(1), 16) == m.frame_id
        assert r.group(3) == m.senders[0]
        assert r.group(4) == CYCLE_TEXT[m.send_type].format(m.cycle_time), m.name
        assert (m.send_type == "Event") == (not m.cycle_time), m.name
