"""Pointing against propellant for the PWPF modulator on the seed-003 vehicle: JSON and a plot.

What it does: runs ``scenarios/three_axis_tracking_cascade.toml`` (seed 003: cascade
QPD-LQR, pure-torque pseudo-inverse allocation, 8 on-off 15 N thrusters with valve delays
and a 5 ms minimum on-time, gyro and star-tracker noise) in lockstep over a private
portable bus once per PWPF design of a grid: the Schmitt trigger's on-threshold ``U_on``
(the dead zone is ``U_on/K_m`` of full thrust) and its hysteresis ``h = U_on − U_off``
(the minimum pulse is ``−T_m ln(1 − h/K_m)``), ``K_m`` and ``T_m`` as in the scenario
(designs with ``U_off = U_on − h < 0``, which the flight software refuses, are skipped). For
each design it prints the steady-state attitude error (maximum over the scenario's last
window, the acceptance figure), the settling time, the propellant of the whole run and of
the hold (after settling: the limit cycle's cost), valve pulses per second in the hold and
the net delta-v; with ``--plot FILE`` it draws steady-state error against hold propellant
(docs/reproductions.md shows it).

    python benchmarks/pwpf_trade.py --plot docs/img/reproductions/pwpf_trade.png
    python benchmarks/pwpf_trade.py --u-on 0.2 --hysteresis 0.1   # one design

Lockstep runs are deterministic: any invocation gives the same numbers. Each run is a
pair of real processes on a bus channel of its own.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

from reproductions import SCENARIOS, figures, run_scenario

DEFAULT_SCENARIO = SCENARIOS / "three_axis_tracking_cascade.toml"
DEFAULT_U_ON = (0.1, 0.2, 0.3, 0.4)
DEFAULT_HYSTERESIS = (0.05, 0.1, 0.15)
KG_TO_G = 1000.0
PLOT_SIZE_IN = (7.0, 4.5)
PLOT_DPI = 110


def run_design(scenario: Path, u_on: float, hysteresis: float, work: Path) -> dict[str, Any]:
    """One PWPF design: its run's figures (see the module docstring)."""
    out = work / f"u_on{u_on:g}_h{hysteresis:g}"
    sets = (f"flight_sw.modulator.u_on={u_on!r}",
            f"flight_sw.modulator.u_off={round(u_on - hysteresis, 12)!r}")
    summary = run_scenario(scenario, sets, out)
    fig = figures(summary, out)
    hold = fig.get("hold") or {}
    moved = fig.get("net_translation") or {}
    return {
        "u_on": u_on,
        "hysteresis": hysteresis,
        "steady_state_attitude_error_deg": fig.get("steady_state_attitude_error_deg"),
        "settling_time_s": fig.get("settling_time_s"),
        "propellant_g": None if fig.get("propellant_kg") is None
        else fig["propellant_kg"] * KG_TO_G,
        "hold_propellant_g": None if hold.get("propellant_kg") is None
        else hold["propellant_kg"] * KG_TO_G,
        "hold_pulses_per_s": hold.get("pulses_per_s"),
        "net_delta_v_m_s": moved.get("delta_v_m_s"),
        "error": fig.get("error"),
    }


def plot(rows: list[dict[str, Any]], dest: Path) -> None:
    """Steady-state error against hold propellant, one line per hysteresis."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=PLOT_SIZE_IN)
    for h in sorted({r["hysteresis"] for r in rows}):
        pts = [r for r in rows if r["hysteresis"] == h and r["hold_propellant_g"] is not None]
        pts.sort(key=lambda r: r["u_on"])
        ax.plot([r["hold_propellant_g"] for r in pts],
                [r["steady_state_attitude_error_deg"] for r in pts], marker="o",
                label=f"h = {h:g}")
        for r in pts:
            ax.annotate(f"{r['u_on']:g}", (r["hold_propellant_g"],
                                           r["steady_state_attitude_error_deg"]),
                        textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.set_xlabel("propellant in the hold [g] (after settling)")
    ax.set_ylabel("steady-state attitude error [deg] (max, last window)")
    ax.set_title("Seed 003 vehicle, PWPF designs (labels: U_on)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    dest.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(dest, dpi=PLOT_DPI, bbox_inches="tight")
    plt.close(fig)


def main(argv: list[str]) -> None:
    """Run the grid and print the JSON report."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--scenario", type=Path, default=DEFAULT_SCENARIO)
    p.add_argument("--u-on", type=float, nargs="+", default=DEFAULT_U_ON,
                   help="Schmitt on-thresholds U_on (filter-output units)")
    p.add_argument("--hysteresis", type=float, nargs="+", default=DEFAULT_HYSTERESIS,
                   help="hysteresis widths h = U_on - U_off")
    p.add_argument("--plot", type=Path, help="write the trade plot (PNG) here")
    args = p.parse_args(argv[1:])
    work = Path(tempfile.mkdtemp(prefix="pwpf-trade-"))
    try:
        rows = []
        for h in args.hysteresis:
            for u_on in args.u_on:
                if u_on - h < 0.0:  # the flight software refuses U_off < 0
                    continue
                rows.append(run_design(args.scenario, u_on, h, work))
                print(f"U_on {u_on:g}, h {h:g}: {rows[-1]}", file=sys.stderr, flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    if args.plot is not None:
        plot(rows, args.plot)
    print(json.dumps({"scenario": str(args.scenario), "designs": rows}, indent=2))


if __name__ == "__main__":
    main(sys.argv)
