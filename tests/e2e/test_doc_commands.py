"""Every command shown in a fenced ``sh`` block of README.md and docs/*.md runs (slow).

:data:`PLANS` says, for each command exactly as the doc shows it (its trailing comment
cut), how the test runs it; a test fails if a doc shows a command without a plan or a plan
names a command no doc shows, so the two cannot drift. Each document's commands run in a
scratch folder of its own (``scenarios``, ``dbc``, ``benchmarks`` and ``tests`` link to the
repository's; ``runs/...`` are created there) with a private ``XDG_RUNTIME_DIR``, on a
private hilbus channel (``{private}``), in the document's order.

How (``Plan.how``):
- ``run``: ``Plan.command`` (the doc's command, with ``{private}`` for the private channel and,
  for ``thruster-hil run``/``bench``, a short ``--duration`` and an ``--out`` where the doc
  has none; every change is written out below) must exit with one of ``Plan.exits``.
  A run shortened below its scenario's length may fail its expectations: exit 0 or 1;
- ``live``: needs a running bench; run while one quickstart runs in realtime on ``{private}``;
- ``pair``: the bench alone and then the flight software on its bus (the doc's two
  commands: ``bench ... --bus socketcan:can0`` for a board, and ``python -m flight_sw``);
- ``skip``: not run, ``why`` says why (hardware, a VM, the test suite itself).
"""

from __future__ import annotations

import contextlib
import os
import re
import selectors
import signal
import subprocess
import sys
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.e2e.conftest import RUN_TIMEOUT_S

REPO = Path(__file__).resolve().parents[2]
DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
LINKED = ("scenarios", "dbc", "benchmarks", "tests")
SHORT = "--duration 2"  # a shortened run: 100 control cycles
READY_TIMEOUT_S = 120.0  # wall-clock limit for a background bench to start: a hang guard
STOP_TIMEOUT_S = 60.0
RUN_OR_FAIL = (0, 1)  # a shortened run may miss its scenario's expectations


@dataclass(frozen=True)
class Plan:
    """How the test runs one documented command."""

    how: str  # run, live, pair, skip
    command: str = ""
    exits: tuple[int, ...] = (0,)
    why: str = ""


