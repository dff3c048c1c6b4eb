"""Single-failure campaign: every thruster stuck closed, then stuck open, one lockstep run each.

``python -m bench.operator.campaign SCENARIO --out DIR [--fault-time S] [--jobs N] [--kinds ...]``
(also ``thruster-hil campaign``). Each run is the scenario with one ``[[faults]]`` entry
appended, started as its own ``thruster-hil run`` process on a private portable-bus channel,
``--jobs`` at a time (with more processes than CPUs, their lockstep waits block at once
instead of polling first: see transport.lockstep). The flight software's FDIR report
(FSW_FDIR, in each summary.json) gives detection and isolation. Out, in DIR:
``campaign.csv`` (one row per run: thruster, kind, detected, detection time after the
fault, isolated thruster, isolation correct, expectations met, final attitude and position
error, propellant), ``campaign.json``, ``campaign.png`` (detection time per thruster and
kind) and ``campaign.html`` (the figure and the table, each case linked to its run's
report.html), plus every run folder. Exit 0 if every run detected and isolated its failure and met
the scenario's expectations, 1 if not, 2 on bad input, 3 if a run could not complete.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path
from typing import Any

from bench.campaign.cli import run_campaign_file
from bench.campaign.spec import is_campaign_file
from bench.operator.report_html import campaign_html
from bench.scenario.load import load_scenario
from dbc import options as opt
from dbc.errors import ConfigError, RunError
from dbc.faults import STUCK_CLOSED, STUCK_OPEN
from dbc.options import StrictParser
from dbc.records import write_record
from transport.lockstep import LOCKSTEP_SPIN_ENV, available_cpus

KINDS = (STUCK_CLOSED, STUCK_OPEN)
DEFAULT_FAULT_TIME_S = 10.0
EXIT_BAD_INPUT, EXIT_RUN_ERROR = 2, 3  # as thruster-hil run's
COLUMNS = ["thruster", "kind", "detected", "detection_time_s", "isolated_thruster",
           "isolation_correct", "expectations_met", "final_attitude_error_deg",
           "final_position_error_m", "propellant_kg", "run_dir"]
DPI = 110
PROCESSES_PER_RUN = 2  # bench + flight software
BAR_WIDTH = 30  # characters of the terminal progress bar
MAX_JOBS = 64  # runs at a time: 128 processes, far more than the CPUs of any bench host


def _run_one(scenario: Path, fault: str, out: Path, xdg: Path, spin_off: bool) -> dict[str, Any]:
    out.mkdir(parents=True, exist_ok=True)
    text = scenario.read_text(encoding="utf-8").rstrip() + "\n" + fault
    sc_file = out / "campaign_scenario.toml"
    sc_file.write_text(text, encoding="utf-8")
    env = dict(os.environ, XDG_RUNTIME_DIR=str(xdg))
    if spin_off:  # more processes than CPUs: a polling wait would hold a CPU another needs
        env.setdefault(LOCKSTEP_SPIN_ENV, "0")
    # No --bus: a channel of the run's own, without the 0.25 s listen a named bus gets;
    # no plots per case (0.3-0.7 s each): the campaign draws its own (campaign.png), and
    # `thruster-hil report` draws any case's.
    p = subprocess.run(
        [sys.executable, "-m", "bench.operator.cli", "run", str(sc_file), "--no-plots",
         "--out", str(out / "run")],
        env=env, capture_output=True, text=True, check=False,
    )
    summary = out / "run" / "summary.json"
    if p.returncode == EXIT_BAD_INPUT or not summary.exists():
        last = (p.stderr.strip().splitlines() or ["(no output)"])[-1]
        raise RunError(f"campaign run {out.name} failed (exit {p.returncode}): {last}")
    return json.loads(summary.read_text(encoding="utf-8"))


def _row(k: int, kind: str, fault_t_s: float, s: dict[str, Any], run_dir: Path) -> dict[str, Any]:
    fdir = s.get("fdir") or {}
    iso = fdir.get("failed_thruster")
    t_det = fdir.get("detection_time_s")
    return {
        "thruster": k, "kind": kind, "detected": iso is not None,
        "detection_time_s": None if t_det is None else round(t_det - fault_t_s, 3),
        "isolated_thruster": iso,
        "isolation_correct": iso == k and fdir.get("failure_kind") == kind,
        "expectations_met": bool(s.get("passed")),
        "final_attitude_error_deg": s.get("final_attitude_error_deg"),
        "final_position_error_m": s.get("final_position_error_m"),
        "propellant_kg": s.get("propellant_kg"),
        "run_dir": str(run_dir),
    }


def run_campaign(scenario: Path, out: Path, fault_t_s: float, jobs: int,
                 kinds: tuple[str, ...] = KINDS,
                 progress: Callable[[int, int, dict[str, Any]], None] | None = None,
                 ) -> list[dict[str, Any]]:
    """Run every single-thruster failure of ``kinds``; write the CSV, JSON and PNG.

    ``progress(done, total, row)`` is called as each run finishes (in the order they
    finish); the rows returned are in case order.
    """
    sc = load_scenario(scenario)
    if not 0.0 <= fault_t_s < sc.duration_s:  # also NaN
        raise ConfigError("command line", "--fault-time", fault_t_s,
                          f"a time in [0, {sc.duration_s:g}) s (the scenario's duration)")
    if not 1 <= jobs <= MAX_JOBS:
        raise ConfigError("command line", "--jobs", jobs, f"an integer in [1, {MAX_JOBS}]")
    n = len(sc.thrusters)
    out.mkdir(parents=True, exist_ok=True)
    cases = [(k, kind) for kind in kinds for k in range(n)]
    spin_off = PROCESSES_PER_RUN * min(jobs, len(cases)) > available_cpus()
    with tempfile.TemporaryDirectory(prefix="thil-campaign-") as tmp:
        xdg = Path(tmp)
        xdg.chmod(0o700)

        def job(case: tuple[int, str]) -> dict[str, Any]:
            k, kind = case
            d = out / f"{kind}_T{k:02d}"
            fault = f'\n[[faults]]\nt_s = {fault_t_s}\nkind = "{kind}"\nthruster = {k}\n'
            return _row(k, kind, fault_t_s, _run_one(scenario, fault, d, xdg, spin_off),
                        d / "run")

        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = [pool.submit(job, case) for case in cases]
            try:
                for done, fut in enumerate(as_completed(futures), start=1):
                    row = fut.result()
                    if progress is not None:
                        progress(done, len(cases), row)
                rows = [fut.result() for fut in futures]
            except BaseException:  # one run failed: do not start the others
                for fut in futures:
                    fut.cancel()
                raise
    with open(out / "campaign.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    write_record(out / "campaign.json", {"cases": rows})
    _plot(rows, out / "campaign.png")
    (out / "campaign.html").write_text(
        campaign_html(rows, COLUMNS, (out / "campaign.png").read_bytes(), out),
        encoding="utf-8")
    return rows


def _plot(rows: list[dict[str, Any]], path: Path) -> None:
    from bench.operator.plots import (
        plt,  # matplotlib is loaded only when there is something to plot
    )

    fig, ax = plt.subplots(figsize=(9, 4))
    width = 0.4
    kinds = [k for k in KINDS if any(r["kind"] == k for r in rows)]
    for i, kind in enumerate(kinds):
        sel = [r for r in rows if r["kind"] == kind]
        xs = [r["thruster"] + (i - 0.5) * width for r in sel]
        ys = [r["detection_time_s"] if r["detection_time_s"] is not None else 0.0 for r in sel]
        bars = ax.bar(xs, ys, width, label=kind)
        for bar, r in zip(bars, sel, strict=True):
            if not r["detected"] or not r["isolation_correct"]:
                bar.set_hatch("//")
                bar.set_edgecolor("red")
    ax.set_xlabel("failed thruster")
    ax.set_ylabel("detection time after the fault [s]")
    ax.set_title("Single-failure campaign (hatched: not detected or wrongly isolated)")
    ax.legend()
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def add_arguments(p: argparse.ArgumentParser, default_jobs: int) -> None:
    """The campaign's options (shared with ``thruster-hil campaign``), each checked as it is
    parsed (:mod:`dbc.options`); the fault time against the scenario's duration later."""
    p.add_argument("scenario", type=opt.text("SCENARIO", "a scenario file"),
                   help="a campaign file (with a [campaign] table: dispersions, Monte Carlo, "
                   "sweeps; docs/campaigns.md) or a scenario TOML file (every single "
                   "stuck_closed / stuck_open failure of its thrusters)")
    p.add_argument("--out", required=True, type=opt.text("--out", "a folder path"),
                   help="folder for campaign.csv/.json/.png and runs")
    p.add_argument("--fault-time", type=opt.number("--fault-time", 0.0, unit="s"),
                   help="when each fault starts [s], before the scenario's end "
                   f"(default {DEFAULT_FAULT_TIME_S:g})")
    p.add_argument("--jobs", type=opt.integer("--jobs", 1, MAX_JOBS),
                   help=f"runs at a time, 1..{MAX_JOBS} (default {default_jobs}; a campaign "
                   "file: Dask workers, default one per CPU)")
    p.add_argument("--scheduler", type=opt.text("--scheduler", "tcp://HOST:PORT"),
                   help="a campaign file's cases on this running Dask scheduler (its workers "
                   "have the project installed and see --out at the same path); default: a "
                   "local Dask cluster sized to the machine")
    p.add_argument("--kinds", nargs="+", type=opt.choice("--kinds", KINDS), metavar="KIND",
                   help=f"failure kinds: {' '.join(KINDS)} (default both)")


