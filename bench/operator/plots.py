"""PNG plots of a run folder: attitude error, body rates, thruster firing raster, latency.

In: ``telemetry.csv`` and ``valve_pulses.csv`` of a run folder. Out: ``attitude_error.png``,
``rates.png``, ``thruster_raster.png`` in the same folder. Matplotlib's Agg backend (no
display needed). Reads files only, so ``thruster-hil report RUN_DIR`` can redraw any run.
"""

from __future__ import annotations

import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

RAD_DEG = 180.0 / np.pi
DPI = 110
ERROR_FLOOR_DEG = 1e-4


def _read_csv(path: Path) -> dict[str, np.ndarray]:
    if not path.exists():  # a run refused or killed before its first row
        return {}
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    if not rows:
        return {}
    head, body = rows[0], rows[1:]
    data = (
        np.array([[float(x) for x in r] for r in body], dtype=float)
        if body
        else np.zeros((0, len(head)))
    )
    return {h: data[:, i] for i, h in enumerate(head)}


def plot_run(run_dir: Path, band_deg: float | None = None) -> list[Path]:
    """Draw every plot of ``run_dir``; returns the written paths."""
    tel = _read_csv(run_dir / "telemetry.csv")
    out: list[Path] = []
    if not tel or len(tel["t_s"]) == 0:
        return out
    t = tel["t_s"]

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.semilogy(t, np.maximum(tel["att_err_deg"], ERROR_FLOOR_DEG), label="truth vs target")
    if "fsw_est_err_deg" in tel:
        ax.semilogy(
            t,
            np.maximum(tel["fsw_est_err_deg"], ERROR_FLOOR_DEG),
            label="FSW estimate vs truth",
            alpha=0.7,
        )
    if band_deg:
        ax.axhline(band_deg, color="k", ls="--", lw=0.8, label=f"settling band {band_deg} deg")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("attitude error [deg]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    ax.set_title("Attitude error")
    out.append(run_dir / "attitude_error.png")
    fig.tight_layout()
    fig.savefig(out[-1], dpi=DPI)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(8, 4))
    for axis in "xyz":
        ax.plot(t, tel[f"w{axis}_rad_s"] * RAD_DEG, label=f"omega_{axis}")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("body rate [deg/s]")
    ax.grid(True, alpha=0.3)
    ax.legend()
    ax.set_title("Body rates (truth)")
    out.append(run_dir / "rates.png")
    fig.tight_layout()
    fig.savefig(out[-1], dpi=DPI)
    plt.close(fig)

    n_thr = sum(1 for k in tel if k.startswith("thrust_T"))
    pulses = (
        _read_csv(run_dir / "valve_pulses.csv") if (run_dir / "valve_pulses.csv").exists() else {}
    )
    fig, ax = plt.subplots(figsize=(8, 0.35 * max(n_thr, 4) + 1.2))
    if pulses and len(pulses.get("t_on_s", [])):
        for k in range(n_thr):
            sel = pulses["thruster"] == k
            on, off = pulses["t_on_s"][sel], pulses["t_off_s"][sel]
            ax.broken_barh(list(zip(on, off - on, strict=True)), (k - 0.4, 0.8), color="C0")
    ax.set_yticks(range(n_thr))
    ax.set_yticklabels([f"T{k}" for k in range(n_thr)])
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time [s]")
    ax.set_title("Thruster firing raster (commanded coil-on intervals)")
    out.append(run_dir / "thruster_raster.png")
    fig.tight_layout()
    fig.savefig(out[-1], dpi=DPI)
    plt.close(fig)
    return out
