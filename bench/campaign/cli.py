"""``thruster-hil campaign CAMPAIGN.toml --out DIR``: a statistical campaign, end to end.

Reads the campaign file (:mod:`bench.campaign.spec`), builds and checks every case
(:mod:`bench.campaign.cases`: each case's scenario is validated here, so an impossible
dispersed vehicle is refused before any process starts, naming the case), runs them on
Dask (:mod:`bench.campaign.engine`; each case recorded lean unless ``keep = "all"``:
summary, events, 10 Hz telemetry and the trace as trace.blf, bench.results.record), keeps
the trace only for failing and worst cases (a case's whole folder: ``thruster-hil campaign
rerun``, exact), and writes the tables and the report (:mod:`bench.campaign.report`). The
console shows progress (cases done, pass rate so far, ETA), then each requirement's pass
rate with its 95 % interval, the wall time, cases per minute and the CPU used.

The folder: ``campaign.toml`` and ``scenario.toml`` (copies: the campaign reruns from its
folder alone), ``manifest.json`` (what the cases are: running the same campaign into the
same folder resumes it, with more cases extends it; another campaign there is refused),
``cases/NAME/`` per case.

Exit: 0 every case passed; 1 some failed; 2 bad input (also a case the flight software
refused: the others still run); 3 a case could not complete.
"""

from __future__ import annotations

import contextlib
import copy
import gzip
import hashlib
import json
import os
import shlex
import shutil
import signal
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from bench.campaign.case_run import RESULT_FILE, STATUS_OK, STATUS_REFUSED, run_command
from bench.campaign.cases import Case, build_cases
from bench.campaign.engine import check_scheduler, done_rows, run_cases
from bench.campaign.report import write_html, write_tables
from bench.campaign.spec import CASE_TIMEOUT_BASE_S, CampaignSpec, load_campaign
from bench.campaign.stats import statistics
from bench.results.record import (
    LEAN_TELEMETRY_EVERY,
    RECORD_LEAN,
    RECORD_STANDARD,
    read_lines,
    run_file,
)
from bench.scenario.load import apply_overrides, override_of
from bench.scenario.parse import parse_scenario
from dbc.datafile import parse_toml, read_text
from dbc.errors import ConfigError, RunError
from dbc.records import write_record
from transport.lockstep import available_cpus

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT, EXIT_RUN_ERROR = 0, 1, 2, 3
SCENARIO_COPY = "scenario.toml"
CAMPAIGN_COPY = "campaign.toml"
MANIFEST = "manifest.json"
MANIFEST_FORMAT = 2
"""The manifest's format: 2 since cases' ``trace_sha256`` is the run's own trace digest
(summary.json; 1, unnamed, was the SHA-256 of trace.asc's lines)."""
"""A pruned case keeps every this-many-th telemetry row (100 Hz -> 10 Hz)."""
PRUNED = ("trace.asc", "trace.blf", "frames.csv", "chains.csv", "valve_pulses.csv")
"""Per-case files removed from cases that neither failed nor are among the worst."""


def case_dict(c: Case, spec: CampaignSpec) -> dict[str, Any]:
    """A case as the engine and case.json carry it."""
    d = {"index": c.index, "name": c.name, "vehicle": c.vehicle, "seed": c.seed,
         "overrides": list(c.overrides), "values": [list(v) for v in c.values],
         "failure": None if c.failure is None else list(c.failure),
         "fault_time_s": spec.fault_time_s}
    d["command"] = " ".join(["thruster-hil", *_quoted(run_command(
        Path(SCENARIO_COPY), d, Path(f"runs/{c.name}")))])
    return d


def _quoted(args: list[str]) -> list[str]:
    return [shlex.quote(a) for a in args]


def new_folder(out: Path) -> Path:
    """``--out``: a folder that does not exist or is empty (nothing of the user's replaced)."""
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise ConfigError("command line", "--out", str(out), "a new or empty folder")
    return out


