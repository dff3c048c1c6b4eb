"""Known-answer tests of bench.station.valves.valve: delays, rise and tail, min on-time, faults."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from bench.station.valves.params import (
    NEVER_NS,
    OPEN_THRESHOLD_FRACTION,
    THRUST_CUTOFF_FRACTION,
    ValveParams,
)
from bench.station.valves.valve import Valve
from dbc.errors import ConfigError
from tests.bench.station.thrust_reference import MEAN_REL_TOL, step_mean_reference_N
from tests.values import same_value

MS = 1_000_000  # ns per millisecond
FMAX_N = 22.0
ISP_S = 220.0
OPEN_DELAY_S = 0.003
CLOSE_DELAY_S = 0.004
RISE_TAU_S = 0.002
TAIL_TAU_S = 0.004
MIN_ON_S = 0.010
REL_TOL = 1e-12
IMPULSE_REL_TOL = 1e-6
QUADRATURE_STEP_NS = 1_000  # 1 µs Simpson panels for the numerical impulse


def _params(**overrides: float) -> ValveParams:
    base = {
        "max_thrust_N": FMAX_N,
        "isp_s": ISP_S,
        "open_delay_s": OPEN_DELAY_S,
        "close_delay_s": CLOSE_DELAY_S,
        "rise_tau_s": RISE_TAU_S,
        "tail_tau_s": TAIL_TAU_S,
        "min_on_s": MIN_ON_S,
    }
    base.update(overrides)
    return ValveParams(**base)  # type: ignore[arg-type]


def _numerical_impulse(v: Valve, t0_ns: int, t1_ns: int) -> float:
    """Composite Simpson over [t0, t1] on a 1 µs grid (kinks fall on grid points)."""
    n = (t1_ns - t0_ns) // QUADRATURE_STEP_NS
    n -= n % 2
    h = QUADRATURE_STEP_NS * 1e-9
    total = v.thrust_N(t0_ns) + v.thrust_N(t0_ns + n * QUADRATURE_STEP_NS)
    for k in range(1, n):
        total += (4.0 if k % 2 else 2.0) * v.thrust_N(t0_ns + k * QUADRATURE_STEP_NS)
    return total * h / 3.0


# --- configuration ----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("max_thrust_N", 0.0),
        ("isp_s", -1.0),
        ("rise_tau_s", 0.0),
        ("tail_tau_s", math.inf),
        ("open_delay_s", -0.001),
        ("close_delay_s", math.nan),
        ("min_on_s", -1e-3),
    ],
)
def test_params_validation_names_key_and_value(key: str, value: float) -> None:
    """Each invalid parameter raises ConfigError carrying its key, value and the source."""
    base = {
        "max_thrust_N": FMAX_N,
        "isp_s": ISP_S,
        "open_delay_s": OPEN_DELAY_S,
        "close_delay_s": CLOSE_DELAY_S,
        "rise_tau_s": RISE_TAU_S,
        "tail_tau_s": TAIL_TAU_S,
        "min_on_s": MIN_ON_S,
        key: value,
    }
    with pytest.raises(ConfigError) as exc:
        ValveParams(**base, source="scenario.toml [thrusters]")
    assert exc.value.key == key
    assert same_value(exc.value.value, value)
    assert key in str(exc.value)
    assert repr(value) in str(exc.value)
    assert str(exc.value).startswith("scenario.toml [thrusters]")


# --- the pulse shape ------------------------------------------------------------------------
def test_rest_valve_is_idle_and_silent() -> None:
    """A valve never commanded produces no thrust and is idle."""
    v = Valve(_params())
    assert v.thrust_N(0) == 0.0
    assert v.is_idle(0)
    assert v.status(0) == (False, False, False)
    assert v.openings == 0


def test_pulse_shape_known_values() -> None:
    """Zero until the opening delay, then Fmax(1−e^{−x/τr}); F_c e^{−x/τt} after closing."""
    p = _params()
    v = Valve(p)
    t_cmd = 5 * MS
    on_ns = 20 * MS
    v.command(t_cmd, on_ns)
    t_a = t_cmd + round(OPEN_DELAY_S * 1e9)
    t_b = t_cmd + on_ns + round(CLOSE_DELAY_S * 1e9)
    assert v.thrust_N(t_cmd) == 0.0
    assert v.thrust_N(t_a - 1) == 0.0
    assert v.thrust_N(t_a) == 0.0
    x = 1.5 * MS
    assert v.thrust_N(t_a + round(x)) == pytest.approx(
        FMAX_N * -math.expm1(-x * 1e-9 / RISE_TAU_S), rel=REL_TOL
    )
    f_c = FMAX_N * -math.expm1(-(t_b - t_a) * 1e-9 / RISE_TAU_S)
    assert v.thrust_N(t_b) == pytest.approx(f_c, rel=REL_TOL)
    y = 3 * MS
    assert v.thrust_N(t_b + y) == pytest.approx(f_c * math.exp(-y * 1e-9 / TAIL_TAU_S), rel=REL_TOL)
    assert not v.is_idle(t_b + y)


def test_tail_cut_off_makes_valve_idle() -> None:
    """Below THRUST_CUTOFF_FRACTION·Fmax the tail is exactly zero and the valve is idle."""
    p = _params()
    v = Valve(p)
    v.command(0, 20 * MS)
    t_idle = v.idle_from_ns
    assert t_idle < NEVER_NS
    assert v.thrust_N(t_idle - 1) > 0.0
    assert v.thrust_N(t_idle - 1) == pytest.approx(THRUST_CUTOFF_FRACTION * FMAX_N, rel=1e-6)
    assert v.thrust_N(t_idle) == 0.0
    assert v.is_idle(t_idle)
    assert not v.is_idle(t_idle - 1)
    assert v.thrust_N(t_idle + 10**12) == 0.0


def test_pulse_impulse_matches_closed_form() -> None:
    """The integral of thrust_N over an isolated 20 ms pulse equals pulse_impulse_Ns."""
    p = _params()
    v = Valve(p)
    v.command(0, 20 * MS)
    numeric = _numerical_impulse(v, 0, v.idle_from_ns + QUADRATURE_STEP_NS)
    assert numeric == pytest.approx(Valve.pulse_impulse_Ns(p, 0.020), rel=IMPULSE_REL_TOL)


def test_pulse_impulse_closed_form_values() -> None:
    """The closed form reduces to known limits: zero on-time, D < 0, and a long pulse."""
    p = _params(min_on_s=0.0)
    assert Valve.pulse_impulse_Ns(p, 0.0) == 0.0
    # on + close_delay < open_delay: the valve never opens
    q = _params(open_delay_s=0.010, close_delay_s=0.001, min_on_s=0.0)
    assert Valve.pulse_impulse_Ns(q, 0.005) == 0.0
    # long pulse: I → Fmax (D − τr + τt)
    on = 10.0
    d = on + CLOSE_DELAY_S - OPEN_DELAY_S
    assert Valve.pulse_impulse_Ns(p, on) == pytest.approx(
        FMAX_N * (d - RISE_TAU_S + TAIL_TAU_S), rel=REL_TOL
    )


def test_pulse_shorter_than_opening_delay_gives_no_thrust() -> None:
    """If on + close_delay ≤ open_delay the valve never opens (D clamped at 0)."""
    p = _params(open_delay_s=0.010, close_delay_s=0.001, min_on_s=0.0)
    v = Valve(p)
    v.command(0, 5 * MS)
    assert all(v.thrust_N(t) == 0.0 for t in range(0, 30 * MS, MS // 4))
    assert v.openings == 1


def test_min_on_time_extends_short_commands() -> None:
    """A 2 ms command is stretched to the 10 ms minimum: coil and impulse as for 10 ms."""
    p = _params()
    v = Valve(p)
    v.command(0, 2 * MS)
    assert v.coil_energised(9 * MS)
    assert not v.coil_energised(10 * MS)
    numeric = _numerical_impulse(v, 0, v.idle_from_ns + QUADRATURE_STEP_NS)
    assert numeric == pytest.approx(Valve.pulse_impulse_Ns(p, 0.010), rel=IMPULSE_REL_TOL)
    assert Valve.pulse_impulse_Ns(p, 0.002) == Valve.pulse_impulse_Ns(p, 0.010)


def test_recommand_while_energised_extends_without_new_opening() -> None:
    """A command while energised replaces the close time; no new transient, no new opening."""
    p = _params()
    v = Valve(p)
    v.command(0, 20 * MS)
    f_before = v.thrust_N(15 * MS)
    v.command(15 * MS, 30 * MS)  # close now at 45 ms instead of 20 ms
    assert v.openings == 1
    assert v.thrust_N(15 * MS) == pytest.approx(f_before, rel=REL_TOL)
    t_a = round(OPEN_DELAY_S * 1e9)
    t = 40 * MS
    assert v.thrust_N(t) == pytest.approx(
        FMAX_N * -math.expm1(-(t - t_a) * 1e-9 / RISE_TAU_S), rel=REL_TOL
    )
    assert v.coil_energised(44 * MS)
    assert not v.coil_energised(45 * MS)


def test_recommand_cannot_shorten_below_min_on() -> None:
    """Replacing the close time never ends the coil pulse before pulse start + min_on."""
    v = Valve(_params())
    v.command(0, 20 * MS)
    v.command(2 * MS, 1 * MS)
    assert v.coil_energised(9 * MS)
    assert not v.coil_energised(10 * MS)


def test_zero_on_time_deenergises_now() -> None:
    """on = 0 de-energises at once; the tail starts after the closing delay."""
    v = Valve(_params())
    v.command(0, 50 * MS)
    v.command(12 * MS, 0)
    assert not v.coil_energised(12 * MS)
    t_b = 12 * MS + round(CLOSE_DELAY_S * 1e9)
    f_c = v.thrust_N(t_b)
    assert v.thrust_N(t_b + 2 * MS) == pytest.approx(
        f_c * math.exp(-2e-3 / TAIL_TAU_S), rel=REL_TOL
    )
    v.command(13 * MS, 0)  # already off: no effect
    assert v.openings == 1


def test_reopening_during_tail_continues_from_current_thrust() -> None:
    """Re-opened in the tail, thrust rises from where it is: Fmax + (F_a − Fmax)e^{−x/τr}."""
    v = Valve(_params())
    v.command(0, 20 * MS)
    t2 = 30 * MS  # coil off at 20, decaying from 24 ms
    v.command(t2, 20 * MS)
    assert v.openings == 2
    t_a2 = t2 + round(OPEN_DELAY_S * 1e9)
    f_a = v.thrust_N(t_a2)
    assert 0.0 < f_a < FMAX_N * OPEN_THRESHOLD_FRACTION * 10
    x = 2 * MS
    assert v.thrust_N(t_a2 + x) == pytest.approx(
        FMAX_N + (f_a - FMAX_N) * math.exp(-x * 1e-9 / RISE_TAU_S), rel=REL_TOL
    )


def test_recommand_before_delayed_close_keeps_valve_open() -> None:
    """A new pulse whose opening precedes the previous delayed closing merges: no dip."""
    v = Valve(_params(open_delay_s=0.001, close_delay_s=0.004))
    v.command(0, 20 * MS)  # physical close would be at 24 ms
    v.command(22 * MS, 20 * MS)  # physical reopening at 23 ms < 24 ms
    samples = [v.thrust_N(t) for t in range(22 * MS, 42 * MS, MS // 10)]
    assert all(b >= a for a, b in itertools.pairwise(samples))
    assert v.openings == 2


def test_command_may_be_delivered_inside_a_step() -> None:
    """After a command at t1, thrust at t0 (previous command ≤ t0 < t1) is the pre-command value."""
    v = Valve(_params())
    v.command(0, 20 * MS)
    f_mid = v.thrust_N(10 * MS)
    v.command(10_300_000, 0)
    assert v.thrust_N(10 * MS) == pytest.approx(f_mid, rel=REL_TOL)


def test_time_order_and_on_time_are_checked() -> None:
    """Commands must be in time order and on-times non-negative."""
    v = Valve(_params())
    v.command(10 * MS, 20 * MS)
    with pytest.raises(ValueError):
        v.command(5 * MS, 20 * MS)
    with pytest.raises(ValueError):
        v.command(11 * MS, -1)


def test_openings_count_rising_edges() -> None:
    """Openings count coil rising edges: continuations do not count, separate pulses do."""
    v = Valve(_params())
    for k in range(5):
        v.command(k * 100 * MS, 20 * MS)
    v.command(500 * MS, 20 * MS)
    v.command(510 * MS, 20 * MS)  # continuation
    v.command(530 * MS, 20 * MS)  # exactly at the close instant: continuation
    assert v.openings == 6


def test_status_reports_coil_open_and_current() -> None:
    """status = (coil energised, thrust > 10 % Fmax, current) through a pulse."""
    v = Valve(_params())
    v.command(0, 20 * MS)
    assert v.status(1 * MS) == (True, False, True)  # still in the opening delay
    assert v.status(15 * MS) == (True, True, True)
    assert v.status(21 * MS) == (False, True, False)  # closing delay, still thrusting
    assert v.status(60 * MS) == (False, False, False)


def test_stage_thrusts_are_the_mean_thrust_of_the_step() -> None:
    """stage_thrusts_N(t, dt) is the step's mean of thrust_N (numeric quadrature) three times,
    across random pulse trains commanded anywhere inside steps, with and without faults."""
    rng = np.random.default_rng(7)
    dt = MS
    for fault_at in (None, "stuck_open", "stuck_closed"):
        v = Valve(_params())
        t = 0
        next_cmd = 0
        while t < 400 * MS:
            if t >= next_cmd:
                at = t + int(rng.integers(0, dt))
                v.command(at, int(rng.integers(0, 25 * MS)))
                next_cmd = at + int(rng.integers(0, 40 * MS))
                if fault_at is not None and t > 200 * MS and v.fault is None:
                    v.set_fault(fault_at, at)
            got = v.stage_thrusts_N(t, dt)
            want = step_mean_reference_N(v, t, dt)
            assert got[0] == got[1] == got[2]
            assert got[0] == pytest.approx(want, rel=MEAN_REL_TOL,
                                           abs=THRUST_CUTOFF_FRACTION * FMAX_N)
            t += dt


# --- faults ------------------------------------------------------------------------------------
def test_stuck_closed_gives_zero_thrust_but_current() -> None:
    """A stuck-closed valve never thrusts; the coil still energises and reports current."""
    v = Valve(_params())
    v.set_fault("stuck_closed")
    v.command(0, 20 * MS)
    assert all(v.thrust_N(t) == 0.0 for t in range(0, 60 * MS, MS // 4))
    assert v.status(10 * MS) == (True, False, True)
    assert v.openings == 1
    assert v.is_idle(0)


def test_stuck_closed_mid_pulse_decays_with_tail() -> None:
    """Sticking closed while firing: the thrust decays from its value at the fault time."""
    v = Valve(_params())
    v.command(0, 50 * MS)
    f = v.thrust_N(20 * MS)
    v.set_fault("stuck_closed", 20 * MS)
    assert v.thrust_N(22 * MS) == pytest.approx(f * math.exp(-2e-3 / TAIL_TAU_S), rel=REL_TOL)
    v.command(100 * MS, 20 * MS)
    assert v.thrust_N(115 * MS) == 0.0


def test_stuck_open_gives_full_thrust_regardless_of_commands() -> None:
    """A stuck-open valve opens at the next command and then stays at full thrust."""
    v = Valve(_params())
    v.set_fault("stuck_open")
    v.command(0, 20 * MS)
    v.command(10 * MS, 0)  # commanded closed
    t_a = round(OPEN_DELAY_S * 1e9)
    t = 200 * MS
    assert v.thrust_N(t) == pytest.approx(
        FMAX_N * -math.expm1(-(t - t_a) * 1e-9 / RISE_TAU_S), rel=REL_TOL
    )
    assert v.thrust_N(10**10) == FMAX_N
    assert not v.is_idle(10**10)
    assert v.status(10**10) == (False, True, False)


def test_clearing_stuck_open_closes_the_valve() -> None:
    """Clearing stuck_open while the coil is off lets the thrust decay with the tail."""
    v = Valve(_params())
    v.set_fault("stuck_open")
    v.command(0, 20 * MS)
    v.set_fault(None, 500 * MS)
    assert v.thrust_N(500 * MS) == pytest.approx(FMAX_N, rel=REL_TOL)
    assert v.thrust_N(502 * MS) == pytest.approx(FMAX_N * math.exp(-2e-3 / TAIL_TAU_S), rel=1e-9)
    assert v.idle_from_ns < NEVER_NS


def test_unknown_fault_kind_is_rejected() -> None:
    """An unknown fault kind is a ConfigError naming 'kind' and the value."""
    v = Valve(_params())
    with pytest.raises(ConfigError) as exc:
        v.set_fault("sticky")
    assert exc.value.key == "kind"
    assert exc.value.value == "sticky"
