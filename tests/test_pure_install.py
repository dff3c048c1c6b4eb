"""A pure-Python install (``THRUSTER_HIL_PURE=1``) removes the compiled modules an earlier
install left in the source tree, naming each, so that no stale extension shadows a source."""

from __future__ import annotations

import importlib.machinery
import runpy
import shutil
from pathlib import Path

import pytest
import setuptools

REPO = Path(__file__).resolve().parent.parent
SUFFIX = importlib.machinery.EXTENSION_SUFFIXES[0]


def _run_pure_setup(tree: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, object]:
    """Execute ``tree/setup.py`` as a pure install's build backend does, setup() a no-op."""
    monkeypatch.setattr(setuptools, "setup", lambda **kwargs: None)
    monkeypatch.setenv("THRUSTER_HIL_PURE", "1")
    return runpy.run_path(str(tree / "setup.py"), run_name="__main__")


def test_pure_install_removes_stale_extensions(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    """Every listed module's extension and each shared library go, each named on stderr;
    sources and unrelated files stay."""
    shutil.copy(REPO / "setup.py", tmp_path / "setup.py")
    stale = [tmp_path / "bench/station/dynamics/rigid_body", tmp_path / "dbc/codec",
             tmp_path / "flight_sw/compiled__mypyc"]
    keep = [tmp_path / "bench/station/dynamics/rigid_body.py",
            tmp_path / "bench/station/dynamics/other.cpython-311-x86_64-linux-gnu.so"]
    for stem in stale:
        stem.parent.mkdir(parents=True, exist_ok=True)
        stem.with_name(stem.name + SUFFIX).write_bytes(b"\x7fELF")
    for path in keep:
        path.write_text("x")
    _run_pure_setup(tmp_path, monkeypatch)
    err = capsys.readouterr().err
    for stem in stale:
        name = stem.with_name(stem.name + SUFFIX)
        assert not name.exists()
        assert f"removed {name.relative_to(tmp_path)}" in err, err
    assert all(p.exists() for p in keep)


def test_stale_extension_listing_covers_every_compiled_module(tmp_path: Path,
                                                              monkeypatch: pytest.MonkeyPatch
                                                              ) -> None:
    """stale_extensions() finds an extension beside each module of COMPILED."""
    shutil.copy(REPO / "setup.py", tmp_path / "setup.py")
    ns = _run_pure_setup(tmp_path, monkeypatch)
    compiled = ns["COMPILED"]
    assert isinstance(compiled, list)
    for rel in compiled:
        ext = (tmp_path / rel).with_suffix(SUFFIX)
        ext.parent.mkdir(parents=True, exist_ok=True)
        ext.write_bytes(b"")
    found = ns["stale_extensions"](tmp_path)  # type: ignore[operator]
    assert len(found) == len(compiled)