def _row_line(r: dict[str, Any]) -> str:
    """One run's outcome as the console shows it."""
    return (f"T{r['thruster']:02d} {r['kind']:12s} detected={r['detected']!s:5} "
            f"t={r['detection_time_s']} isolated={r['isolated_thruster']} "
            f"ok={r['isolation_correct']} expectations={r['expectations_met']}")


def _progress_printer() -> Callable[[int, int, dict[str, Any]], None]:
    """On a terminal: a progress bar on stderr, redrawn per finished run. Otherwise (a
    log, a pipe, CI): one line per finished run on stdout, flushed at once, so that a
    redirected campaign of many minutes shows its runs as they end."""
    tty = sys.stderr.isatty()

    def show(done: int, total: int, row: dict[str, Any]) -> None:
        if tty:
            n = done * BAR_WIDTH // total
            sys.stderr.write(f"\r[{'#' * n}{'.' * (BAR_WIDTH - n)}] {done}/{total} runs "
                             f"(last: T{row['thruster']:02d} {row['kind']})")
            if done == total:
                sys.stderr.write("\n")
            sys.stderr.flush()
        else:
            print(f"[{done}/{total}] {_row_line(row)}", flush=True)

    return show


def main(argv: list[str] | None = None) -> int:
    """Command line; exit 0 if every run was detected, isolated and met its expectations."""
    p = StrictParser(prog="thruster-hil campaign", description=__doc__.split("\n")[0])
    add_arguments(p, default_jobs=max(1, (os.cpu_count() or 2) // 2))
    args = opt.parse_or_exit_code(p, argv)
    if isinstance(args, int):
        return args
    try:
        if is_campaign_file(args.scenario):
            for option, given in (("--fault-time", args.fault_time), ("--kinds", args.kinds)):
                if given is not None:
                    opt.refuse(option, given, "absent with a campaign file (its [campaign] "
                               "table says fault_time_s and failures)")
            return run_campaign_file(Path(args.scenario), Path(args.out), args.jobs,
                                     args.scheduler)
        if args.scheduler is not None:
            opt.refuse("--scheduler", args.scheduler, "absent with a scenario file (the "
                       "single-failure sweep runs locally; a campaign file runs on Dask)")
        rows = run_campaign(Path(args.scenario), Path(args.out),
                            DEFAULT_FAULT_TIME_S if args.fault_time is None else args.fault_time,
                            args.jobs or max(1, (os.cpu_count() or 2) // 2),
                            tuple(args.kinds or KINDS), _progress_printer())
    except ConfigError as exc:
        print(f"thruster-hil campaign: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RunError as exc:
        print(f"thruster-hil campaign: run error: {exc}", file=sys.stderr)
        return EXIT_RUN_ERROR
    if sys.stderr.isatty():  # a redirected campaign has printed each run as it ended
        for r in rows:
            print(_row_line(r))
    passed = sum(bool(r["detected"] and r["isolation_correct"] and r["expectations_met"])
                 for r in rows)
    print(f"campaign: {passed}/{len(rows)} runs detected, isolated and met the expectations; "
          f"{Path(args.out) / 'campaign.csv'}")
    return 0 if passed == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
