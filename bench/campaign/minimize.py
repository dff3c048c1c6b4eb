"""Minimal failure: the smallest set of a failing case's dispersions that still fails.

From a failing case of a campaign folder, each dispersed value is either kept (as drawn)
or put back to nominal (the scenario's value, with the campaign's ``set`` overrides and
the case's injected failure always kept). First whole dispersions (every element of one
key: ``thrusters.actual_thrust_scale``), then single elements of what is left, are put
back one at a time, in the case's order; one that the case still fails without stays at
nominal (Zeller and Hildebrandt's ddmin with single-element steps, IEEE TSE 28(2), 2002:
the result is 1-minimal, every value left is needed for the failure). Each trial is one
run in ``OUT/trials/NN/`` (:mod:`bench.campaign.case_run`), the case's seed every time.

Out: ``OUT/minimal.json``: the values left, the trials (what was at nominal, pass or
fail) and their count. A case that also fails at nominal has an empty set; a case that
no longer fails as drawn is reported, not minimised.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

from bench.campaign.case_run import CASE_FILE, STATUS_OK, run_case
from bench.campaign.cases import with_defaults
from bench.campaign.paths import get_value, leaf_key, leaf_path, parse_key, set_value, toml_value
from bench.campaign.spec import CASE_TIMEOUT_BASE_S
from bench.campaign.zygote import Zygote
from bench.scenario.load import apply_overrides
from bench.scenario.parse import parse_scenario
from dbc.datafile import parse_toml, read_text
from dbc.errors import ConfigError, RunError
from dbc.records import write_record

DEFAULT_MAX_RUNS = 60
"""Trials before giving up (thruster-hil campaign minimize --max-runs)."""


def _split(case: dict[str, Any]) -> tuple[list[str], dict[str, Any]]:
    """The case's overrides that are not dispersions (kept), and its values by key."""
    values = {k: v for k, v in case["values"]}
    leaves = {leaf_key(parse_key(CASE_FILE, "values", k)) for k in values}
    kept = [o for o in case["overrides"] if o.partition("=")[0] not in leaves]
    return kept, values


def _overrides(base: dict[str, Any], chosen: dict[str, Any]) -> list[str]:
    """Leaf overrides that set ``chosen`` values on the nominal ``base``."""
    data = copy.deepcopy(base)
    leaves: dict[str, Any] = {}
    for key, v in chosen.items():
        parts = parse_key(CASE_FILE, "values", key)
        set_value(data, parts, v)
        leaves[leaf_key(parts)] = leaf_path(parts)
    return [f"{k}={toml_value(get_value(data, p))}" for k, p in leaves.items()]


def minimize(campaign_dir: Path, name: str, out: Path,
             max_runs: int = DEFAULT_MAX_RUNS) -> dict[str, Any]:
    """Minimise case ``name`` (module docstring); the result, also in ``out/minimal.json``."""
    try:
        case = json.loads((campaign_dir / "cases" / name / CASE_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ConfigError("command line", "CASE", name, f"a case of the campaign folder "
                          f"{campaign_dir}") from exc
    scenario = campaign_dir / "scenario.toml"
    text = read_text(scenario, "scenario file")
    kept, values = _split(case)
    base = parse_toml(text, str(scenario))
    apply_overrides(base, kept, f"{name}: kept overrides")
    sc = parse_scenario(copy.deepcopy(base), str(scenario))
    n = len(sc.thrusters)
    base = with_defaults([parse_key(CASE_FILE, "values", k) for k in values], base, n)
    timeout = CASE_TIMEOUT_BASE_S + sc.duration_s
    trials: list[dict[str, Any]] = []
    result: dict[str, Any] = {}
    known: dict[frozenset[str], bool] = {}  # a set already run is not run again

    def fails(chosen: dict[str, Any]) -> bool:
        key = frozenset(chosen)
        if key in known:
            return known[key]
        if len(trials) >= max_runs:
            write_record(out / "minimal.json", dict(result, minimal=None, partial=True,
                                                    runs=len(trials), trials=trials))
            raise RunError(f"minimal failure of {name}: more than {max_runs} runs needed "
                           f"(--max-runs); the trials so far are in {out / 'minimal.json'}")
        c = dict(case, index=len(trials), name=f"{len(trials):02d}",
                 overrides=kept + _overrides(base, chosen))
        row = run_case(c, str(scenario), str(out / "trials"), timeout, {}, warm=zygote)
        if row["status"] != STATUS_OK:
            raise RunError(f"minimal failure of {name}, trial {len(trials)}: {row['error']}")
        trials.append({"folder": f"trials/{c['name']}",
                       "nominal": sorted(set(values) - set(chosen)),
                       "passed": row["passed"], "requirements": row["requirements"]})
        known[key] = not row["passed"]
        return known[key]

    out.mkdir(parents=True, exist_ok=True)
    result.update(campaign=str(campaign_dir), case=name, dispersed=len(values))
    with Zygote() as zygote:  # each trial forked warm (bench.campaign.zygote)
        if not fails(values):
            result.update(minimal=None, note="the case passes as drawn: nothing to minimise")
        elif fails({}):
            result.update(minimal={}, note="the case fails at nominal too: no dispersion is needed")
        else:
            chosen = dict(values)
            groups: dict[str, list[str]] = {}
            for k in values:
                groups.setdefault(leaf_key(parse_key(CASE_FILE, "values", k)), []).append(k)
            for keys in groups.values():  # whole dispersions first
                trial = {k: v for k, v in chosen.items() if k not in keys}
                if len(trial) < len(chosen) and fails(trial):
                    chosen = trial
            for k in list(chosen):  # then single elements
                trial = {x: v for x, v in chosen.items() if x != k}
                if len(chosen) > 1 and fails(trial):
                    chosen = trial
            result.update(minimal=chosen, note=None)
    result.update(runs=len(trials), trials=trials)
    write_record(out / "minimal.json", result)
    return result
