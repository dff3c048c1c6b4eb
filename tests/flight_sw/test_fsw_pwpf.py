"""Tests of the PWPF modulator: static characteristic, dead zone, min on-time, exactness."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.modulation.pwpf import (
    PwpfModulator,
    PwpfParams,
    pwpf_duty_cycle,
    pwpf_min_pulse_s,
    pwpf_on_off_times_s,
    pwpf_pulse_frequency_hz,
)

PERIOD_S = 0.02  # 50 Hz control period
FINE_PERIOD_S = 0.001  # for counting pulses
KM, TM_S, U_ON, U_OFF = 4.5, 0.15, 0.45, 0.15
DEAD_ZONE_EDGE = U_ON / KM
LONG_RUN_S = 200.0
SETTLE_S = 5.0
DUTY_TOL = 1e-3  # absolute; the window cuts at most one limit cycle (≤ 0.2 s) out of 195 s
FREQUENCY_RTOL = 5e-3  # pulse counting over a 40 s window (≥ 280 pulses)
INVARIANCE_TOL = 1e-12
MIN_ON_S = 0.015  # above the 6.9 ms natural minimum pulse of these parameters
T_NS = 0


def params(min_on_s: float = 0.0, u_off: float = U_OFF) -> PwpfParams:
    """Krøvel-style parameters (K_m 4.5, T_m 0.15 s, U_on 0.45, U_off 0.15)."""
    return PwpfParams(km=KM, tm_s=TM_S, u_on=U_ON, u_off=u_off, min_on_s=min_on_s)


def run(mod: PwpfModulator, u: float, duration_s: float, period_s: float) -> np.ndarray:
    """On-times of consecutive periods at constant ``u``."""
    n = round(duration_s / period_s)
    return np.array([mod.on_time_s(T_NS, u, period_s) for _ in range(n)])


@pytest.mark.parametrize("u", [0.15, 0.3, 0.5, 0.7, 0.9, 1.0])
def test_long_run_duty_matches_static_characteristic(u: float) -> None:
    """Measured duty over a long constant-u run equals pwpf_duty_cycle."""
    on = run(PwpfModulator(params()), u, LONG_RUN_S, PERIOD_S)
    settled = on[round(SETTLE_S / PERIOD_S) :]
    measured = settled.sum() / (settled.size * PERIOD_S)
    assert abs(measured - pwpf_duty_cycle(params(), u)) <= DUTY_TOL


@pytest.mark.parametrize("u", [0.2, 0.5, 0.8])
def test_pulse_frequency_matches_static_characteristic(u: float) -> None:
    """Rising edges counted with 1 ms periods match pwpf_pulse_frequency_hz."""
    on = run(PwpfModulator(params()), u, 40.0 + SETTLE_S, FINE_PERIOD_S)
    settled = on[round(SETTLE_S / FINE_PERIOD_S) :] > 0.0
    rising = np.count_nonzero(settled[1:] & ~settled[:-1])
    measured_hz = rising / (settled.size * FINE_PERIOD_S)
    assert math.isclose(measured_hz, pwpf_pulse_frequency_hz(params(), u), rel_tol=FREQUENCY_RTOL)


def test_static_formulas_known_values() -> None:
    """T_on, T_off, duty and minimum pulse from the closed forms, evaluated by hand."""
    u = 0.5
    t_on, t_off = pwpf_on_off_times_s(params(), u)
    assert math.isclose(t_on, TM_S * math.log((KM * 0.5 + U_ON) / (KM * 0.5 + U_OFF)))
    assert math.isclose(t_off, TM_S * math.log((KM * 0.5 - U_OFF) / (KM * 0.5 - U_ON)))
    assert math.isclose(pwpf_duty_cycle(params(), u), t_on / (t_on + t_off))
    assert math.isclose(pwpf_min_pulse_s(params()), -TM_S * math.log(1 - (U_ON - U_OFF) / KM))
    assert pwpf_duty_cycle(params(), DEAD_ZONE_EDGE) == 0.0
    assert pwpf_pulse_frequency_hz(params(), 0.0) == 0.0


def test_min_pulse_is_the_pulse_at_the_dead_zone_edge() -> None:
    """From f = U_on at u = U_on/K_m the modulator emits exactly one minimum pulse."""
    mod = PwpfModulator(params())
    mod.reset(filter_output=U_ON)
    on = mod.on_time_s(T_NS, DEAD_ZONE_EDGE, 1.0)
    assert math.isclose(on, pwpf_min_pulse_s(params()), rel_tol=INVARIANCE_TOL)


def test_dead_zone_never_fires_from_rest() -> None:
    """u below U_on/K_m never fires."""
    on = run(PwpfModulator(params()), 0.95 * DEAD_ZONE_EDGE, LONG_RUN_S, PERIOD_S)
    assert np.all(on == 0.0)


def test_dead_zone_stops_firing_after_transient() -> None:
    """After firing at u = 0.5, dropping u into the dead zone stops the pulses for good."""
    mod = PwpfModulator(params())
    assert run(mod, 0.5, 2.0, PERIOD_S).sum() > 0.0
    transient_s = 10 * TM_S
    after = run(mod, 0.9 * DEAD_ZONE_EDGE, transient_s + 60.0, PERIOD_S)
    assert np.all(after[round(transient_s / PERIOD_S) :] == 0.0)


def test_saturation_keeps_valve_open() -> None:
    """With U_off < 0 and u ≥ 1 + U_off/K_m the valve stays open (duty 1)."""
    p = params(u_off=-0.1)
    assert pwpf_duty_cycle(p, 1.0) == 1.0
    on = run(PwpfModulator(p), 1.0, 10.0, PERIOD_S)
    assert np.all(on[round(SETTLE_S / PERIOD_S) :] == PERIOD_S)


@pytest.mark.parametrize("u", [0.11, 0.15, 0.3, 0.5])
def test_min_on_time_respected_without_losing_impulse(u: float) -> None:
    """Pulses are 0 or ≥ min_on_s; cumulative impulse tracks the exact PWPF within min_on_s."""
    assert pwpf_min_pulse_s(params()) < MIN_ON_S
    limited = PwpfModulator(params(min_on_s=MIN_ON_S))
    exact = PwpfModulator(params())  # same filter trajectory: the rule never touches f
    n = round(LONG_RUN_S / PERIOD_S)
    on = np.array([limited.on_time_s(T_NS, u, PERIOD_S) for _ in range(n)])
    raw = np.array([exact.on_time_s(T_NS, u, PERIOD_S) for _ in range(n)])
    assert np.all((on == 0.0) | (on >= MIN_ON_S))
    assert np.any((raw > 0.0) & (raw < MIN_ON_S))  # the rule had work to do
    assert np.max(np.abs(np.cumsum(on) - np.cumsum(raw))) <= MIN_ON_S
    assert math.isclose(limited.impulse_debt_s, on.sum() - raw.sum(), abs_tol=INVARIANCE_TOL)
    settled = on[round(SETTLE_S / PERIOD_S) :]
    measured = settled.sum() / (settled.size * PERIOD_S)
    assert abs(measured - pwpf_duty_cycle(params(), u)) <= DUTY_TOL


def test_min_on_longer_than_period_is_capped() -> None:
    """A minimum on-time above the period rounds a short pulse up to the whole period."""
    p = params(min_on_s=2 * PERIOD_S)
    mod = PwpfModulator(p)
    mod.reset(filter_output=U_ON)
    on = mod.on_time_s(T_NS, DEAD_ZONE_EDGE, PERIOD_S)
    assert on in (0.0, PERIOD_S)


def test_exact_discretisation_is_invariant_to_period_splitting(rng: np.random.Generator) -> None:
    """One 20 ms period and ten 2 ms periods give the same on-time and filter state."""
    coarse = PwpfModulator(params())
    fine = PwpfModulator(params())
    n_sub = 10
    for u in rng.uniform(0.0, 1.0, 2000):
        on_coarse = coarse.on_time_s(T_NS, float(u), PERIOD_S)
        on_fine = sum(fine.on_time_s(T_NS, float(u), PERIOD_S / n_sub) for _ in range(n_sub))
        assert abs(on_coarse - on_fine) <= INVARIANCE_TOL
        assert abs(coarse.filter_output - fine.filter_output) <= INVARIANCE_TOL
        assert coarse.trigger_on == fine.trigger_on


def test_input_is_clipped_and_output_bounded() -> None:
    """u outside [0, 1] is clipped, NaN counts as 0, on-time stays in [0, period]."""
    mod = PwpfModulator(params())
    for u in (-3.0, 7.0, float("nan"), 1.0, 0.0):
        on = mod.on_time_s(T_NS, u, PERIOD_S)
        assert 0.0 <= on <= PERIOD_S
    fresh = PwpfModulator(params())
    assert fresh.on_time_s(T_NS, float("nan"), PERIOD_S) == 0.0
    with pytest.raises(ValueError):
        fresh.on_time_s(T_NS, 0.5, 0.0)


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"km": 0.0}, "km"),
        ({"tm_s": -1.0}, "tm_s"),
        ({"u_on": KM}, "u_on"),
        ({"u_off": U_ON}, "u_off"),
        ({"u_off": U_ON - KM}, "u_off"),
        ({"min_on_s": -0.001}, "min_on_s"),
        ({"km": float("nan")}, "km"),
    ],
)
def test_params_validate(kwargs: dict[str, float], key: str) -> None:
    """Invalid parameters raise ConfigError naming the key."""
    base: dict[str, float] = {"km": KM, "tm_s": TM_S, "u_on": U_ON, "u_off": U_OFF}
    with pytest.raises(ConfigError) as info:
        PwpfParams(**{**base, **kwargs})
    assert info.value.key == key
