"""Lockstep speed as JSON: real-time factor per scenario, where a cycle goes, what a command costs.

Runs ``thruster-hil run SCENARIO`` (real processes, lockstep, each without ``--bus``, so
on a portable-bus channel of its own, and in its own folder) ``--runs`` times per
scenario, the scenarios taking turns (run 1 of each, then run 2 of each, ...) so that a
change in the machine's load spreads over all of them; then the quickstart command
``--runs`` times with and without ``--no-plots``, alternating. Prints one JSON object:

- ``scenarios``: per scenario the median real-time factor (simulated s per wall s of the
  loop), the bench's cycle wall time p50/p99 [µs] and, within it, the wait for the flight
  software's answer (``lockstep_wall_us`` in summary.json), the flight software's cycle
  (SYNC receipt to last command frame sent, its own clock) p50/p99 [µs], and the bench's
  own share of a cycle (cycle p50 minus wait p50);
- ``command``: the whole ``thruster-hil run scenarios/quickstart.toml`` as a user runs it
  (interpreter start to exit, measured here), its loop time (``wall_time_s``) and the
  difference, the overhead, with plots, with ``--no-plots`` and with plots but the
  flight software's prestart off (``THRUSTER_HIL_PRESTART=0``: started cold once the
  bench is up; ``prestart_gain_s``: the median of the paired differences); the parts of
  the overhead measured alone: the command's own start (``thruster-hil --help``: the
  interpreter and the console's imports), the flight software's start-up
  (``python -m flight_sw --check``: interpreter, imports and design-time set-up) and the
  plots (the median difference of the two commands).

Two builds (``--baseline PYTHON``): the interpreter of another install of thruster-hil
(a virtual environment with an earlier commit installed, ``pip install <checkout>``) runs
each scenario too, taking turns with this one (run 1 here, run 1 there, ...: the machine's
load falls on both alike), and the JSON gains ``baseline``: its figures per scenario and
``ratios``, per scenario the medians of the paired ratios this build / the baseline of the
real-time factor and of the flight software's cycle p50 and p99. Every run of a comparison
starts in the scratch folder, so each interpreter imports its own install, never the
checkout's sources.

Bytecode: an installed package has its modules compiled (pip writes the ``.pyc`` files at
install; an editable checkout gets them on its first run), but a shell with
``PYTHONDONTWRITEBYTECODE`` set never writes them, and then every command compiles ~100
of the project's modules from source again (~0.05 s for each process that starts). With
``--bytecode cached`` (the default) the project's packages are compiled first
(``python -m compileall``), as a user's install has them; ``--bytecode source`` leaves
the checkout as it is. The JSON says which.

Figures are medians of one invocation: this machine is shared and noisy; compare ratios of
runs made together. ``wall`` clock reads here are the benchmark's own.

    python benchmarks/lockstep_speed.py                  # 3 runs, every shipped scenario
    python benchmarks/lockstep_speed.py --runs 5 --scenarios quickstart fdir_16thr
    python benchmarks/lockstep_speed.py --runs 5 --no-command --baseline ../old-venv/bin/python
"""

from __future__ import annotations

import argparse
import compileall
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
SCENARIOS = REPO / "scenarios"
QUICKSTART = SCENARIOS / "quickstart.toml"
NS_PER_S = 1e9
PACKAGES = ("bench", "dbc", "flight_sw", "transport")
# a lockstep cycle's parts, in order (summary.json lockstep_wall_us; bench.lockstep)
SPLIT = ("before_sync", "meanwhile", "waiting_for_fsw", "after_commands")
CONSOLE = (sys.executable, "-m", "bench.operator.entry")  # what the console script runs
# the command's variants, taking turns: (options, environment)
VARIANTS: dict[str, tuple[tuple[str, ...], dict[str, str]]] = {
    "plots": ((), {}),
    "no_plots": (("--no-plots",), {}),
    "plots_prestart_off": ((), {"THRUSTER_HIL_PRESTART": "0"}),
}


