"""bench.operator.warm_start: a program forked from this process runs as a fresh one would."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from bench.operator.warm_start import (
    WARM_ENV,
    ForkedProcess,
    exit_code,
    fork_program,
    run_module,
    warm_module,
)

PROGRAM_EXIT = 7  # what the test program exits with
WAIT_S = 30.0  # a hang guard for the children, not a measurement
SHORT_WAIT_S = 0.05
PROGRAM = '''
import atexit, json, os, signal, sys
report = {
    "argv": sys.argv[1:],
    "sigterm_default": signal.getsignal(signal.SIGTERM) == signal.SIG_DFL,
    "sigusr1_default": signal.getsignal(signal.SIGUSR1) == signal.SIG_DFL,
    "sigint_python": signal.getsignal(signal.SIGINT) is signal.default_int_handler,
    "blocked": sorted(int(s) for s in signal.pthread_sigmask(signal.SIG_BLOCK, [])),
    "fds_open": [],
}
for fd in json.loads(os.environ["TEST_INHERITED_FDS"]):
    try:
        os.fstat(fd)
        report["fds_open"].append(fd)
    except OSError:
        pass
print(json.dumps(report))
atexit.register(lambda: print("atexit ran", file=sys.stderr))
if sys.argv[1] == "crash":
    raise RuntimeError("boom")
if sys.argv[1] == "wait":
    signal.pause()
sys.exit(int(sys.argv[1]))
'''


@pytest.fixture
def program(tmp_path: Path) -> Iterator[str]:
    """A package ``warm_probe_<n>`` whose ``__main__`` reports its state, imported here."""
    import importlib

    name = f"warm_probe_{os.getpid()}_{abs(hash(tmp_path)) % 10**6}"
    pkg = tmp_path / name
    pkg.mkdir()
    (pkg / "__init__.py").write_text("", encoding="utf-8")
    (pkg / "__main__.py").write_text("if __name__ == '__main__':\n" + "".join(
        f"    {line}\n" for line in PROGRAM.strip().splitlines()), encoding="utf-8")
    sys.path.insert(0, str(tmp_path))
    try:
        importlib.import_module(f"{name}.__main__")
        yield name
    finally:
        sys.path.remove(str(tmp_path))
        for m in [m for m in sys.modules if m.startswith(name)]:
            del sys.modules[m]


def _run(program: str, arg: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
         inherited: list[int]) -> tuple[ForkedProcess, Path, Path]:
    monkeypatch.setenv("TEST_INHERITED_FDS", json.dumps(inherited))
    out, err = tmp_path / "out.txt", tmp_path / "err.txt"
    with open(out, "wb") as fo, open(err, "wb") as fe:
        child = fork_program(run_module(program, [arg]), fo.fileno(), fe.fileno())
    return child, out, err


def test_warm_module_needs_the_request_the_interpreter_and_the_imported_main(
        program: str) -> None:
    """Only ``[this python, -m, M, ...]`` with M.__main__ imported and WARM_ENV=1 is warm."""
    env = {WARM_ENV: "1"}
    assert warm_module([sys.executable, "-m", program, "x"], env) == program
    assert warm_module([sys.executable, "-m", program], {}) is None
    assert warm_module([sys.executable, "-m", "not_imported_pkg"], env) is None
    assert warm_module(["/bin/true", "-m", program], env) is None
    assert warm_module([sys.executable, program], env) is None


def test_the_child_gets_fresh_signals_no_inherited_fds_and_its_exit_code(
        program: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Handlers set here are back to the defaults, SIGINT raises KeyboardInterrupt, no
    signal is blocked, a descriptor open here is closed there; argv, stdout, the exit code
    and the exit handlers are the program's."""
    r, w = os.pipe()
    old_term = signal.signal(signal.SIGTERM, lambda *_: None)
    old_usr1 = signal.signal(signal.SIGUSR1, lambda *_: None)
    try:
        child, out, err = _run(program, str(PROGRAM_EXIT), tmp_path, monkeypatch, [r, w])
        assert child.wait(WAIT_S) == PROGRAM_EXIT
    finally:
        signal.signal(signal.SIGTERM, old_term)
        signal.signal(signal.SIGUSR1, old_usr1)
        os.close(r)
        os.close(w)
    report = json.loads(out.read_text(encoding="utf-8"))
    assert report == {"argv": [str(PROGRAM_EXIT)], "sigterm_default": True,
                      "sigusr1_default": True, "sigint_python": True, "blocked": [],
                      "fds_open": []}
    assert "atexit ran" in err.read_text(encoding="utf-8")
    assert child.poll() == PROGRAM_EXIT and child.returncode == PROGRAM_EXIT


def test_an_uncaught_exception_prints_its_traceback_and_exits_1(
        program: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """As the interpreter does: traceback on stderr, exit status 1, exit handlers run."""
    child, _, err = _run(program, "crash", tmp_path, monkeypatch, [])
    assert child.wait(WAIT_S) == 1
    text = err.read_text(encoding="utf-8")
    assert "RuntimeError: boom" in text and "atexit ran" in text


def test_wait_times_out_and_a_signal_ends_the_child(
        program: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """wait() raises TimeoutExpired while it runs; terminate() ends it: -SIGTERM."""
    child, _, _ = _run(program, "wait", tmp_path, monkeypatch, [])
    with pytest.raises(subprocess.TimeoutExpired):
        child.wait(SHORT_WAIT_S)
    assert child.poll() is None
    child.terminate()
    assert child.wait(WAIT_S) == -signal.SIGTERM
    child.kill()  # reaped already: nothing to signal, no error


@pytest.mark.parametrize(("code", "expected"), [(None, 0), (0, 0), (3, 3), ("bad", 1)])
def test_exit_code_is_what_sys_exit_gives(code: object, expected: int) -> None:
    """sys.exit(None) 0, an int itself, anything else 1."""
    assert exit_code(code) == expected