def error_exit(exc: ConfigError | RunError) -> int:
    """The campaign commands' one line for a refused input (exit 2) or a run that could not
    complete (exit 3)."""
    if isinstance(exc, ConfigError):
        print(f"thruster-hil campaign: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(f"thruster-hil campaign: run error: {exc}", file=sys.stderr)
    return EXIT_RUN_ERROR


def checked_cases(spec: CampaignSpec) -> tuple[str, list[dict[str, Any]], float]:
    """The scenario's text, every case (each validated as its run will), the timeout."""
    text = read_text(spec.scenario, "scenario file")
    data = parse_toml(text, str(spec.scenario))
    if "campaign" in data:
        raise ConfigError(spec.source, "campaign.scenario", str(spec.scenario),
                          "a scenario file (this one is a campaign file)")
    where = f"{spec.source}: campaign.set"
    apply_overrides(data, list(spec.overrides), where)
    try:
        sc = parse_scenario(copy.deepcopy(data), str(spec.scenario))
    except ConfigError as exc:  # an error the campaign's own overrides caused: name them
        item = override_of(exc.key, list(spec.overrides))
        if item is None:
            raise
        raise ConfigError(f"{where} {item!r} (on {spec.scenario})", exc.key, exc.value,
                          exc.expected) from exc
    if spec.failures and not spec.fault_time_s < sc.duration_s:
        raise ConfigError(spec.source, "campaign.fault_time_s", spec.fault_time_s,
                          f"a time before the scenario's end ({sc.duration_s:g} s)")
    cases = build_cases(spec, data, len(sc.thrusters), sc.seed)
    raw = parse_toml(text, str(spec.scenario))
    for c in cases:
        d = copy.deepcopy(raw)
        src = f"{spec.source}: case {c.name}"
        apply_overrides(d, list(c.overrides), src)
        try:
            parse_scenario(d, src)
        except ConfigError as exc:
            raise ConfigError(src, exc.key, exc.value,
                              f"{exc.expected} (a value a dispersion gave this case: check "
                              "its distribution)") from exc
    timeout = spec.case_timeout_s or CASE_TIMEOUT_BASE_S + sc.duration_s
    return text, [case_dict(c, spec) for c in cases], timeout


def _prepare(out: Path, spec: CampaignSpec, text: str, cases: list[dict[str, Any]]) -> None:
    if out.exists() and not out.is_dir():
        new_folder(out)
    # what the results depend on: the scenario, which traces are kept, and each case (a
    # campaign with more or fewer cases of the same draws extends or trims this one)
    digests = {c["name"]: _sha(json.dumps(c, sort_keys=True)) for c in cases}
    new: dict[str, Any] = {"scenario_sha256": _sha(text), "keep": spec.keep,
                           "worst": spec.worst, "format": MANIFEST_FORMAT}
    man = out / MANIFEST
    if man.exists():
        old = json.loads(man.read_text(encoding="utf-8"))
        why = next((f"{k} differs" for k in ("scenario_sha256", "keep", "worst")
                    if old.get(k) != new[k]), None)
        if old.get("format") != MANIFEST_FORMAT:
            why = ("its cases were run by an earlier version, whose trace digest was of "
                   "trace.asc: a campaign cannot mix the two")
        why = why or next((f"case {n} differs" for n, d in digests.items()
                           if old.get("cases", {}).get(n, d) != d), None)
        if why is not None:
            raise ConfigError("command line", "--out", str(out), "an empty folder or this "
                              f"campaign's own (it holds another campaign: {why})")
        digests = {**old.get("cases", {}), **digests}
    else:
        new_folder(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / SCENARIO_COPY).write_text(text, encoding="utf-8")
    shutil.copyfile(spec.source, out / CAMPAIGN_COPY)
    write_record(man, dict(new, cases=digests))


@contextlib.contextmanager
def stop_signals_interrupt() -> Iterator[None]:
    """SIGTERM and SIGHUP (a CI job cancelled, a closed terminal) stop the campaign as
    Ctrl-C does: its Dask cluster closed, its zygotes ended, complete cases kept."""

    def interrupt(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    old = {s: signal.signal(s, interrupt) for s in (signal.SIGTERM, signal.SIGHUP)}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def _sha(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _decimate(run_dir: Path) -> None:
    """Keep the header and every LEAN_TELEMETRY_EVERY-th row, streamed (flat memory): a
    case recorded in full (by an earlier version) ends as a lean one does."""
    path = run_file(run_dir, "telemetry.csv")
    if not path.exists():
        return
    tmp = path.with_name(path.name + ".tmp")
    opener = gzip.open if path.suffix == ".gz" else open
    with opener(tmp, "wt", encoding="utf-8") as f:
        f.writelines(line for i, line in enumerate(read_lines(path))
                     if i == 0 or (i - 1) % LEAN_TELEMETRY_EVERY == 0)
    tmp.replace(path)


def case_record(keep: str) -> str:
    """The record level of a campaign's cases: ``lean`` unless every case keeps its whole
    folder (bench.results.record: the summary is the same; the trace is trace.blf)."""
    return RECORD_STANDARD if keep == "all" else RECORD_LEAN


def prune(out: Path, rows: list[dict[str, Any]], stats: dict[str, Any], keep: str) -> int:
    """Drop the trace of passing cases that are not among the worst (and the tables of a
    case recorded in full, decimating its telemetry as a lean record does). The number of
    cases pruned."""
    if keep == "all":
        return 0
    worst = {w["name"] for ws in stats["worst"].values() for w in ws}
    n = 0
    for r in rows:
        run_dir = out / "cases" / r["name"] / "run"
        if r["status"] != STATUS_OK or not r["passed"] or r["name"] in worst:
            continue
        if not (out / "cases" / r["name"] / RESULT_FILE).exists():
            continue
        full = run_file(run_dir, "trace.asc").exists()
        for base in PRUNED:
            p = run_file(run_dir, base)
            if p.exists():
                p.unlink()
        if full:
            _decimate(run_dir)
        n += 1
    return n


def _progress() -> Any:
    tty = sys.stderr.isatty()
    t0 = time.monotonic()
    passed = [0]

    def show(done: int, total: int, row: dict[str, Any]) -> None:
        passed[0] += bool(row["passed"])
        dt = time.monotonic() - t0
        eta = dt / done * (total - done) if done else 0.0
        outcome = (row["status"] if row["status"] != STATUS_OK else
                   "pass" if row["passed"] else "FAIL")
        line = (f"[{done}/{total}] pass {passed[0]}/{done}, ETA {eta:.0f} s; last "
                f"{row['name']}: {outcome}")
        if tty:
            sys.stderr.write("\r" + line[:120].ljust(120))
            if done == total:
                sys.stderr.write("\n")
            sys.stderr.flush()
        else:
            say(line)

    return show


def say(line: str, err: bool = False) -> None:
    """Print a console line; a reader that went away (``| head``) ends the printing, not
    the campaign (its files are still written)."""
    stream = sys.stderr if err else sys.stdout
    try:
        print(line, file=stream, flush=True)
    except BrokenPipeError:
        devnull = open(os.devnull, "w")  # noqa: SIM115 - stands in for the closed stream
        if err:
            sys.stderr = devnull
        else:
            sys.stdout = devnull


def check_fsw_config(sc_path: Path, overrides: list[str], source: str) -> None:
    """The flight software's own check of the configuration a case gives it
    (``python -m flight_sw --check``), so a refused ``[flight_sw]`` is bad input before any
    run starts, not a campaign of refused runs."""
    import subprocess
    import tempfile

    from bench.scenario.load import load_scenario

    with tempfile.TemporaryDirectory(prefix="thil-fsw-check-") as tmp:
        config = Path(tmp) / "fsw_config.json"
        write_record(config, load_scenario(sc_path, overrides).fsw_config())
        p = subprocess.run([sys.executable, "-m", "flight_sw", "--config", str(config),
                            "--check"], capture_output=True, text=True, check=False)
    if p.returncode != 0:
        why = (p.stderr.strip().splitlines() or ["(no output)"])[-1]
        raise ConfigError(source, "flight_sw", "(its configuration)",
                          f"one the flight software accepts; it said: {why}")


def run_campaign_file(path: Path, out: Path, workers: int | None, scheduler: str | None,
                      ) -> int:
    """Run the campaign file at ``path`` into ``out`` (module docstring); the exit code."""
    spec = load_campaign(path)
    text, cases, timeout = checked_cases(spec)
    check_fsw_config(spec.scenario, list(spec.overrides), spec.source)
    if scheduler is not None:
        check_scheduler(scheduler)  # before the folder is made: a typo leaves nothing
    _prepare(out, spec, text, cases)
    resumed = len(done_rows(out / "cases", cases))
    n_workers = min(workers or available_cpus(), max(1, len(cases) - resumed))
    where = scheduler or f"a local Dask cluster of {n_workers} workers"
    say(f"campaign {spec.name}: {len(cases)} cases of {spec.scenario.name} on {where}; "
        f"folder {out}")
    if resumed:
        say(f"resuming: {resumed} of {len(cases)} cases already complete in {out}")
    cpu0, t0 = os.times(), time.monotonic()
    try:
        with stop_signals_interrupt():
            rows = run_cases(cases, out / SCENARIO_COPY, out, timeout, scheduler, n_workers,
                             _progress(), notice=lambda line: say(line, err=True),
                             record=case_record(spec.keep))
    except KeyboardInterrupt:
        done = len(done_rows(out / "cases", cases))
        say(f"campaign stopped: {done} of {len(cases)} cases complete in {out}; the same "
            "command resumes it", err=True)
        raise
    wall = time.monotonic() - t0
    cpu1 = os.times()
    cpu_s = ((cpu1.children_user - cpu0.children_user)
             + (cpu1.children_system - cpu0.children_system))
    ran = len(cases) - resumed
    local = scheduler is None
    meta: dict[str, Any] = {
        "name": spec.name, "scenario": spec.scenario.name, "study": spec.study,
        "seed": spec.seed, "cases": len(cases), "resumed_cases": resumed, "cases_run": ran,
        "wall_time_s": wall, "cases_per_min": 60.0 * ran / wall if ran and wall > 0 else None,
        "workers": n_workers if local else None, "scheduler": scheduler,
        "cpu_s": cpu_s if local else None,
        "cpu_use": cpu_s / (wall * available_cpus()) if local and ran and wall else None}
    stats = statistics(rows, spec.worst)
    stats["pruned"] = prune(out, rows, stats, spec.keep)
    if not write_tables(out, rows, stats, meta):
        say("campaign.parquet left out: pyarrow is not installed (pip install pyarrow)")
    page = write_html(out, rows, stats, meta)
    for name, r in stats["pass_rates"].items():
        rate = "n/a" if r["rate"] is None else f"{r['rate']:.3f}"
        say(f"  {name}: {r['passes']}/{r['cases']} = {rate}, 95 % interval "
            f"[{r['ci_low']:.3f}, {r['ci_high']:.3f}]")
    warned = [r for r in rows if r.get("warnings")]
    if warned:
        say(f"  run warnings in {len(warned)} cases, e.g. {warned[0]['name']}: "
            f"{warned[0]['warnings'][0]}")
    refused = [r for r in rows if r["status"] == STATUS_REFUSED]
    for r in rows:
        if r["status"] != STATUS_OK:
            say(f"  {r['status'].upper()} {r['name']}: {r['error']}")
    if ran:
        use = "" if meta["cpu_use"] is None else f", CPU use {100 * meta['cpu_use']:.0f} %"
        pace = f"{ran} cases run in {wall:.1f} s ({meta['cases_per_min']:.1f} per minute{use})"
    else:
        pace = "every case was already complete"
    say(f"campaign: {len(rows)} cases, {pace}; {stats['errors']} errors; {page}")
    if refused:  # the flight software refused what a dispersion gave it: bad input
        return EXIT_BAD_INPUT
    if stats["errors"]:
        return EXIT_RUN_ERROR
    return EXIT_OK if stats["pass_rates"]["passed"]["passes"] == len(rows) else EXIT_FAILED


def rerun_case(campaign_dir: Path, name: str, out: Path | None) -> int:
    """``thruster-hil campaign rerun DIR CASE``: run the case again from its case.json; exit
    0 if its trace records equal the campaign's (``trace_sha256``), 1 if not."""
    from bench.campaign.case_run import CASE_FILE

    case_dir = campaign_dir / "cases" / name
    try:
        case = json.loads((case_dir / CASE_FILE).read_text(encoding="utf-8"))
        row = json.loads((case_dir / RESULT_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ConfigError("command line", "CASE", name, f"a case of the campaign folder "
                          f"{campaign_dir} (cannot read {case_dir}/{CASE_FILE} and "
                          f"{RESULT_FILE}: {getattr(exc, 'strerror', None) or exc})") from exc
    if out is None:  # the campaign's own reruns folder: an earlier rerun is replaced
        run_dir = campaign_dir / "reruns" / name
        if run_dir.exists():
            shutil.rmtree(run_dir)
    else:
        run_dir = new_folder(out)
    import subprocess

    args = run_command(campaign_dir / SCENARIO_COPY, case, run_dir, plots=True)
    cmd = [sys.executable, "-m", "bench.operator.cli", *args]
    print("rerun: " + " ".join(["thruster-hil", *_quoted(args)]), flush=True)
    p = subprocess.run(cmd, check=False)
    if not (run_dir / "summary.json").exists():
        raise RunError(f"rerun of {name} did not complete (exit {p.returncode})")
    got = json.loads((run_dir / "summary.json").read_text(encoding="utf-8")).get("trace_sha256")
    same = got is not None and got == row["trace_sha256"]
    print(f"rerun {name}: trace {'identical to' if same else 'DIFFERENT from'} the "
          f"campaign's (trace_sha256 {got}); {run_dir}")
    return EXIT_OK if same else EXIT_FAILED
