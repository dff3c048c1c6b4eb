"""The station is the pure core: it imports no clock, socket, file or bus module, directly or
through any project module it imports."""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
STATION = REPO / "bench" / "station"
PROJECT = ("bench", "dbc", "flight_sw", "transport")
# modules that read clocks, open sockets or files, or talk to a bus
FORBIDDEN = frozenset({"time", "datetime", "socket", "select", "selectors", "os", "io",
                       "pathlib", "shutil", "tempfile", "subprocess", "threading", "signal",
                       "can", "asyncio", "csv", "json", "tomllib", "tomli", "sys"})
# project modules outside the station that the station may import: their own imports are
# checked the same way (the closure below)
ALLOWED_OUTSIDE = ("bench.scenario.spec", "bench.scenario.limits", "bench.scenario", "bench")
# the project's error tree derives its bus errors from python-can's exception classes
# (can.CanError ...): it imports python-can for those classes, and opens no bus
EXCEPTION_BASES = {("dbc/errors.py", "can")}


def _imports(path: Path) -> set[str]:
    """Top-level names of every module ``path`` imports (TYPE_CHECKING blocks excluded)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip.update(id(n) for n in ast.walk(node))
    out = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.add(node.module)
    return out


def _module_path(name: str) -> Path | None:
    p = REPO / Path(*name.split("."))
    if p.with_suffix(".py").exists():
        return p.with_suffix(".py")
    if (p / "__init__.py").exists():
        return p / "__init__.py"
    return None


def _closure(start: list[Path]) -> dict[Path, set[str]]:
    """Every project module reachable from ``start`` by imports, with its imports."""
    seen: dict[Path, set[str]] = {}
    todo = list(start)
    while todo:
        path = todo.pop()
        if path in seen:
            continue
        seen[path] = _imports(path)
        for name in seen[path]:
            if name.split(".")[0] not in PROJECT:
                continue
            parts = name.split(".")
            # importing a.b.c runs a/__init__.py and a/b/__init__.py too
            for i in range(1, len(parts) + 1):
                mod = _module_path(".".join(parts[:i]))
                if mod is not None:
                    todo.append(mod)
    return seen


def test_station_imports_no_clock_socket_file_or_bus_module() -> None:
    """No module of bench/station (or one it reaches) imports a clock, socket, file or bus."""
    station = sorted(STATION.rglob("*.py"))
    assert station, "no station modules found"
    offenders = {
        str(path.relative_to(REPO)): sorted(
            n for n in names if n.split(".")[0] in FORBIDDEN
            and (str(path.relative_to(REPO)), n) not in EXCEPTION_BASES)
        for path, names in _closure(station).items()
    }
    offenders = {k: v for k, v in offenders.items() if v}
    assert offenders == {}


def test_station_reaches_only_itself_the_scenario_and_the_contract() -> None:
    """The station's project imports stay inside bench.station, the scenario and dbc."""
    outside = set()
    for path in _closure(sorted(STATION.rglob("*.py"))):
        mod = ".".join(path.relative_to(REPO).with_suffix("").parts).removesuffix(".__init__")
        if not (mod.startswith(("bench.station", "dbc")) or mod in ALLOWED_OUTSIDE):
            outside.add(mod)
    assert outside == set()