HIL_Q = "thruster-hil run scenarios/quickstart.toml"
PLANS: dict[str, Plan] = {
    # README.md
    'pip install -e ".[test]"': Plan(
        "skip", why="installs the package: the test session runs inside that install (CI's "
        "install stage runs this command)"),
    "thruster-hil run scenarios/quickstart.toml": Plan(
        "run", f"{HIL_Q} --bus {{private}} {SHORT} --out runs/q", RUN_OR_FAIL),
    "pytest": Plan("skip", why="the test suite itself, of which this test is part"),
    "thruster-hil run scenarios/quickstart.toml --mode realtime": Plan(
        "run", f"{HIL_Q} --mode realtime --bus {{private}} {SHORT} --out runs/rt", RUN_OR_FAIL),
    "thruster-hil run scenarios/quickstart.toml --bus socketcan:vcan0 --seed 7 --out runs/a": Plan(
        "run", f"{HIL_Q} --bus {{private}} --seed 7 --out runs/a {SHORT}", RUN_OR_FAIL,
        why="socketcan:vcan0 needs the kernel's vcan module (CI's SocketCAN stage runs runs "
        "on it); the private hilbus channel instead"),
    'thruster-hil run SCENARIO --fsw-cmd "./my_fsw --can {bus} --cfg {config}"': Plan(
        "run", f'{HIL_Q} --fsw-cmd "./my_fsw --can {{bus}} --cfg {{config}}" --bus {{private}} '
        f"{SHORT} --out runs/own", RUN_OR_FAIL,
        why="SCENARIO is the quickstart; ./my_fsw is a script in the scratch folder that "
        "starts our flight software with those arguments (--can BUS --cfg CONFIG)"),
    "thruster-hil bench scenarios/quickstart.toml --bus socketcan:can0": Plan(
        "pair", f"thruster-hil bench scenarios/quickstart.toml --bus {{private}} {SHORT} "
        "--out runs/board", RUN_OR_FAIL,
        why="socketcan:can0 is a board's bus: the bench runs on the private channel and the "
        "doc's next command, our flight software alone, plays the board"),
    "python -m flight_sw --config runs/a/fsw_config.json --bus hilbus:default --mode lockstep":
        Plan("pair", "python -m flight_sw --config runs/board/fsw_config.json --bus {private} "
             "--mode lockstep",
             why="runs until Ctrl-C: here the flight software of the bench-alone run above, "
             "on its channel, stopped (SIGTERM, exit 0) when that run has ended"),
    "thruster-hil report runs/a": Plan("run", "thruster-hil report runs/a", RUN_OR_FAIL),
    "thruster-hil export runs/a --format csv": Plan("run", "thruster-hil export runs/a "
                                                    "--format csv"),
    "thruster-hil replay runs/a": Plan("run", "thruster-hil replay runs/a"),
    "thruster-hil run scenarios/quickstart.toml --no-plots": Plan(
        "run", f"{HIL_Q} --no-plots --bus {{private}} {SHORT} --out runs/noplots", RUN_OR_FAIL),
    "thruster-hil run scenarios/quickstart.toml --junit runs/results.xml": Plan(
        "run", f"{HIL_Q} --junit runs/results.xml --no-plots --bus {{private}} {SHORT} "
        "--out runs/junit", RUN_OR_FAIL),
    "thruster-hil run scenarios/quickstart.toml --set bus.bitrate_bps=125000": Plan(
        "run", f"{HIL_Q} --set bus.bitrate_bps=125000 --bus {{private}} {SHORT} --out runs/slow",
        RUN_OR_FAIL),
    "thruster-hil timing runs/a": Plan("run", "thruster-hil timing runs/a"),
    "thruster-hil timing --live --bus socketcan:can0 --duration 10": Plan(
        "live", "thruster-hil timing --live --bus {private} --duration 1",
        why="can0 is a hardware bus: the private channel of a running bench, listened to 1 s"),
    "thruster-hil monitor --bus socketcan:can0": Plan(
        "live", "thruster-hil monitor --bus {private} --duration 1",
        why="can0 is a hardware bus: the private channel of a running bench, watched 1 s "
        "(no terminal here: headless, the last picture printed)"),
    "python benchmarks/bus_roundtrip.py": Plan("run", "python benchmarks/bus_roundtrip.py"),
    "bash benchmarks/vcan_vm.sh": Plan(
        "skip", why="boots a QEMU guest for SocketCAN (minutes); CI's SocketCAN stage boots "
        "the same guest"),
    "thruster-hil inject stuck_open --target 3 --bus hilbus:default": Plan(
        "live", "thruster-hil inject stuck_open --target 3 --bus {private}"),
    "thruster-hil inject drop --target 0x40 --param 0.2 --duration 5": Plan(
        "live", "thruster-hil inject drop --target 0x40 --param 0.2 --duration 5 --bus {private}",
        why="the default bus is the running bench's private channel here"),
    "thruster-hil inject stuck_open --target 3 --print-frame 0": Plan(
        "run", "thruster-hil inject stuck_open --target 3 --print-frame 0"),
    "thruster-hil campaign scenarios/fdir_16thr.toml --out runs/campaign": Plan(
        "run", "thruster-hil campaign short.toml --out runs/campaign --fault-time 2 "
        "--kinds stuck_open --jobs 2", RUN_OR_FAIL,
        why="32 runs of 44 s each: the same campaign on short.toml, the quickstart cut to "
        "10 s (8 thrusters, stuck_open only)"),
    "python -m bench.operator.hostile --bus hilbus:default --frames 100000 --forgeries": Plan(
        "live", "python -m bench.operator.hostile --bus {private} --frames 1000 --forgeries",
        why="1000 frames instead of 100 000 (the doc's count is benchmarks/hostile_frames.py's "
        "measurement)"),
    "thruster-hil run scenarios/three_axis_tracking_cascade.toml": Plan(
        "run", f"thruster-hil run scenarios/three_axis_tracking_cascade.toml --bus {{private}} "
        f"{SHORT} --out runs/s003", RUN_OR_FAIL),
    "thruster-hil run scenarios/formation_keeping_nftsm.toml": Plan(
        "run", f"thruster-hil run scenarios/formation_keeping_nftsm.toml --bus {{private}} "
        f"{SHORT} --out runs/s000", RUN_OR_FAIL),
    "thruster-hil run scenarios/formation_keeping_nftsm.toml --set "
    "\"flight_sw.controller={kind='tsm_dq'}\" --set expectations.settling_time_s_max=80 --set "
    "expectations.position_settling_time_s_max=80": Plan(
        "run", "thruster-hil run scenarios/formation_keeping_nftsm.toml --set "
        "\"flight_sw.controller={kind='tsm_dq'}\" --set expectations.settling_time_s_max=80 "
        f"--set expectations.position_settling_time_s_max=80 --bus {{private}} {SHORT} "
        "--out runs/tsm", RUN_OR_FAIL,
        why="shortened: the full 100 s run passes (exit 0), measured when the example was "
        "written"),
    "thruster-hil run scenarios/mrp_trajectory_tracking.toml": Plan(
        "run", f"thruster-hil run scenarios/mrp_trajectory_tracking.toml --bus {{private}} "
        f"{SHORT} --out runs/s001", RUN_OR_FAIL),
    "thruster-hil run scenarios/capture_inertia_identification.toml": Plan(
        "run", f"thruster-hil run scenarios/capture_inertia_identification.toml --bus {{private}} "
        f"{SHORT} --out runs/rls", RUN_OR_FAIL),
    "python benchmarks/reproductions.py --plots docs/img/reproductions": Plan(
        "skip", why="the benchmark behind docs/reproductions.md: 30 full-length runs (many "
        "minutes); each scenario runs above, and tests/e2e/test_reproductions.py runs the "
        "headline variants at full length"),
    "thruster-hil campaign scenarios/campaigns/quickstart_monte_carlo.toml --out runs/mc": Plan(
        "skip", why="200 cases (minutes): docs/campaigns.md's smoke campaign runs below, with the "
        "same machinery"),
    # docs/campaigns.md
    "thruster-hil campaign scenarios/campaigns/quickstart_smoke.toml --out runs/smoke": Plan(
        "run", "thruster-hil campaign scenarios/campaigns/quickstart_smoke.toml --out runs/smoke",
        RUN_OR_FAIL),
    "thruster-hil campaign minimize runs/mc 0042": Plan(
        "skip", why="needs a failing case of a 200-case campaign: tests/e2e/"
        "test_campaign_file.py minimises a failing case of its own"),
    "thruster-hil campaign rerun runs/smoke 0003": Plan(
        "run", "thruster-hil campaign rerun runs/smoke 0003"),
    "thruster-hil campaign margin scenarios/three_axis_tracking_cascade.toml --key "
    "thrust_scale --toward 0.2 --out runs/margin": Plan(
        "run", "thruster-hil campaign margin scenarios/three_axis_tracking_cascade.toml --key "
        "thrust_scale --toward 0.2 --out runs/margin --set scenario.duration_s=20 --set "
        "expectations.steady_state_window_s=5 --tolerance 0.2",
        why="about 8 runs of 60 s: the same search on the scenario cut to 20 s, a coarser "
        "bracket"),
    "python -m dask scheduler --port 8786": Plan(
        "skip", why="a cluster on shared storage: tests/benchmarks/test_campaign_scale_script.py "
        "starts a scheduler and two workers with these commands and runs a campaign on them"),
    "python -m dask worker tcp://HOST:8786 --nthreads 1": Plan(
        "skip", why="as above"),
    "thruster-hil campaign scenarios/campaigns/quickstart_monte_carlo.toml --scheduler "
    "tcp://HOST:8786 --out /shared/runs/mc": Plan(
        "skip", why="as above (a campaign on a scheduler, with its results compared to the "
        "local ones)"),
    "python benchmarks/campaign_scale.py": Plan(
        "skip", why="the acceptance figures: a 200-case campaign and more (many minutes); "
        "tests/benchmarks/test_campaign_scale_script.py runs a small version"),
    # docs/timing-tests.md
    "thruster-hil run scenarios/quickstart.toml --out runs/a --duration 10": Plan(
        "run", f"{HIL_Q} --out runs/a --duration 10 --bus {{private}}", (1,),
        why="as documented: exit 1 (10 s is too short for the quickstart's expectations)"),
    "thruster-hil timing runs/a --json": Plan("run", "thruster-hil timing runs/a --json"),
    "thruster-hil timing runs/a --window-ms 1 --abs-tol-ms 0.5 --rel-tol-pct 5": Plan(
        "run", "thruster-hil timing runs/a --window-ms 1 --abs-tol-ms 0.5 --rel-tol-pct 5"),
    "thruster-hil timing runs/a --strict": Plan("run", "thruster-hil timing runs/a --strict"),
    "thruster-hil timing --live --bus socketcan:vcan0 --duration 10": Plan(
        "live", "thruster-hil timing --live --bus {private} --duration 1",
        why="vcan0 needs the kernel's vcan module: the private channel, 1 s"),
    "thruster-hil timing --live --bus hilbus:default --duration 5 --json": Plan(
        "live", "thruster-hil timing --live --bus {private} --duration 1 --json"),
    'thruster-hil timing --live --bus "pcan:PCAN_USBBUS1?bitrate=1000000" --duration 30 '
    "--bitrate 1000000": Plan(
        "live", "thruster-hil timing --live --bus {private} --duration 1 --bitrate 1000000",
        why="a PEAK USB adapter: the private channel, 1 s, the same --bitrate"),
    "pytest tests/timing_examples": Plan(
        "run", "python -m pytest -q -p no:cacheprovider tests/timing_examples"),
    "pytest tests/timing_examples --hil-bus socketcan:vcan0": Plan(
        "skip", why="SocketCAN: the same tests as the line above, over vcan0 (CI's SocketCAN "
        "stage runs the socketcan-marked tests)"),
    "pytest my_tests --hil-bus socketcan:can0 --hil-fsw-cmd none": Plan(
        "skip", why="a board running flight software on can0"),
    "pytest my_tests --hil-mode realtime": Plan(
        "skip", why="wall-clock assertions, for exploration only (the project's rule: "
        "realtime measurements stay out of pass/fail tests)"),
    "python -m can.logconvert runs/a/trace.asc.gz /tmp/a.log": Plan(
        "run", "python -m can.logconvert runs/a/trace.asc.gz a.log",
        why="a.log in the scratch folder instead of the shared /tmp"),
    "cantools decode --single-line dbc/thruster_hil.dbc < /tmp/a.log": Plan(
        "run", "cantools decode --single-line dbc/thruster_hil.dbc < a.log",
        why="a.log in the scratch folder instead of the shared /tmp"),
}

