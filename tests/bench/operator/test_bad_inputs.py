"""Every row of ``bad_inputs.ROWS`` exits 2 with exactly its one line, and
``docs/bad-inputs.md`` shows exactly that list."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bench.operator.cli import main as cli_main
from flight_sw.__main__ import main as fsw_main
from tests.bench.operator.bad_inputs import FSW, REPO, ROWS, Row, make_files, table

DOC = REPO / "docs" / "bad-inputs.md"
EXIT_BAD_INPUT = 2


@pytest.fixture(scope="module")
def scratch(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The rows' working directory with the files they name (made once: huge.toml is 10 MB)."""
    folder = tmp_path_factory.mktemp("bad-inputs")
    make_files(folder)
    return folder


@pytest.fixture
def in_scratch(scratch: Path, monkeypatch: pytest.MonkeyPatch, runtime: Path) -> Iterator[Path]:
    """Run in the scratch folder, with a private hilbus runtime directory."""
    monkeypatch.chdir(scratch)
    yield scratch


@pytest.mark.parametrize("row", ROWS, ids=[f"{r.tool} {r.input_text}"[:80] for r in ROWS])
def test_bad_input_exits_2_with_its_one_line(row: Row, in_scratch: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    """The row's input: exit 2, its message as the only line on stderr, nothing on stdout."""
    main = fsw_main if row.tool == FSW else cli_main
    code = main(list(row.args))
    out, err = capsys.readouterr()
    assert (code, err, out) == (EXIT_BAD_INPUT, row.message + "\n", "")


def test_doc_table_is_the_list() -> None:
    """docs/bad-inputs.md holds the table of ROWS, row for row."""
    assert table() in DOC.read_text(encoding="utf-8")