def _timed(argv: list[str], env: dict[str, str], cwd: Path = REPO) -> float:
    """Wall time [s] of one command, start to exit (its output discarded)."""
    t0 = time.perf_counter_ns()
    subprocess.run(argv, cwd=cwd, env=env, capture_output=True, check=False)
    return (time.perf_counter_ns() - t0) / NS_PER_S


def _run(scenario: Path, scratch: Path, env: dict[str, str], extra: tuple[str, ...] = (),
         python: str | None = None) -> tuple[float, dict[str, Any]]:
    """One ``thruster-hil run`` as a user types it: no ``--bus``, so a channel of its own
    (a named bus would add the 0.25 s listen for another run); its wall time [s] and its
    summary. ``python``: another install's interpreter (started in ``scratch``, so it
    imports that install; module docstring)."""
    out = scratch / f"{scenario.stem}-{uuid.uuid4().hex[:8]}"
    console = CONSOLE if python is None else (python, *CONSOLE[1:])
    wall_s = _timed([*console, "run", str(scenario), "--out", str(out), *extra], env,
                    REPO if python is None else scratch)
    summary: dict[str, Any] = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    return wall_s, summary


def _median(xs: list[float]) -> float:
    return float(statistics.median(xs))


def _scenario_figures(summaries: list[dict[str, Any]]) -> dict[str, Any]:
    """Medians over a scenario's runs."""
    cycle = [s["lockstep_wall_us"]["cycle"] for s in summaries]
    wait = [s["lockstep_wall_us"]["waiting_for_fsw"] for s in summaries]
    fsw = [s["fsw"].get("cycle_time_us") or {} for s in summaries]
    cycle_p50 = _median([c["p50"] for c in cycle])
    wait_p50 = _median([w["p50"] for w in wait])
    return {
        "runs": len(summaries),
        "sim_time_s": summaries[0]["sim_time_s"],
        "realtime_factor": [s["realtime_factor"] for s in summaries],
        "realtime_factor_median": _median([s["realtime_factor"] for s in summaries]),
        "cycle_wall_us": {"p50": cycle_p50, "p99": _median([c["p99"] for c in cycle])},
        "waiting_for_fsw_us": {"p50": wait_p50, "p99": _median([w["p99"] for w in wait])},
        "bench_own_us_p50": cycle_p50 - wait_p50,
        "split_us_p50": {part: _median([s["lockstep_wall_us"][part]["p50"] for s in summaries])
                         for part in SPLIT},
        "fsw_cycle_us": {k: _median([f[k] for f in fsw if k in f]) for k in ("p50", "p99", "max")
                         if any(k in f for f in fsw)},
        "passed": [s["passed"] for s in summaries],
    }


def _ratios(new: list[dict[str, Any]], old: list[dict[str, Any]]) -> dict[str, float]:
    """Medians of the paired ratios this build / the baseline (runs taken in turn)."""
    def fsw(s: dict[str, Any], key: str) -> float:
        return float((s["fsw"].get("cycle_time_us") or {}).get(key, math.nan))

    pairs = list(zip(new, old, strict=True))
    return {"realtime_factor": _median([n["realtime_factor"] / o["realtime_factor"]
                                        for n, o in pairs]),
            "fsw_cycle_p50": _median([fsw(n, "p50") / fsw(o, "p50") for n, o in pairs]),
            "fsw_cycle_p99": _median([fsw(n, "p99") / fsw(o, "p99") for n, o in pairs])}


def _check_baseline(python: str, scratch: Path) -> str | None:
    """Why ``python`` cannot serve as a baseline (None if it can)."""
    try:
        done = subprocess.run([python, "-c", "import bench.operator.entry"], cwd=scratch,
                              capture_output=True, text=True, check=False)
    except OSError as exc:
        return f"cannot start it ({exc.strerror or exc})"
    if done.returncode != 0:
        return "it has no thruster-hil installed (import bench.operator.entry failed)"
    return None


