"""Campaign input checks and a failing run: exit codes and one clear line, no traceback."""

from __future__ import annotations

from pathlib import Path

import pytest

from bench.campaign.cli import EXIT_BAD_INPUT, EXIT_RUN_ERROR
from bench.operator.campaign import main

QUICKSTART = Path(__file__).resolve().parents[3] / "scenarios" / "quickstart.toml"


@pytest.mark.parametrize("option, value, says", [
    ("--fault-time", "-5", "--fault-time = '-5': expected a finite number >= 0 [s]"),
    ("--fault-time", "60", "--fault-time = 60.0"),
    ("--jobs", "0", "--jobs = '0': expected an integer in [1, 64]"),
])
def test_bad_options_exit_2_before_any_run(option: str, value: str, says: str, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    """A fault time outside the run or no worker: exit 2 naming it; no run folder started."""
    code = main([str(QUICKSTART), "--out", str(tmp_path / "c"), option, value])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and says in err, err
    assert not (tmp_path / "c").exists()


@pytest.mark.slow
def test_a_run_that_fails_is_reported_with_its_reason(tmp_path: Path, runtime: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    """A scenario the flight software refuses: exit 3 with the run's own error line."""
    bad = tmp_path / "bad.toml"
    bad.write_text(QUICKSTART.read_text(encoding="utf-8").replace('kind = "pwpf"', 'kind = "pwfp"'),
                   encoding="utf-8")
    code = main([str(bad), "--out", str(tmp_path / "c"), "--kinds", "stuck_open"])
    err = capsys.readouterr().err
    assert code == EXIT_RUN_ERROR, err
    assert "case stuck_open_T00: run exited 2" in err and "'pwfp'" in err
    assert "Traceback" not in err
