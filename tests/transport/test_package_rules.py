"""The transport package's own rules, checked on its source: what it may import, how big
its modules and classes may grow."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import transport

PACKAGE_DIR = Path(transport.__file__).parent
MODULES = sorted(PACKAGE_DIR.glob("*.py"))
MODULE_MAX_LINES = 500
CLASS_MAX_LINES = 300
#: the project's packages transport may import from (bench and flight_sw import transport)
ALLOWED_PROJECT_IMPORTS = {"dbc.errors", "transport"}
PROJECT_PACKAGES = {"bench", "flight_sw", "dbc", "transport"}


def _imported(tree: ast.Module) -> set[str]:
    """Absolute module names a module imports (``from X import y`` gives X)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out.add(node.module)
    return out


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.name)
def test_transport_imports_only_dbc_errors_of_the_project(path: Path) -> None:
    """A transport module imports the project's dbc.errors and transport, never bench,
    flight_sw or the rest of dbc (the interface contract)."""
    for name in _imported(ast.parse(path.read_text(encoding="utf-8"))):
        if name.split(".")[0] in PROJECT_PACKAGES:
            assert name in ALLOWED_PROJECT_IMPORTS or name.startswith("transport."), name


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.name)
def test_modules_and_classes_stay_small(path: Path) -> None:
    """Every transport module is under 500 lines and none of its classes over 300."""
    text = path.read_text(encoding="utf-8")
    assert len(text.splitlines()) < MODULE_MAX_LINES
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.ClassDef):
            assert node.end_lineno is not None
            assert node.end_lineno - node.lineno + 1 <= CLASS_MAX_LINES, node.name
