"""PNG plots of a run folder: attitude error, body rates, thruster firing raster, latency.

In: ``telemetry.csv`` and ``valve_pulses.csv`` of a run folder. Out: ``attitude_error.png``,
``rates.png``, ``thruster_raster.png`` in the same folder. Matplotlib's Agg backend (no
display needed). Reads files only, so ``thruster-hil report RUN_DIR`` can redraw any run.

Memory: the files are read line by line and only the plotted columns are kept, packed
(8 bytes a value: a 2 h run's 720 000 telemetry rows are 5.8 MB a column); a series longer
than :data:`MAX_PLOT_POINTS` is drawn as the minimum and maximum of each of that many
buckets (an envelope: every spike stays visible, the picture is the same at 880 pixels),
so a long run's plots cost what a short one's do.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import traceback
from array import array
from collections.abc import Callable, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from bench.operator.lifecycle import STOP_SIGNALS, exit_now
from bench.results.record import read_lines, run_file
from transport.lockstep import available_cpus

RAD_DEG = 180.0 / np.pi
DPI = 110
# Titles sit at the top of the axes (nothing is drawn above it but the event numbers).
# Given explicitly, matplotlib skips placing them around top tick labels, which cost
# ~0.05 s a figure in layout and changed no pixel (same PNG bytes).
TITLE_Y = 1.0
ERROR_FLOOR_DEG = 1e-4
# Points of a line plot at most: 2000 buckets, each drawn as its minimum and maximum
MAX_PLOT_POINTS = 4000
TELEMETRY_COLUMNS = ("t_s", "att_err_deg", "fsw_est_err_deg", "wx_rad_s", "wy_rad_s",
                     "wz_rad_s")
PULSE_COLUMNS = ("thruster", "t_on_s", "t_off_s")
FLOAT64 = "d"
# Fixed margins [in] (left, right, top, bottom): room for the tick labels, the axis labels
# and the title. Measuring the text instead (tight_layout) cost ~40 % of the drawing time.
MARGINS_IN = (0.8, 0.2, 0.4, 0.55)
AXES_SUFFIX = ".axes.json"  # beside a PNG: where its time axis lies (report.html)
MAX_MARKED_EVENTS = 200  # events marked on a figure at most (report.html lists them all)


def _fixed_margins(fig: plt.Figure) -> None:
    """Place the axes with :data:`MARGINS_IN` around them, whatever the figure's size."""
    w, h = fig.get_size_inches()
    left, right, top, bottom = MARGINS_IN
    fig.subplots_adjust(left=left / w, right=1.0 - right / w, top=1.0 - top / h,
                        bottom=bottom / h)


def _read_columns(path: Path, wanted: tuple[str, ...]) -> tuple[list[str], dict[str, np.ndarray]]:
    """The header of a CSV and its ``wanted`` columns (those it has), read line by line; a
    line cut short (a killed run's last) or not numeric is skipped. ({} if no file.)"""
    if not path.exists():  # a run refused or killed before its first row
        return [], {}
    lines = read_lines(path)
    head = next(lines, "").rstrip("\n").split(",")
    index = {c: head.index(c) for c in wanted if c in head}
    cols: dict[str, array[float]] = {c: array(FLOAT64) for c in index}
    for line in lines:
        parts = line.rstrip("\n").split(",")
        if len(parts) != len(head):
            continue
        try:
            values = [float(parts[i]) for i in index.values()]
        except ValueError:
            continue
        for col, v in zip(cols.values(), values, strict=True):
            col.append(v)
    return head, {c: np.frombuffer(a, dtype=float) if len(a) else np.zeros(0)
                  for c, a in cols.items()}


