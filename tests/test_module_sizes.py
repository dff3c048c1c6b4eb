"""The project's size rule (issue 18), checked on its source: every module under 500 lines,
every class under 300.

Modules: every ``.py`` file under bench/, dbc/, transport/, flight_sw/ and benchmarks/.
A module's length is its number of lines; a class's, from its ``class`` line to its last
line (decorators not counted). ``test_modules_and_classes_stay_small`` lists every
offender.
"""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
CHECKED = ("bench", "dbc", "transport", "flight_sw", "benchmarks")
MODULE_MAX_LINES = 500  # a module of this many lines or more is too long
CLASS_MAX_LINES = 300  # a class of this many lines or more is too long

#: Offenders left when the limits were set (their own splits are other work): the module,
#: or ``module:Class``.


def _modules() -> list[Path]:
    return sorted(p for top in CHECKED for p in (REPO / top).rglob("*.py"))


def _offenders() -> dict[str, int]:
    """``module`` or ``module:Class`` -> its length in lines, for each one over a limit."""
    out: dict[str, int] = {}
    for path in _modules():
        name = path.relative_to(REPO).as_posix()
        text = path.read_text(encoding="utf-8")
        n_lines = len(text.splitlines())
        if n_lines >= MODULE_MAX_LINES:
            out[name] = n_lines
        for node in ast.walk(ast.parse(text, filename=name)):
            if isinstance(node, ast.ClassDef):
                assert node.end_lineno is not None
                n_class = node.end_lineno - node.lineno + 1
                if n_class >= CLASS_MAX_LINES:
                    out[f"{name}:{node.name}"] = n_class
    return out


def _listing(offenders: dict[str, int]) -> str:
    return "\n".join(f"  {name}: {n} lines" for name, n in sorted(offenders.items()))


def test_the_checked_folders_hold_modules() -> None:
    """The check sees the project's modules (a moved folder would make it pass vacuously)."""
    modules = {p.relative_to(REPO).parts[0] for p in _modules()}
    assert modules == set(CHECKED)


def test_modules_and_classes_stay_small() -> None:
    """No module of 500 lines or more, no class of 300 lines or more; lists the offenders."""
    offenders = _offenders()
    assert not offenders, (
        f"modules >= {MODULE_MAX_LINES} lines or classes >= {CLASS_MAX_LINES} lines:\n"
        + _listing(offenders)
    )
