"""Expected-thrust model of the FDIR: pulse impulse, merging of consecutive pulses, samples."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flight_sw.fdir.thrust_model import ThrustModel
from flight_sw.fdir.valve_timing import DEFAULT_TIMING
from tests.flight_sw.thrust_model_reference import ReferenceThrustModel

N = 4
NS = 1_000_000_000
MIN_ON_S = 0.005
T = DEFAULT_TIMING  # the fdir_16thr valve data
DELAY_S, OD_S, CD_S = T.command_delay_s, T.open_delay_s, T.close_delay_s
TR_S, TT_S = T.rise_tau_s, T.tail_tau_s
HORIZON_NS = 2 * NS
IMPULSE_TOL_S = 1e-9
PERIOD_NS = 20_000_000


def model() -> ThrustModel:
    """A 4-thruster model with the fdir_16thr valve data."""
    return ThrustModel(N, MIN_ON_S, DEFAULT_TIMING, HORIZON_NS)


def pulse_thrust_time_s(on_s: float) -> float:
    """Closed form of one isolated pulse from rest (the valve model's), over T_max [s]."""
    d = max(0.0, max(on_s, MIN_ON_S) + CD_S - OD_S)
    peak = 1.0 - math.exp(-d / TR_S)
    return d - TR_S * peak + peak * TT_S


@pytest.mark.parametrize("on_s", [0.001, 0.005, 0.012, 0.02])
def test_single_pulse_thrust_time_matches_the_closed_form(on_s: float) -> None:
    """∫F/T_max of a pulse equals the valve's closed-form impulse (short pulses extended)."""
    m = model()
    on = np.zeros(N)
    on[1] = on_s
    m.command(0, on)
    tau = m.thrust_time_s(0, NS)
    assert tau[1] == pytest.approx(pulse_thrust_time_s(on_s), abs=IMPULSE_TOL_S)
    assert tau[[0, 2, 3]] == pytest.approx(0.0)


def test_window_splits_the_impulse() -> None:
    """Thrust-time over [0, t] + [t, ∞) is the whole pulse's."""
    m = model()
    on = np.full(N, 0.01)
    m.command(0, on)
    t_mid = 8_000_000
    whole = m.thrust_time_s(0, NS)
    assert m.thrust_time_s(0, t_mid) + m.thrust_time_s(t_mid, NS) == pytest.approx(whole)


def test_consecutive_full_pulses_merge_into_continuous_thrust() -> None:
    """Full-period pulses every period: no new opening, thrust ≈ T_max after the rise."""
    m = model()
    on = np.full(N, PERIOD_NS / NS)
    for k in range(10):
        m.command(k * PERIOD_NS, on)
    t = np.arange(50_000_000, 180_000_000, 5_000_000)
    frac, _ = m.fraction_at(t)
    assert frac == pytest.approx(1.0, abs=1e-6)


def test_zero_command_switches_a_pulse_off() -> None:
    """A 0 arriving during a long pulse cuts it: thrust decays from then on."""
    m = model()
    on = np.zeros(N)
    on[0] = 0.1  # 100 ms requested
    m.command(0, on)
    m.command(PERIOD_NS, np.zeros(N))
    t_cut = PERIOD_NS + round(DELAY_S * NS) + round(CD_S * NS)
    frac, _ = m.fraction_at(np.array([t_cut + 30_000_000]))
    assert frac[0, 0] < 1e-3


def test_sampled_fraction_follows_rise_and_tail() -> None:
    """Samples: 0 before opening, 1 − e^{−t/τr} while driven, exponential tail after."""
    m = model()
    on = np.zeros(N)
    on[2] = 0.01
    m.command(0, on)
    t_open = round((DELAY_S + OD_S) * NS)
    t_close = round((DELAY_S + 0.01 + CD_S) * NS)
    samples = np.array([t_open - 1, t_open + 2_000_000, t_close + 3_000_000])
    frac, rate = m.fraction_at(samples)
    peak = 1.0 - math.exp(-(t_close - t_open) / NS / TR_S)
    assert frac[:, 2] == pytest.approx([0.0, 1.0 - math.exp(-1.0), peak * math.exp(-1.0)], rel=1e-9)
    assert rate[1, 2] == pytest.approx(math.exp(-1.0) / TR_S, rel=1e-9)


def test_stuck_open_is_full_thrust() -> None:
    """A thruster known stuck open: thrust-time = window, fraction 1."""
    m = model()
    m.stuck_open[3] = True
    assert m.thrust_time_s(0, 300_000_000)[3] == pytest.approx(0.3)
    assert m.fraction_at(np.array([1, 2]))[0][:, 3] == pytest.approx(1.0)


# --- the package's float form against the array form (tests/flight_sw/thrust_model_reference.py)

# The two use different exp implementations, an ulp apart at most; the thrust-time of a
# short window subtracts two close exponentials, so its relative difference can be larger
# (8e-12 for 1 ms, whole digits for 1 ns): compared to this many seconds absolute.
EQUIVALENCE_RTOL = 1e-12
THRUST_TIME_ATOL_S = 1e-15
N_RANDOM = 16  # the fdir_16thr vehicle
RANDOM_CYCLES = 120
EDGE_GUARD_NS = 1_000_000  # 2 × the residual FDIR's edge uncertainty


def _random_on_times(rng: np.random.Generator) -> np.ndarray:
    """A PWPF-like command: most thrusters off, some short pulses, some whole periods."""
    on = np.where(rng.random(N_RANDOM) < 0.3, rng.uniform(0.0, 0.025, N_RANDOM), 0.0)
    on[rng.random(N_RANDOM) < 0.05] = PERIOD_NS / NS  # continuous firing
    return on


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_float_form_matches_the_array_form(seed: int) -> None:
    """Every query of the float model equals the array reference's after each command,
    windows long and short, with a stuck-open thruster and segments pruned (queries within
    the horizon)."""
    rng = np.random.default_rng(seed)
    horizon_ns = 300_000_000
    fast = ThrustModel(N_RANDOM, MIN_ON_S, DEFAULT_TIMING, horizon_ns)
    ref = ReferenceThrustModel(N_RANDOM, MIN_ON_S, DEFAULT_TIMING, horizon_ns)
    for k in range(RANDOM_CYCLES):
        t = k * PERIOD_NS
        on = _random_on_times(rng)
        fast.command(t, on)
        ref.command(t, on)
        if k == RANDOM_CYCLES // 2:
            fast.stuck_open[5] = ref.stuck_open[5] = True
        t_a = t - 200_000_000 + int(rng.integers(0, 10_000_000))
        for t_b in (t + int(rng.integers(0, 30_000_000)),  # a residual window
                    t_a + int(rng.integers(1, 2_000_000)),  # between two gyro samples
                    t_a - 1):  # reversed: no thrust (stuck open: negative, as before)
            np.testing.assert_allclose(fast.thrust_time_s(t_a, t_b),
                                       ref.thrust_time_s(t_a, t_b),
                                       rtol=EQUIVALENCE_RTOL, atol=THRUST_TIME_ATOL_S)
        edge_t = t + int(rng.integers(-20_000_000, 20_000_000))
        np.testing.assert_array_equal(fast.boundary_segments(edge_t, EDGE_GUARD_NS),
                                      ref.boundary_segments(edge_t, EDGE_GUARD_NS))
        samples = np.sort(rng.integers(t - 100_000_000, t + 25_000_000, 7))
        for got, want in zip(fast.fraction_at(samples), ref.fraction_at(samples), strict=True):
            np.testing.assert_allclose(got, want, rtol=EQUIVALENCE_RTOL, atol=0.0)
    assert fast.fraction_at(np.array([], dtype=np.int64))[0].shape == (0, N_RANDOM)
