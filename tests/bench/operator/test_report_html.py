"""report.html: self-contained, every event numbered and marked on each figure's time axis."""

from __future__ import annotations

import base64
import json
import re
from html.parser import HTMLParser
from pathlib import Path

from bench.operator.plots import AXES_SUFFIX, MAX_PLOT_POINTS, plot_run
from bench.operator.report_html import FIGURES, event_marks, read_events, write_report
from tests.bench.operator.run_telemetry import write_telemetry

EVENTS = [
    {"event": "run_started", "mode": "lockstep", "t_s": 0.0},
    {"event": "fault_injected", "kind": "stuck_open", "thruster": 2, "t_s": 5.0},
    {"event": "fsw_mode", "mode": "SAFE", "note": "<b>&'\"", "t_s": 7.5},
]


class _Page(HTMLParser):
    """Ids, image sources and links of a page."""

    def __init__(self) -> None:
        super().__init__()
        self.ids: set[str] = set()
        self.srcs: list[str] = []
        self.links: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(str(a["id"]))
        if tag in ("img", "script") and a.get("src"):
            self.srcs.append(str(a["src"]))
        if a.get("href"):
            self.links.append(str(a["href"]))


def _run_folder(tmp_path: Path) -> Path:
    write_telemetry(tmp_path, 2, 2 * MAX_PLOT_POINTS)
    (tmp_path / "valve_pulses.csv").write_text("thruster,t_on_s,t_off_s\n1,0.5,0.6\n")
    (tmp_path / "events.jsonl").write_text("".join(json.dumps(e) + "\n" for e in EVENTS))
    (tmp_path / "summary.json").write_text(json.dumps({
        "scenario": "q", "verdict": "FAIL: converged", "abnormal": ["SAFE at 7.5 s"],
        "converged": False, "expectations": [{"name": "settling_time_s", "value": None,
                                              "max": 10.0, "pass": False, "req": "R-1"}]}))
    return tmp_path


def test_every_event_is_marked_on_every_figure_and_listed(tmp_path: Path) -> None:
    """Markers FIGURE-event-N for each event and figure; the events table escapes their
    text; the axis placement files are gone."""
    run = _run_folder(tmp_path)
    plot_run(run, 0.5, event_marks(read_events(run)))
    text = write_report(run).read_text(encoding="utf-8")  # type: ignore[union-attr]
    page = _Page()
    page.feed(text)
    for name, _ in FIGURES:
        for i in range(len(EVENTS)):
            assert f"{name}-event-{i}" in page.ids, (name, i)
    assert "&lt;b&gt;&amp;" in text and "<b>&" not in text
    assert "R-1" in text and "ABNORMAL SAFE at 7.5 s" in text
    assert not list(run.glob("*" + AXES_SUFFIX))


def test_the_page_fetches_nothing(tmp_path: Path) -> None:
    """No script, no link, every image a data: URI holding the figure's PNG bytes."""
    run = _run_folder(tmp_path)
    plot_run(run, 0.5, event_marks(read_events(run)))
    text = write_report(run).read_text(encoding="utf-8")  # type: ignore[union-attr]
    page = _Page()
    page.feed(text)
    assert "<script" not in text and page.links == []
    assert len(page.srcs) == len(FIGURES)
    for src, (name, _) in zip(page.srcs, FIGURES, strict=True):
        head, data = src.split(",", 1)
        assert head == "data:image/png;base64"
        assert base64.b64decode(data) == (run / f"{name}.png").read_bytes()
    assert not re.search(r"(src|href)=['\"]https?:", text)


def test_without_figures_the_report_says_so(tmp_path: Path) -> None:
    """--no-plots: the report has its tables and says how to draw the figures."""
    run = _run_folder(tmp_path)
    text = write_report(run).read_text(encoding="utf-8")  # type: ignore[union-attr]
    assert "no figures" in text and "thruster-hil report RUN_DIR" in text
    assert "fault_injected" in text


def test_campaign_page_links_each_case_relative_to_its_folder(tmp_path: Path) -> None:
    """One row and one relative link per case; text escaped; the figure inline."""
    from bench.operator.report_html import campaign_html

    rows = [{"thruster": k, "kind": "stuck_open", "expectations_met": k != 1,
             "run_dir": str(tmp_path / f"stuck_open_T{k:02d}" / "run")} for k in range(3)]
    page = campaign_html(rows, ["thruster", "kind", "expectations_met", "run_dir"], b"png",
                         tmp_path)
    assert re.findall(r"href='([^']+)'", page) == [
        f"stuck_open_T{k:02d}/run/report.html" for k in range(3)]
    assert "3 cases, 1 not meeting" in page and "data:image/png;base64," in page