def _command_figures(runs: int, scratch: Path, env: dict[str, str]) -> dict[str, Any]:
    """The quickstart command with and without plots (alternating), and its parts alone."""
    rows: dict[str, list[tuple[float, float]]] = {key: [] for key in VARIANTS}
    for _ in range(runs):
        for key, (extra, env_extra) in VARIANTS.items():
            wall_s, s = _run(QUICKSTART, scratch, env | env_extra, extra)
            rows[key].append((wall_s, s["wall_time_s"]))
    config = next(scratch.glob("quickstart-*/fsw_config.json"))
    help_s = [_timed([*CONSOLE, "--help"], env)
              for _ in range(runs)]
    fsw_s = [_timed([sys.executable, "-m", "flight_sw", "--check", "--config", str(config)],
                    env) for _ in range(runs)]
    out: dict[str, Any] = {}
    for key, pairs in rows.items():
        out[key] = {
            "command_s_median": _median([c for c, _ in pairs]),
            "loop_s_median": _median([lp for _, lp in pairs]),
            "overhead_s": [round(c - lp, 3) for c, lp in pairs],
            "overhead_s_median": _median([c - lp for c, lp in pairs]),
        }
    out["parts_alone_s"] = {
        "command_start": _median(help_s),
        "fsw_start_up": _median(fsw_s),
        "plots": out["plots"]["overhead_s_median"] - out["no_plots"]["overhead_s_median"],
    }
    out["prestart_gain_s"] = _median([off[0] - on[0] for on, off in
                                      zip(rows["plots"], rows["plots_prestart_off"],
                                          strict=True)])
    return out


def main() -> None:
    """Parse arguments, run, print JSON."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--runs", type=int, default=3, help="runs per scenario and variant (3)")
    p.add_argument("--scenarios", nargs="*", default=None,
                   help="scenario names in scenarios/ (default: every shipped one)")
    p.add_argument("--no-command", action="store_true", help="skip the command timing")
    p.add_argument("--baseline", metavar="PYTHON", default=None,
                   help="another install's interpreter: its runs take turns with these, "
                        "and the JSON compares the two (module docstring)")
    p.add_argument("--bytecode", choices=("cached", "source"), default="cached",
                   help="cached: compile the project's modules first, as an install has them "
                        "(default); source: leave the checkout as it is")
    args = p.parse_args()
    if args.runs < 1:
        p.error(f"--runs {args.runs}: at least 1")
    names = args.scenarios or sorted(x.stem for x in SCENARIOS.glob("*.toml"))
    missing = [n for n in names if not (SCENARIOS / f"{n}.toml").is_file()]
    if missing:
        p.error(f"--scenarios: no scenarios/{missing[0]}.toml")
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    if args.bytecode == "cached":
        for pkg in PACKAGES:
            compileall.compile_dir(REPO / pkg, quiet=1)
    with tempfile.TemporaryDirectory(prefix="thil-speed-") as tmp:
        scratch = Path(tmp)
        if args.baseline is not None and (why := _check_baseline(args.baseline, scratch)):
            p.error(f"--baseline {args.baseline}: {why}")
        per: dict[str, list[dict[str, Any]]] = {n: [] for n in names}
        base: dict[str, list[dict[str, Any]]] = {n: [] for n in names}
        for _ in range(args.runs):
            for n in names:
                scenario = SCENARIOS / f"{n}.toml"
                if args.baseline is None:
                    per[n].append(_run(scenario, scratch, env, ("--no-plots",))[1])
                    continue
                per[n].append(_run(scenario, scratch, env, ("--no-plots",), sys.executable)[1])
                base[n].append(_run(scenario, scratch, env, ("--no-plots",), args.baseline)[1])
        result: dict[str, Any] = {
            "benchmark": "lockstep_speed",
            "cpus": os.cpu_count(),
            "bytecode": args.bytecode,
            "load_avg_1min": os.getloadavg()[0],
            "scenarios": {n: _scenario_figures(s) for n, s in per.items()},
        }
        if args.baseline is not None:
            result["baseline"] = {
                "python": args.baseline,
                "scenarios": {n: _scenario_figures(s) for n, s in base.items()},
                "ratios": {n: _ratios(per[n], base[n]) for n in names},
            }
        if not args.no_command:
            result["command"] = _command_figures(args.runs, scratch, env)
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
