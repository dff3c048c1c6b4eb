"""Valve-telemetry FDIR: known THR_STATUS patterns of stuck-closed and stuck-open valves."""

from __future__ import annotations

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.fdir.base import FailureKind, ThrusterFailure
from flight_sw.fdir.valve_status import ValveStatusFdir, ValveStatusParams

N = 8
PERIOD_NS = 20_000_000
FULL_ON_S = 0.02  # a full-period pulse: the coil is still energised at the next sample
SHORT_ON_S = 0.005


def run(
    fdir: ValveStatusFdir,
    cycles: int,
    on_s: np.ndarray,
    status: list[tuple[np.ndarray, np.ndarray]],
    t0: int = 0,
) -> tuple[int, ThrusterFailure | None]:
    """Cycle k: THR_STATUS sample k, evaluate, then command ``on_s``; first failure."""
    for k in range(cycles):
        t = t0 + k * PERIOD_NS
        cmd, opened = status[k % len(status)]
        fdir.on_valve_status(t, cmd, opened, cmd)
        v = fdir.evaluate(t)
        if v.failure is not None:
            return k, v.failure
        fdir.on_command(t, on_s)
    return cycles, None


def flags(*idx: int) -> np.ndarray:
    """Boolean vector with ``idx`` set."""
    a = np.zeros(N, dtype=bool)
    a[list(idx)] = True
    return a


def test_stuck_closed_declared_after_the_configured_samples() -> None:
    """Coil energised but valve closed on 3 samples: thruster 2 stuck closed at the 3rd."""
    fdir = ValveStatusFdir(N, ValveStatusParams(stuck_closed_samples=3))
    on = np.zeros(N)
    on[2] = FULL_ON_S
    k, f = run(fdir, 10, on, [(flags(2), flags())])
    assert f is not None and (f.thruster, f.kind) == (2, FailureKind.STUCK_CLOSED)
    assert k == 2  # samples 0, 1, 2
    assert f.t_detect_ns == f.t_isolate_ns == 2 * PERIOD_NS


def test_healthy_pulsing_valve_is_never_declared() -> None:
    """Energised and open, or closed with its closing tail seen open: no failure."""
    fdir = ValveStatusFdir(N, ValveStatusParams())
    on = np.full(N, SHORT_ON_S)
    # alternate: energised+open, and de-energised but still open (the tail after a pulse)
    k, f = run(fdir, 200, on, [(flags(*range(N)), flags(*range(N))), (flags(), flags(0, 1))])
    assert f is None and k == 200


def test_one_healthy_sample_resets_the_stuck_closed_count() -> None:
    """Energised-closed, energised-open, energised-closed ...: never 2 in a row, no failure."""
    fdir = ValveStatusFdir(N, ValveStatusParams(stuck_closed_samples=2))
    on = np.full(N, FULL_ON_S)
    _, f = run(fdir, 50, on, [(flags(4), flags()), (flags(4), flags(4))])
    assert f is None


def test_old_evidence_is_forgotten() -> None:
    """Two energised-closed samples further apart than the window do not add up."""
    fdir = ValveStatusFdir(N, ValveStatusParams(stuck_closed_samples=2, window_samples=5))
    on = np.zeros(N)
    pattern = [(flags(3), flags())] + [(flags(), flags())] * 6
    _, f = run(fdir, 70, on, pattern)
    assert f is None


def test_stuck_open_declared_when_open_and_not_commanded() -> None:
    """Open with the coil off and no command for 2 cycles, 3 samples: stuck open."""
    fdir = ValveStatusFdir(N, ValveStatusParams(stuck_open_samples=3, quiet_cycles=2))
    k, f = run(fdir, 10, np.zeros(N), [(flags(), flags(6))])
    assert f is not None and (f.thruster, f.kind) == (6, FailureKind.STUCK_OPEN)
    assert k == 4  # 2 cycles of command history first, then 3 samples


def test_open_after_a_recent_command_is_a_tail_not_a_failure() -> None:
    """A thruster commanded every other cycle and always seen open is never stuck open."""
    fdir = ValveStatusFdir(N, ValveStatusParams(stuck_open_samples=2, quiet_cycles=2))
    on_a = np.zeros(N)
    on_a[1] = SHORT_ON_S
    for k in range(40):
        t = k * PERIOD_NS
        fdir.on_valve_status(t, flags(), flags(1), flags())
        assert fdir.evaluate(t).failure is None
        fdir.on_command(t, on_a if k % 2 == 0 else np.zeros(N))


def test_known_failures_are_not_declared_again() -> None:
    """After set_failures the isolated thruster is ignored."""
    fdir = ValveStatusFdir(N, ValveStatusParams(stuck_open_samples=1, quiet_cycles=1))
    fdir.on_command(0, np.zeros(N))
    fdir.set_failures(0, [ThrusterFailure(5, FailureKind.STUCK_OPEN, 0, 0, "test")])
    _, f = run(fdir, 10, np.zeros(N), [(flags(), flags(5))], t0=PERIOD_NS)
    assert f is None


@pytest.mark.parametrize(
    "key", ["stuck_closed_samples", "window_samples", "stuck_open_samples", "quiet_cycles"]
)
def test_bad_counts_are_named(key: str) -> None:
    """A count below 1 raises ConfigError naming it."""
    with pytest.raises(ConfigError) as err:
        ValveStatusParams(**{key: 0})  # type: ignore[arg-type]
    assert err.value.key == key
