"""Single-failure campaign: every thruster stuck closed, then stuck open, one lockstep run each.

``python -m bench.operator.campaign SCENARIO --out DIR [--fault-time S] [--jobs N] [--kinds ...]``
(also ``thruster-hil campaign``; a campaign file given there goes to
:func:`bench.campaign.cli.run_campaign_file`). Each run is the scenario with one
``[[faults]]`` entry appended (``--set faults=[...]``): a case of :mod:`bench.campaign`,
run as its own ``thruster-hil run`` process on a private portable-bus channel, on a local
Dask cluster of ``--jobs`` workers (with more processes than CPUs, their lockstep waits
block at once instead of polling first: see transport.lockstep). The flight software's FDIR report
(FSW_FDIR, in each summary.json) gives detection and isolation. Out, in DIR:
``campaign.csv`` (one row per run: thruster, kind, detected, detection time after the
fault, isolated thruster, isolation correct, expectations met, final attitude and position
error, propellant), ``campaign.json``, ``campaign.png`` (detection time per thruster and
kind) and ``campaign.html`` (the figure and the table, each case linked to its run's
report.html), plus every run folder (``cases/KIND_TNN/run``). Exit 0 if every run detected
and isolated its failure and met the scenario's expectations, 1 if not, 2 on bad input, 3
if a run could not complete.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bench.campaign.cases import build_cases
from bench.campaign.cli import (
    SCENARIO_COPY,
    error_exit,
    run_campaign_file,
)
from bench.campaign.spec import is_campaign_file
from bench.operator.report_html import campaign_html
from bench.scenario.load import load_scenario
from dbc import options as opt
from dbc.datafile import parse_toml
from dbc.errors import ConfigError, RunError
from dbc.faults import STUCK_CLOSED, STUCK_OPEN
from dbc.options import StrictParser
from dbc.records import write_record

KINDS = (STUCK_CLOSED, STUCK_OPEN)
DEFAULT_FAULT_TIME_S = 10.0
COLUMNS = ["thruster", "kind", "detected", "detection_time_s", "isolated_thruster",
           "isolation_correct", "expectations_met", "final_attitude_error_deg",
           "final_position_error_m", "propellant_kg", "run_dir"]
DPI = 110
BAR_WIDTH = 30  # characters of the terminal progress bar
MAX_JOBS = 64  # runs at a time: 128 processes, far more than the CPUs of any bench host


def _row(k: int, kind: str, s: dict[str, Any], detection_s: float | None,
         run_dir: Path) -> dict[str, Any]:
    fdir = s.get("fdir") or {}
    iso = fdir.get("failed_thruster")
    return {
        "thruster": k, "kind": kind, "detected": iso is not None,
        "detection_time_s": None if detection_s is None else round(detection_s, 3),
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

    The cases are a campaign of one undispersed vehicle with ``failures`` (one
    implementation of a case and of running cases: :mod:`bench.campaign`), on a local
    Dask cluster of ``jobs`` workers; each case's run folder is ``out/cases/KIND_TNN/run``.
    ``progress(done, total, row)`` is called as each run finishes (in the order they
    finish); the rows returned are in case order.
    """
    from bench.campaign.cli import case_dict
    from bench.campaign.engine import run_cases
    from bench.campaign.spec import CASE_TIMEOUT_BASE_S, CampaignSpec

    sc = load_scenario(scenario)
    if not 0.0 <= fault_t_s < sc.duration_s:  # also NaN
        raise ConfigError("command line", "--fault-time", fault_t_s,
                          f"a time in [0, {sc.duration_s:g}) s (the scenario's duration)")
    if not 1 <= jobs <= MAX_JOBS:
        raise ConfigError("command line", "--jobs", jobs, f"an integer in [1, {MAX_JOBS}]")
    spec = CampaignSpec(source="command line", name=scenario.stem, scenario=scenario.resolve(),
                        study="monte_carlo", cases=1, seed=0, vary_seed=False,
                        failures=tuple(kinds), fault_time_s=fault_t_s, dispersions=(),
                        case_timeout_s=None, worst=0, keep="all")
    text = scenario.read_text(encoding="utf-8")
    data = parse_toml(text, str(scenario))
    cases = [case_dict(c, spec) for c in build_cases(spec, data, len(sc.thrusters), sc.seed)]
    out.mkdir(parents=True, exist_ok=True)
    (out / SCENARIO_COPY).write_text(text, encoding="utf-8")

    made: dict[str, dict[str, Any]] = {}  # each case's row, read from its summary once

    def row_of(r: dict[str, Any]) -> dict[str, Any]:
        if r["name"] not in made:
            kind, k = r["failure"]
            run_dir = out / "cases" / r["name"] / "run"
            s = json.loads((run_dir / "summary.json").read_text(encoding="utf-8"))
            made[r["name"]] = _row(k, kind, s, r["figures"]["detection_time_s"], run_dir)
        return made[r["name"]]

    def show(done: int, total: int, r: dict[str, Any]) -> None:
        if progress is not None and r["status"] == "ok":  # the others: an error below
            progress(done, total, row_of(r))

    results = run_cases(cases, out / SCENARIO_COPY, out, CASE_TIMEOUT_BASE_S + sc.duration_s,
                        None, jobs, show,
                        notice=lambda line: print(line, file=sys.stderr, flush=True))
    bad = [r for r in results if r["status"] != "ok"]
    if bad:
        raise RunError(f"campaign run {bad[0]['name']} failed: {bad[0]['error']}")
    rows = [row_of(r) for r in results]
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


def from_namespace(args: argparse.Namespace) -> int:
    """``thruster-hil campaign``'s parsed options (:func:`add_arguments`) run as :func:`main`."""
    argv = [args.scenario, "--out", args.out]
    for option, value in (("--fault-time", args.fault_time), ("--jobs", args.jobs),
                          ("--scheduler", args.scheduler)):
        if value is not None:
            argv += [option, str(value)]
    if args.kinds is not None:
        argv += ["--kinds", *args.kinds]
    return main(argv)


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
    except (ConfigError, RunError) as exc:
        return error_exit(exc)
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
