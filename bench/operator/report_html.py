"""The one-page report of a run: ``report.html``, self-contained (no network, no script).

In: a run folder's summary.json, events.jsonl, the figures' PNGs and the placement of
their time axes that :func:`bench.operator.plots.plot_run` writes beside them
(``NAME.axes.json``, read here and then removed). Out: ``report.html`` beside them: the
verdict and every abnormal line; the scenario, mode, seed, bus and the versions of the
software; the expectations (value, bound, requirement ID, pass/fail); the attitude, rate
and firing-raster figures (the PNGs, inline as data: URIs) with every event of
events.jsonl marked on their time axes: the figure draws a dotted line and the event's
number, and the page lays a marker over it (``id="FIGURE-event-N"``, its title the event)
placed from the axis placement; the events in a table, numbered alike; the pointing,
position and propellant figures; frame counts and rejects per message; latency and the
lockstep cycle split; the faults and FDIR. A run drawn with ``--no-plots`` gets the
report without its figures.

:func:`campaign_html` is a campaign's page: its figure and one row per case, linking each
case's report.html by a relative path. Everything from the files is escaped
(html.escape); styles are inline. Opens from a mail
attachment: nothing is fetched.
"""

from __future__ import annotations

import base64
import html
import json
import platform
from importlib import metadata
from pathlib import Path
from typing import Any

AXES_SUFFIX = ".axes.json"  # bench.operator.plots.AXES_SUFFIX (no matplotlib import here)
FIGURES = (("attitude_error", "Attitude error"), ("rates", "Body rates"),
           ("thruster_raster", "Thruster firing raster"))
VERSIONED = ("thruster-hil", "python-can", "cantools", "numpy", "scipy", "matplotlib")
STYLE = ("body{font-family:sans-serif;max-width:60em;margin:1em auto;color:#222}"
         "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #bbb;"
         "padding:2px 6px;text-align:left;font-size:90%}.pass{color:#060}.fail{color:#a00;"
         "font-weight:bold}.abn{color:#a00}svg{max-width:100%;height:auto}")


def read_events(run_dir: Path) -> list[dict[str, Any]]:
    """The events of ``run_dir``'s events.jsonl (a line cut by a kill is skipped)."""
    path = run_dir / "events.jsonl"
    out = []
    if path.exists():
        for line in path.read_text(encoding="utf-8").splitlines():
            try:
                ev = json.loads(line)
            except ValueError:
                continue
            if isinstance(ev, dict):
                out.append(ev)
    return out


def event_marks(events: list[dict[str, Any]]) -> list[tuple[float, str]]:
    """(time [s], name) of each event, numbered by position: what the figures mark."""
    return [(float(ev.get("t_s", 0.0)), str(ev.get("event", "?"))) for ev in events]


def _e(x: Any) -> str:
    return html.escape("n/a" if x is None else str(x))


def html_table(head: list[str], rows: list[list[Any]]) -> str:
    out = ["<table><tr>" + "".join(f"<th>{_e(h)}</th>" for h in head) + "</tr>"]
    out += ["<tr>" + "".join(f"<td>{c if isinstance(c, Raw) else _e(c)}</td>" for c in r)
            + "</tr>" for r in rows]
    return "".join(out) + "</table>"


class Raw(str):
    """Markup made here (already escaped): put into a table cell as it is."""


def _versions() -> list[list[Any]]:
    rows: list[list[Any]] = [["python", platform.python_version()]]
    for name in VERSIONED:
        try:
            rows.append([name, metadata.version(name)])
        except metadata.PackageNotFoundError:
            rows.append([name, "not installed"])
    return rows


