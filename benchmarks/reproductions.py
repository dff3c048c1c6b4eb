"""The seed papers' simulations, rerun over the bus; figures as JSON, plots for the docs.

Each reproduction is a scenario in ``scenarios/`` run with ``thruster-hil run`` in lockstep
over a private portable bus (two real processes), in two actuator variants:
``on_off`` (the scenario as written: on-off valves with delays, rise/tail and minimum
on-time, driven by PWPF modulators) and ``continuous`` (ideal continuous thrust: the
bench's throttled valve model, no delays, and the proportional modulator). Prints one JSON
object with each run's figures (settling, steady-state errors, position convergence,
propellant, allocation residual and saturation, the scenario's expectations) and, with
``--plots DIR``, writes comparison plots (PNG) there: docs/reproductions.md shows them.

    python benchmarks/reproductions.py --plots docs/img/reproductions
    python benchmarks/reproductions.py --only formation_keeping_nftsm
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bench.results.record import read_lines, run_file

PROGRESS_BAR_WIDTH = 30  # characters of the terminal progress bar
REPO = Path(__file__).resolve().parents[1]
SCENARIOS = REPO / "scenarios"
CONTINUOUS = (
    "thrusters.valve_model='throttled'",
    "flight_sw.modulator={kind='proportional'}",
)
SUMMARY_KEYS = (
    "converged",
    "settling_time_s",
    "steady_state_attitude_error_deg",
    "steady_state_rate_error_deg_s",
    "final_attitude_error_deg",
    "position_settling_time_s",
    "steady_state_position_error_m",
    "propellant_kg",
    "valve_openings",
    "final_position_error_m",
    "net_translation",
    "realtime_factor",
)


@dataclass(frozen=True)
class Reproduction:
    """One paper simulation: a scenario, and variants as extra ``--set`` overrides."""

    name: str
    scenario: str
    paper: str
    variants: dict[str, tuple[str, ...]] = field(default_factory=dict)


def _variants(**extra: tuple[str, ...]) -> dict[str, tuple[str, ...]]:
    out: dict[str, tuple[str, ...]] = {}
    for label, sets in extra.items():
        out[f"{label}/on_off"] = sets
        out[f"{label}/continuous"] = sets + CONTINUOUS
    return out


REPRODUCTIONS = (
    Reproduction(
        "three_axis_tracking_cascade",
        "three_axis_tracking_cascade.toml",
        "seed 003, Table 2",
        _variants(
            cascade_lqr=(),
            table1_gains=("flight_sw.controller={kind='cascade_lqr',table1=true,"
                          "max_rate_deg_s=8.0}",),
            quaternion_pd=("flight_sw.controller={kind='quaternion_pd',"
                           "natural_frequency_rad_s=2.5,damping_ratio=0.9,max_rate_deg_s=8.0}",),
        ),
    ),
    Reproduction(
        "formation_keeping_nftsm",
        "formation_keeping_nftsm.toml",
        "seed 000, Figs. 2-4",
        _variants(
            nftsm=(),
            # the baseline, judged by the paper's own TSM figure (78 s)
            tsm=("flight_sw.controller={kind='tsm_dq'}",
                 "expectations.position_settling_time_s_max=80.0",
                 "expectations.settling_time_s_max=80.0"),
        ),
    ),
    Reproduction(
        "mrp_trajectory_tracking",
        "mrp_trajectory_tracking.toml",
        "seed 001, Figs. 4-6",
        _variants(
            case1=("flight_sw.controller.case=1",),
            case2=("flight_sw.controller.case=2",),
            case3=("flight_sw.controller.case=3",),
        ),
    ),
    Reproduction(
        "capture_inertia_identification",
        "capture_inertia_identification.toml",
        "seed 001, section 2",
        _variants(
            rls=(),
            no_identification=("flight_sw.inertia_identification.min_information=1e30",),
        ),
    ),
    Reproduction(
        "robust_allocation_tracking",
        "mrp_trajectory_tracking.toml",
        "seed 001, Figs. 7-11",
        _variants(
            pseudo_inverse=("flight_sw.allocator={kind='pseudo_inverse'}",),
            robust_polyhedral=("flight_sw.allocator={kind='robust_polyhedral'}",),
            robust_polytopic=("flight_sw.allocator={kind='robust_polytopic'}",),
            robust_lft=("flight_sw.allocator={kind='robust_lft'}",),
        ),
    ),
)


def run_scenario(scenario: Path, sets: tuple[str, ...], out: Path) -> dict[str, Any]:
    """``thruster-hil run`` in lockstep on a private portable bus; the run's summary."""
    xdg = Path(tempfile.mkdtemp(prefix="xdg-"))
    env = dict(os.environ, XDG_RUNTIME_DIR=str(xdg))
    cmd = [sys.executable, "-m", "bench.operator.entry", "run", str(scenario), "--out", str(out),
           "--bus", f"hilbus:rp{uuid.uuid4().hex[:8]}"]
    for s in sets:
        cmd += ["--set", s]
    done = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, check=False)
    summary_path = out / "summary.json"
    if not summary_path.exists():
        return {"error": done.stderr.strip().splitlines()[-1:] or ["no summary"]}
    summary: dict[str, Any] = json.loads(summary_path.read_text(encoding="utf-8"))
    return summary


