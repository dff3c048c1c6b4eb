"""Tests of bench.station.valves.thruster_set: wrench, RK4-consistent impulse, propellant."""

from __future__ import annotations

import math

import pytest

from bench.station.dynamics.rigid_body import (
    MassProperties,
    State,
    linear_momentum_N,
    make_state,
    quat_normalize,
    rk4_step,
    state_omega_BN_B,
)
from bench.station.valves.params import ValveParams
from bench.station.valves.thruster_set import G0_M_S2, ThrusterGeometry, ThrusterSet
from bench.station.valves.valve import Valve
from dbc.errors import ConfigError

MS = 1_000_000  # ns per millisecond
FMAX_N = 22.0
ISP_S = 220.0
MASS_KG = 50.0
J_FULL = ((5.0, 0.1, 0.0), (0.1, 6.0, 0.2), (0.0, 0.2, 7.0))
Q_TILTED = quat_normalize((0.9, 0.2, -0.1, 0.3))
IMPULSE_REL_TOL = 1e-6
BOOKKEEPING_REL_TOL = 1e-12
ROUNDOFF_ABS_N = 1e-12
REL_TOL = 1e-12
ROUNDOFF_ABS_N = 1e-12
PULSE_NS = 20 * MS
# A pulse's booked impulse against its closed form, edges anywhere in a step [N·s]
# (issue: exact valve impulse); round-off of ~100 steps of ~1e-2 N·s is ~1e-16.
EXACT_IMPULSE_ABS_NS = 1e-9
# Simpson on thrust sampled at the stage times, 1 kHz, 2 ms rise, against the exact impulse
# (the bias the mean-thrust stages remove: 1.6e-6 measured for a 20 ms pulse)
SAMPLED_SIMPSON_REL_TOL = 1e-5
# Where in the 1 ms step a command lands [ns]: on the grid, early, mid-step, late.
COMMAND_PHASES_NS = (0, 1, 123_457, 500_000, 777_777, 999_999)
SHORT_PULSES_NS = (5 * MS, 7_345_678, 12_000_001)


def _params(rise_tau_s: float = 0.002, tail_tau_s: float = 0.004, **kw: float) -> ValveParams:
    base = {
        "max_thrust_N": FMAX_N,
        "isp_s": ISP_S,
        "open_delay_s": 0.003,
        "close_delay_s": 0.004,
        "rise_tau_s": rise_tau_s,
        "tail_tau_s": tail_tau_s,
        "min_on_s": 0.005,
    }
    base.update(kw)
    return ValveParams(**base)  # type: ignore[arg-type]


def _through_com() -> ThrusterGeometry:
    """A thruster behind the centre of mass pushing along +x_B: no torque."""
    return ThrusterGeometry((-0.5, 0.0, 0.0), (1.0, 0.0, 0.0))


def _fly(ts: ThrusterSet, s: State, t_ns: int, dt_ns: int, mp: MassProperties) -> tuple[State, int]:
    """Integrate with RK4 until every valve is idle."""
    while not ts.is_idle(t_ns):
        w0, wm, w1 = ts.stage_wrenches(t_ns, dt_ns)
        s = rk4_step(s, dt_ns * 1e-9, w0, wm, w1, mp)
        t_ns += dt_ns
    return s, t_ns


# --- configuration ------------------------------------------------------------------------
def test_geometry_rejects_non_unit_direction() -> None:
    """A non-unit thrust direction is a ConfigError naming d_thr_B and the value."""
    with pytest.raises(ConfigError) as exc:
        ThrusterGeometry((0.0, 0.0, 0.0), (1.0, 1.0, 0.0), source="thrusters[3]")
    assert exc.value.key == "d_thr_B"
    assert exc.value.value == (1.0, 1.0, 0.0)
    assert "thrusters[3]" in str(exc.value)
    with pytest.raises(ConfigError) as exc:
        ThrusterGeometry((0.0, 0.0), (1.0, 0.0, 0.0))  # type: ignore[arg-type]
    assert exc.value.key == "r_thr_B_m"


def test_set_rejects_mismatched_params() -> None:
    """A params sequence of the wrong length, or a bad g0, is a ConfigError naming the key."""
    g = [_through_com(), _through_com()]
    with pytest.raises(ConfigError) as exc:
        ThrusterSet(g, [_params()])
    assert exc.value.key == "params"
    with pytest.raises(ConfigError) as exc:
        ThrusterSet(g, _params(), g0_m_s2=0.0)
    assert exc.value.key == "g0_m_s2"
    assert exc.value.value == 0.0
    with pytest.raises(ConfigError) as exc:
        ThrusterSet([], _params())
    assert exc.value.key == "geometries"


