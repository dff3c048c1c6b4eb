"""Physical effect of every thruster and sensor fault (DESIGN.md §7), with named tolerances."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from bench.station.dynamics.rigid_body import (
    MassProperties,
    Quat,
    Vec3,
    linear_momentum_N,
    make_state,
    quat_conjugate,
    quat_multiply,
    quat_normalize,
    rk4_step,
)
from bench.station.sensors.accelerometer import Accelerometer, AccelerometerParams
from bench.station.sensors.gyro import Gyro, GyroParams, InertialSensor, SensorOutageError
from bench.station.sensors.star_tracker import RAD_PER_ARCSEC, StarTracker, StarTrackerParams
from bench.station.valves.params import (
    HISTORY_NS,
    NEVER_NS,
    OPEN_THRESHOLD_FRACTION,
    THRUST_CUTOFF_FRACTION,
    ValveParams,
)
from bench.station.valves.thruster_set import G0_M_S2, ThrusterGeometry, ThrusterSet
from bench.station.valves.valve import Valve
from dbc.errors import ConfigError
from tests.bench.station.thrust_reference import MEAN_REL_TOL, step_mean_reference_N

SEED = 20240611
MS = 1_000_000  # ns per millisecond
NS_PER_S = 1_000_000_000
DT_NS = MS  # 1 kHz plant step
FMAX_N = 22.0
ISP_S = 220.0
OPEN_DELAY_S = 0.003
CLOSE_DELAY_S = 0.004
# Valve time constants for which 1 kHz Simpson reproduces the closed-form pulse impulse
# to 1e-6 (see test_thruster_set.test_pulse_impulse_through_rk4_matches_closed_form).
RISE_TAU_S = 0.004
TAIL_TAU_S = 0.006
MIN_ON_S = 0.005
PULSE_NS = 20 * MS
PULSE_PERIOD_NS = 250 * MS  # the tail is < 1e-14·Fmax before the next pulse: isolated
MASS_KG = 50.0
J_FULL = ((5.0, 0.1, 0.0), (0.1, 6.0, 0.2), (0.0, 0.2, 7.0))

ROUNDOFF_REL = 1e-12  # relations that hold exactly up to floating-point round-off
IMPULSE_REL_TOL = 1e-6  # 1 kHz Simpson booking against a closed-form impulse
ANGLE_TOL_DEG = 1e-9
# Statistics: a binomial fraction within 5σ = 5·√(p(1−p)/N); a mean of N normals within
# 5σ/√N; a sample standard deviation within 5σ/√(2N) (false-failure odds ~1e-6; the
# seeds are fixed anyway).
N_SIGMA = 5.0
N_PULSES = 4000
N_SAMPLES = 20_000
MEAN_TOL_FRACTION = N_SIGMA / math.sqrt(N_SAMPLES)
STD_REL_TOL = N_SIGMA / math.sqrt(2.0 * N_SAMPLES)


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


def _through_com() -> ThrusterGeometry:
    """A thruster behind the centre of mass pushing along +x_B: no torque."""
    return ThrusterGeometry((-0.5, 0.0, 0.0), (1.0, 0.0, 0.0))


def _book(ts: ThrusterSet, t0_ns: int, t1_ns: int) -> None:
    """Book the impulse of [t0, t1] in 1 kHz steps (the plant's stage_wrenches calls)."""
    for t in range(t0_ns, t1_ns, DT_NS):
        ts.stage_wrenches(t, DT_NS)


def _pulse_train(ts: ThrusterSet, n: int, t0_ns: int = 0) -> int:
    """Fire ``n`` isolated 20 ms pulses of thruster 0 from ``t0_ns``, booking every step.

    Returns the end time.
    """
    t = t0_ns
    for _ in range(n):
        ts.command(t, 0, PULSE_NS)
        _book(ts, t, t + PULSE_PERIOD_NS)
        t += PULSE_PERIOD_NS
    return t


def _angle_deg(a: Vec3, b: Vec3) -> float:
    """Angle between two vectors [deg] (atan2 form: accurate for small angles)."""
    cx = a[1] * b[2] - a[2] * b[1]
    cy = a[2] * b[0] - a[0] * b[2]
    cz = a[0] * b[1] - a[1] * b[0]
    dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    return math.degrees(math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), dot))


