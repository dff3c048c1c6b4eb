"""``thruster-hil campaign rerun`` and ``thruster-hil campaign margin``: one case again, and
a requirement's margin on one key.

- ``rerun CAMPAIGN_DIR CASE [--out RUN_DIR]``: the case's run again, from the campaign
  folder alone (its ``scenario.toml`` copy and the case's ``case.json``); exit 0 if the
  trace records equal the campaign's, 1 if not (:func:`bench.campaign.cli.rerun_case`).
- ``minimize CAMPAIGN_DIR CASE [--out DIR] [--max-runs N]``: the smallest set of a failing
  case's dispersed values that still fails, the others at nominal
  (:mod:`bench.campaign.minimize`).
- ``margin SCENARIO --key KEY --toward VALUE --out DIR [--requirement NAME]
  [--tolerance T] [--set KEY=VALUE ...]``: bisection from the scenario's value toward a failing one
  (:mod:`bench.campaign.margin`); prints the boundary, its uncertainty, the margin and
  the number of runs.
Exit codes: rerun 0 identical, 1 different; margin 0 a margin or a lower bound found, 1
the scenario fails at its own value; minimize 0; all: 2 bad input, 3 a run could not
complete.
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from bench.campaign.cli import EXIT_FAILED, error_exit, new_folder
from bench.campaign.minimize import DEFAULT_MAX_RUNS
from dbc import options as opt
from dbc.errors import ConfigError, RunError
from dbc.options import StrictParser

MAX_MINIMIZE_RUNS = 10_000


def _parser() -> StrictParser:
    p = StrictParser(prog="thruster-hil campaign", description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="tool", required=True, metavar="TOOL")
    r = sub.add_parser("rerun", help="run one case of a campaign again, byte for byte")
    r.add_argument("campaign_dir", metavar="CAMPAIGN_DIR",
                   type=opt.text("CAMPAIGN_DIR", "a campaign folder"))
    r.add_argument("case", metavar="CASE", type=opt.text("CASE", "a case name, e.g. 0007"))
    r.add_argument("--out", type=opt.text("--out", "a folder path"),
                   help="the rerun's run folder (default CAMPAIGN_DIR/reruns/CASE)")
    z = sub.add_parser("minimize", help="the smallest set of a failing case's dispersions "
                       "that still fails")
    z.add_argument("campaign_dir", metavar="CAMPAIGN_DIR",
                   type=opt.text("CAMPAIGN_DIR", "a campaign folder"))
    z.add_argument("case", metavar="CASE", type=opt.text("CASE", "a case name, e.g. 0007"))
    z.add_argument("--out", type=opt.text("--out", "a folder path"),
                   help="folder for the trials and minimal.json (default "
                   "CAMPAIGN_DIR/minimal/CASE)")
    z.add_argument("--max-runs", type=opt.integer("--max-runs", 1, MAX_MINIMIZE_RUNS),
                   default=DEFAULT_MAX_RUNS,
                   help=f"give up after this many runs (default {DEFAULT_MAX_RUNS})")
    m = sub.add_parser("margin", help="bisect one key for the value where a requirement "
                       "starts failing")
    m.add_argument("scenario", metavar="SCENARIO", type=opt.text("SCENARIO", "a scenario file"))
    m.add_argument("--key", required=True, type=opt.text("--key", "a scenario key or alias"),
                   help="a scenario key (bus.fsw_response_delay_s) or a campaign alias "
                   "(latency, thrust_scale, open_delay, ...: docs/campaigns.md)")
    m.add_argument("--toward", required=True, type=opt.number("--toward"),
                   help="a value of KEY at which the requirement fails")
    m.add_argument("--requirement", default="passed",
                   type=opt.text("--requirement", "an expectation name"),
                   help="an expectation of the scenario, e.g. settling_time_s "
                   "(default passed: all of them)")
    m.add_argument("--tolerance", type=opt.number("--tolerance", 0.0, lo_open=True),
                   help="stop when the bracket is this narrow (default 1/64 of its start)")
    m.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scenario value for every step, as `run --set`")
    m.add_argument("--out", required=True, type=opt.text("--out", "a folder path"))
    return p


def _minimize(args: argparse.Namespace) -> int:
    from bench.campaign.minimize import minimize

    d = Path(args.campaign_dir)
    if args.out:
        out = new_folder(Path(args.out))
    else:  # the campaign's own folder for it: an earlier search is replaced
        out = d / "minimal" / args.case
        shutil.rmtree(out, ignore_errors=True)
    r = minimize(d, args.case, out, args.max_runs)
    if r["minimal"] is None or not r["minimal"]:
        print(f"minimal failure of {args.case}: {r['note']} ({_runs(r['runs'])})")
    else:
        print(f"minimal failure of {args.case}: {len(r['minimal'])} of {r['dispersed']} "
              f"dispersed values still fail ({r['runs']} runs; the rest at nominal):")
        for k, v in r["minimal"].items():
            print(f"  {k} = {v}")
    print(f"  {out / 'minimal.json'}")
    return 0


def _runs(n: int) -> str:
    return f"{n} run" if n == 1 else f"{n} runs"


def main(argv: list[str]) -> int:
    """Command line (module docstring)."""
    args = opt.parse_or_exit_code(_parser(), argv)
    if isinstance(args, int):
        return args
    try:
        if args.tool == "rerun":
            from bench.campaign.cli import rerun_case

            return rerun_case(Path(args.campaign_dir), args.case,
                              None if args.out is None else Path(args.out))
        if args.tool == "minimize":
            return _minimize(args)
        from bench.campaign.margin import margin_search

        r = margin_search(Path(args.scenario), args.key, args.toward, args.requirement,
                          new_folder(Path(args.out)), args.tolerance, tuple(args.overrides))
    except (ConfigError, RunError) as exc:
        return error_exit(exc)
    if r.get("boundary") is None:
        print(f"margin of {r['key']} for {r['requirement']}: {r['note']} ({_runs(r['runs'])})")
        if r.get("nominal_fails"):
            return EXIT_FAILED
    else:
        rel = "" if r["margin_relative"] is None else f" ({100 * r['margin_relative']:+.1f} %)"
        print(f"margin of {r['key']} for {r['requirement']}: fails from {r['boundary']:.6g} "
              f"± {r['uncertainty']:.2g} (last pass {r['last_pass']:.6g}, first fail "
              f"{r['first_fail']:.6g}; nominal {r['nominal']:g}): margin "
              f"{r['margin']:+.6g}{rel}; {r['runs']} runs; {Path(args.out) / 'margin.json'}")
    return 0
