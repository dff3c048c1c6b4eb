"""No DBC ID, counter width, value-table entry or fault kind is written as a literal outside
dbc/: the bench, the flight software, the transport and the benchmarks read them from the
DBC (dbc.icd) or from dbc.faults."""

from __future__ import annotations

import ast
import re
from pathlib import Path

from dbc.database import load_database
from dbc.faults import FAULT_KINDS

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("bench", "flight_sw", "transport", "benchmarks")
HEX = re.compile(r"\b0x([0-9A-Fa-f]{3})\b")  # IDs are written 0xNNN (flag bits 0xNN)
# constants the code once held and now reads from the DBC (a new one of these names means
# an ICD fact copied again)
COPIED_FACTS = frozenset({
    "THRUSTERS_PER_CMD_FRAME", "MAX_CMD_FRAMES", "CMD_FRAMES", "ON_TIME_SIGNALS",
    "CYCLE_MODULUS", "STATUS_CYCLE_MODULUS", "OVERRUN_MAX", "ON_TIME_LSB_S",
    "NO_FAILED_THRUSTER", "NO_THRUSTER", "FAULT_CMD_NONE", "COUNTER_NONE", "MODE_BOOT",
    "NAV_POS_MAX_M", "NAV_VEL_MAX_M_S", "DETECTION_TIME_MAX_S", "ISOLATION_DELAY_MAX_S",
    "ALLOC_RESIDUAL_MAX_NM", "ALLOC_RESIDUAL_MAX_N", "HEALTH_WATCHDOG", "HEALTH_FSW_SILENT",
    "FAULT_CMD_KINDS", "FAULT_CMD_NODES", "FSW_FRAMES", "BENCH_FRAMES", "FAILURE_KINDS",
})


def _sources() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in (REPO / pkg).rglob("*.py"))


def _docstring_nodes(tree: ast.AST) -> set[int]:
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                out.add(id(body[0].value))
    return out


def test_no_fault_kind_is_compared_as_a_literal() -> None:
    """Fault kinds are compared through dbc.faults' names, never as string literals."""
    kinds = set(FAULT_KINDS)
    found = []
    for path in _sources():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        docs = _docstring_nodes(tree)
        for node in ast.walk(tree):
            if isinstance(node, ast.Compare):
                for c in ast.walk(node):
                    if (isinstance(c, ast.Constant) and c.value in kinds
                            and id(c) not in docs):
                        found.append(f"{path.relative_to(REPO)}:{node.lineno} {c.value!r}")
            elif isinstance(node, ast.Assign) and isinstance(node.value, (ast.Tuple, ast.Set)):
                vals = [e.value for e in node.value.elts if isinstance(e, ast.Constant)]
                if vals and all(v in kinds for v in vals):
                    found.append(f"{path.relative_to(REPO)}:{node.lineno} {vals}")
    assert found == []


def test_no_frame_id_is_written_in_hex() -> None:
    """No hexadecimal literal equal to a DBC frame ID appears in code."""
    ids = {m.frame_id for m in load_database().messages}
    found = []
    for path in _sources():
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            code = line.split("#", 1)[0]
            for m in HEX.finditer(code):
                if int(m.group(1), 16) in ids and not code.strip().startswith(('"', "'")):
                    found.append(f"{path.relative_to(REPO)}:{n} {m.group(0)}")
    assert found == []


def test_no_icd_fact_is_copied_into_a_constant() -> None:
    """None of the constants that once copied ICD facts is defined again."""
    found = []
    for path in _sources():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets = (node.targets if isinstance(node, ast.Assign)
                       else [node.target] if isinstance(node, ast.AnnAssign) else [])
            for t in targets:
                if isinstance(t, ast.Name) and t.id in COPIED_FACTS:
                    found.append(f"{path.relative_to(REPO)}:{node.lineno} {t.id}")
    assert found == []