def envelope(t: np.ndarray, y: np.ndarray,
             max_points: int = MAX_PLOT_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """``(t, y)`` itself when short; else per bucket of consecutive samples its minimum and
    maximum, in time order, at the bucket's first and last time (``max_points`` at most)."""
    n = len(t)
    if n <= max_points:
        return t, y
    buckets = max_points // 2
    size = -(-n // buckets)  # samples per bucket, rounded up
    pad = buckets * size - n
    yp = np.concatenate([y, np.full(pad, y[-1])]).reshape(buckets, size)
    tp = np.concatenate([t, np.full(pad, t[-1])]).reshape(buckets, size)
    lo, hi = np.argmin(yp, axis=1), np.argmax(yp, axis=1)
    first = np.minimum(lo, hi)
    second = np.maximum(lo, hi)
    rows = np.arange(buckets)
    t_out = np.column_stack([tp[rows, first], tp[rows, second]]).ravel()
    y_out = np.column_stack([yp[rows, first], yp[rows, second]]).ravel()
    return t_out, y_out


def plot_run(run_dir: Path, band_deg: float | None = None,
             events: Sequence[tuple[float, str]] = ()) -> list[Path]:
    """Draw every plot of ``run_dir``; returns the written paths.

    The figures are drawn by :func:`draw_each`: with more than one CPU, at the same time
    (drawing is ~0.1 s a figure, most of it tick and text layout). ``events`` (time [s],
    name) are marked on every time axis: a dotted line and the event's number (the first
    :data:`MAX_MARKED_EVENTS`). Beside each PNG, ``NAME.axes.json`` says where its time
    axis lies in the picture (figure fractions and limits), for report.html's overlay.
    """
    head, tel = _read_columns(run_file(run_dir, "telemetry.csv"), TELEMETRY_COLUMNS)
    if not tel or len(tel["t_s"]) == 0:
        return []
    n_thr = sum(1 for k in head if k.startswith("thrust_T"))
    marks = list(events)[:MAX_MARKED_EVENTS]
    figures: list[tuple[Path, Callable[[Path], None]]] = [
        (run_dir / "attitude_error.png",
         lambda p: _save(_attitude_error(tel, band_deg), p, marks)),
        (run_dir / "rates.png", lambda p: _save(_rates(tel), p, marks)),
    ]
    pulses_path = run_file(run_dir, "valve_pulses.csv")
    if pulses_path.exists():  # not at the lean record level: no raster rather than an empty one
        _, pulses = _read_columns(pulses_path, PULSE_COLUMNS)
        figures.append((run_dir / "thruster_raster.png",
                        lambda p: _save(_raster(tel["t_s"], pulses, n_thr), p, marks)))
    return draw_each(figures)


def draw_each(figures: list[tuple[Path, Callable[[Path], None]]]) -> list[Path]:
    """Write each figure's PNG with its drawer; returns the paths.

    With more than one CPU the figures are drawn at the same time, one group per CPU: the
    first figures (list the slowest first) each in a forked child of its own, this process
    drawing the rest in turn (it has matplotlib loaded already, the children share it). On
    two CPUs with three figures that is the slow log-scale one alone and the other two one
    after the other, ~0.1 s sooner than three processes sharing two CPUs. A child that
    fails makes this raise :class:`RuntimeError` naming the figure (its traceback is
    printed)."""
    workers = min(len(figures), available_cpus()) if hasattr(os, "fork") else 1
    if workers < 2:
        for path, draw in figures:
            draw(path)
        return [path for path, _ in figures]
    children: list[tuple[int, Path]] = []
    for path, draw in figures[:workers - 1]:
        pid = os.fork()
        if pid == 0:  # pragma: no cover - the child reports through its exit status
            code = 0
            for s in STOP_SIGNALS:  # a stop reaches the parent, which waits for this figure
                signal.signal(s, signal.SIG_IGN)
            try:
                draw(path)
            except BaseException:
                traceback.print_exc()
                code = 1
            finally:
                exit_now(code, (sys.stderr,))
        children.append((pid, path))
    error: BaseException | None = None
    try:
        for path, draw in figures[workers - 1:]:  # each one, even after one failed
            try:
                draw(path)
            except Exception as exc:
                error = error or exc
    finally:
        failed = [path.name for pid, path in children
                  if os.waitpid(pid, 0)[1] != 0]
    if error is not None:
        raise error
    if failed:
        raise RuntimeError(f"drawing {', '.join(failed)} failed (see the traceback above)")
    return [path for path, _ in figures]


def _attitude_error(tel: dict[str, np.ndarray], band_deg: float | None) -> plt.Figure:
    """Attitude error (truth vs target, estimate vs truth), log scale, with the band."""
    t = tel["t_s"]
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.semilogy(*envelope(t, np.maximum(tel["att_err_deg"], ERROR_FLOOR_DEG)),
                label="truth vs target")
    if "fsw_est_err_deg" in tel:
        ax.semilogy(
            *envelope(t, np.maximum(tel["fsw_est_err_deg"], ERROR_FLOOR_DEG)),
            label="FSW estimate vs truth",
            alpha=0.7,
        )
    if band_deg:
        ax.axhline(band_deg, color="k", ls="--", lw=0.8, label=f"settling band {band_deg} deg")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("attitude error [deg]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    ax.set_title("Attitude error", y=TITLE_Y)
    return fig


def _rates(tel: dict[str, np.ndarray]) -> plt.Figure:
    """Body rates (truth) [deg/s]."""
    t = tel["t_s"]
    fig, ax = plt.subplots(figsize=(8, 4))
    for axis in "xyz":
        ax.plot(*envelope(t, tel[f"w{axis}_rad_s"] * RAD_DEG), label=f"omega_{axis}")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("body rate [deg/s]")
    ax.grid(True, alpha=0.3)
    ax.legend()
    ax.set_title("Body rates (truth)", y=TITLE_Y)
    return fig


def _raster(t: np.ndarray, pulses: dict[str, np.ndarray], n_thr: int) -> plt.Figure:
    """Commanded coil-on intervals per thruster over the run."""
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
    ax.set_title("Thruster firing raster (commanded coil-on intervals)",
                 y=TITLE_Y)
    return fig


def _save(fig: plt.Figure, path: Path, events: Sequence[tuple[float, str]] = ()) -> None:
    """Events marked, fixed margins, the PNG and its axis placement written, figure freed."""
    ax = fig.axes[0]
    xlim = ax.get_xlim()  # the data's limits, before the markers could widen them
    for i, (t_s, _) in enumerate(events):
        ax.axvline(t_s, color="0.35", lw=0.7, ls=":")
        ax.text(t_s, 1.0, str(i), transform=ax.get_xaxis_transform(), fontsize=6,
                ha="center", va="bottom", color="0.35")
    ax.set_xlim(xlim)
    _fixed_margins(fig)
    fig.savefig(path, dpi=DPI)
    box = ax.get_position()
    path.with_suffix(AXES_SUFFIX).write_text(json.dumps({
        "xlim": list(xlim), "x_frac": [box.x0, box.x1], "y_frac": [box.y0, box.y1]}),
        encoding="utf-8")
    plt.close(fig)
