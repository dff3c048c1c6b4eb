"""Run one campaign case as ``thruster-hil run`` and turn its run folder into a result row.

A case runs as its own ``thruster-hil run SCENARIO --seed S --set ... --no-plots`` process
(bench + flight software on a portable-bus channel of its own: no ``--bus``), in a fresh
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
files in ``cases/NAME/run/``. ``trace_sha256`` is the digest of the CAN trace's records
(the ASC header's wall-clock date lines left out), the figure a rerun is compared on.
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import uuid
from pathlib import Path
from typing import Any

from bench.operator.verdict import abnormal_events
from bench.results.record import read_lines, run_file
from dbc.errors import RunError
from dbc.records import write_record

EXIT_BAD_INPUT = 2
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
STOP_GRACE_S = 10.0
"""After SIGTERM, seconds a run gets to end its pair and write its folder before SIGKILL."""
TRACE_HEADER = ("date", "Begin Triggerblock")
"""ASC header lines that carry the wall-clock date (left out of the trace digest)."""
RESULT_FILE = "result.json"
CASE_FILE = "case.json"
ATTEMPT_MARK = ".attempt-"
STATUS_OK, STATUS_ERROR, STATUS_REFUSED = "ok", "error", "refused"
NO_ABNORMAL_EVENT = "no_abnormal_event"
"""A campaign requirement of every case: nothing abnormal happened beyond the faults asked
for (:func:`bench.operator.verdict.abnormal_events`: no SAFE latch, deadline miss, watchdog
trip, restart, rejected frame); a run can meet its expectations and still fail this."""
STDERR_TAIL_LINES = 5


class CaseTimeoutError(RunError):
    """The case's run was still going after its timeout (stopped; retried once)."""


def run_command(scenario: Path, case: dict[str, Any], out: Path) -> list[str]:
    """The ``thruster-hil run`` arguments that run ``case`` into ``out``."""
    cmd = ["run", str(scenario), "--seed", str(case["seed"]), "--no-plots", "--out", str(out)]
    for o in case["overrides"]:
        cmd += ["--set", o]
    return cmd


def _die_with_parent() -> None:  # pragma: no cover - runs in the child before exec
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def trace_digest(run_dir: Path) -> str | None:
    """SHA-256 of the run's CAN trace records (module docstring); None without a trace."""
    try:
        path = run_file(run_dir, "trace.asc")
    except FileNotFoundError:
        return None
    if not path.exists():
        return None
    h = hashlib.sha256()
    for line in read_lines(path):
        if not line.startswith(TRACE_HEADER):
            h.update(line.encode("utf-8"))
    return h.hexdigest()


def _metric(s: dict[str, Any], key: str) -> float | None:
    v = s.get(key)
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else None


METRICS = ("settling_time_s", "steady_state_attitude_error_deg", "final_attitude_error_deg",
           "steady_state_rate_error_deg_s", "final_position_error_m",
           "steady_state_position_error_m", "propellant_kg", "latency_p99_us",
           "deadline_misses", "detection_time_s")
"""The figures every row carries (None where the run has none)."""


def result_row(case: dict[str, Any], s: dict[str, Any], run_dir: Path,
               attempt: int = 1) -> dict[str, Any]:
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
        "trace_sha256": trace_digest(run_dir),
        "wall_time_s": _metric(s, "wall_time_s"), "attempts": attempt,
    }


def error_row(case: dict[str, Any], message: str, attempts: int = 1) -> dict[str, Any]:
    """The row of a case that could not complete (recorded, never dropped)."""
    return {"case": case["index"], "name": case["name"], "vehicle": case["vehicle"],
            "seed": case["seed"], "status": STATUS_ERROR, "error": message,
            "failure": case.get("failure"), "passed": False, "requirements": {},
            "figures": dict.fromkeys(METRICS), "values": dict(case["values"]),
            "abnormal": [], "trace_sha256": None, "wall_time_s": None, "attempts": attempts}


def _stop(p: subprocess.Popen[str]) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.killpg(p.pid, signal.SIGTERM)
    try:
        p.wait(STOP_GRACE_S)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, signal.SIGKILL)
        p.wait()


def run_case(case: dict[str, Any], scenario: str, cases_dir: str, timeout_s: float,
             env_extra: dict[str, str], attempt: int = 1) -> dict[str, Any]:
    """Run ``case`` of the campaign (module docstring); its result row (``attempt``: which
    attempt this is, recorded in the row)."""
    final = Path(cases_dir) / case["name"]
    folder = Path(cases_dir) / f"{case['name']}{ATTEMPT_MARK}{uuid.uuid4().hex[:8]}"
    folder.mkdir(parents=True)
    write_record(folder / CASE_FILE, case)
    run_dir = folder / "run"
    env = dict(os.environ, **env_extra)
    cmd = [sys.executable, "-m", "bench.operator.cli",
           *run_command(Path(scenario), case, run_dir)]
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         text=True, start_new_session=True, preexec_fn=_die_with_parent)
    try:
        _, err = p.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        _stop(p)
        shutil.rmtree(folder, ignore_errors=True)
        raise CaseTimeoutError(f"case {case['name']}: still running after {timeout_s:g} s "
                          "(stopped)") from None
    except BaseException:
        _stop(p)
        shutil.rmtree(folder, ignore_errors=True)
        raise
    summary = run_dir / "summary.json"
    if p.returncode == EXIT_BAD_INPUT or not summary.exists():
        tail = " | ".join(err.strip().splitlines()[-STDERR_TAIL_LINES:]) or "(no output)"
        shutil.rmtree(folder, ignore_errors=True)
        message = f"case {case['name']}: run exited {p.returncode}: {tail}"
        if p.returncode == EXIT_BAD_INPUT:
            return dict(error_row(case, message, attempt), status=STATUS_REFUSED)
        raise RunError(message)
    s = json.loads(summary.read_text(encoding="utf-8"))
    row = result_row(case, s, run_dir, attempt)
    write_record(folder / RESULT_FILE, row)
    if final.exists():  # an earlier attempt that finished after all: this one replaces it
        shutil.rmtree(final)
    os.replace(folder, final)
    return row