# --- degraded ------------------------------------------------------------------------------------
def test_degraded_half_gives_half_the_pulse_impulse() -> None:
    """degraded factor 0.5: booked impulse = 0.5 × pulse_impulse_Ns (1e-6) = m·Δv (1e-12)."""
    factor = 0.5
    p = _params()
    ts = ThrusterSet([_through_com()], p)
    ts.set_fault(0, "degraded", 0, factor=factor)
    mp = MassProperties(MASS_KG, J_FULL)
    s = make_state()
    ts.command(0, 0, PULSE_NS)
    t = 0
    while not ts.is_idle(t):
        w0, wm, w1 = ts.stage_wrenches(t, DT_NS)
        s = rk4_step(s, DT_NS / NS_PER_S, w0, wm, w1, mp)
        t += DT_NS
    expected = factor * Valve.pulse_impulse_Ns(p, PULSE_NS / NS_PER_S)
    assert ts.impulse_Ns[0] == pytest.approx(expected, rel=IMPULSE_REL_TOL)
    assert linear_momentum_N(s, mp)[0] == pytest.approx(ts.impulse_Ns[0], rel=ROUNDOFF_REL)
    assert ts.propellant_kg[0] == pytest.approx(
        ts.impulse_Ns[0] / (ISP_S * G0_M_S2), rel=ROUNDOFF_REL
    )


