"""A campaign's results as files: the table, the statistics and a one-page report.

Out, in the campaign folder:
- ``campaign.csv``: one row per case: name, seed, status, pass/fail of every requirement,
  every figure, every dispersed value (column ``value:KEY``), the trace digest, its folder.
- ``campaign.json``: the rows and :func:`bench.campaign.stats.statistics`.
- ``campaign.parquet``: the CSV's table as Apache Parquet (where pyarrow is installed: the
  ``[parquet]`` extra), typed columns for pandas, polars or DuckDB.
- ``campaign.html``: pass rates with their 95 % intervals, percentiles, histograms of the
  figures, each figure against its most sensitive dispersed key, the sensitivity table,
  and the worst cases, each linked to its run's folder by a relative path (the campaign
  folder can move).
Figures are drawn with matplotlib (Agg), imported only here.
"""

from __future__ import annotations

import base64
import csv
import html
import io
from pathlib import Path
from typing import Any

from bench.campaign.case_run import METRICS
from bench.campaign.stats import SIGNIFICANCE
from bench.operator.report_html import STYLE, Raw, html_table
from dbc.records import write_record

DPI = 90
HIST_BINS = 20
FIGURE_SIZE_IN = (4.2, 3.0)
SHOWN_SENSITIVITIES = 5
VALUES_SHOWN_CHARS = 300
"""Characters of a worst case's dispersed values in the report's table."""
"""Dispersed keys listed per figure in the sensitivity table (largest |rho| first)."""


def csv_columns(rows: list[dict[str, Any]]) -> list[str]:
    """The CSV's columns for ``rows`` (requirements and values as the rows have them)."""
    reqs: dict[str, None] = {}
    vals: dict[str, None] = {}
    for r in rows:
        reqs.update(dict.fromkeys(r["requirements"]))
        vals.update(dict.fromkeys(r["values"]))
    return (["case", "name", "vehicle", "seed", "status", "failure_kind", "failure_thruster",
             "passed"] + [f"req:{k}" for k in reqs] + list(METRICS)
            + [f"value:{k}" for k in vals]
            + ["trace_sha256", "wall_time_s", "attempts", "error", "run_dir"])


def _flat(r: dict[str, Any]) -> dict[str, Any]:
    f = r.get("failure") or (None, None)
    out = {"case": r["case"], "name": r["name"], "vehicle": r["vehicle"], "seed": r["seed"],
           "status": r["status"], "failure_kind": f[0], "failure_thruster": f[1],
           "passed": r["passed"], "trace_sha256": r["trace_sha256"],
           "wall_time_s": r["wall_time_s"], "attempts": r.get("attempts"),
           "error": r["error"],
           "run_dir": f"cases/{r['name']}/run" if r["status"] == "ok" else None}
    out.update({f"req:{k}": v for k, v in r["requirements"].items()})
    out.update(r["figures"])
    out.update({f"value:{k}": v for k, v in r["values"].items()})
    return out


def write_tables(out: Path, rows: list[dict[str, Any]], stats: dict[str, Any],
                 meta: dict[str, Any]) -> bool:
    """campaign.csv, campaign.json and, where pyarrow is installed (the ``[parquet]``
    extra), campaign.parquet with the CSV's columns; whether the Parquet file was written."""
    columns = csv_columns(rows)
    flat = [_flat(r) for r in rows]
    with open(out / "campaign.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=columns)
        w.writeheader()
        w.writerows(flat)
    write_record(out / "campaign.json", {"campaign": meta, "statistics": stats, "cases": rows})
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return False
    kinds = {"case": pa.int64(), "vehicle": pa.int64(), "seed": pa.uint64(),
             "failure_thruster": pa.int64(), "attempts": pa.int64(), "passed": pa.bool_(),
             "wall_time_s": pa.float64()}
    kinds.update({m: pa.float64() for m in METRICS})
    fields = []
    for c in columns:  # fixed types, so that every campaign's file has the same schema
        kind = kinds.get(c) or (pa.bool_() if c.startswith("req:") else None)
        if kind is None and not c.startswith("value:"):
            kind = pa.string()
        if kind is None:  # a dispersed value: its type, float64 when no case has it
            kind = pa.array([r.get(c) for r in flat]).type
            kind = pa.float64() if pa.types.is_null(kind) else kind
        fields.append(pa.field(c, kind))
    table = pa.Table.from_pylist([{c: r.get(c) for c in columns} for r in flat],
                                 schema=pa.schema(fields))
    pq.write_table(table, out / "campaign.parquet")
    return True


def _png(fig: Any) -> Raw:
    from bench.operator.plots import plt

    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=DPI)
    plt.close(fig)
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return Raw(f"<img alt='figure' src='data:image/png;base64,{data}'>")