def figures(summary: dict[str, Any], run_dir: Path) -> dict[str, Any]:
    """The figures of one run that the reproduction tables quote."""
    out = {k: summary.get(k) for k in SUMMARY_KEYS if k in summary}
    out["expectations_passed"] = summary.get("passed")
    out["failed_expectations"] = [
        e for e in summary.get("expectations", []) if isinstance(e, dict) and not e.get("pass")
    ]
    if "error" not in summary:
        out["hold"] = hold_figures(run_dir, summary)
    stats_path = run_dir / "fsw_stats.json"
    if stats_path.exists():
        stats = json.loads(stats_path.read_text(encoding="utf-8"))
        out["allocation"] = stats.get("allocation")
        out["fsw_cycle_time_us"] = stats.get("cycle_time_us")
        out["inertia_estimate_B_kgm2"] = stats.get("inertia_estimate_B_kgm2")
    if "error" in summary:
        out["error"] = summary["error"]
    return out


def hold_figures(run_dir: Path, summary: dict[str, Any]) -> dict[str, Any] | None:
    """Valve activity and propellant once converged: from the later of the attitude and
    position settling times to the end (None if the run never settled): valve pulses per
    second (all thrusters), propellant [kg] and its fraction of the run's total."""
    settled = [summary.get(k) for k in ("settling_time_s", "position_settling_time_s")]
    if summary.get("settling_time_s") is None:
        return None
    t_from = max(t for t in settled if t is not None)
    tel = read_telemetry(run_dir)
    t, prop = tel["t_s"], tel["propellant_kg"]
    total = float(prop[-1])
    used = total - float(np.interp(t_from, t, prop))
    pulse_rows = csv.DictReader(read_lines(run_file(run_dir, "valve_pulses.csv")))
    n_hold = sum(1 for r in pulse_rows if float(r["t_on_s"]) >= t_from)
    span = float(t[-1]) - t_from
    return {
        "from_s": t_from,
        "pulses_per_s": n_hold / span if span > 0 else None,
        "propellant_kg": used,
        "propellant_fraction": used / total if total > 0 else None,
    }


def read_telemetry(run_dir: Path) -> dict[str, np.ndarray]:
    """Columns of ``telemetry.csv`` as float arrays (non-numeric columns skipped)."""
    rows = list(csv.DictReader(read_lines(run_file(run_dir, "telemetry.csv"))))
    cols: dict[str, np.ndarray] = {}
    for key in rows[0] if rows else []:
        try:
            cols[key] = np.array([float(r[key]) for r in rows])
        except ValueError:
            continue
    return cols


