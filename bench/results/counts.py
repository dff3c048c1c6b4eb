"""Frame counts per message of the ICD, merged from what each node sent and received.

In: the DBC's messages and senders; per node, the frames it sent (by name) and its
receive statistics (dbc.codec.FrameChecker.summary: received, accepted, gaps, rejected
by cause). Out: ``summary.json``'s ``frames`` table (per message: sender, sent by its
sender, received / gaps / rejected by cause at its receivers, and ``at_sender``: frames of
this message that its own sender heard from another node, by cause: ``unexpected`` for
well-formed ones, a second sender; ``crc``, ``dlc`` ... for malformed ones),
and ``rejected_other`` (frames that are no message of the ICD: unknown or extended IDs,
error frames, summed per cause for each node that heard them).

A message's sender never overwrites its receivers' counts: the bench's count of a second
SYNC sender and the flight software's count of the SYNC frames it received both survive.
"""

from __future__ import annotations

from typing import Any

from dbc.icd import Icd


def frame_table(icd: Icd) -> dict[str, dict[str, Any]]:
    """An empty per-message table of the ICD (see the module docstring)."""
    return {
        name: {"sender": sender or "?", "sent": None, "received": None, "gaps": None,
               "rejected": {}, "at_sender": {}}
        for name, sender in icd.sender.items()
    }


def merge_counts(
    table: dict[str, dict[str, Any]], other: dict[str, dict[str, int]], node: str,
    sent: dict[str, int], received: dict[str, dict[str, Any]],
) -> None:
    """Merge what ``node`` sent and received into ``table`` and ``other``."""
    for name, n in sent.items():
        if name in table:
            table[name]["sent"] = n
    mine = other.setdefault(node, {})
    for name, r in received.items():
        row = table.get(name)
        if row is None:
            for cause, n in r["rejected"].items():
                mine[cause] = mine.get(cause, 0) + n
        elif row["sender"] == node:  # our own message, from someone else
            at = row["at_sender"]
            for cause, n in r["rejected"].items():
                at[cause] = at.get(cause, 0) + n
        else:
            row["received"] = (row["received"] or 0) + int(r["received"])
            row["gaps"] = (row["gaps"] or 0) + int(r["gaps"])
            rejected = row["rejected"]
            for cause, n in r["rejected"].items():
                rejected[cause] = rejected.get(cause, 0) + n


def zero_unheard(table: dict[str, dict[str, Any]], reported: set[str]) -> None:
    """Messages their sender sent that no reporting receiver heard: ``received`` 0, not None.

    ``reported``: the nodes whose receive counts were merged (a node that wrote no report
    leaves its messages' reception unknown, None).
    """
    for row in table.values():
        if row["sent"] and row["received"] is None and reported - {row["sender"]}:
            row["received"], row["gaps"] = 0, 0


EVIDENCE = ("unexpected", "sequence", "second_sender")


def second_senders(table: dict[str, dict[str, Any]]) -> dict[str, int]:
    """Messages with evidence of a second sender: well-formed frames heard at their own
    sender, regressed alive counters or a second frame for one cycle at a receiver; by
    message name."""
    out = {}
    for name, row in table.items():
        rej = row.get("rejected") or {}
        at = row.get("at_sender") or {}
        n = sum(int(rej.get(c, 0)) + int(at.get(c, 0)) for c in EVIDENCE)
        if n:
            out[name] = n
    return out
