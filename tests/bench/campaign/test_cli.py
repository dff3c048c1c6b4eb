"""The campaign command's refusals: before any process starts, one line naming the case,
the key and the value; a folder holding another campaign is not overwritten."""

from __future__ import annotations

from pathlib import Path

import pytest

from bench.campaign.cli import EXIT_BAD_INPUT
from bench.operator.campaign import main

REPO = Path(__file__).resolve().parents[3]
QUICKSTART = REPO / "scenarios" / "quickstart.toml"


def _write(tmp: Path, body: str) -> Path:
    f = tmp / "c.toml"
    f.write_text(f'[campaign]\nscenario = "{QUICKSTART}"\ncases = 3\n{body}', encoding="utf-8")
    return f


def test_an_impossible_draw_is_refused_naming_case_and_key(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Ix scaled x10 breaks the triangle inequality: exit 2 naming case 0000 and the inertia."""
    f = _write(tmp_path, '[[dispersions]]\nname = "inertia_xx"\ndist = "sweep"\n'
               'values = [10.0]\napply = "scale"\n')
    code = main([str(f), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT, err
    assert "case 0000" in err and "inertia_B_kgm2" in err and "check its distribution" in err
    assert not (tmp_path / "out").exists()


def test_legacy_options_are_refused_with_a_campaign_file(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """--fault-time belongs to the campaign file's [campaign] table: exit 2 saying so."""
    f = _write(tmp_path, "")
    code = main([str(f), "--out", str(tmp_path / "out"), "--fault-time", "3"])
    assert code == EXIT_BAD_INPUT and "fault_time_s" in capsys.readouterr().err


def test_a_folder_holding_something_else_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """--out with files of something else: exit 2, the files untouched."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine", encoding="utf-8")
    f = _write(tmp_path, '[[dispersions]]\nname = "latency"\ndist = "sweep"\nvalues = [0.001]\n')
    code = main([str(f), "--out", str(out)])
    assert code == EXIT_BAD_INPUT and "a new or empty folder" in capsys.readouterr().err
    assert (out / "keep.txt").read_text(encoding="utf-8") == "mine"


def test_rerun_never_deletes_a_folder_it_did_not_make(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """rerun --out naming a folder with files: exit 2 before any run, the files kept."""
    from bench.campaign.tools import main as tool_main

    case = tmp_path / "camp" / "cases" / "0001"
    case.mkdir(parents=True)
    (case / "case.json").write_text('{"name": "0001"}', encoding="utf-8")
    (case / "result.json").write_text('{"trace_sha256": null}', encoding="utf-8")
    out = tmp_path / "mine"
    out.mkdir()
    (out / "keep.txt").write_text("mine", encoding="utf-8")
    code = tool_main(["rerun", str(tmp_path / "camp"), "0001", "--out", str(out)])
    assert code == EXIT_BAD_INPUT and "a new or empty folder" in capsys.readouterr().err
    assert (out / "keep.txt").read_text(encoding="utf-8") == "mine"


def test_prune_drops_a_passing_case_trace_and_keeps_every_tenth_row(tmp_path: Path) -> None:
    """A passing case that is not among the worst: its traces gone, its telemetry the header
    and rows 0, 10, 20; a failing case untouched."""
    import gzip

    from bench.campaign.cli import prune
    from bench.results.record import LEAN_TELEMETRY_EVERY

    rows = []
    for name, passed in (("0000", True), ("0001", False)):
        run = tmp_path / "cases" / name / "run"
        run.mkdir(parents=True)
        (run.parent / "result.json").write_text("{}", encoding="utf-8")
        with gzip.open(run / "telemetry.csv.gz", "wt", encoding="utf-8") as f:
            f.write("t_s\n" + "".join(f"{i}\n" for i in range(25)))
        with gzip.open(run / "trace.asc.gz", "wt", encoding="utf-8") as f:
            f.write("date x\n")
        (run / "trace.blf").write_bytes(b"LOGG")
        rows.append({"name": name, "status": "ok", "passed": passed})
    assert prune(tmp_path, rows, {"worst": {}}, "failing") == 1
    kept = tmp_path / "cases" / "0000" / "run"
    with gzip.open(kept / "telemetry.csv.gz", "rt", encoding="utf-8") as f:
        assert f.read().split() == ["t_s", *(str(i) for i in range(0, 25, LEAN_TELEMETRY_EVERY))]
    assert not (kept / "trace.asc.gz").exists() and not (kept / "trace.blf").exists()
    assert (tmp_path / "cases" / "0001" / "run" / "trace.asc.gz").exists()
    assert (tmp_path / "cases" / "0001" / "run" / "trace.blf").exists()


def test_prune_leaves_a_lean_case_telemetry_as_it_is(tmp_path: Path) -> None:
    """A passing lean case (no trace.asc: its telemetry already a tenth): only its trace.blf
    goes; every telemetry row stays."""
    import gzip

    from bench.campaign.cli import prune

    run = tmp_path / "cases" / "0000" / "run"
    run.mkdir(parents=True)
    (run.parent / "result.json").write_text("{}", encoding="utf-8")
    rows_text = "t_s\n" + "".join(f"{i}\n" for i in range(25))
    with gzip.open(run / "telemetry.csv.gz", "wt", encoding="utf-8") as f:
        f.write(rows_text)
    (run / "trace.blf").write_bytes(b"LOGG")
    rows = [{"name": "0000", "status": "ok", "passed": True}]
    assert prune(tmp_path, rows, {"worst": {}}, "failing") == 1
    with gzip.open(run / "telemetry.csv.gz", "rt", encoding="utf-8") as f:
        assert f.read() == rows_text
    assert not (run / "trace.blf").exists()


def test_a_folder_of_an_earlier_digest_format_is_not_resumed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A manifest without this version's format (its rows digested trace.asc): exit 2 saying
    so, the folder left as it was."""
    import json

    f = _write(tmp_path, "")
    out = tmp_path / "out"
    out.mkdir()
    old = {"scenario_sha256": "x", "keep": "failing", "worst": 5, "cases": {}}
    (out / "manifest.json").write_text(json.dumps(old), encoding="utf-8")
    code = main([str(f), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and "earlier version" in err, err
    assert json.loads((out / "manifest.json").read_text(encoding="utf-8")) == old


def test_a_scheduler_that_refuses_is_bad_input_at_once_and_makes_no_folder(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """--scheduler at a port nobody listens on: exit 2 naming the address, without Dask's
    30 s of retries, and no campaign folder made."""
    import socket

    with socket.socket() as s:  # a port that was free a moment ago
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    f = _write(tmp_path, "")
    out = tmp_path / "out"
    code = main([str(f), "--out", str(out), "--scheduler", f"tcp://127.0.0.1:{port}"])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and f"127.0.0.1:{port}" in err, err
    assert not out.exists()
