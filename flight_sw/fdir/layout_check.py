"""What the thrusters left after an isolation can still do: full control, or only seed 004's.

What it does: for the availability mask after a thruster isolation, :func:`check_layout`
finds the signed torque axes (and force axes, when this flight software controls
translation) that no non-negative thrust of the available thrusters gives
(:func:`flight_sw.allocation.authority.unreached_axes`). Where some are, full control is
lost, and it runs seed 004's configuration check on the available thrusters in all six
control frames (:func:`flight_sw.control.underactuated.geometry.qualifying_triples`):
the sets of three that satisfy conditions (i)–(iii) are those with which underactuated
control (attitude and position with three thrusters) would still be possible.
:func:`describe` makes that one line for the run's warnings (``summary.json`` and the
console: nothing about a lost axis stays silent).

The flight computer calls it on every reconfiguration (flight_sw.computer), in the cycle
of an isolation only: one linear programme when the survivors still positively span the
controlled axes (:func:`positively_spans`: every axis reached, the usual single
failure), else one per signed axis (12 at most) to name the lost ones and the triple
check (few thrusters left, few triples).
It reports; it does not switch controllers (seed 004 over the bus is not flown yet:
docs/reproductions.md).

Inputs: the 6×n nominal effectiveness matrix (rows force per newton, then torque per
newton [m]), the nominal inertia [kg m²] (the triple check needs it diagonal in body axes:
principal axes; otherwise it is reported as not checked), the mask (True = available).
Source: seed 004 §2.1–2.3 (conditions (i)–(iii)); the cone test of authority.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dbc.errors import ConfigError
from flight_sw.allocation.authority import positive_null_vector, unreached_axes
from flight_sw.control.underactuated.geometry import CONTROL_FRAMES, qualifying_triples

FORCE_ROWS = slice(0, 3)
TORQUE_ROWS = slice(3, 6)
SHOWN_TRIPLES = 4  # triples named in the warning line (the count is always given)


@dataclass(frozen=True)
class LayoutCheck:
    """The available thrusters (indices), the signed axes they cannot reach ("torque +x",
    "force -z"), and the qualifying triples with their control frame (None: not checked,
    ``why_unchecked`` says why)."""

    available: tuple[int, ...]
    unreached: tuple[str, ...]
    triples: tuple[tuple[tuple[int, int, int], str], ...] | None
    why_unchecked: str = ""

    @property
    def full_control(self) -> bool:
        """Every needed axis is still reached."""
        return not self.unreached


def positively_spans(rows: np.ndarray) -> bool:
    """Whether the columns of ``rows`` (m × n) positively span R^m: they span it and some
    strictly positive combination of them is 0 (Davis 1954): one linear programme
    (:func:`~flight_sw.allocation.authority.positive_null_vector`, the pseudo-inverse
    allocator's), instead of one per signed axis."""
    m, n = rows.shape
    if n <= m or np.linalg.matrix_rank(rows) < m:
        return False
    return positive_null_vector(rows, np.linalg.pinv(rows)) is not None


def check_layout(effectiveness: np.ndarray, inertia_B_kgm2: np.ndarray, mask: np.ndarray,
                 controls_force: bool) -> LayoutCheck:
    """The check of the module docstring for the thrusters ``mask`` leaves."""
    b = np.asarray(effectiveness, dtype=float)
    ok = np.asarray(mask, dtype=bool)
    available = tuple(int(k) for k in np.flatnonzero(ok))
    cols = b[:, ok]
    # one LP when the survivors still positively span what is controlled (every axis
    # reached: the usual single failure); the per-axis LPs only to name what is lost
    if positively_spans(cols if controls_force else cols[TORQUE_ROWS]):
        return LayoutCheck(available, (), None, "full control remains")
    unreached = [f"torque {a}" for a in unreached_axes(cols[TORQUE_ROWS])]
    if controls_force:
        unreached += [f"force {a}" for a in unreached_axes(cols[FORCE_ROWS])]
    if not unreached:
        return LayoutCheck(available, (), None, "full control remains")
    try:
        good, _ = qualifying_triples(b, inertia_B_kgm2, ok, CONTROL_FRAMES)
    except ConfigError as exc:  # an inertia that is not diagonal in body axes
        return LayoutCheck(available, tuple(unreached), None, str(exc))
    triples = tuple((g.check.thrusters, g.frame) for g in good)
    return LayoutCheck(available, tuple(unreached), triples)


def describe(check: LayoutCheck, t_s: float) -> str | None:
    """One warning line for an isolation at ``t_s`` [s] that cost full control (None if
    full control remains)."""
    if check.full_control:
        return None
    head = (f"after the isolation at {t_s:.2f} s the {len(check.available)} thrusters left "
            f"({', '.join(map(str, check.available))}) cannot give "
            f"{', '.join(check.unreached)}: full control is lost")
    if check.triples is None:
        return f"{head}; underactuated control (seed 004) not checked: {check.why_unchecked}"
    if not check.triples:
        return (f"{head}; no three of them satisfy seed 004's conditions (i)-(iii): "
                "underactuated control is not possible either")
    shown = ", ".join(f"{t} ({frame})" for t, frame in check.triples[:SHOWN_TRIPLES])
    more = "" if len(check.triples) <= SHOWN_TRIPLES else ", ..."
    return (f"{head}; underactuated control (seed 004) is possible with "
            f"{len(check.triples)} triple(s): {shown}{more}")
