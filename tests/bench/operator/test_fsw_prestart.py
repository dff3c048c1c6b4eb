"""bench.operator.fsw_prestart: the flight software's interpreter started before its command
line is known runs that command as a cold start would, and ends with the bench."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from bench.operator.entry import wants_prestart
from bench.operator.fsw_prestart import PRESTART_ENV, FswPrestart
from bench.operator.warm_start import WARM_ENV

pytestmark = pytest.mark.skipif(not hasattr(os, "pidfd_open"), reason="Linux only")

PROGRAM_EXIT = 7  # what the test program exits with
WAIT_S = 30.0  # a hang guard for the processes, not a measurement
POLL_S = 0.005  # polling the child's log for its first line
MARK = "TEST_PRESTART_MARK"
ENDED_BY_CLOSE = (0, -signal.SIGTERM)
PROGRAM = '''
import json, os, signal, sys
def on_term(*_):
    print("terminated", flush=True)
    sys.exit(0)
signal.signal(signal.SIGTERM, on_term)
print(json.dumps({
    "argv": sys.argv[1:],
    "cwd": os.getcwd(),
    "mark": os.environ.get("TEST_PRESTART_MARK"),
    "sigint_python": signal.getsignal(signal.SIGINT) is signal.default_int_handler,
    "stdin": os.path.realpath(f"/proc/self/fd/0"),
    "parent_is_prestart": b"fsw_prestart" in open(f"/proc/{os.getppid()}/cmdline", "rb").read(),
}), flush=True)
if sys.argv[1] == "wait":
    while True:
        signal.pause()
sys.exit(int(sys.argv[1]))
'''


@pytest.fixture
def program(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    """A package ``prestart_probe_<n>`` whose ``__main__`` reports its state, on the
    PYTHONPATH of the processes started here."""
    name = f"prestart_probe_{os.getpid()}_{abs(hash(tmp_path)) % 10**6}"
    pkg = tmp_path / "lib" / name
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("", encoding="utf-8")
    (pkg / "__main__.py").write_text("if __name__ == '__main__':\n" + "".join(
        f"    {line}\n" for line in PROGRAM.strip().splitlines()), encoding="utf-8")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        [str(tmp_path / "lib"), *filter(None, [os.environ.get("PYTHONPATH")])]))
    yield name


@pytest.fixture
def prestart(program: str) -> Iterator[FswPrestart]:
    """A prestart for the test program, reaped after the test."""
    p = FswPrestart(program)
    try:
        yield p
    finally:
        p.close()


def _argv(program: str, arg: str) -> list[str]:
    return [sys.executable, "-m", program, arg]


def _report(log: Path) -> dict[str, object]:
    return json.loads(log.read_text(encoding="utf-8").splitlines()[0])


def _running(log: Path) -> None:
    """Wait until the child has printed its report (its SIGTERM handler is set by then)."""
    deadline = time.monotonic() + WAIT_S
    while not log.read_text(encoding="utf-8").endswith("\n"):
        assert time.monotonic() < deadline, "the child never started"
        time.sleep(POLL_S)


def test_the_command_runs_with_its_argv_environment_folder_and_log(
        prestart: FswPrestart, program: str, tmp_path: Path) -> None:
    """argv, environment, working folder, log and exit code are the request's; SIGINT is
    the interpreter's own (KeyboardInterrupt), stdin /dev/null; the prestart then ends."""
    log = tmp_path / "fsw.log"
    env = dict(os.environ, **{MARK: "yes"})
    proc = prestart.run(_argv(program, str(PROGRAM_EXIT)), env, str(tmp_path), str(log))
    assert proc is not None
    assert proc.wait(WAIT_S) == PROGRAM_EXIT and proc.poll() == PROGRAM_EXIT
    assert _report(log) == {"argv": [str(PROGRAM_EXIT)], "cwd": str(tmp_path), "mark": "yes",
                            "sigint_python": True, "stdin": os.devnull,
                            "parent_is_prestart": True}
    prestart.release()  # the bench closed its end on the exit record: the console's too
    assert prestart._proc.wait(WAIT_S) == 0


