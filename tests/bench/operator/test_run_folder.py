"""Run folders: a new one per run, never shared, never outside runs/; --out guarded."""

from __future__ import annotations

from pathlib import Path

import pytest

from bench.operator.run_folder import default_run_folder, prepare_run_folder, safe_name
from dbc.errors import ConfigError

SAME_SECOND_RUNS = 50
NOW_S = 1_800_000_000.0


def test_runs_started_in_the_same_second_get_folders_of_their_own(tmp_path: Path) -> None:
    """Fifty folders for one scenario at one instant: all distinct, all created, all empty."""
    made = {default_run_folder("quickstart", tmp_path, NOW_S) for _ in range(SAME_SECOND_RUNS)}
    assert len(made) == SAME_SECOND_RUNS
    assert all(p.is_dir() and not any(p.iterdir()) and p.parent == tmp_path for p in made)


@pytest.mark.parametrize("name", ["../../etc", "/abs/path", "..", ".hidden", "a b/c"])
def test_scenario_names_cannot_leave_the_runs_folder(tmp_path: Path, name: str) -> None:
    """A name with separators or dots becomes one plain path component inside runs/."""
    p = default_run_folder(name, tmp_path, NOW_S)
    assert p.parent == tmp_path and "/" not in safe_name(name)
    assert not safe_name(name).startswith(".")


def test_an_existing_run_is_refused_without_replace(tmp_path: Path) -> None:
    """--out on a folder holding a run: exit-2 error naming --out and --replace."""
    run = tmp_path / "run"
    run.mkdir()
    (run / "summary.json").write_text("{}", encoding="utf-8")
    with pytest.raises(ConfigError, match="--replace") as info:
        prepare_run_folder(run, replace=False)
    assert info.value.key == "--out"
    assert prepare_run_folder(run, replace=True) == run and not run.exists()


def test_a_non_run_folder_is_never_deleted(tmp_path: Path) -> None:
    """--replace on a folder that holds no run: refused, its files left alone."""
    other = tmp_path / "photos"
    other.mkdir()
    (other / "cat.png").write_bytes(b"x")
    with pytest.raises(ConfigError, match="holds no run"):
        prepare_run_folder(other, replace=True)
    assert (other / "cat.png").exists()


def test_a_new_or_empty_folder_is_taken(tmp_path: Path) -> None:
    """A missing or empty --out folder is fine as it is."""
    (tmp_path / "empty").mkdir()
    assert prepare_run_folder(tmp_path / "empty", replace=False) == tmp_path / "empty"
    assert prepare_run_folder(tmp_path / "new", replace=False) == tmp_path / "new"
