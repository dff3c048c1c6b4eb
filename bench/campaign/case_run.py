"""Run one campaign case as ``thruster-hil run`` and turn its run folder into a result row.

A case runs as its own ``thruster-hil run SCENARIO --seed S --set ... --no-plots`` process
(bench + flight software on a portable-bus channel of its own: no ``--bus``): on a Dask
worker of the campaign, forked by the worker's zygote (bench.campaign.zygote: the same
run without the imports, ~0.6 CPU-s less a case); elsewhere a new interpreter. In a fresh
attempt folder ``cases/NAME.attempt-<hex>/`` that is renamed to ``cases/NAME/`` only
once the run has ended and its result is written, so a killed or repeated attempt never
leaves a half case under the final name and a case is never counted twice. The run is
started in a session of its own and is told to stop (SIGTERM, its run lifecycle then
ends the pair) if the process that started it dies (Linux ``PR_SET_PDEATHSIG``): a lost
Dask worker takes its run with it. A run still going after ``timeout_s`` is stopped and
:class:`CaseTimeoutError` raised (the engine retries once). Exit 2 (a refused input) returns
a row with status ``"refused"``: not retried (the same input is refused again).

Out: ``cases/NAME/case.json`` (the case: overrides, seed, the command that reproduces it)
and ``cases/NAME/result.json`` (the row: :func:`result_row`), beside the run folder's
files in ``cases/NAME/run/`` and the run's console output, ``cases/NAME/console.log``.
``trace_sha256`` is the run's own digest of its CAN trace (summary.json, bench.wire.trace:
the frames and trace events in order, whatever the record level or file format), the figure
a rerun is compared on.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import uuid
from pathlib import Path
from typing import Any

from bench.campaign.zygote import Zygote
from bench.operator.verdict import abnormal_events
from bench.operator.warm_start import die_with_parent
from bench.results.record import RECORD_STANDARD
from dbc.errors import RunError
from dbc.records import write_record

EXIT_BAD_INPUT = 2
STOP_GRACE_S = 10.0
"""After SIGTERM, seconds a run gets to end its pair and write its folder before SIGKILL."""
RESULT_FILE = "result.json"
CASE_FILE = "case.json"
CONSOLE_FILE = "console.log"
"""The run's console output (stdout and stderr: progress, notices, warnings, the verdict),
kept with the case."""
ATTEMPT_MARK = ".attempt-"
STATUS_OK, STATUS_ERROR, STATUS_REFUSED = "ok", "error", "refused"
NO_ABNORMAL_EVENT = "no_abnormal_event"
"""A campaign requirement of every case: nothing abnormal happened beyond the faults asked
for (:func:`bench.operator.verdict.abnormal_events`: no SAFE latch, deadline miss, watchdog
trip, restart, rejected frame); a run can meet its expectations and still fail this."""
STDERR_TAIL_LINES = 5


class CaseTimeoutError(RunError):
    """The case's run was still going after its timeout (stopped; retried once)."""


def run_command(scenario: Path, case: dict[str, Any], out: Path,
                record: str = RECORD_STANDARD, plots: bool = False) -> list[str]:
    """The ``thruster-hil run`` arguments that run ``case`` into ``out`` (at the record
    level ``record``, bench.results.record; with its plots if ``plots``)."""
    cmd = ["run", str(scenario), "--seed", str(case["seed"]), "--out", str(out)]
    if not plots:
        cmd.insert(4, "--no-plots")
    if record != RECORD_STANDARD:
        cmd += ["--record", record]
    for o in case["overrides"]:
        cmd += ["--set", o]
    return cmd


def _metric(s: dict[str, Any], key: str) -> float | None:
    v = s.get(key)
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else None


METRICS = ("settling_time_s", "steady_state_attitude_error_deg", "final_attitude_error_deg",
           "steady_state_rate_error_deg_s", "final_position_error_m",
           "steady_state_position_error_m", "propellant_kg", "latency_p99_us",
           "deadline_misses", "detection_time_s")
"""The figures every row carries (None where the run has none)."""