# --- wrench ---------------------------------------------------------------------------------
def test_wrench_known_answer() -> None:
    """One thruster at r = (1, 0, 0) m along +y: F = (0, F, 0), τ = r × F = (0, 0, F)."""
    ts = ThrusterSet([ThrusterGeometry((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))], _params())
    assert ts.wrench_B(0) == (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    ts.command(0, 0, 10**12)
    t = 10**10
    f = ts.valves[0].thrust_N(t)
    assert f == pytest.approx(FMAX_N, rel=REL_TOL)
    assert ts.wrench_B(t) == pytest.approx((0.0, f, 0.0, 0.0, 0.0, f), rel=REL_TOL)
    assert ts.thrusts_N(t) == (f,)


def test_wrench_sums_thrusters_and_pure_couples_cancel_force() -> None:
    """Two opposite thrusters at ±x along ∓y/±y: zero force, torque 2·r·F about z."""
    geo = [
        ThrusterGeometry((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
        ThrusterGeometry((-1.0, 0.0, 0.0), (0.0, -1.0, 0.0)),
        ThrusterGeometry((0.0, 1.0, 0.0), (1.0, 0.0, 0.0)),  # never fired
    ]
    ts = ThrusterSet(geo, _params())
    ts.command(0, 0, 10**12)
    ts.command(0, 1, 10**12)
    t = 10**10
    fx, fy, fz, tx, ty, tz = ts.wrench_B(t)
    assert (fx, fy, fz, tx, ty) == pytest.approx((0.0,) * 5, abs=1e-12)
    assert tz == pytest.approx(2.0 * FMAX_N, rel=REL_TOL)


# --- impulse bookkeeping through RK4 --------------------------------------------------------
@pytest.mark.parametrize(
    ("dt_ns", "rise_tau_s", "tail_tau_s"),
    [(1 * MS, 0.004, 0.006), (MS // 4, 0.002, 0.004)],
    ids=["1kHz", "4kHz-fast-valve"],
)
def test_pulse_impulse_through_rk4_matches_closed_form(
    dt_ns: int, rise_tau_s: float, tail_tau_s: float
) -> None:
    """A 20 ms pulse integrated by RK4: booked impulse = pulse_impulse_Ns (1e-6) = m·Δv (1e-12)."""
    p = _params(rise_tau_s, tail_tau_s)
    ts = ThrusterSet([_through_com()], p)
    mp = MassProperties(MASS_KG, J_FULL)
    s0 = make_state(Q_TILTED)
    ts.command(0, 0, PULSE_NS)
    s, _t = _fly(ts, s0, 0, dt_ns, mp)
    booked = ts.impulse_Ns[0]
    expected = Valve.pulse_impulse_Ns(p, PULSE_NS * 1e-9)
    assert booked == pytest.approx(expected, rel=IMPULSE_REL_TOL)
    momentum = math.sqrt(sum(x * x for x in linear_momentum_N(s, mp)))
    assert momentum == pytest.approx(booked, rel=BOOKKEEPING_REL_TOL)
    assert state_omega_BN_B(s) == (0.0, 0.0, 0.0)
    assert ts.propellant_kg[0] == pytest.approx(booked / (ISP_S * G0_M_S2), rel=REL_TOL)


@pytest.mark.parametrize("phase_ns", COMMAND_PHASES_NS)
@pytest.mark.parametrize("on_ns", SHORT_PULSES_NS)
def test_pulse_with_mid_step_edges_books_the_closed_form_impulse(
    phase_ns: int, on_ns: int
) -> None:
    """A pulse commanded anywhere inside a 1 ms step: the booked impulse and the body's
    momentum equal pulse_impulse_Ns to 1e-9 N·s (drive edges mid-step, min_on applied)."""
    p = _params()
    ts = ThrusterSet([_through_com()], p)
    mp = MassProperties(MASS_KG, J_FULL)
    dt = 1 * MS
    s = make_state(Q_TILTED)
    w0, wm, w1 = ts.stage_wrenches(0, dt)  # idle first step: a command arrives inside the next
    s = rk4_step(s, dt * 1e-9, w0, wm, w1, mp)
    ts.command(dt + phase_ns, 0, on_ns)
    s, _t = _fly(ts, s, dt, dt, mp)
    expected = Valve.pulse_impulse_Ns(p, on_ns * 1e-9)
    assert abs(ts.impulse_Ns[0] - expected) <= EXACT_IMPULSE_ABS_NS
    momentum = math.sqrt(sum(x * x for x in linear_momentum_N(s, mp)))
    assert abs(momentum - expected) <= EXACT_IMPULSE_ABS_NS


def test_bookkeeping_is_exact_for_switching_inside_steps() -> None:
    """Pulses starting and ending off the step grid: booked impulse still equals m·Δv."""
    ts = ThrusterSet([_through_com()], _params())
    mp = MassProperties(MASS_KG, J_FULL)
    s = make_state(Q_TILTED)
    dt = 1 * MS
    t = 0
    for k, on_ns in enumerate((7_345_678, 12_000_001, 3_000_000)):
        start = 40 * MS * k + 123_457
        while t + dt <= start:
            w0, wm, w1 = ts.stage_wrenches(t, dt)
            s = rk4_step(s, dt * 1e-9, w0, wm, w1, mp)
            t += dt
        ts.command(start, 0, on_ns)  # delivered inside the step [t, t + dt]
    s, t = _fly(ts, s, t, dt, mp)
    momentum = math.sqrt(sum(x * x for x in linear_momentum_N(s, mp)))
    assert momentum == pytest.approx(ts.impulse_Ns[0], rel=BOOKKEEPING_REL_TOL)
    assert ts.openings == (3,)


def test_account_books_like_stage_wrenches() -> None:
    """account(t, dt) books the same impulse as stage_wrenches, step by step."""
    p = _params()
    a = ThrusterSet([_through_com()], p)
    b = ThrusterSet([_through_com()], p)
    for ts in (a, b):
        ts.command(0, 0, PULSE_NS)
    dt = MS
    for k in range(60):
        t = k * dt
        a.stage_wrenches(t, dt)
        b.account(t, dt)
        assert b.impulse_Ns == a.impulse_Ns
    assert b.impulse_Ns == pytest.approx(a.impulse_Ns, rel=REL_TOL)
    c = ThrusterSet([_through_com()], p)
    c.command(0, 0, PULSE_NS)
    for k in range(60):
        t = k * dt
        c.accumulate(dt * 1e-9, c.thrusts_N(t), c.thrusts_N(t + dt // 2), c.thrusts_N(t + dt))
    # Simpson on the instantaneous thrust (a caller sampling itself) against the exact means
    assert c.impulse_Ns == pytest.approx(a.impulse_Ns, rel=SAMPLED_SIMPSON_REL_TOL)


def test_stage_wrenches_rejects_odd_or_nonpositive_step() -> None:
    """dt_ns must be positive and even so that the midpoint is an exact nanosecond."""
    ts = ThrusterSet([_through_com()], _params())
    for dt in (0, -2, 1_000_001):
        with pytest.raises(ValueError):
            ts.stage_wrenches(0, dt)


def test_propellant_per_thruster_uses_its_own_isp() -> None:
    """propellant = impulse / (Isp g0) per thruster, with per-thruster parameters."""
    p1, p2 = _params(), _params(isp_s=300.0)
    ts = ThrusterSet([_through_com(), _through_com()], [p1, p2])
    mp = MassProperties(MASS_KG, J_FULL)
    ts.command(0, 0, PULSE_NS)
    ts.command(0, 1, 2 * PULSE_NS)
    _fly(ts, make_state(), 0, MS, mp)
    i1, i2 = ts.impulse_Ns
    assert ts.propellant_kg == pytest.approx((i1 / (ISP_S * G0_M_S2), i2 / (300.0 * G0_M_S2)))
    assert ts.total_propellant_kg == pytest.approx(sum(ts.propellant_kg), rel=REL_TOL)


# --- faults, counters, status ------------------------------------------------------------------
def test_stuck_closed_gives_zero_impulse() -> None:
    """A stuck-closed thruster books no impulse and moves nothing; its coil still counts."""
    ts = ThrusterSet([_through_com()], _params())
    mp = MassProperties(MASS_KG, J_FULL)
    ts.set_fault(0, "stuck_closed")
    ts.command(0, 0, PULSE_NS)
    s = make_state()
    for k in range(100):
        w0, wm, w1 = ts.stage_wrenches(k * MS, MS)
        s = rk4_step(s, 1e-3, w0, wm, w1, mp)
    assert ts.impulse_Ns == (0.0,)
    assert ts.propellant_kg == (0.0,)
    assert linear_momentum_N(s, mp) == (0.0, 0.0, 0.0)
    assert ts.openings == (1,)
    assert ts.status(10 * MS) == [(True, False, True)]


def test_stuck_open_gives_full_thrust() -> None:
    """A stuck-open thruster keeps full thrust after its pulse: impulse ≈ Fmax·window later on."""
    ts = ThrusterSet([_through_com()], _params())
    ts.set_fault(0, "stuck_open")
    ts.command(0, 0, PULSE_NS)
    t0 = 1_000 * MS
    for k in range(1000):
        ts.stage_wrenches(t0 + k * MS, MS)
    assert ts.impulse_Ns[0] == pytest.approx(FMAX_N * 1.0, rel=REL_TOL)
    assert ts.wrench_B(10**12)[0] == FMAX_N


def test_openings_close_all_and_status() -> None:
    """Openings count per thruster; close_all de-energises every coil at once."""
    geo = [_through_com(), ThrusterGeometry((0.0, 0.0, 0.0), (0.0, 1.0, 0.0))]
    ts = ThrusterSet(geo, _params())
    for k in range(3):
        ts.command(k * 100 * MS, 0, PULSE_NS)
    ts.command(300 * MS, 1, 10**9)
    ts.command(300 * MS, 0, 10**9)
    assert ts.openings == (4, 1)
    ts.close_all(310 * MS)
    assert [st[0] for st in ts.status(310 * MS)] == [False, False]
    assert all(st[1] for st in ts.status(311 * MS))  # closing delay: still open
    assert ts.is_idle(500 * MS)
    assert ts.wrench_B(500 * MS) == (0.0,) * 6
    assert len(ts) == 2
