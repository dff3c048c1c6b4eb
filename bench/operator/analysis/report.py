"""Presentation of :class:`~bench.operator.analysis.timing.RunTiming`: table, JSON, histograms.

In: a :class:`RunTiming`. Out: the per-message table with chain and bus-load lines
(:func:`format_report`), ``timing.json`` (:func:`write_json`) and two PNG files
(:func:`write_histograms`): ``latency_hist.png`` (``t_rx - t_ready`` per message, in µs,
with the worst-case bound as a dashed line) and ``chain_age_hist.png`` (age of the IMU
data at the command's reception and at the first valve opening, in µs). Matplotlib's Agg
backend; no display needed. Times in the table: periods in ms, everything else in µs.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from bench.operator.analysis.records import US_PER_S, LoadFigures, MessageTiming, Percentiles
from bench.operator.analysis.timing import RunTiming
from dbc.records import write_record

TIMING_JSON = "timing.json"
LATENCY_PNG = "latency_hist.png"
CHAIN_PNG = "chain_age_hist.png"
DPI = 110
HIST_BINS = 50
HIST_COLUMNS = 3
SUBPLOT_W_IN, SUBPLOT_H_IN = 4.0, 2.6
KBIT = 1000
MISSING = "-"

COLUMNS = (
    ("message", 12, "<"),
    ("sender", 8, "<"),
    ("count", 6, ">"),
    ("period_ms", 9, ">"),
    ("jit_std_us", 10, ">"),
    ("jit_pp_us", 9, ">"),
    ("lat_p50_us", 10, ">"),
    ("lat_p99_us", 10, ">"),
    ("lat_max_us", 10, ">"),
    ("bound_us", 8, ">"),
    ("missed", 6, ">"),
    ("viol_abs/rel", 12, ">"),
    ("flag", 4, "<"),
)
FLAG_TEXT = "OVER"


def _num(value: float | None, digits: int = 1) -> str:
    if value is None or not math.isfinite(value):
        return MISSING
    return f"{value:.{digits}f}"


def _count(value: int | None) -> str:
    return MISSING if value is None else str(value)


def _row(m: MessageTiming) -> list[str]:
    lat = m.latency
    return [
        m.name,
        m.sender,
        str(m.count),
        _num(m.period_mean_ms, 3),
        _num(m.jitter_std_us),
        _num(m.jitter_pp_us),
        _num(lat.p50_us),
        _num(lat.p99_us),
        _num(lat.max_us),
        _num(m.bound_us, 0),
        str(m.missed_cycles),
        f"{_count(m.cycle_violations_abs)}/{_count(m.cycle_violations_rel)}",
        FLAG_TEXT if m.above_bound else "",
    ]


def _fmt_row(cells: list[str]) -> str:
    return "  ".join(
        f"{c:{align}{width}}" for c, (_, width, align) in zip(cells, COLUMNS, strict=True)
    ).rstrip()


def _pct(p: Percentiles) -> str:
    return f"p50 {_num(p.p50_us)} / p99 {_num(p.p99_us)} / max {_num(p.max_us)} us (n={p.n})"


def _load(f: LoadFigures) -> str:
    return f"mean {_num(f.mean_pct)} %, peak {_num(f.peak_pct)} %"


def format_report(rt: RunTiming) -> str:
    """The per-message table, then the chain and bus-load lines, flags and notes."""
    o = rt.options
    lines = [
        f"timing | mode {rt.mode} | bitrate {rt.bitrate_bps // KBIT} kbit/s"
        + (f" | {rt.run_dir}" if rt.run_dir is not None else ""),
        _fmt_row([c[0] for c in COLUMNS]),
    ]
    lines += [_fmt_row(_row(m)) for m in rt.messages.values()]
    abs_tol = "off" if o.cycle_abs_tolerance_ms is None else f"±{o.cycle_abs_tolerance_ms:g} ms"
    rel_tol = "off" if o.cycle_rel_tolerance_pct is None else f"±{o.cycle_rel_tolerance_pct:g} %"
    lines.append(
        f"cycle-time windows: absolute {abs_tol}, relative {rel_tol} of GenMsgCycleTime; "
        f"bound = worst-case response time (Davis et al. 2007)"
    )
    ch = rt.chain()
    if ch.cycles:
        lines.append(f"chain IMU->command      {_pct(ch.imu_to_command)}")
        lines.append(f"chain command->valve    {_pct(ch.command_to_valve)}")
        lines.append(
            f"chain IMU->valve (age)  {_pct(ch.imu_to_valve)}; "
            f"{ch.cycles} cycles, {ch.cycles_without_valve} without a valve opening"
        )
    load = rt.bus_load()
    per_node = " | ".join(f"{n} {_load(f)}" for n, f in load.per_node.items())
    lines.append(
        f"bus load ({load.window_ms:g} ms windows, n={load.n_windows}): {_load(load.total)}"
        + (f" at {load.total.peak_window_start_s:.3f} s" if load.n_windows else "")
        + (f" | {per_node}" if per_node else "")
    )
    unheard = rt.unheard()
    if unheard:
        lines.append("FLAG: sent but never received: " + ", ".join(
            f"{n} ({rt.sent[n]} frames sent)" for n in unheard))
    flagged = rt.flagged()
    if flagged:
        what = (
            "a bug in the bus model or in the analysis"
            if rt.mode == "lockstep"
            else "the host transport was slower than an ideal bus"
        )
        lines.append(
            f"FLAG: measured maximum latency above the worst-case bound: "
            f"{', '.join(flagged)} ({what})"
        )
    if rt.mode != "lockstep":
        unknown = (
            "the flight software logged no reception of that message (fsw_rx.csv)"
            if rt.mode == "realtime"
            else "latency needs the sender's time, which hilbus carries and SocketCAN does not"
        )
        lines.append(
            f"note: {rt.mode} latencies are measured on the host (transport and scheduling "
            f"included); '-': {unknown}"
        )
    return "\n".join(lines)


def write_json(rt: RunTiming, out_dir: Path) -> Path:
    """``timing.json`` with :meth:`RunTiming.to_dict` in ``out_dir``; returns its path."""
    path = out_dir / TIMING_JSON
    write_record(path, rt.to_dict())
    return path


def write_histograms(rt: RunTiming, out_dir: Path) -> list[Path]:
    """Latency histograms per message and the chain-age histogram; returns written paths.

    A file is written only when it has samples to show.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out: list[Path] = []
    lat = {n: rt.message_latency_s(n) * US_PER_S for n in rt.messages}
    lat = {n: a for n, a in lat.items() if a.size}
    if lat:
        rows = math.ceil(len(lat) / HIST_COLUMNS)
        cols = min(HIST_COLUMNS, len(lat))
        fig, axes = plt.subplots(
            rows, cols, figsize=(SUBPLOT_W_IN * cols, SUBPLOT_H_IN * rows), squeeze=False
        )
        for ax, (name, a) in zip(axes.flat, lat.items(), strict=False):
            b = rt.messages[name].bound_us
            bound = float(b) if b is not None and math.isfinite(b) else None
            # bins over the whole axis (0 .. the bound): a narrow spread far below its bound
            # stays visible as a bar instead of slivers a fraction of a pixel wide
            hi = max(float(a.max()), 0.0 if bound is None else bound)
            lo = min(float(a.min()), 0.0)
            ax.hist(a, bins=np.linspace(lo, hi, HIST_BINS + 1) if hi > lo else HIST_BINS,
                    color="C0")
            if bound is not None:
                ax.axvline(bound, color="C3", ls="--", lw=1, label=f"bound {bound:.0f} us")
                ax.legend(fontsize="small")
            ax.set_title(f"{name} (n={a.size})", fontsize="medium")
            ax.set_xlabel("t_rx - t_ready [us]")
        for ax in list(axes.flat)[len(lat) :]:
            ax.set_visible(False)
        fig.suptitle(f"Frame latency per message ({rt.mode})")
        fig.tight_layout()
        out.append(out_dir / LATENCY_PNG)
        fig.savefig(out[-1], dpi=DPI)
        plt.close(fig)
    if rt.chains is not None and len(rt.chains):
        c = rt.chains
        to_cmd = (c.t_cmd_rx_s - c.t_imu_tx_s) * US_PER_S
        to_valve = rt.chain_age_s() * US_PER_S
        fig, ax = plt.subplots(figsize=(8, 4))
        for a, label, color in (
            (to_cmd, "IMU sample -> last command received", "C0"),
            (to_valve, "IMU sample -> first valve opening", "C1"),
        ):
            a = a[np.isfinite(a)]
            if a.size:
                ax.hist(a, bins=HIST_BINS, alpha=0.7, color=color, label=f"{label} (n={a.size})")
        ax.set_xlabel("age of the IMU data [us]")
        ax.set_ylabel("cycles")
        ax.set_title(f"End-to-end chain IMU -> command -> valve ({rt.mode})")
        ax.legend()
        ax.grid(True, alpha=0.3)
        fig.tight_layout()
        out.append(out_dir / CHAIN_PNG)
        fig.savefig(out[-1], dpi=DPI)
        plt.close(fig)
    return out