def plot_comparison(
    rep: Reproduction, run_dirs: dict[str, Path], dest: Path, six_dof: bool
) -> list[Path]:
    """Attitude error (and position error in 6 DoF) of every variant on shared axes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tel = {v: read_telemetry(d) for v, d in run_dirs.items()
           if run_file(d, "telemetry.csv").exists()}
    if not tel:
        return []
    fig, axes = plt.subplots(2 if six_dof else 1, 1, figsize=(8, 6 if six_dof else 3.5),
                             squeeze=False)
    for variant, t in tel.items():
        axes[0][0].semilogy(t["t_s"], np.maximum(t["att_err_deg"], 1e-4), label=variant)
        if six_dof:
            pos = np.sqrt(t["rx_m"] ** 2 + t["ry_m"] ** 2 + t["rz_m"] ** 2)
            axes[1][0].semilogy(t["t_s"], np.maximum(pos, 1e-4), label=variant)
    axes[0][0].set_ylabel("attitude error [deg]")
    axes[0][0].set_title(f"{rep.name} ({rep.paper}), lockstep over the bus")
    if six_dof:
        axes[1][0].set_ylabel("position error [m]")
    axes[-1][0].set_xlabel("t [s]")
    for ax in axes[:, 0]:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    dest.mkdir(parents=True, exist_ok=True)
    path = dest / f"{rep.name}.png"
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return [path]


def copy_run_plots(rep: Reproduction, run_dirs: dict[str, Path], dest: Path) -> list[Path]:
    """The first variant's own run plots (thruster raster, rates), renamed for the docs."""
    variant, run_dir = next(iter(run_dirs.items()))
    copied = []
    for png in ("thruster_raster.png", "rates.png"):
        src = run_dir / png
        if src.exists():
            target = dest / f"{rep.name}-{variant.replace('/', '-')}-{png}"
            shutil.copyfile(src, target)
            copied.append(target)
    return copied


def show_progress(done: int, total: int, name: str, summary: dict[str, Any]) -> None:
    """On stderr, as each run ends: a bar on a terminal; a flushed line when redirected
    (a log, CI), so a many-minute benchmark shows its runs as they finish."""
    verdict = summary.get("verdict") or ("PASS" if summary.get("passed") else "FAIL")
    if sys.stderr.isatty():
        n = done * PROGRESS_BAR_WIDTH // total
        sys.stderr.write(f"\r[{'#' * n}{'.' * (PROGRESS_BAR_WIDTH - n)}] {done}/{total} "
                         f"{name[:40]:40s}" + ("\n" if done == total else ""))
    else:
        sys.stderr.write(f"[{done}/{total}] {name}: {verdict}\n")
    sys.stderr.flush()


def main() -> None:
    """Parse arguments, run every reproduction and variant, print JSON."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--only", action="append", help="run only this reproduction (repeatable)")
    p.add_argument("--plots", help="write comparison plots (PNG) to this directory")
    p.add_argument("--keep", help="keep the run folders under this directory")
    args = p.parse_args()
    chosen = [r for r in REPRODUCTIONS if not args.only or r.name in args.only]
    result: dict[str, Any] = {"benchmark": "reproductions", "runs": {}}
    total = sum(len(r.variants) for r in chosen)
    done = 0
    with tempfile.TemporaryDirectory(prefix="thil-repro-") as tmp:
        root = Path(args.keep) if args.keep else Path(tmp)
        for rep in chosen:
            dirs: dict[str, Path] = {}
            six_dof = False
            for variant, sets in rep.variants.items():
                out = root / rep.name / variant.replace("/", "-")
                summary = run_scenario(SCENARIOS / rep.scenario, sets, out)
                result["runs"][f"{rep.name}/{variant}"] = figures(summary, out)
                dirs[variant] = out
                done += 1
                show_progress(done, total, f"{rep.name}/{variant}", summary)
                six_dof = six_dof or summary.get("position_band_m") is not None
            if args.plots:
                dest = Path(args.plots).resolve()
                paths = plot_comparison(rep, dirs, dest, six_dof)
                paths += copy_run_plots(rep, dirs, dest)
                result.setdefault("plots", []).extend(
                    str(x.relative_to(REPO) if x.is_relative_to(REPO) else x) for x in paths
                )
    print(json.dumps(result, indent=2, default=str))


if __name__ == "__main__":
    main()