def result_row(case: dict[str, Any], s: dict[str, Any], attempt: int = 1) -> dict[str, Any]:
    """A case's result: what it was, what its run reported, its requirements."""
    lat = (s.get("latency_us") or {}).get("sensor_to_command") or {}
    fdir = s.get("fdir") or {}
    failure = case.get("failure")
    t_det = fdir.get("detection_time_s")
    figures: dict[str, float | None] = {k: _metric(s, k) for k in METRICS}
    figures["latency_p99_us"] = _metric(lat, "p99")
    figures["detection_time_s"] = (None if failure is None or t_det is None
                                   else round(t_det - case["fault_time_s"], 6))
    reqs = {e["name"]: bool(e["pass"]) for e in s.get("expectations", [])}
    events = abnormal_events(s)
    reqs[NO_ABNORMAL_EVENT] = not events
    if failure is not None:
        reqs["failure_isolated"] = (fdir.get("failed_thruster") == failure[1]
                                    and fdir.get("failure_kind") == failure[0])
    return {
        "case": case["index"], "name": case["name"], "vehicle": case["vehicle"],
        "seed": case["seed"], "status": STATUS_OK, "error": None,
        "failure": failure, "passed": bool(s.get("passed")) and all(reqs.values()),
        "requirements": reqs, "figures": figures, "values": dict(case["values"]),
        "abnormal": events, "warnings": list(s.get("warnings") or []),
        "trace_sha256": s.get("trace_sha256"),
        "wall_time_s": _metric(s, "wall_time_s"), "attempts": attempt,
    }


def error_row(case: dict[str, Any], message: str, attempts: int = 1) -> dict[str, Any]:
    """The row of a case that could not complete (recorded, never dropped)."""
    return {"case": case["index"], "name": case["name"], "vehicle": case["vehicle"],
            "seed": case["seed"], "status": STATUS_ERROR, "error": message,
            "failure": case.get("failure"), "passed": False, "requirements": {},
            "figures": dict.fromkeys(METRICS), "values": dict(case["values"]),
            "abnormal": [], "trace_sha256": None, "wall_time_s": None, "attempts": attempts}


def _stop(p: subprocess.Popen[bytes]) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.killpg(p.pid, signal.SIGTERM)
    try:
        p.wait(STOP_GRACE_S)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, signal.SIGKILL)
        p.wait()


def _run_cold(argv: list[str], env: dict[str, str], console: Path, timeout_s: float) -> int:
    """``thruster-hil ARGV`` as a new interpreter; its exit code (TimeoutExpired: stopped)."""
    with open(console, "wb") as out:
        p = subprocess.Popen([sys.executable, "-m", "bench.operator.entry", *argv], env=env,
                             stdin=subprocess.DEVNULL, stdout=out, stderr=out,
                             start_new_session=True, preexec_fn=die_with_parent)
    try:
        return p.wait(timeout_s)
    except BaseException:
        _stop(p)
        raise


def _tail(path: Path) -> str:
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return "(no output)"
    return " | ".join(text.strip().splitlines()[-STDERR_TAIL_LINES:]) or "(no output)"


def run_case(case: dict[str, Any], scenario: str, cases_dir: str, timeout_s: float,
             env_extra: dict[str, str], attempt: int = 1, warm: str | Zygote | None = None,
             record: str = RECORD_STANDARD) -> dict[str, Any]:
    """Run ``case`` of the campaign (module docstring); its result row (``attempt``: which
    attempt this is, recorded in the row; ``warm``: the zygote that starts the run, or the
    name of the Dask worker plugin whose zygote does, bench.campaign.warm_workers; None: a
    new interpreter; ``record``: the run's record level, bench.results.record)."""
    final = Path(cases_dir) / case["name"]
    folder = Path(cases_dir) / f"{case['name']}{ATTEMPT_MARK}{uuid.uuid4().hex[:8]}"
    folder.mkdir(parents=True)
    write_record(folder / CASE_FILE, case)
    run_dir = folder / "run"
    env = dict(os.environ, **env_extra)
    argv = run_command(Path(scenario), case, run_dir, record)
    console = folder / CONSOLE_FILE
    zygote = warm if isinstance(warm, Zygote) else None
    if isinstance(warm, str):
        from bench.campaign.warm_workers import worker_zygote

        zygote = worker_zygote(warm)
    try:
        if zygote is not None:
            returncode = zygote.run(argv, env, console, timeout_s)
        else:
            returncode = _run_cold(argv, env, console, timeout_s)
    except subprocess.TimeoutExpired:
        shutil.rmtree(folder, ignore_errors=True)
        raise CaseTimeoutError(f"case {case['name']}: still running after {timeout_s:g} s "
                               "(stopped)") from None
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    summary = run_dir / "summary.json"
    if returncode == EXIT_BAD_INPUT or not summary.exists():
        tail = _tail(console)
        shutil.rmtree(folder, ignore_errors=True)
        message = f"case {case['name']}: run exited {returncode}: {tail}"
        if returncode == EXIT_BAD_INPUT:
            return dict(error_row(case, message, attempt), status=STATUS_REFUSED)
        raise RunError(message)
    s = json.loads(summary.read_text(encoding="utf-8"))
    row = result_row(case, s, attempt)
    write_record(folder / RESULT_FILE, row)
    if final.exists():  # an earlier attempt that finished after all: this one replaces it
        shutil.rmtree(final)
    os.replace(folder, final)
    return row