def test_degraded_scales_thrust_exactly_and_clearing_restores_it() -> None:
    """Mid-pulse degradation scales the thrust at once; clearing gives the nominal thrust back."""
    nominal, faulty = Valve(_params()), Valve(_params())
    for v in (nominal, faulty):
        v.command(0, 60 * MS)
    faulty.set_fault("degraded", 10 * MS, factor=0.25)
    for t in range(10 * MS, 40 * MS, MS // 3):
        assert faulty.thrust_N(t) == pytest.approx(0.25 * nominal.thrust_N(t), rel=ROUNDOFF_REL)
    assert faulty.status(30 * MS) == (True, True, True)  # 0.25 Fmax > 10 %: open
    faulty.clear_fault("degraded", 40 * MS)
    for t in range(40 * MS, 120 * MS, MS // 3):
        assert faulty.thrust_N(t) == pytest.approx(nominal.thrust_N(t), rel=ROUNDOFF_REL)
    assert faulty.fault is None


# --- leak ----------------------------------------------------------------------------------------
def test_leak_impulse_is_thrust_times_duration() -> None:
    """A leak of L newtons over T seconds books L·T of impulse and its propellant, uncommanded."""
    leak_N, duration_ns = 0.3, 2_000 * MS
    ts = ThrusterSet([_through_com()], _params())
    ts.set_fault(0, "leak", 0, thrust_N=leak_N)
    _book(ts, 0, duration_ns)
    expected = leak_N * duration_ns / NS_PER_S
    assert ts.impulse_Ns[0] == pytest.approx(expected, rel=ROUNDOFF_REL)
    assert ts.propellant_kg[0] == pytest.approx(expected / (ISP_S * G0_M_S2), rel=ROUNDOFF_REL)
    assert ts.wrench_B(duration_ns)[0] == pytest.approx(leak_N, rel=ROUNDOFF_REL)
    assert not ts.is_idle(duration_ns)
    assert ts.status(duration_ns) == [(False, False, False)]  # below 10 % Fmax: not open


def test_leak_adds_to_a_pulse_and_clearing_stops_it() -> None:
    """Pulse + leak: impulse = pulse_impulse_Ns + L·T; after clearing the valve goes idle."""
    leak_N = 0.5
    p = _params()
    ts = ThrusterSet([_through_com()], p)
    ts.set_fault(0, "leak", 0, thrust_N=leak_N)
    t_end = _pulse_train(ts, 1)
    expected = Valve.pulse_impulse_Ns(p, PULSE_NS / NS_PER_S) + leak_N * t_end / NS_PER_S
    assert ts.impulse_Ns[0] == pytest.approx(expected, rel=IMPULSE_REL_TOL)
    ts.clear_fault(0, "leak", t_end)
    assert ts.valves[0].thrust_N(t_end) == 0.0
    assert ts.is_idle(t_end)
    assert ts.faults_active == {}


# --- delayed -------------------------------------------------------------------------------------
def test_delayed_shifts_the_opening_by_the_extra_delay() -> None:
    """extra_delay_s: no thrust until open_delay + extra, then the nominal rise from there."""
    extra_s = 0.007
    v = Valve(_params())
    v.set_fault("delayed", 0, extra_delay_s=extra_s)
    v.command(0, 30 * MS)
    t_open = round((OPEN_DELAY_S + extra_s) * NS_PER_S)
    assert v.thrust_N(t_open - 1) == 0.0
    assert v.status(t_open - 1) == (True, False, True)
    for dt in (1, MS // 2, 2 * MS, 5 * MS):
        rise = -math.expm1(-dt / NS_PER_S / RISE_TAU_S)
        assert v.thrust_N(t_open + dt) == pytest.approx(FMAX_N * rise, rel=ROUNDOFF_REL)
    assert v.faults_active == {"delayed": {"extra_delay_s": extra_s}}


def test_delayed_pulse_impulse_and_clearing_restores_the_nominal_delay() -> None:
    """A delayed pulse books the closed-form impulse of a longer open delay; cleared: nominal."""
    extra_s = 0.004
    p = _params()
    ts = ThrusterSet([_through_com()], p)
    ts.set_fault(0, "delayed", 0, extra_delay_s=extra_s)
    t_end = _pulse_train(ts, 1)
    slow = dataclasses.replace(p, open_delay_s=OPEN_DELAY_S + extra_s)
    delayed_impulse = Valve.pulse_impulse_Ns(slow, PULSE_NS / NS_PER_S)
    assert ts.impulse_Ns[0] == pytest.approx(delayed_impulse, rel=IMPULSE_REL_TOL)
    ts.clear_fault(0, "delayed", t_end)
    _pulse_train(ts, 1, t_end)
    nominal_impulse = Valve.pulse_impulse_Ns(p, PULSE_NS / NS_PER_S)
    assert ts.impulse_Ns[0] - delayed_impulse == pytest.approx(nominal_impulse, rel=IMPULSE_REL_TOL)
    assert ts.faults_active == {}


# --- intermittent --------------------------------------------------------------------------------
def test_intermittent_dropout_fraction_matches_probability() -> None:
    """Over 4000 pulses the dropped fraction is p ± 5σ (binomial), reproducible from the seed."""
    p_drop = 0.25
    counts = []
    for _ in range(2):
        v = Valve(_params(), np.random.default_rng(SEED))
        v.set_fault("intermittent", 0, dropout_probability=p_drop)
        for k in range(N_PULSES):
            v.command(k * PULSE_PERIOD_NS, PULSE_NS)
        counts.append(v.dropped_pulses)
    tol = N_SIGMA * math.sqrt(p_drop * (1.0 - p_drop) / N_PULSES)
    assert abs(counts[0] / N_PULSES - p_drop) <= tol
    assert counts[0] == counts[1]
    assert v.openings == N_PULSES


def test_intermittent_dropped_pulse_has_current_but_no_thrust() -> None:
    """A dropped pulse: coil energised and current, not open, zero thrust and impulse."""
    ts = ThrusterSet([_through_com()], _params())
    ts.set_fault(0, "intermittent", 0, dropout_probability=1.0, rng=np.random.default_rng(SEED))
    ts.command(0, 0, PULSE_NS)
    _book(ts, 0, PULSE_PERIOD_NS)
    assert ts.status(10 * MS) == [(True, False, True)]
    assert ts.impulse_Ns == (0.0,)
    assert ts.dropped_pulses == (1,)
    assert ts.openings == (1,)


def test_intermittent_impulse_counts_only_the_pulses_that_fired() -> None:
    """Booked impulse = (pulses − dropped) × pulse_impulse_Ns; set-level rng seeds each valve."""
    n, p_drop = 120, 0.4
    p = _params()
    ts = ThrusterSet([_through_com()], p, rng=np.random.default_rng(SEED))
    ts.set_fault(0, "intermittent", 0, dropout_probability=p_drop)
    _pulse_train(ts, n)
    fired = n - ts.dropped_pulses[0]
    assert 0 < fired < n
    expected = fired * Valve.pulse_impulse_Ns(p, PULSE_NS / NS_PER_S)
    assert ts.impulse_Ns[0] == pytest.approx(expected, rel=IMPULSE_REL_TOL)


def test_intermittent_clearing_stops_dropouts_and_needs_a_generator() -> None:
    """After clearing, no pulse is dropped; without any generator the fault is a ConfigError."""
    v = Valve(_params(), np.random.default_rng(SEED))
    v.set_fault("intermittent", 0, dropout_probability=1.0)
    v.command(0, PULSE_NS)
    v.clear_fault("intermittent", 5 * MS)  # the pulse in progress may now open
    assert v.thrust_N(15 * MS) > OPEN_THRESHOLD_FRACTION * FMAX_N
    for k in range(1, 50):
        v.command(k * PULSE_PERIOD_NS, PULSE_NS)
    assert v.dropped_pulses == 1
    with pytest.raises(ConfigError) as exc:
        Valve(_params()).set_fault("intermittent", dropout_probability=0.1)
    assert exc.value.key == "rng"


# --- stuck -------------------------------------------------------------------------------------
def test_stuck_status_flags() -> None:
    """stuck_open: open with the coil off; stuck_closed: coil and current but not open."""
    ts = ThrusterSet([_through_com(), _through_com()], _params())
    ts.set_fault(0, "stuck_open", 0)
    ts.set_fault(1, "stuck_closed", 0)
    ts.command(0, 0, PULSE_NS)
    ts.command(0, 1, 2_000 * MS)
    assert ts.status(1_000 * MS) == [(False, True, False), (True, False, True)]
    ts.set_fault(1, "stuck_open", 1_000 * MS)  # replaces stuck_closed
    assert ts.faults_active == {0: {"stuck_open": {}}, 1: {"stuck_open": {}}}
    assert ts.status(1_500 * MS)[1] == (True, True, True)


# --- misaligned --------------------------------------------------------------------------------
def test_misalignment_rotates_the_torque_by_the_angle() -> None:
    """Rotating d about an axis parallel to r rotates τ = r × F by the same angle, |τ| kept."""
    angle_deg = 5.0
    ts = ThrusterSet([ThrusterGeometry((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))], _params())
    ts.command(0, 0, 10**12)
    t = 10**10
    nominal = ts.wrench_B(t)
    ts.set_fault(0, "misaligned", t, angle_deg=angle_deg, axis_B=(1.0, 0.0, 0.0))
    faulty = ts.wrench_B(t)
    assert _angle_deg(nominal[3:], faulty[3:]) == pytest.approx(angle_deg, abs=ANGLE_TOL_DEG)
    assert _angle_deg(nominal[:3], faulty[:3]) == pytest.approx(angle_deg, abs=ANGLE_TOL_DEG)
    a = math.radians(angle_deg)
    assert faulty[3:] == pytest.approx((0.0, -FMAX_N * math.sin(a), FMAX_N * math.cos(a)))
    ts.clear_fault(0, "misaligned", t)
    assert ts.wrench_B(t) == nominal


def test_misalignment_about_any_axis_changes_force_and_torque_rows() -> None:
    """Force rotated by the angle about the axis (component along it kept); τ = r × F'."""
    angle_deg, axis = 7.0, (0.0, 0.6, 0.8)
    r = (0.3, 0.2, -0.5)
    ts = ThrusterSet([ThrusterGeometry(r, (1.0, 0.0, 0.0))], _params())
    ts.set_fault(0, "misaligned", 0, angle_deg=angle_deg, axis_B=axis)
    ts.command(0, 0, 10**12)
    t = 10**10
    fx, fy, fz, tx, ty, tz = ts.wrench_B(t)
    f = (fx, fy, fz)
    along = sum(fi * ai for fi, ai in zip(f, axis, strict=True))
    assert along == pytest.approx(0.0, abs=ROUNDOFF_REL * FMAX_N)  # d ⊥ axis here
    perp_nominal = (FMAX_N, 0.0, 0.0)
    assert _angle_deg(perp_nominal, f) == pytest.approx(angle_deg, abs=ANGLE_TOL_DEG)
    expected_tau = (r[1] * fz - r[2] * fy, r[2] * fx - r[0] * fz, r[0] * fy - r[1] * fx)
    assert (tx, ty, tz) == pytest.approx(expected_tau, rel=ROUNDOFF_REL)
    assert ts.faults_active == {0: {"misaligned": {"angle_deg": angle_deg, "axis_B": axis}}}
    ts.set_fault(0, None, t)  # legacy clear-all also restores the geometry
    assert ts.effective_geometries == ts.geometries


# --- combinations and bookkeeping -----------------------------------------------------------
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_faults_keep_stage_thrusts_and_bookkeeping_exact(seed: int) -> None:
    """Random pulses and fault events: stage thrusts = the step's mean thrust; impulse = m·Δv."""
    rng = np.random.default_rng(seed)
    ts = ThrusterSet([_through_com()], _params(rise_tau_s=0.002, tail_tau_s=0.004), rng=rng)
    v = ts.valves[0]
    mp = MassProperties(MASS_KG, J_FULL)
    s = make_state()
    kinds = {
        "degraded": lambda: {"factor": float(rng.uniform(0.0, 1.0))},
        "leak": lambda: {"thrust_N": float(rng.uniform(0.01, 1.0))},
        "delayed": lambda: {"extra_delay_s": float(rng.uniform(0.0, 0.01))},
        "intermittent": lambda: {"dropout_probability": 0.3},
        "stuck_open": dict,
        "stuck_closed": dict,
    }
    names = sorted(kinds)
    t, next_cmd = 0, 0
    while t < 1_500 * MS:
        if t >= next_cmd:
            at = t + int(rng.integers(0, DT_NS))
            ts.command(at, 0, int(rng.integers(0, 25 * MS)))
            kind = names[int(rng.integers(len(names)))]
            at2 = at + int(rng.integers(0, DT_NS // 4))  # a second event in the same step
            if kind in v.faults_active and rng.random() < 0.5:
                ts.clear_fault(0, kind, at2)
            elif rng.random() < 0.6:
                ts.set_fault(0, kind, at2, **kinds[kind]())
            next_cmd = at + int(rng.integers(0, 40 * MS))
        got = v.stage_thrusts_N(t, DT_NS)
        want = step_mean_reference_N(v, t, DT_NS)
        assert got[0] == got[1] == got[2]
        assert got[0] == pytest.approx(want, rel=MEAN_REL_TOL, abs=THRUST_CUTOFF_FRACTION * FMAX_N)
        assert min(got) >= 0.0
        w0, wm, w1 = ts.stage_wrenches(t, DT_NS)
        s = rk4_step(s, DT_NS / NS_PER_S, w0, wm, w1, mp)
        t += DT_NS
    assert linear_momentum_N(s, mp)[0] == pytest.approx(ts.impulse_Ns[0], rel=ROUNDOFF_REL)


def test_events_inside_one_step_keep_the_step_start_valid() -> None:
    """Several events inside a step: the thrust at the step start is still the pre-event
    thrust, and the step's stage samples are its mean thrust over the events."""
    v = Valve(_params())
    v.command(0, 50 * MS)
    t = 20 * MS
    before = v.thrust_N(t)
    v.command(t + 300_000, 10 * MS)
    v.set_fault("degraded", t + 400_000, factor=0.5)
    v.command(t + 500_000, 10 * MS)
    assert v.thrust_N(t) == before
    got = v.stage_thrusts_N(t, DT_NS)
    assert got[0] == pytest.approx(step_mean_reference_N(v, t, DT_NS), rel=MEAN_REL_TOL)
    assert DT_NS <= HISTORY_NS


def test_faults_combine() -> None:
    """degraded + leak + delayed on one valve: thrust = leak + factor·(nominal delayed rise)."""
    factor, leak_N, extra_s = 0.5, 0.2, 0.002
    v = Valve(_params())
    v.set_fault("degraded", 0, factor=factor)
    v.set_fault("leak", 0, thrust_N=leak_N)
    v.set_fault("delayed", 0, extra_delay_s=extra_s)
    v.command(0, 30 * MS)
    t_open = round((OPEN_DELAY_S + extra_s) * NS_PER_S)
    assert v.thrust_N(t_open) == pytest.approx(leak_N, rel=ROUNDOFF_REL)
    dt = 3 * MS
    rise = -math.expm1(-dt / NS_PER_S / RISE_TAU_S)
    assert v.thrust_N(t_open + dt) == pytest.approx(
        leak_N + factor * FMAX_N * rise, rel=ROUNDOFF_REL
    )
    assert v.fault == "degraded+leak+delayed"
    v.set_fault(None, 100 * MS)
    assert v.faults_active == {}
    assert v.idle_from_ns < NEVER_NS


@pytest.mark.parametrize(
    ("kind", "params", "key"),
    [
        ("degraded", {"factor": 1.5}, "factor"),
        ("degraded", {}, "factor"),
        ("delayed", {"extra_delay_s": -0.001}, "extra_delay_s"),
        ("intermittent", {"dropout_probability": math.nan}, "dropout_probability"),
        ("leak", {"thrust_N": 0.0}, "thrust_N"),
        ("leak", {"thrust_N": 2 * FMAX_N}, "thrust_N"),
        ("leak", {"thrust_N": 0.1, "angle_deg": 3.0}, "angle_deg"),
        ("stuck_open", {"factor": 0.5}, "factor"),
        ("misaligned", {"angle_deg": 200.0, "axis_B": (1.0, 0.0, 0.0)}, "angle_deg"),
        ("misaligned", {"angle_deg": 2.0, "axis_B": (1.0, 1.0, 0.0)}, "axis_B"),
        ("misaligned", {"angle_deg": 2.0}, "axis_B"),
        ("jammed", {}, "kind"),
    ],
)
def test_bad_thruster_fault_parameters_are_config_errors(
    kind: str, params: dict[str, object], key: str
) -> None:
    """Bad kinds or parameters raise ConfigError naming the key (and nothing changes)."""
    ts = ThrusterSet([_through_com()], _params())
    with pytest.raises(ConfigError) as exc:
        ts.set_fault(0, kind, 0, **params)
    assert exc.value.key == key
    assert ts.faults_active == {}
    with pytest.raises(ConfigError) as exc:
        ts.set_fault(1, "stuck_open", 0)
    assert exc.value.key == "index"


# --- inertial sensors ----------------------------------------------------------------------------
PERIOD_NS = 5_000_000
PERIOD_S = PERIOD_NS / NS_PER_S
TRUTH = (0.01, -0.02, 0.03)
WHITE = 1e-4  # ARW [rad/√s] or VRW [m/s/√s]
BIAS = (1e-4, -2e-4, 3e-4)
JUMP = (2e-3, -1e-3, 5e-4)


def _inertial(kind: str, seed: int = SEED) -> tuple[InertialSensor, str]:
    """A gyro or an accelerometer with white noise and bias, and its bias-jump key."""
    rng = np.random.default_rng(seed)
    if kind == "gyro":
        return Gyro(GyroParams(BIAS, 0.0, WHITE, period_s=PERIOD_S), rng), "jump_rad_s"
    return (
        Accelerometer(AccelerometerParams(BIAS, WHITE, period_s=PERIOD_S), rng),
        "jump_m_s2",
    )


def _errors(sensor: InertialSensor, k0: int, n: int) -> np.ndarray:
    return np.array([sensor.sample(k * PERIOD_NS, TRUTH) for k in range(k0, k0 + n)]) - TRUTH


SENSORS = ["gyro", "accelerometer"]


@pytest.mark.parametrize("name", SENSORS)
def test_bias_jump_shifts_the_mean_by_the_jump(name: str) -> None:
    """After bias_jump the mean error is bias + jump (5σ/√N); clearing returns it to the bias."""
    sensor, key = _inertial(name)
    sigma = WHITE / math.sqrt(PERIOD_S)
    sensor.set_fault("bias_jump", 0, **{key: JUMP})
    err = _errors(sensor, 0, N_SAMPLES)
    expected = np.array(BIAS) + np.array(JUMP)
    assert np.all(np.abs(err.mean(axis=0) - expected) <= MEAN_TOL_FRACTION * sigma)
    assert sensor.faults_active == {"bias_jump": {key: JUMP}}
    sensor.clear_fault("bias_jump", N_SAMPLES * PERIOD_NS)
    err = _errors(sensor, N_SAMPLES, N_SAMPLES)
    assert np.all(np.abs(err.mean(axis=0) - np.array(BIAS)) <= MEAN_TOL_FRACTION * sigma)


@pytest.mark.parametrize("name", SENSORS)
def test_frozen_repeats_exactly_and_clearing_resumes_the_same_sequence(name: str) -> None:
    """Frozen: every sample equals the last one before the fault; cleared: as if never frozen."""
    sensor, _key = _inertial(name)
    twin, _ = _inertial(name)
    n_before, n_frozen, n_after = 10, 50, 10
    last = None
    for k in range(n_before):
        last = sensor.sample(k * PERIOD_NS, TRUTH)
        twin.sample(k * PERIOD_NS, TRUTH)
    sensor.set_fault("frozen", n_before * PERIOD_NS)
    for k in range(n_before, n_before + n_frozen):
        assert sensor.measure(k * PERIOD_NS, (1.0, 2.0, 3.0)) == (last, True)
        twin.sample(k * PERIOD_NS, TRUTH)
    sensor.clear_fault("frozen", (n_before + n_frozen) * PERIOD_NS)
    for k in range(n_before + n_frozen, n_before + n_frozen + n_after):
        assert sensor.sample(k * PERIOD_NS, TRUTH) == twin.sample(k * PERIOD_NS, TRUTH)


@pytest.mark.parametrize("name", SENSORS)
def test_outage_makes_samples_invalid(name: str) -> None:
    """Outage: sample raises SensorOutageError; measure gives (last valid, False); clear: valid."""
    sensor, _key = _inertial(name)
    last = sensor.sample(0, TRUTH)
    sensor.set_fault("outage", PERIOD_NS)
    with pytest.raises(SensorOutageError) as exc:
        sensor.sample(PERIOD_NS, TRUTH)
    assert exc.value.last_output == last
    assert sensor.measure(2 * PERIOD_NS, TRUTH) == (last, False)
    sensor.clear_fault("outage", 3 * PERIOD_NS)
    out, valid = sensor.measure(3 * PERIOD_NS, TRUTH)
    assert valid
    assert out != last


@pytest.mark.parametrize("name", SENSORS)
def test_noise_factor_scales_sigma(name: str) -> None:
    """noise factor 3: the white-noise σ is 3× nominal (5σ/√(2N)); cleared: nominal again."""
    factor = 3.0
    sensor, _key = _inertial(name)
    sigma = WHITE / math.sqrt(PERIOD_S)
    sensor.set_fault("noise", 0, factor=factor)
    err = _errors(sensor, 0, N_SAMPLES)
    assert np.all(np.abs(err.std(axis=0, ddof=1) / (factor * sigma) - 1.0) <= STD_REL_TOL)
    sensor.set_fault(None, N_SAMPLES * PERIOD_NS)
    err = _errors(sensor, N_SAMPLES, N_SAMPLES)
    assert np.all(np.abs(err.std(axis=0, ddof=1) / sigma - 1.0) <= STD_REL_TOL)
    assert sensor.faults_active == {}


@pytest.mark.parametrize(
    ("kind", "params", "key"),
    [
        ("noise", {"factor": -1.0}, "factor"),
        ("noise", {}, "factor"),
        ("bias_jump", {"jump_rad_s": (1.0, 2.0)}, "jump_rad_s"),
        ("bias_jump", {"jump_m_s2": (1.0, 2.0, 3.0)}, "jump_m_s2"),
        ("frozen", {"factor": 2.0}, "factor"),
        ("stuck", {}, "kind"),
    ],
)
def test_bad_gyro_fault_parameters_are_config_errors(
    kind: str, params: dict[str, object], key: str
) -> None:
    """Bad sensor fault kinds or parameters raise ConfigError naming the key."""
    gyro, _key = _inertial("gyro")
    with pytest.raises(ConfigError) as exc:
        gyro.set_fault(kind, None, **params)
    assert exc.value.key == key
    assert gyro.faults_active == {}


def test_sensor_fault_events_must_not_precede_the_last_sample() -> None:
    """A fault event before the last sample is out of time order (ValueError)."""
    gyro, _key = _inertial("gyro")
    gyro.sample(10 * PERIOD_NS, TRUTH)
    with pytest.raises(ValueError):
        gyro.set_fault("frozen", 9 * PERIOD_NS)


# --- star tracker --------------------------------------------------------------------------------
Q_TRUE = quat_normalize((0.3, -0.6, 0.2, 0.7))


def _error_arcsec(q_true: Quat, q_meas: Quat) -> Vec3:
    """Body-axes rotation vector θ [arcsec] with q_meas = q_true ⊗ exp(θ/2)."""
    d = quat_multiply(quat_conjugate(q_true), q_meas)
    if d[0] < 0.0:
        d = (-d[0], -d[1], -d[2], -d[3])
    vn = math.sqrt(d[1] ** 2 + d[2] ** 2 + d[3] ** 2)
    k = 2.0 * math.atan2(vn, d[0]) / vn / RAD_PER_ARCSEC if vn > 0.0 else 0.0
    return (k * d[1], k * d[2], k * d[3])


def test_star_tracker_bias_jump_rotates_the_output_by_the_misalignment() -> None:
    """Noiseless tracker with bias_jump β: the output error rotation vector is β [arcsec]."""
    beta = (20.0, -10.0, 30.0)
    st = StarTracker(StarTrackerParams(), np.random.default_rng(SEED))
    st.set_fault("bias_jump", 0, misalignment_arcsec=beta)
    q, valid = st.sample(0, Q_TRUE)
    assert valid
    assert _error_arcsec(Q_TRUE, q) == pytest.approx(beta, abs=ANGLE_TOL_DEG * 3600.0)
    st.clear_fault("bias_jump", 1)
    q, _valid = st.sample(1, Q_TRUE)
    assert _error_arcsec(Q_TRUE, q) == pytest.approx((0.0, 0.0, 0.0), abs=ANGLE_TOL_DEG * 3600.0)


def test_star_tracker_noise_factor_scales_sigma() -> None:
    """noise factor 4: the about-boresight error σ is 4× nominal (5σ/√(2N))."""
    factor, about = 4.0, 40.0
    st = StarTracker(StarTrackerParams(0.0, about), np.random.default_rng(SEED))
    st.set_fault("noise", 0, factor=factor)
    theta_z = np.array(
        [_error_arcsec(Q_TRUE, st.sample(k, Q_TRUE)[0])[2] for k in range(N_SAMPLES)]
    )
    assert abs(theta_z.std(ddof=1) / (factor * about) - 1.0) <= STD_REL_TOL


def test_star_tracker_frozen_and_outage() -> None:
    """Frozen repeats the last output as valid; outage (fault or set_outage) flags it invalid."""
    st = StarTracker(StarTrackerParams(5.0, 20.0), np.random.default_rng(SEED))
    last, _valid = st.sample(0, Q_TRUE)
    st.set_fault("frozen", 1)
    assert st.sample(1, quat_normalize((0.1, 0.9, 0.0, 0.0))) == (last, True)
    st.set_fault("outage", 2)
    assert st.outage
    assert st.sample(2, Q_TRUE) == (last, False)
    st.set_outage(False)
    assert st.faults_active == {"frozen": {}}
    st.clear_fault("frozen", 3)
    q, valid = st.sample(3, Q_TRUE)
    assert valid
    assert q != last
    with pytest.raises(ConfigError) as exc:
        st.set_fault("bias_jump", misalignment_arcsec=(1.0, math.inf, 0.0))
    assert exc.value.key == "misalignment_arcsec"


def test_stuck_open_on_an_idle_valve_fails_open_after_the_opening_delay() -> None:
    """A closed, idle valve that sticks open starts thrusting one opening delay later."""
    p = _params()
    v = Valve(p)
    t_fault = 1_000_000_000
    v.set_fault("stuck_open", t_fault)
    t_open = t_fault + round(p.open_delay_s * 1e9)
    assert v.thrust_N(t_open) == 0.0
    assert v.thrust_N(t_open + 20 * round(p.rise_tau_s * 1e9)) == pytest.approx(p.max_thrust_N)
    assert v.status(t_open + 20 * round(p.rise_tau_s * 1e9))[1]  # reported open