FENCE = re.compile(r"^```sh\n(.*?)^```", re.S | re.M)


def _uncomment(line: str) -> str:
    """``line`` without a shell comment (a ``#`` after a blank, outside quotes)."""
    quote = ""
    for i, c in enumerate(line):
        if quote:
            quote = "" if c == quote else quote
        elif c in "\"'":
            quote = c
        elif c == "#" and (i == 0 or line[i - 1].isspace()):
            return line[:i].strip()
    return line.strip()


def doc_commands(doc: Path) -> list[str]:
    """The commands of ``doc``'s fenced sh blocks, in order, comments cut."""
    out = []
    for block in FENCE.findall(doc.read_text(encoding="utf-8")):
        out += [c for c in (_uncomment(line) for line in block.splitlines()) if c]
    return out


def test_every_documented_command_has_a_plan() -> None:
    """Each command shown has a plan, each plan a command shown, and each skip a reason."""
    shown = {c for doc in DOCS for c in doc_commands(doc)}
    assert shown - PLANS.keys() == set(), "documented commands without a plan"
    assert PLANS.keys() - shown == set(), "plans for commands no doc shows"
    assert all(p.why for p in PLANS.values() if p.how == "skip")


def _scratch(tmp: Path) -> Path:
    for name in LINKED:
        (tmp / name).symlink_to(REPO / name)
    quick = (REPO / "scenarios" / "quickstart.toml").read_text(encoding="utf-8")
    (tmp / "short.toml").write_text(quick.replace("duration_s = 60.0", "duration_s = 10.0"))
    fsw = tmp / "my_fsw"  # "your flight software": takes --can BUS --cfg CONFIG
    fsw.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m flight_sw --bus "$2" --config "$4"\n')
    fsw.chmod(0o755)
    return tmp