def test_a_signal_reaches_the_child_and_its_exit_is_reported(
        prestart: FswPrestart, program: str, tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    """wait() times out while it runs; SIGTERM ends it (its handler: exit 0), SIGKILL
    gives -9; signalling an ended child is a no-op."""
    log = tmp_path / "fsw.log"
    proc = prestart.run(_argv(program, "wait"), dict(os.environ), str(tmp_path), str(log))
    assert proc is not None
    _running(log)
    with pytest.raises(subprocess.TimeoutExpired):
        proc.wait(0.05)
    assert proc.poll() is None
    proc.terminate()
    assert proc.wait(WAIT_S) == 0
    assert "terminated" in log.read_text(encoding="utf-8")

    def must_not_signal(*_args: object) -> None:
        raise AssertionError("an ended child was signalled")

    monkeypatch.setattr(signal, "pidfd_send_signal", must_not_signal)
    proc.kill()  # ended: nothing is signalled
    assert proc.returncode == 0


def test_the_bench_gone_stops_the_child_and_ends_the_prestart(
        prestart: FswPrestart, program: str, tmp_path: Path) -> None:
    """Every end of the pipe let go (the bench died) while the child runs: the child gets
    SIGTERM (as a cold child's PR_SET_PDEATHSIG gives it), then the prestart ends, 0."""
    log = tmp_path / "fsw.log"
    proc = prestart.run(_argv(program, "wait"), dict(os.environ), str(tmp_path), str(log))
    assert proc is not None
    _running(log)
    pid = proc.pid
    prestart.release()
    proc._request.close()  # the bench's own end: as its death closes it
    prestart._proc.wait(WAIT_S)
    assert prestart._proc.returncode == 0
    assert "terminated" in log.read_text(encoding="utf-8")
    with pytest.raises(ProcessLookupError):  # reaped: no zombie left
        os.kill(pid, 0)


def test_sigterm_to_the_prestart_stops_the_child_and_reports_its_exit(
        prestart: FswPrestart, program: str, tmp_path: Path) -> None:
    """SIGTERM to the prestart (a whole process group stopped): the child gets SIGTERM,
    its own exit code (0 from its handler) still reaches the bench, the prestart ends."""
    log = tmp_path / "fsw.log"
    proc = prestart.run(_argv(program, "wait"), dict(os.environ), str(tmp_path), str(log))
    assert proc is not None
    _running(log)
    prestart._proc.terminate()
    assert proc.wait(WAIT_S) == 0
    assert "terminated" in log.read_text(encoding="utf-8")
    assert prestart._proc.wait(WAIT_S) == 0


def test_without_a_request_it_ends_with_its_pipe(prestart: FswPrestart) -> None:
    """A run refused before its flight software: the prestart's stdin closes (the bench
    and the console let go), it exits 0 once imported."""
    prestart.release()
    assert prestart._proc.wait(WAIT_S) == 0


def test_the_console_end_stops_one_still_there(prestart: FswPrestart) -> None:
    """close() at the console's end: a prestart whose pipe is still open elsewhere (no end
    of file would end it) gets SIGTERM (0 from its handler, or -SIGTERM before the
    interpreter set it), whatever it was doing."""
    assert prestart._proc.stdin is not None
    held = os.dup(prestart._proc.stdin.fileno())  # another holder of the request pipe
    try:
        prestart.close()
        assert prestart._proc.returncode in ENDED_BY_CLOSE
    finally:
        os.close(held)


def test_another_command_or_interpreter_set_up_is_not_its_to_run(
        prestart: FswPrestart, program: str, tmp_path: Path) -> None:
    """Another module, interpreter or PYTHON* start-up variable: None (start it cold)."""
    env = dict(os.environ)
    log = str(tmp_path / "fsw.log")
    assert prestart.run([sys.executable, "-m", "other_module"], env, str(tmp_path), log) is None
    assert prestart.run(["/bin/true", "-m", program], env, str(tmp_path), log) is None
    assert prestart.run(_argv(program, "0"), env | {"PYTHONHASHSEED": "1234"}, str(tmp_path),
                        log) is None
    assert prestart.serves(_argv(program, "0"), env | {"PYTHONUNBUFFERED": "1"})


def test_failed_imports_answer_none(tmp_path: Path) -> None:
    """A module that cannot be imported: no child, None (the bench starts the command,
    whose log then says why)."""
    p = FswPrestart("no_such_module_for_prestart")
    try:
        argv = [sys.executable, "-m", "no_such_module_for_prestart"]
        assert p.run(argv, dict(os.environ), str(tmp_path), str(tmp_path / "log")) is None
        p.release()
        assert p._proc.wait(WAIT_S) == 0  # it answered the error and ended (a crash: 1)
    finally:
        p.close()


@pytest.mark.parametrize(("argv", "expected"), [
    (["run", "s.toml"], True),
    (["run", "s.toml", "--no-plots", "--seed", "3"], True),
    (["run", "s.toml", "--fsw-cmd", "x"], False),
    (["run", "s.toml", "--fsw-cmd=x"], False),
    (["run", "s.toml", "--fsw", "x"], False),
    (["run", "s.toml", "--fsw-c=x"], False),
    (["run", "s.toml", "--f", "x"], False),
    (["run", "--help"], False),
    (["bench", "s.toml"], False),
    (["report", "d"], False),
    ([], False),
])
def test_only_a_run_of_the_default_flight_software_wants_one(
        argv: list[str], expected: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    """``run`` without ``--fsw-cmd`` or help; not when turned off or already warm."""
    monkeypatch.delenv(PRESTART_ENV, raising=False)
    monkeypatch.delenv(WARM_ENV, raising=False)
    assert wants_prestart(argv) is expected
    monkeypatch.setenv(PRESTART_ENV, "0")
    assert wants_prestart(argv) is False
    monkeypatch.setenv(PRESTART_ENV, "1")
    monkeypatch.setenv(WARM_ENV, "1")
    assert wants_prestart(argv) is False


def test_the_console_script_is_the_entry() -> None:
    """pyproject's ``thruster-hil`` runs bench.operator.entry:main (the prestart's start)."""
    import tomllib

    pyproject = Path(__file__).resolve().parents[3] / "pyproject.toml"
    scripts = tomllib.loads(pyproject.read_text(encoding="utf-8"))["project"]["scripts"]
    assert scripts["thruster-hil"] == "bench.operator.entry:main"
