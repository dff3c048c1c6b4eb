"""What an isolation leaves: full control kept, lost with a seed-004 triple left, or lost."""

from __future__ import annotations

import numpy as np

from bench.station.valves.layouts import LAYOUTS
from flight_sw.allocation.authority import unreached_axes
from flight_sw.allocation.effectiveness import effectiveness_matrix
from flight_sw.control.underactuated.geometry import CONTROL_FRAMES, qualifying_triples
from flight_sw.fdir.layout_check import (
    SHOWN_TRIPLES,
    LayoutCheck,
    check_layout,
    describe,
    positively_spans,
)

SEED000_NOMINAL_INERTIA = np.diag([18.0, 18.0, 24.0])  # fdir_16thr's [vehicle.nominal]
ARM_R_M, LENGTH_L_M = 0.5, 0.3
N_THR = 16
T_S = 12.345


def _b(layout: str) -> np.ndarray:
    geo = LAYOUTS[layout](ARM_R_M, LENGTH_L_M)
    return effectiveness_matrix(np.array([g[0] for g in geo]), np.array([g[1] for g in geo]))


def _mask(keep: tuple[int, ...]) -> np.ndarray:
    m = np.zeros(N_THR, dtype=bool)
    m[list(keep)] = True
    return m


def test_one_isolation_keeps_full_control_and_says_nothing() -> None:
    """Any single failure of the conventional 16 keeps every torque and force axis (their
    positive span survives it): no check of triples, no warning line."""
    for failed in range(N_THR):
        mask = np.ones(N_THR, dtype=bool)
        mask[failed] = False
        c = check_layout(_b("seed000_conventional_16"), SEED000_NOMINAL_INERTIA, mask, True)
        assert c.full_control and c.triples is None and describe(c, T_S) is None


def test_three_left_of_the_canted_layout_may_still_qualify() -> None:
    """The three thrusters of a qualifying canted triple, alone: full control is lost
    (three vectors never positively span three axes) and the line names that triple."""
    b = _b("seed000_canted_16")
    good, _ = qualifying_triples(b, SEED000_NOMINAL_INERTIA, frames=CONTROL_FRAMES)
    triple, frame = good[0].check.thrusters, good[0].frame
    c = check_layout(b, SEED000_NOMINAL_INERTIA, _mask(triple), controls_force=False)
    assert c.available == triple and not c.full_control
    assert all(u.startswith("torque ") for u in c.unreached)
    assert c.triples == ((triple, frame),)
    line = describe(c, T_S)
    assert line is not None and "at 12.35 s" in line
    assert f"possible with 1 triple(s): {triple} ({frame})" in line


def test_three_left_of_the_conventional_layout_cannot_qualify() -> None:
    """The same three of the conventional layout: lost, and no triple qualifies (every
    torque has a zero component there); the force axes are named when translation is
    controlled."""
    b = _b("seed000_canted_16")
    good, _ = qualifying_triples(b, SEED000_NOMINAL_INERTIA, frames=CONTROL_FRAMES)
    keep = good[0].check.thrusters
    c = check_layout(_b("seed000_conventional_16"), SEED000_NOMINAL_INERTIA, _mask(keep), True)
    assert c.triples == () and any(u.startswith("force ") for u in c.unreached)
    line = describe(c, T_S)
    assert line is not None and "underactuated control is not possible either" in line


def test_every_qualifying_triple_among_the_survivors_is_counted() -> None:
    """Six canted thrusters left (4, 7, 8, 11, 13, 15): four torque axes lost, three
    triples qualify, each named, as the configuration check finds them."""
    b = _b("seed000_canted_16")
    keep = (4, 7, 8, 11, 13, 15)
    c = check_layout(b, SEED000_NOMINAL_INERTIA, _mask(keep), controls_force=False)
    assert c.unreached == ("torque +x", "torque -y", "torque +z", "torque -z")
    expected, _ = qualifying_triples(b, SEED000_NOMINAL_INERTIA, _mask(keep), CONTROL_FRAMES)
    assert c.triples == tuple((g.check.thrusters, g.frame) for g in expected)
    assert len(expected) == 3
    line = describe(c, T_S)
    assert line is not None and "3 triple(s)" in line and not line.endswith("...")


def test_a_long_list_of_triples_is_cut_with_the_count_kept() -> None:
    """More qualifying triples than the line names: the first few, then "...", and the
    count of all of them."""
    triples = tuple(((k, k + 1, k + 2), "III=+x") for k in range(SHOWN_TRIPLES + 2))
    c = LayoutCheck((0, 1, 2), ("torque +x",), triples)
    line = describe(c, T_S)
    assert line is not None and line.endswith(", ...")
    assert f"{SHOWN_TRIPLES + 2} triple(s)" in line
    assert str(triples[SHOWN_TRIPLES - 1][0]) in line and str(triples[SHOWN_TRIPLES][0]) not in line


def test_a_non_diagonal_inertia_is_reported_unchecked() -> None:
    """The triple check needs principal body axes: otherwise the line says it was not
    checked and why, instead of guessing."""
    j = SEED000_NOMINAL_INERTIA.copy()
    j[0, 1] = j[1, 0] = 0.5
    c = check_layout(_b("seed000_canted_16"), j, _mask((0, 5, 9)), controls_force=False)
    line = describe(c, T_S)
    assert c.triples is None and line is not None and "not checked" in line


def test_positive_span_agrees_with_the_per_axis_check() -> None:
    """The one-LP test says "spans" exactly when no signed torque axis is unreached (a cone
    holding ±e_x, ±e_y, ±e_z is all of R³), on 60 random survivor sets of both layouts;
    on the wrench rows "spans" implies every torque and force axis reached."""
    rng = np.random.default_rng(20)
    for layout in ("seed000_conventional_16", "seed000_canted_16"):
        b = _b(layout)
        for _ in range(30):
            keep = rng.choice(N_THR, int(rng.integers(3, N_THR + 1)), replace=False)
            cols = b[:, _mask(tuple(keep.tolist()))]
            assert positively_spans(cols[3:]) == (unreached_axes(cols[3:]) == [])
            if positively_spans(cols):
                assert unreached_axes(cols[3:]) == [] and unreached_axes(cols[:3]) == []
    assert positively_spans(_b("seed000_conventional_16"))  # docs: the 6×16 spans
    assert not positively_spans(_b("seed000_conventional_16")[:, :6])  # n ≤ m never does
