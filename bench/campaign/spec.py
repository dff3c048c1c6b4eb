"""A campaign file: which scenario, which study, what is dispersed, validated.

```toml
[campaign]
scenario = "../quickstart.toml"   # relative to this file
study = "monte_carlo"             # or "factorial" (every combination of the sweeps)
cases = 200                       # monte_carlo: dispersed vehicles
seed = 2026                       # the campaign's seed: every case's draws and run seed
failures = ["stuck_closed"]       # optional: every single-thruster failure x every vehicle
fault_time_s = 10.0               # when those failures start

[[dispersions]]
name = "thrust_scale"             # a name from ALIASES, or key = "a.scenario.key[*]"
dist = "normal"                   # uniform | normal | choice | sweep (distributions.py)
mean = 1.0
sigma = 0.02
apply = "value"                   # value (default) | offset (nominal + x) | scale (nominal * x)
```

Optional in ``[campaign]``: ``set`` (``["KEY=VALUE", ...]``: overrides of the scenario
for every case, e.g. ``"scenario.duration_s=20"``), ``name`` (default: the file's stem),
``vary_seed`` (true: each vehicle's run seed drawn from the campaign seed; false: the
scenario's seed for every case, so that a factorial study's factors are not mixed with
sensor noise; default true for a Monte Carlo, false for a factorial study),
``case_timeout_s`` (a case still running after this is killed, retried once, then
recorded as an error), ``worst`` (cases listed as worst per figure, traces kept), ``keep``
(``"failing"``: full traces only for failing and worst cases; ``"all"``).
Every error names the file and the key.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bench.campaign.distributions import DIST_KEYS, Distribution, parse_distribution
from bench.campaign.paths import Part, parse_key
from bench.scenario.limits import SEED_MAX
from dbc import validation as check
from dbc.datafile import parse_toml, read_text
from dbc.errors import ConfigError
from dbc.faults import STUCK_CLOSED, STUCK_OPEN

STUDIES = ("monte_carlo", "factorial")
APPLY = ("value", "offset", "scale")
SINGLE_FAILURES = (STUCK_CLOSED, STUCK_OPEN)
KEEP = ("failing", "all")
MAX_CASES = 100_000
DEFAULT_FAULT_TIME_S = 10.0
DEFAULT_WORST = 5
MAX_WORST = 100
MIN_CASE_TIMEOUT_S = 1.0
CASE_TIMEOUT_BASE_S = 120.0
"""A case's default timeout: this plus its simulated duration (a run slower than real
time after two minutes of start-up is hung, not slow)."""

ALIASES: dict[str, str] = {
    "mass": "vehicle.mass_kg",
    "inertia_xx": "vehicle.inertia_B_kgm2[0][0]",
    "inertia_yy": "vehicle.inertia_B_kgm2[1][1]",
    "inertia_zz": "vehicle.inertia_B_kgm2[2][2]",
    "com_offset": "vehicle.com_offset_B_m[*]",
    "thrust_scale": "thrusters.actual_thrust_scale[*]",
    "misalignment": "thrusters.actual_misalignment_deg[*][*]",
    "isp": "thrusters.isp_s",
    "open_delay": "thrusters.open_delay_s",
    "close_delay": "thrusters.close_delay_s",
    "min_on_time": "thrusters.min_on_s",
    "gyro_bias": "sensors.gyro.bias_deg_h[*]",
    "gyro_noise": "sensors.gyro.arw_deg_sqrt_h",
    "accel_bias": "sensors.accelerometer.bias_ug[*]",
    "star_tracker_noise": "sensors.star_tracker.noise_cross_arcsec",
    "initial_attitude": "initial.attitude_offset_deg[*]",
    "initial_rate": "initial.omega_BN_B_deg_s[*]",
    "initial_position": "initial.r_N_m[*]",
    "initial_velocity": "initial.v_N_m_s[*]",
    "bitrate": "bus.bitrate_bps",
    "latency": "bus.fsw_response_delay_s",
    "fault_time": "faults[*].t_s",
    "fault_target": "faults[*].thruster",
}
"""Names users know → scenario keys (docs/campaigns.md lists them with their units)."""


@dataclass(frozen=True)
class Dispersion:
    """One dispersed scenario key: its distribution and how a draw becomes the value."""

    key: str
    parts: tuple[Part, ...]
    dist: Distribution
    apply: str = "value"


@dataclass(frozen=True)
class CampaignSpec:
    """A validated campaign file (module docstring)."""

    source: str
    name: str
    scenario: Path
    study: str
    cases: int
    seed: int
    vary_seed: bool
    failures: tuple[str, ...]
    fault_time_s: float
    dispersions: tuple[Dispersion, ...]
    case_timeout_s: float | None
    worst: int
    keep: str
    overrides: tuple[str, ...] = ()
    """``[campaign] set``: ``KEY=VALUE`` overrides applied to the scenario for every case
    (before the dispersions), as ``thruster-hil run --set`` takes them."""

    def __post_init__(self) -> None:
        if self.study == "factorial":
            for i, d in enumerate(self.dispersions):
                if not d.dist.levels():
                    raise ConfigError(self.source, f"dispersions[{i}].dist",
                                      type(d.dist).__name__.lower(),
                                      "a sweep or a choice in a factorial study")


def _near(word: object, choices: Any) -> str:
    """`` (did you mean X?)`` for a near miss among ``choices``, else nothing."""
    import difflib

    near = difflib.get_close_matches(str(word), sorted(choices), n=1)
    return f" (did you mean {near[0]!r}?)" if near else ""


def _dispersion(source: str, i: int, t: object) -> Dispersion:
    where = f"dispersions[{i}]"
    if not isinstance(t, dict):
        raise ConfigError(source, where, t, "a table ([[dispersions]])")
    extra = set(t) - DIST_KEYS - {"name", "key", "apply"}
    if extra:
        bad = sorted(extra)[0]
        raise ConfigError(source, f"{where}.{bad}", t[bad], "no such key (name, key, apply, "
                          "dist and its parameters)")
    if ("name" in t) == ("key" in t):
        raise ConfigError(source, where, sorted(t), "exactly one of name (an alias) or key")
    if "name" in t:
        if t["name"] not in ALIASES:
            raise ConfigError(source, f"{where}.name", t["name"], "one of "
                              + ", ".join(sorted(ALIASES)) + _near(t["name"], ALIASES))
        key = ALIASES[t["name"]]
    else:
        key = t["key"]
    parts = parse_key(source, f"{where}.key", key)
    apply = t.get("apply", "value")
    if apply not in APPLY:
        raise ConfigError(source, f"{where}.apply", apply, "one of " + ", ".join(APPLY))
    return Dispersion(key, parts, parse_distribution(source, where, t), apply)


def parse_campaign(data: dict[str, Any], source: str, base: Path) -> CampaignSpec:
    """Validate campaign data read from ``source``; paths are relative to ``base``."""
    unknown = set(data) - {"campaign", "dispersions"}
    if unknown:
        bad = sorted(unknown)[0]
        raise ConfigError(source, bad, data[bad], "no such table ([campaign], [[dispersions]])")
    c = data.get("campaign")
    if not isinstance(c, dict):
        raise ConfigError(source, "campaign", c, "a [campaign] table")
    known = {"name", "scenario", "study", "cases", "seed", "vary_seed", "failures",
             "fault_time_s", "case_timeout_s", "worst", "keep", "set"}
    if set(c) - known:
        bad = sorted(set(c) - known)[0]
        raise ConfigError(source, f"campaign.{bad}", c[bad], "no such key ("
                          + ", ".join(sorted(known)) + ")" + _near(bad, known))
    sc = c.get("scenario")
    if not isinstance(sc, str) or not sc:
        raise ConfigError(source, "campaign.scenario", sc, "a scenario file path")
    study = c.get("study", "monte_carlo")
    if study not in STUDIES:
        raise ConfigError(source, "campaign.study", study, "one of " + ", ".join(STUDIES))
    failures = c.get("failures", [])
    if not isinstance(failures, list) or any(f not in SINGLE_FAILURES for f in failures):
        raise ConfigError(source, "campaign.failures", failures,
                          "a list of " + ", ".join(SINGLE_FAILURES))
    keep = c.get("keep", "failing")
    if keep not in KEEP:
        raise ConfigError(source, "campaign.keep", keep, "one of " + ", ".join(KEEP))
    if study == "factorial" and "cases" in c:
        raise ConfigError(source, "campaign.cases", c["cases"], "absent in a factorial study "
                          "(its cases are every combination of the sweeps)")
    if "fault_time_s" in c and not failures:
        raise ConfigError(source, "campaign.fault_time_s", c["fault_time_s"], "absent "
                          "without failures (it is when each injected failure starts)")
    timeout = c.get("case_timeout_s")
    sets = c.get("set", [])
    if not isinstance(sets, list) or not all(isinstance(x, str) and "=" in x for x in sets):
        raise ConfigError(source, "campaign.set", sets, 'a list of "KEY=VALUE" strings')
    disp = data.get("dispersions", [])
    if not isinstance(disp, list):
        raise ConfigError(source, "dispersions", disp, "an array of tables [[dispersions]]")
    return CampaignSpec(
        source=source,
        name=str(c.get("name", Path(source).stem)),
        scenario=(base / sc).resolve(),
        study=study,
        cases=check.integer(source, "campaign.cases", c.get("cases", 1), 1, MAX_CASES),
        seed=check.integer(source, "campaign.seed", c.get("seed", 0), 0, SEED_MAX),
        vary_seed=check.flag(source, "campaign.vary_seed",
                             c.get("vary_seed", study == "monte_carlo")),
        failures=tuple(dict.fromkeys(failures)),
        fault_time_s=check.number(source, "campaign.fault_time_s",
                                  c.get("fault_time_s", DEFAULT_FAULT_TIME_S), 0.0),
        dispersions=tuple(_dispersion(source, i, t) for i, t in enumerate(disp)),
        case_timeout_s=None if timeout is None else check.number(
            source, "campaign.case_timeout_s", timeout, MIN_CASE_TIMEOUT_S),
        worst=check.integer(source, "campaign.worst", c.get("worst", DEFAULT_WORST), 0,
                            MAX_WORST),
        keep=keep,
        overrides=tuple(sets),
    )


def load_campaign(path: str | Path) -> CampaignSpec:
    """Read and validate the campaign file at ``path``."""
    p = Path(path)
    data = parse_toml(read_text(p, "campaign file"), str(p))
    return parse_campaign(data, str(p), p.resolve().parent)


def is_campaign_file(path: str | Path) -> bool:
    """Whether the TOML file at ``path`` is a campaign file (it has a ``[campaign]`` table)
    rather than a scenario; unreadable files are left to the loaders' errors."""
    try:
        return "campaign" in parse_toml(read_text(Path(path), "campaign file"), str(path))
    except ConfigError:
        return False
