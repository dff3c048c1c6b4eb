"""Run plots: the min/max envelope of long series, streamed column reading, PNGs drawn."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bench.operator.plots import MAX_PLOT_POINTS, _read_columns, envelope, plot_run
from tests.bench.operator.run_telemetry import write_telemetry

N_THRUSTERS = 4


def test_short_series_are_drawn_whole() -> None:
    """At most MAX_PLOT_POINTS samples: the series itself."""
    t = np.arange(100.0)
    te, ye = envelope(t, t * 2)
    assert te is t and np.array_equal(ye, t * 2)


def test_long_series_keep_every_extreme_in_time_order() -> None:
    """A million samples with spikes: at most MAX_PLOT_POINTS points, the global extremes and
    every spike kept, times non-decreasing, every point a sample of the series."""
    rng = np.random.default_rng(3)
    n = 1_000_003
    t = np.arange(n) * 0.01
    y = rng.normal(0.0, 1.0, n)
    spikes = rng.choice(n, 25, replace=False)
    y[spikes] = 100.0 + np.arange(25)
    te, ye = envelope(t, y)
    assert len(te) <= MAX_PLOT_POINTS
    assert ye.max() == y.max() and ye.min() == y.min()
    assert set((100.0 + np.arange(25)).tolist()) <= set(ye.tolist())
    assert np.all(np.diff(te) >= 0)
    assert np.array_equal(ye, y[np.rint(te / 0.01).astype(int)])


def test_columns_are_read_line_by_line_skipping_a_cut_line(tmp_path: Path) -> None:
    """Only the wanted columns; a last line cut short by a kill is skipped."""
    path = tmp_path / "x.csv"
    path.write_text("a,b,c\n1,2,3\n4,5,6\n7,8")
    head, cols = _read_columns(path, ("c", "a", "missing"))
    assert head == ["a", "b", "c"]
    assert set(cols) == {"a", "c"}
    assert cols["a"].tolist() == [1.0, 4.0] and cols["c"].tolist() == [3.0, 6.0]
    assert _read_columns(tmp_path / "none.csv", ("a",)) == ([], {})


def test_plots_are_drawn_from_a_run_folder(tmp_path: Path) -> None:
    """A telemetry.csv and valve_pulses.csv of a long run give the three PNGs."""
    write_telemetry(tmp_path, N_THRUSTERS, 3 * MAX_PLOT_POINTS)
    (tmp_path / "valve_pulses.csv").write_text("thruster,t_on_s,t_off_s\n1,0.5,0.6\n3,2.0,2.1\n")
    paths = plot_run(tmp_path, 0.1)
    assert [p.name for p in paths] == ["attitude_error.png", "rates.png", "thruster_raster.png"]
    assert all(p.stat().st_size > 0 for p in paths)


def test_a_figure_that_fails_is_named_and_the_others_are_written(tmp_path: Path) -> None:
    """draw_each: a drawer raising (in a forked child where there are CPUs for it, or
    here) stops the call with the figure's name; the figures that could be drawn are."""
    from bench.operator.plots import draw_each

    def ok(path: Path) -> None:
        path.write_bytes(b"png")

    def broken(path: Path) -> None:
        raise ValueError("no data")

    figures = [(tmp_path / "a.png", ok), (tmp_path / "b.png", broken), (tmp_path / "c.png", ok)]
    with pytest.raises((RuntimeError, ValueError), match=r"b\.png|no data"):
        draw_each(figures)
    assert (tmp_path / "a.png").exists() and (tmp_path / "c.png").exists()
    assert draw_each([figures[0], figures[2]]) == [tmp_path / "a.png", tmp_path / "c.png"]