def _env(runtime: Path) -> dict[str, str]:
    bin_dir = str(Path(sys.executable).parent)
    return dict(os.environ, XDG_RUNTIME_DIR=str(runtime),
                PATH=bin_dir + os.pathsep + os.environ.get("PATH", ""))


def _sh(command: str, cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["bash", "-c", command], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=RUN_TIMEOUT_S)


def _check(command: str, done: subprocess.CompletedProcess[str], exits: tuple[int, ...]) -> None:
    tail = "\n".join((done.stderr or "").splitlines()[-5:])
    assert done.returncode in exits, f"{command}: exit {done.returncode}\n{tail}"
    assert "Traceback" not in done.stderr, f"{command}:\n{done.stderr[-3000:]}"


@contextlib.contextmanager
def _background(command: str, cwd: Path, env: dict[str, str],
                ready: str) -> Iterator[subprocess.Popen[str]]:
    """``command`` in its own process group, entered once a stderr line starts with
    ``ready``; on exit stopped with SIGINT (then killed if it does not end)."""
    p = subprocess.Popen(["bash", "-c", f"exec {command}"], cwd=cwd, env=env,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    try:
        assert p.stderr is not None
        with selectors.DefaultSelector() as sel:
            sel.register(p.stderr, selectors.EVENT_READ)
            while True:
                assert sel.select(timeout=READY_TIMEOUT_S), f"{command}: not ready"
                line = p.stderr.readline()
                assert line, f"{command}: ended before it was ready"
                if line.startswith(ready):
                    break
        yield p
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGINT)
            try:
                p.communicate(timeout=STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.communicate()


@pytest.mark.slow
@pytest.mark.parametrize("doc", [d for d in DOCS if doc_commands(d)], ids=lambda d: d.name)
def test_documented_commands_run(doc: Path, tmp_path: Path, runtime: Path) -> None:
    """Each command of ``doc`` runs as planned and exits as it should, with no traceback."""
    commands = doc_commands(doc)
    cwd, env = _scratch(tmp_path), _env(runtime)
    bus = f"hilbus:d{uuid.uuid4().hex[:10]}"
    plans = [PLANS[c] for c in commands]
    pair = [p for p in plans if p.how == "pair"]
    for plan in plans:
        if plan.how == "run":
            command = plan.command.replace("{private}", bus)
            _check(command, _sh(command, cwd, env), plan.exits)
        elif plan.how == "pair" and plan is pair[0]:
            bench, fsw = (p.command.replace("{private}", bus) for p in pair)
            with _background(bench, cwd, env, "bench ready") as b:
                flight = subprocess.Popen(["bash", "-c", f"exec {fsw}"], cwd=cwd, env=env,
                                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                          text=True)
                _, err = b.communicate(timeout=RUN_TIMEOUT_S)
                flight.send_signal(signal.SIGTERM)
                _, fsw_err = flight.communicate(timeout=STOP_TIMEOUT_S)
            assert b.returncode in plan.exits and "Traceback" not in err, err[-3000:]
            assert flight.returncode == 0 and "Traceback" not in fsw_err, fsw_err[-3000:]
    live = [p for p in plans if p.how == "live"]
    if live:
        bench = (f"thruster-hil run scenarios/quickstart.toml --mode realtime --bus {bus} "
                 "--out runs/live")
        with _background(bench, cwd, env, "progress"):
            for plan in live:
                command = plan.command.replace("{private}", bus)
                _check(command, _sh(command, cwd, env), plan.exits)
