"""Margin search: the value of one scenario key at which a requirement starts failing.

From the scenario's own (nominal) value, which must pass, toward a value that must fail,
bisect: each step runs the scenario once with the key at the midpoint of the bracket
(the same seed every time, so a step's outcome depends on the key alone), and keeps the
half where the outcome changes, until the bracket is no wider than ``tolerance``. The
boundary is the bracket's centre, its uncertainty the half-width; the margin is the
boundary's distance from nominal, absolute and relative to the nominal value. The search
assumes one crossing between nominal and ``toward`` (a requirement that passes, fails and
passes again inside the bracket is found at one of its crossings).

Each step is one case of :mod:`bench.campaign.case_run` (``--set`` overrides built by
:mod:`bench.campaign.cases` from a one-value sweep, so aliases such as ``thrust_scale``
and ``latency`` work as in a campaign file), in ``OUT/steps/NN/``. Out: ``margin.json``.
"""

from __future__ import annotations

import copy
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

from bench.campaign.case_run import STATUS_OK, run_case
from bench.campaign.cases import build_cases, with_defaults
from bench.campaign.distributions import Sweep
from bench.campaign.paths import expand, get_value, parse_key
from bench.campaign.spec import ALIASES, CASE_TIMEOUT_BASE_S, CampaignSpec, Dispersion
from bench.campaign.zygote import Zygote
from bench.scenario.load import apply_overrides
from bench.scenario.parse import parse_scenario
from dbc.datafile import parse_toml, read_text
from dbc.errors import ConfigError, RunError
from dbc.records import write_record

DEFAULT_STEPS = 6
"""Without a tolerance: bisect until the bracket is 2^-DEFAULT_STEPS of its start."""
MAX_STEPS = 40


def _spec(scenario: Path, key: str, overrides: tuple[str, ...]) -> CampaignSpec:
    full = ALIASES.get(key, key)
    parts = parse_key("command line", "--key", full)
    return CampaignSpec(source="command line", name="margin", scenario=scenario,
                        study="factorial", cases=1, seed=0, vary_seed=False, failures=(),
                        fault_time_s=0.0, dispersions=(Dispersion(full, parts, Sweep((0.0,))),),
                        case_timeout_s=None, worst=0, keep="all", overrides=overrides)


def margin_search(scenario: Path, key: str, toward: float, requirement: str, out: Path,
                  tolerance: float | None = None,
                  overrides: tuple[str, ...] = ()) -> dict[str, Any]:
    """Bisect (module docstring); the result written to ``out/margin.json`` and returned.
    ``overrides``: ``KEY=VALUE`` changes to the scenario for every step (``--set``)."""
    spec = _spec(scenario, key, overrides)
    text = read_text(scenario, "scenario file")
    data = parse_toml(text, str(scenario))
    apply_overrides(data, list(overrides), "command line --set")
    sc = parse_scenario(copy.deepcopy(data), str(scenario))
    base = with_defaults([spec.dispersions[0].parts], data, len(sc.thrusters))
    try:
        paths = expand(base, spec.dispersions[0].parts)
    except KeyError as exc:
        raise ConfigError("command line", "--key", key,
                          f"a key the scenario has ({exc.args[0]})") from exc
    nominals = {get_value(base, p) for p in paths}
    if len(nominals) != 1 or not all(isinstance(v, int | float) for v in nominals):
        have = sorted(map(str, nominals))
        raise ConfigError("command line", "--key", key,
                          f"a number, the same for every element (the scenario has {have})")
    nominal = float(nominals.pop())
    if not math.isfinite(toward) or toward == nominal:
        raise ConfigError("command line", "--toward", toward, f"a value other than the "
                          f"nominal {nominal:g}")
    tol = tolerance if tolerance is not None else abs(toward - nominal) / 2 ** DEFAULT_STEPS
    if not tol > 0.0:
        raise ConfigError("command line", "--tolerance", tolerance, "a positive number")
    timeout = CASE_TIMEOUT_BASE_S + sc.duration_s

    def case_at(value: float) -> Any:
        s = replace(spec, dispersions=(replace(spec.dispersions[0], dist=Sweep((value,))),))
        (c,) = build_cases(s, data, len(sc.thrusters), sc.seed)
        return c

    checked = parse_toml(text, str(scenario))  # --toward as the runs will read it
    apply_overrides(checked, list(case_at(toward).overrides), "command line --set")
    try:
        parse_scenario(checked, "command line")
    except ConfigError as exc:
        raise ConfigError("command line", "--toward", toward, f"a value the scenario takes "
                          f"at {key} ({exc.key}: {exc.expected})") from exc
    out.mkdir(parents=True, exist_ok=True)
    (out / "scenario.toml").write_text(text, encoding="utf-8")
    steps: list[dict[str, Any]] = []
    failed_at_nominal: list[str] = []

    def passes(value: float) -> bool:
        c = case_at(value)
        case = {"index": len(steps), "name": f"{len(steps):02d}", "vehicle": 0, "seed": c.seed,
                "overrides": list(c.overrides), "values": [list(v) for v in c.values],
                "failure": None, "fault_time_s": 0.0}
        row = run_case(case, str(out / "scenario.toml"), str(out / "steps"), timeout, {},
                       warm=zygote)
        if row["status"] != STATUS_OK:
            raise RunError(f"margin step {value:g}: {row['error']}")
        reqs = row["requirements"]
        if requirement != "passed" and requirement not in reqs:
            raise ConfigError("command line", "--requirement", requirement,
                              "one of passed, " + ", ".join(reqs))
        ok = row["passed"] if requirement == "passed" else reqs[requirement]
        if not steps and not ok:
            failed_at_nominal.extend(k for k, v in reqs.items() if not v)
        steps.append({"value": value, "pass": ok, "figures": row["figures"]})
        print(f"  step {len(steps)}: {key} = {value:.6g}: {'pass' if ok else 'FAIL'}", flush=True)
        return bool(ok)

    result: dict[str, Any] = {"scenario": str(scenario), "overrides": list(overrides),
                              "key": key, "requirement": requirement,
                              "nominal": nominal, "toward": toward, "tolerance": tol}
    with Zygote() as zygote:  # each step forked warm (bench.campaign.zygote)
        if not passes(nominal):
            result.update(boundary=None, nominal_fails=True, note="the nominal value fails ("
                          + (", ".join(failed_at_nominal) or requirement) + "): no margin")
        elif passes(toward):
            result.update(boundary=None, note=f"still passes at {toward:g}: the margin is at "
                          f"least {abs(toward - nominal):g}")
        else:
            lo, hi = nominal, toward
            while abs(hi - lo) > tol and len(steps) < MAX_STEPS:
                mid = 0.5 * (lo + hi)
                if passes(mid):
                    lo = mid
                else:
                    hi = mid
            boundary = 0.5 * (lo + hi)
            result.update(boundary=boundary, uncertainty=abs(hi - lo) / 2, last_pass=lo,
                          first_fail=hi, margin=boundary - nominal,
                          margin_relative=(boundary - nominal) / nominal if nominal else None)
    result.update(runs=len(steps), steps=steps)
    write_record(out / "margin.json", result)
    return result