def _figures(rows: list[dict[str, Any]], stats: dict[str, Any]) -> list[Raw]:
    from bench.operator.plots import plt

    ok = [r for r in rows if r["status"] == "ok"]
    imgs = []
    for fig_name in stats["percentiles"]:
        xs = [r["figures"][fig_name] for r in ok if r["figures"].get(fig_name) is not None]
        fig, ax = plt.subplots(figsize=FIGURE_SIZE_IN)
        ax.hist(xs, bins=HIST_BINS, color="#4a7ab5")
        ax.set_xlabel(fig_name)
        ax.set_ylabel("cases")
        imgs.append(_png(fig))
        sens = stats["sensitivity"].get(fig_name) or {}
        if sens:
            key, s = next(iter(sens.items()))
            rho = s["rho"]
            pts = [(r["values"][key], r["figures"][fig_name]) for r in ok
                   if key in r["values"] and r["figures"].get(fig_name) is not None]
            fig, ax = plt.subplots(figsize=FIGURE_SIZE_IN)
            colours = ["#060" if r["passed"] else "#a00" for r in ok
                       if key in r["values"] and r["figures"].get(fig_name) is not None]
            ax.scatter([p[0] for p in pts], [p[1] for p in pts], s=8, c=colours)
            ax.set_xlabel(f"{key} (Spearman {rho:+.2f})")
            ax.set_ylabel(fig_name)
            imgs.append(_png(fig))
    return imgs


def _values_text(values: dict[str, Any]) -> str:
    """A case's dispersed values, short (the full list is in campaign.csv)."""
    text = ", ".join(f"{a}={b:.4g}" if isinstance(b, float) else f"{a}={b}"
                     for a, b in values.items())
    return text if len(text) <= VALUES_SHOWN_CHARS else (
        text[:VALUES_SHOWN_CHARS].rsplit(", ", 1)[0] + ", ... (all in campaign.csv)")


def _link(name: str) -> Raw:
    href = html.escape(f"cases/{name}/run/report.html", quote=True)
    return Raw(f"<a href='{href}'>{html.escape(name)}</a>")


def write_html(out: Path, rows: list[dict[str, Any]], stats: dict[str, Any],
               meta: dict[str, Any]) -> Path:
    """campaign.html (module docstring)."""
    pr = stats["pass_rates"]
    rates = [[k, v["passes"], v["cases"], "n/a" if v["rate"] is None else f"{v['rate']:.3f}",
              f"[{v['ci_low']:.3f}, {v['ci_high']:.3f}]"] for k, v in pr.items()]
    pct = [[k, *(f"{v[f'p{p}']:.4g}" for p in (5, 50, 95, 99)), f"{v['max']:.4g}", v["n"],
            v["missing"] or ""] for k, v in stats["percentiles"].items()]
    sens = [[k, ", ".join(f"{key} {s['rho']:+.2f} (p {s['p']:.2g})" for key, s in
                          list(v.items())[:SHOWN_SENSITIVITIES]) or "none"]
            for k, v in stats["sensitivity"].items()]
    worst = [[k, _link(w["name"]), "never" if w["value"] is None else f"{w['value']:.4g}",
              w["seed"], _values_text(w["values"])]
             for k, ws in stats["worst"].items() for w in ws]
    errors = [[r["name"], r["status"], r["error"]] for r in rows if r["status"] != "ok"]
    imgs = "".join(_figures(rows, stats))
    body = (
        f"<h1>Campaign {html.escape(str(meta['name']))}: {stats['completed']} of "
        f"{stats['cases']} cases completed, pass rate "
        f"{pr['passed']['passes']}/{pr['passed']['cases']}</h1>"
        f"<p>Scenario {html.escape(str(meta['scenario']))}, study "
        f"{html.escape(str(meta['study']))}, seed {meta['seed']}; wall time "
        f"{meta.get('wall_time_s', 0):.1f} s, {meta.get('cases_per_min', 0):.1f} cases/min.</p>"
        "<h2>Requirements (95 % Wilson interval)</h2>"
        + html_table(["requirement", "passed", "cases", "rate", "95 % interval"], rates)
        + "<h2>Figures</h2>"
        + html_table(["figure", "p5", "p50", "p95", "p99", "max", "cases",
                      "never reached"], pct)
        + f"<div>{imgs}</div><h2>Sensitivity (Spearman rank correlation)</h2><p>With few "
        "cases and many dispersed keys some correlations are large by chance: read those "
        f"with p above {SIGNIFICANCE:g} as noise.</p>"
        + html_table(["figure", "most sensitive dispersed keys"], sens)
        + "<h2>Worst cases</h2>"
        + html_table(["figure", "case", "value", "seed", "dispersed values"], worst)
        + ("<h2>Cases that did not complete</h2>"
           + html_table(["case", "status", "why"], errors) if errors else ""))
    path = out / "campaign.html"
    path.write_text("<!DOCTYPE html><html><head><meta charset='utf-8'><title>campaign"
                    f"</title><style>{STYLE}</style></head><body>{body}</body></html>\n",
                    encoding="utf-8")
    return path
