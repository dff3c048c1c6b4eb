"""Where a run writes: a folder of its own, named so that no two runs ever share one.

* :func:`default_run_folder`: ``runs/<scenario>-<YYYYmmdd-HHMMSS>-<4 hex>``, created
  exclusively (two runs started in the same second get two folders); the scenario's name
  is reduced to letters, digits, ``_``, ``.`` and ``-`` (no ``/``, no leading dot), so a
  name cannot lead the folder out of ``runs/``.
* :func:`prepare_run_folder`: an ``--out`` folder given by the user must be new or empty;
  one that holds a run (``summary.json``, ``scenario.toml`` or ``fsw_config.json``) is
  replaced only with ``--replace``; any other non-empty folder is refused (nothing that is
  not a run folder is ever deleted).
Errors are :class:`~dbc.errors.ConfigError` naming ``--out`` and the folder (exit 2).
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
import time
from pathlib import Path

from dbc.errors import ConfigError

RUNS_ROOT = Path("runs")
TIME_FORMAT = "%Y%m%d-%H%M%S"
SUFFIX_BYTES = 2  # 4 hex digits: two runs in one second collide 1 time in 65 536, retried
NAME_RE = re.compile(r"[^A-Za-z0-9_.-]+")
RUN_FOLDER_MARKS = ("summary.json", "scenario.toml", "fsw_config.json")
CREATE_ATTEMPTS = 16
SOURCE = "command line"


def safe_name(name: str) -> str:
    """``name`` as one path component: other characters become ``_``, no leading dot."""
    cleaned = NAME_RE.sub("_", name).lstrip(".")
    return cleaned or "run"


def default_run_folder(name: str, root: Path = RUNS_ROOT, now_s: float | None = None) -> Path:
    """A new, empty folder ``root/<name>-<time>-<hex>``, created here (module docstring)."""
    stamp = time.strftime(TIME_FORMAT, time.localtime(now_s))
    root.mkdir(parents=True, exist_ok=True)
    for _ in range(CREATE_ATTEMPTS):
        path = root / f"{safe_name(name)}-{stamp}-{secrets.token_hex(SUFFIX_BYTES)}"
        try:
            os.mkdir(path)
        except FileExistsError:
            continue
        return path
    raise ConfigError(SOURCE, "--out", str(root), "a runs folder with room for a new run")


def prepare_run_folder(path: Path, replace: bool) -> Path:
    """Check (and with ``replace``, empty) the user's ``--out`` folder (module docstring)."""
    if path.exists() and not path.is_dir():
        raise ConfigError(SOURCE, "--out", str(path), "a folder (this is a file)")
    if not path.exists() or not any(path.iterdir()):
        return path
    is_run = any((path / mark).exists() for mark in RUN_FOLDER_MARKS)
    if not replace:
        hint = "add --replace to overwrite that run" if is_run else "choose another folder"
        raise ConfigError(SOURCE, "--out", str(path), f"a new or empty folder ({hint})")
    if not is_run:
        raise ConfigError(SOURCE, "--out", str(path),
                          "a run folder to replace (this one holds no run: it is left alone)")
    shutil.rmtree(path)
    return path
