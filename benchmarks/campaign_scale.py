"""Campaign scale as JSON: throughput against one case alone, identical results three ways,
a lost worker, and margin searches (issue 21's acceptance figures).

Sections (each runs real ``thruster-hil`` processes; every case on a portable-bus channel of
its own, every campaign in a folder of its own under a scratch directory):

- ``throughput``: the whole ``thruster-hil run`` command of one case alone (interpreter
  start to exit, ``--no-plots`` as a campaign runs its cases), ``--single-runs`` times,
  half before the campaign and half after it, median T1; the Monte Carlo campaign ``--mc``
  (the shipped scenarios/campaigns/quickstart_monte_carlo.toml, ``--mc-cases`` of its
  cases) on the local default (a Dask cluster sized to the machine): wall time, cases per
  minute, CPU use, pass rates with intervals; ``ratio`` = cases per minute / (60 · cores /
  T1), the target 0.8.
- ``three_ways``: ``--three-way-cases`` of the same campaign run on the local default, on
  a real scheduler with two workers started as separate processes with Dask's own
  commands (``python -m dask scheduler`` / ``python -m dask worker``), and
  ``thruster-hil campaign rerun`` of three chosen cases: per-case results compared
  (everything but wall time; the trace digest included).
- ``lost_worker``: the same cases on a scheduler with two workers, one killed (SIGKILL)
  while cases run: the campaign's exit, its case count, duplicates, and equality with the
  local results.
- ``margins``: ``thruster-hil campaign margin`` on scenarios/three_axis_tracking_cascade.toml
  (seed 003) for ``latency`` toward ``--latency-toward`` and ``thrust_scale`` toward
  ``--scale-toward``: the boundary, its uncertainty, the margin, the runs it took.

``--duration S`` shortens every case (a ``set`` override of scenario.duration_s and the
steady-state window) for a quick version; CI runs a small one
(tests/benchmarks/test_campaign_scale_script.py).

    python benchmarks/campaign_scale.py                         # the acceptance figures
    python benchmarks/campaign_scale.py --mc-cases 8 --three-way-cases 4 --duration 4
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
MC_FILE = REPO / "scenarios" / "campaigns" / "quickstart_monte_carlo.toml"
QUICKSTART = REPO / "scenarios" / "quickstart.toml"
CASCADE = REPO / "scenarios" / "three_axis_tracking_cascade.toml"
HIL = [sys.executable, "-m", "bench.operator.entry"]
CLUSTER_WORKERS = 2
CLUSTER_TIMEOUT_S = 60.0
POLL_S = 0.05  # polling the scratch folder for a running case (the benchmark's own loop)
COMPARED = ("status", "passed", "seed", "requirements", "figures", "values", "trace_sha256",
            "failure")
RERUN_PICKS = 3
TARGET_RATIO = 0.8
NS_PER_S = 1e9


def _campaign_file(scratch: Path, cases: int, duration_s: float | None) -> Path:
    """The shipped Monte Carlo file with ``cases`` and, if given, a shorter duration."""
    text = MC_FILE.read_text(encoding="utf-8")
    text = re.sub(r"(?m)^cases = \d+", f"cases = {cases}", text)
    text = text.replace('scenario = "../quickstart.toml"',
                        f"scenario = {json.dumps(str(QUICKSTART))}")
    if duration_s is not None:
        window = min(10.0, duration_s / 3)
        sets = (f'set = ["scenario.duration_s={duration_s}", '
                f'"expectations.steady_state_window_s={window}"]\n')
        text = text.replace("[campaign]\n", "[campaign]\n" + sets, 1)
    path = scratch / f"mc_{cases}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _env(scratch: Path) -> dict[str, str]:
    xdg = scratch / "xdg"
    xdg.mkdir(mode=0o700, exist_ok=True)
    return dict(os.environ, XDG_RUNTIME_DIR=str(xdg), PYTHONPATH=str(REPO))


def _campaign(cfile: Path, out: Path, env: dict[str, str],
              extra: tuple[str, ...] = ()) -> dict[str, Any]:
    t0 = time.perf_counter_ns()
    p = subprocess.run([*HIL, "campaign", str(cfile), "--out", str(out), *extra], env=env,
                       capture_output=True, text=True, check=False)
    wall = (time.perf_counter_ns() - t0) / NS_PER_S
    if p.returncode not in (0, 1):
        raise RuntimeError(f"campaign exit {p.returncode}: {p.stderr[-2000:]}")
    data = json.loads((out / "campaign.json").read_text(encoding="utf-8"))
    return {"exit": p.returncode, "command_wall_s": wall, "meta": data["campaign"],
            "stats": data["statistics"], "cases": data["cases"]}


def _compared(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    return {r["name"]: {k: r[k] for k in COMPARED} for r in rows}


@contextmanager
def _cluster(scratch: Path,
             env: dict[str, str]) -> Iterator[tuple[str, list[subprocess.Popen[bytes]]]]:
    """A scheduler and CLUSTER_WORKERS single-threaded workers, each its own process,
    started with Dask's own commands; yields the address and the worker processes."""
    from distributed import Client

    sfile = scratch / f"scheduler-{time.perf_counter_ns()}.json"
    logs = open(scratch / "dask.log", "ab")  # noqa: SIM115 - closed below
    procs = [subprocess.Popen([sys.executable, "-m", "dask", "scheduler", "--port", "0",
                               "--no-dashboard", "--scheduler-file", str(sfile)],
                              env=env, stdout=logs, stderr=logs)]
    try:
        deadline = time.monotonic() + CLUSTER_TIMEOUT_S
        while not sfile.exists():
            if time.monotonic() > deadline or procs[0].poll() is not None:
                raise RuntimeError("dask scheduler did not start (see dask.log)")
            time.sleep(POLL_S)
        workers = [subprocess.Popen([sys.executable, "-m", "dask", "worker", "--scheduler-file",
                                     str(sfile), "--nthreads", "1", "--no-nanny",
                                     "--no-dashboard"], env=env, stdout=logs, stderr=logs)
                   for _ in range(CLUSTER_WORKERS)]
        procs += workers
        with Client(scheduler_file=str(sfile)) as c:
            c.wait_for_workers(CLUSTER_WORKERS, timeout=CLUSTER_TIMEOUT_S)
            address = c.scheduler.address
        yield address, workers
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                p.terminate()
        for p in procs:
            try:
                p.wait(CLUSTER_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                p.kill()
        logs.close()


def throughput(scratch: Path, env: dict[str, str], args: argparse.Namespace) -> dict[str, Any]:
    """T1 alone, the Monte Carlo on the local default, T1 alone again (module docstring):
    the single runs are split around the campaign, so that both see the same machine."""
    extra = [] if args.duration is None else [
        "--set", f"scenario.duration_s={args.duration}",
        "--set", f"expectations.steady_state_window_s={min(10.0, args.duration / 3)}"]

    def single(i: int) -> float:
        t0 = time.perf_counter_ns()
        r = subprocess.run([*HIL, "run", str(QUICKSTART), "--no-plots", "--out",
                            str(scratch / f"single{i}"), *extra], env=env,
                           capture_output=True, text=True, check=False)
        if r.returncode not in (0, 1):  # 1: ran, but missed an expectation
            raise RuntimeError(f"single case: exit {r.returncode}: {r.stderr[-2000:]}")
        return (time.perf_counter_ns() - t0) / NS_PER_S

    before = (args.single_runs + 1) // 2
    t1 = [single(i) for i in range(before)]
    c = _campaign(_campaign_file(scratch, args.mc_cases, args.duration), scratch / "mc", env)
    t1 += [single(i) for i in range(before, args.single_runs)]
    from transport.lockstep import available_cpus

    cores = available_cpus()
    t1_med = statistics.median(t1)
    ideal = 60.0 * cores / t1_med
    per_min = c["meta"]["cases_per_min"]
    return {"cores": cores, "single_case_command_s": t1, "single_case_median_s": t1_med,
            "ideal_cases_per_min": ideal, "cases": c["meta"]["cases"],
            "wall_time_s": c["meta"]["wall_time_s"], "command_wall_s": c["command_wall_s"],
            "cases_per_min": per_min, "ratio": per_min / ideal, "target_ratio": TARGET_RATIO,
            "cpu_use": c["meta"]["cpu_use"], "errors": c["stats"]["errors"],
            "pass_rates": c["stats"]["pass_rates"], "percentiles": c["stats"]["percentiles"],
            "top_sensitivity": {k: dict(list(v.items())[:3])
                                for k, v in c["stats"]["sensitivity"].items()}}


def three_ways(scratch: Path, env: dict[str, str], args: argparse.Namespace) -> dict[str, Any]:
    """Local default, scheduler + two workers, three reruns: identical per-case results."""
    cfile = _campaign_file(scratch, args.three_way_cases, args.duration)
    local = _campaign(cfile, scratch / "three_local", env)
    with _cluster(scratch, env) as (address, _):
        remote = _campaign(cfile, scratch / "three_sched", env, ("--scheduler", address))
    a, b = _compared(local["cases"]), _compared(remote["cases"])
    names = sorted(a)
    picks = [names[0], names[len(names) // 2], names[-1]][:RERUN_PICKS]
    reruns = {}
    for n in picks:
        p = subprocess.run([*HIL, "campaign", "rerun", str(scratch / "three_local"), n],
                           env=env, capture_output=True, text=True, check=False)
        reruns[n] = p.returncode == 0
    return {"cases": len(a), "local_wall_s": local["meta"]["wall_time_s"],
            "scheduler_wall_s": remote["meta"]["wall_time_s"],
            "scheduler_identical": a == b,
            "differing_cases": [n for n in names if a[n] != b.get(n)],
            "reruns_identical": reruns}


def lost_worker(scratch: Path, env: dict[str, str], args: argparse.Namespace) -> dict[str, Any]:
    """Kill one of two workers while cases run; the campaign must finish, each case once."""
    cfile = _campaign_file(scratch, args.three_way_cases, args.duration)
    if not (scratch / "three_local" / "campaign.json").exists():
        _campaign(cfile, scratch / "three_local", env)
    local = _compared(json.loads(
        (scratch / "three_local" / "campaign.json").read_text())["cases"])
    out = scratch / "lost"
    with _cluster(scratch, env) as (address, workers):
        p = subprocess.Popen([*HIL, "campaign", str(cfile), "--out", str(out), "--scheduler",
                              address], env=env, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
        killed_at = None
        while p.poll() is None:
            cases = out / "cases"
            done = len(list(cases.glob("*/result.json"))) if cases.exists() else 0
            running = ([d for d in cases.iterdir() if ".attempt-" in d.name]
                       if cases.exists() else [])
            if done >= 1 and running:
                workers[0].send_signal(signal.SIGKILL)
                killed_at = done
                break
            time.sleep(POLL_S)
        _, err = p.communicate()
    result = out / "campaign.json"
    rows = json.loads(result.read_text())["cases"] if result.exists() else []
    names = [r["name"] for r in rows]
    left = [d.name for d in (out / "cases").iterdir() if ".attempt-" in d.name]
    got = _compared(rows)
    return {"exit": p.returncode, "killed_after_cases": killed_at, "cases": len(rows),
            "expected_cases": len(local), "duplicates": len(names) - len(set(names)),
            "errors": sum(r["status"] != "ok" for r in rows), "attempt_folders_left": left,
            "identical_to_local": got == local,
            "stderr_tail": err[-500:] if p.returncode > 1 else ""}


def margins(scratch: Path, env: dict[str, str], args: argparse.Namespace) -> dict[str, Any]:
    """Margin searches on the seed-003 scenario (module docstring)."""
    out = {}
    for key, toward in (("latency", args.latency_toward), ("thrust_scale", args.scale_toward)):
        d = scratch / f"margin_{key}"
        cmd = [*HIL, "campaign", "margin", str(CASCADE), "--key", key, "--toward", str(toward),
               "--out", str(d)]
        if args.margin_tolerance is not None:
            cmd += ["--tolerance", str(args.margin_tolerance[key == "thrust_scale"])]
        if args.duration is not None:  # a quick version: the scenario cut short
            cmd += ["--set", f"scenario.duration_s={args.duration}", "--set",
                    f"expectations.steady_state_window_s={min(10.0, args.duration / 3)}"]
        p = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
        if p.returncode != 0:
            raise RuntimeError(f"margin {key}: exit {p.returncode}: {p.stderr[-2000:]}")
        r = json.loads((d / "margin.json").read_text())
        out[key] = {k: r.get(k) for k in ("nominal", "toward", "boundary", "uncertainty",
                                           "margin", "margin_relative", "runs", "note")}
    return out


def main() -> None:
    """Command line (module docstring); prints one JSON object."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--single-runs", type=int, default=5)
    p.add_argument("--mc-cases", type=int, default=200)
    p.add_argument("--three-way-cases", type=int, default=40)
    p.add_argument("--duration", type=float, help="shorten every case to this [s]")
    p.add_argument("--latency-toward", type=float, default=0.019,
                   help="below the 20 ms control period: the scenario refuses longer")
    p.add_argument("--scale-toward", type=float, default=0.2)
    p.add_argument("--margin-tolerance", type=float, nargs=2, metavar=("LATENCY", "SCALE"))
    p.add_argument("--sections", nargs="+", default=["throughput", "three_ways", "lost_worker",
                                                      "margins"])
    args = p.parse_args()
    result: dict[str, Any] = {}
    with tempfile.TemporaryDirectory(prefix="thil-campaign-bench-") as tmp:
        scratch = Path(tmp)
        env = _env(scratch)
        for name in ("throughput", "three_ways", "lost_worker", "margins"):
            if name in args.sections:
                try:
                    result[name] = globals()[name](scratch, env, args)
                except (RuntimeError, OSError, ValueError) as exc:  # the others still run
                    result[name] = {"error": str(exc)}
                print(f"{name}: {json.dumps(result[name])}", file=sys.stderr, flush=True)
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