def report_html(s: dict[str, Any], events: list[dict[str, Any]], figures: dict[str, str],
                run_dir: Path) -> str:
    """The page (module docstring). ``figures``: name -> inline SVG markup."""
    verdict = str(s.get("verdict", "n/a"))
    cls = "pass" if verdict == "PASS" else "fail"
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{_e(s.get('scenario'))}"
             f" - {_e(verdict)}</title><style>{STYLE}</style></head><body>",
             f"<h1>{_e(s.get('scenario'))}: <span class='{cls}'>{_e(verdict)}</span></h1>"]
    abnormal = s.get("abnormal") or []
    parts.append("<ul>" + "".join(f"<li class='abn'>ABNORMAL {_e(a)}</li>" for a in abnormal)
                 + "</ul>" if abnormal else "<p>nothing abnormal</p>")
    run_rows: list[list[Any]] = [
        ["scenario file", s.get("scenario_file")], ["mode", s.get("mode")],
        ["seed", s.get("seed")], ["bus", s.get("bus")], ["ended", s.get("ended")],
        ["simulated [s]", s.get("sim_time_s")], ["wall [s]", s.get("wall_time_s")],
        ["real-time factor", s.get("realtime_factor")], ["run folder", str(run_dir)],
    ]
    parts.append(html_table(["run", ""], run_rows + _versions()))
    reqs = s.get("requirements") or {}
    rows: list[list[Any]] = [["converged", s.get("final_attitude_error_deg"),
                              s.get("settling_band_deg"), reqs.get("converged"),
                              Raw(_verdict_cell(bool(s.get("converged"))))]]
    rows += [[e["name"], e.get("value"), e.get("max"), e.get("req"),
              Raw(_verdict_cell(bool(e.get("pass"))))] for e in s.get("expectations") or []]
    parts += ["<h2>Expectations</h2>",
              html_table(["check", "value", "bound", "requirement", ""], rows)]
    parts += ["<h2>Figures</h2>"]
    parts += [f"<h3>{_e(title)}</h3>{figures[name]}" for name, title in FIGURES
              if name in figures] or ["<p>no figures (the run was drawn with --no-plots: "
                                      "thruster-hil report RUN_DIR draws them)</p>"]
    parts += ["<h2>Events</h2><p>numbered as the figures mark them</p>", html_table(
        ["#", "t [s]", "event", "details"],
        [[i, ev.get("t_s"), ev.get("event"),
          ", ".join(f"{k}={v}" for k, v in ev.items() if k not in ("event", "t_s"))]
         for i, ev in enumerate(events)])]
    parts += ["<h2>Pointing, position, propellant</h2>", html_table(["figure", "value"], [
        [k, s.get(k)] for k in ("settling_time_s", "steady_state_attitude_error_deg",
                                "steady_state_rate_error_deg_s", "final_attitude_error_deg",
                                "final_position_error_m", "steady_state_position_error_m",
                                "propellant_kg", "net_translation", "valve_openings")])]
    frames = s.get("frames") or {}
    parts += ["<h2>Frames</h2>", html_table(["message", "counts"], [
        [name, ", ".join(f"{k}={v}" for k, v in (row or {}).items())]
        for name, row in frames.items()])]
    parts += ["<h2>Timing</h2>", html_table(["measure", "value"], [
        ["latency sensor->command [us]", (s.get("latency_us") or {}).get("sensor_to_command")],
        ["lockstep cycle wall [us]", s.get("lockstep_wall_us")],
        ["deadline misses", s.get("deadline_misses")],
        ["bus overrun drops", s.get("bus_overrun_drops")]])]
    parts += ["<h2>Faults and FDIR</h2>", html_table(["", "value"], [
        ["faults", s.get("faults")], ["fault effects", s.get("fault_effects")],
        ["fdir", s.get("fdir")], ["mode changes", s.get("fsw_mode_changes")]])]
    warnings = s.get("warnings") or []
    if warnings:
        parts.append("<h2>Warnings</h2><ul>" + "".join(f"<li>{_e(w)}</li>" for w in warnings)
                     + "</ul>")
    parts.append("</body></html>\n")
    return "".join(parts)


def figure_html(name: str, png: bytes, axes: dict[str, Any],
                events: list[dict[str, Any]]) -> str:
    """A PNG inline, each event's marker laid over its time axis (module docstring)."""
    (t0, t1), (x0, x1), (y0, y1) = axes["xlim"], axes["x_frac"], axes["y_frac"]
    marks = []
    for i, ev in enumerate(events):
        t = float(ev.get("t_s", 0.0))
        if not t0 <= t <= t1 or t1 <= t0:
            continue
        left = 100.0 * (x0 + (t - t0) / (t1 - t0) * (x1 - x0))
        marks.append(f"<div id='{name}-event-{i}' class='event-{i}' title='{i}: "
                     f"{_e(ev.get('event'))} at {t:g} s' style='position:absolute;"
                     f"left:{left:.3f}%;top:{100.0 * (1.0 - y1):.3f}%;height:"
                     f"{100.0 * (y1 - y0):.3f}%;border-left:2px solid rgba(170,0,0,.35)'>"
                     "</div>")
    data = base64.b64encode(png).decode("ascii")
    return (f"<div style='position:relative'><img alt='{_e(name)}' style='width:100%' "
            f"src='data:image/png;base64,{data}'>{''.join(marks)}</div>")


def _verdict_cell(ok: bool) -> str:
    return "<span class='pass'>PASS</span>" if ok else "<span class='fail'>FAIL</span>"


def write_report(run_dir: Path) -> Path | None:
    """``run_dir/report.html`` from its files (module docstring); None without a summary.
    The figures' SVG files are inlined and removed."""
    path = run_dir / "summary.json"
    try:
        s = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(s, dict):
        return None
    events = read_events(run_dir)
    figures = {}
    for name, _ in FIGURES:
        png, placement = run_dir / f"{name}.png", run_dir / f"{name}{AXES_SUFFIX}"
        if png.exists() and placement.exists():
            axes = json.loads(placement.read_text(encoding="utf-8"))
            figures[name] = figure_html(name, png.read_bytes(), axes, events)
        placement.unlink(missing_ok=True)
    out = run_dir / "report.html"
    out.write_text(report_html(s, events, figures, run_dir), encoding="utf-8")
    return out


def campaign_html(rows: list[dict[str, Any]], columns: list[str], png: bytes | None,
                  out: Path) -> str:
    """A campaign's page: its figure inline and one row per case, each linking the case's
    report.html by a path relative to the campaign folder ``out`` (the folder can move)."""
    cells = []
    for r in rows:
        run_dir = Path(str(r["run_dir"]))
        try:
            href = (run_dir / "report.html").relative_to(out).as_posix()
        except ValueError:
            href = (run_dir / "report.html").as_posix()
        link = Raw(f"<a href='{html.escape(href, quote=True)}'>report</a>")
        cells.append([r.get(c) for c in columns if c != "run_dir"] + [link])
    figure = ("" if png is None else "<img alt='campaign' style='width:100%' src='data:image/"
              f"png;base64,{base64.b64encode(png).decode('ascii')}'>")
    failed = sum(1 for r in rows if not r.get("expectations_met"))
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>campaign</title>"
            f"<style>{STYLE}</style></head><body><h1>Campaign: {len(rows)} cases, "
            f"{failed} not meeting their expectations</h1>{figure}"
            + html_table([c for c in columns if c != "run_dir"] + ["case"], cells)
            + "</body></html>\n")
