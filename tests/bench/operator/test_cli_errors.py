"""Bad command-line input to ``thruster-hil run``: exit 2, one line naming the value, no traceback.

These fail before any process starts, so they run in-process through ``bench.operator.cli.main``.
"""

from __future__ import annotations

import uuid
from pathlib import Path

import pytest

from bench.operator.cli import main

QUICKSTART = str(Path(__file__).resolve().parents[3] / "scenarios" / "quickstart.toml")
EXIT_BAD_INPUT = 2


def _run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = main(["run", QUICKSTART, "--duration", "1", *args])
    return code, capsys.readouterr().err


@pytest.mark.parametrize("bus, says", [
    ("nosuch:foo", "--bus = 'nosuch:foo': expected a python-can interface: one of"),
    ("hilbus:a/b", "hilbus channel 'a/b'"),
])
def test_bad_bus_exits_2_naming_it(bus: str, says: str, tmp_path: Path, runtime: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    """An unknown interface or a bad channel: exit 2 with the spec and the reason, no folder."""
    code, err = _run(["--bus", bus, "--out", str(tmp_path / "run")], capsys)
    assert code == EXIT_BAD_INPUT and says in err and "Traceback" not in err, err
    assert not (tmp_path / "run").exists()


def test_bad_out_exits_2_naming_it(tmp_path: Path, runtime: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    """--out under a file, or on an existing file: exit 2 naming --out and the path."""
    afile = tmp_path / "afile"
    afile.write_text("x")
    bus = f"hilbus:cli{uuid.uuid4().hex[:8]}"
    for out in (afile / "run", afile):
        code, err = _run(["--bus", bus, "--out", str(out)], capsys)
        assert code == EXIT_BAD_INPUT, err
        assert f"--out = '{out}'" in err and "Traceback" not in err, err


def test_bad_fsw_cmd_placeholder_exits_2_before_any_process(
    tmp_path: Path, runtime: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--fsw-cmd with an unknown {placeholder}: exit 2 naming it; no run folder."""
    code, err = _run(["--bus", f"hilbus:cli{uuid.uuid4().hex[:8]}", "--out",
                      str(tmp_path / "run"), "--fsw-cmd", "fsw --config {foo}"], capsys)
    assert code == EXIT_BAD_INPUT and "--fsw-cmd" in err and "{foo}" in err, err
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("template", ["fsw {config.__class__}", "fsw {config[0]}",
                                      "fsw {config!r}", "fsw {config:>9}", "fsw {config"])
def test_fsw_cmd_placeholders_are_plain_names(
    template: str, tmp_path: Path, runtime: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Attribute or index access, conversions, format specs, an unclosed brace: exit 2."""
    code, err = _run(["--bus", f"hilbus:cli{uuid.uuid4().hex[:8]}", "--out",
                      str(tmp_path / "run"), "--fsw-cmd", template], capsys)
    assert code == EXIT_BAD_INPUT and "--fsw-cmd" in err and "placeholders" in err, err
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("command", ["timing", "report"])
def test_not_a_run_folder_exits_2(command: str, tmp_path: Path,
                                  capsys: pytest.CaptureFixture[str]) -> None:
    """timing and report on a folder without summary.json: both exit 2 naming it."""
    code = main([command, str(tmp_path / "nothing")])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and "summary.json" in err, err
