"""Pulse-width pulse-frequency (PWPF) modulator, exactly discretised, and its static characteristic.

What it does: one PWPF modulator per thruster: a first-order lag filter driven by the
error between the demanded thrust fraction ``u`` and the valve state ``y ∈ {0, 1}``,
    ``ḟ = (K_m (u − y) − f) / T_m``,
followed by a Schmitt trigger: ``y`` switches on when ``f ≥ U_on`` and off when
``f ≤ U_off`` (hysteresis ``h = U_on − U_off > 0``).

Exact discretisation (:meth:`PwpfModulator.on_time_s`): over one control period ``u`` is
constant, so between trigger events ``f`` is known in closed form,
``f(t) = f_ss + (f(0) − f_ss) e^{−t/T_m}`` with ``f_ss = K_m (u − y)``; while off, the valve
switches on after ``T_m ln((f_ss − f)/(f_ss − U_on))`` (only if ``f_ss > U_on``); while on,
it switches off after ``T_m ln((f − f_ss)/(U_off − f_ss))`` (only if ``f_ss < U_off``).
The period is walked event by event (any number of switches per period) and the time with
``y = 1`` is returned; the valve pulse of that length is emitted at the start of the
period. The result does not depend on how time is cut into periods (one 20 ms period
gives the same on-time and state as ten 2 ms periods), except through the minimum
on-time rule below.

Minimum on-time rule (error diffusion of the rounding): the modulator keeps an impulse
debt ``e`` [s] = (on-time emitted so far) − (on-time the exact PWPF produced so far). In a
period where the PWPF is on for ``τ > 0``, the wanted emission is ``x = τ − e``; it is
emitted as ``min(x, P)`` if ``x ≥ min_on_s``, rounded up to ``min(min_on_s, P)`` if
``min_on_s/2 ≤ x < min_on_s``, and rounded down to 0 otherwise; then ``e`` is updated. A
period with ``τ = 0`` emits nothing (the rule never creates a pulse the PWPF did not ask
for, so the dead zone stays silent). Hence every emitted pulse is 0 or ≥ ``min_on_s`` (or
the whole period), ``|e|`` stays within about ``min_on_s/2``, and the long-run impulse
equals that of the exact PWPF: nothing is lost or gained systematically. The difference
is accounted in this debt rather than in the filter output ``f``: ``f`` is a leaky
integrator whose mean sets the duty cycle (``ȳ = u − f̄/K_m``), so pushing the rounding
error into ``f`` shifts the duty (measured +4.5 % at u = 0.3 with the parameters of the
tests), whereas the debt keeps ``f`` on its exact trajectory.

Static characteristic (constant ``u``, after the transient; the min-on rule ignored):
- dead zone: no firing for ``K_m u ≤ U_on``, i.e. ``u ≤ U_on/K_m``;
- saturation (valve stays on) for ``K_m (1 − u) + U_off ≤ 0``, i.e. ``u ≥ 1 + U_off/K_m``
  (above 1 for ``U_off > 0``: a PWPF with positive ``U_off`` never saturates at u ≤ 1);
- otherwise a limit cycle: ``f`` falls from ``U_on`` towards ``K_m (u − 1)`` while on and
  rises from ``U_off`` towards ``K_m u`` while off, so
  ``T_on = T_m ln((K_m (1 − u) + U_on) / (K_m (1 − u) + U_off))``,
  ``T_off = T_m ln((K_m u − U_off) / (K_m u − U_on))``,
  duty cycle ``T_on/(T_on + T_off)``, pulse frequency ``1/(T_on + T_off)``;
- minimum pulse (at the dead-zone edge ``K_m u = U_on``): ``Δ_min = −T_m ln(1 − h/K_m)``.

Design rule (measured on the seed-003 vehicle with sensor noise, on-off valves with a
5 ms minimum on-time; ``benchmarks/pwpf_trade.py``, docs/reproductions.md): the dead zone
``U_on/K_m`` sets the pointing of the hold (1 % of full thrust: 0.016°; 0.5 %: 0.013°), and
halving it costs about 1.5× the hold's propellant; ``h`` matters little while the minimum
pulse above is shorter than the valves' minimum on-time (the rounding rule then shapes
the limit cycle). Defaults of the scenarios: K_m 20, T_m 0.1 s, U_on 0.2, U_off 0.1.

Inputs/outputs: ``u`` thrust fraction (dimensionless; clipped to [0, 1], NaN → 0), ``period_s``
[s], on-time [s]; parameters ``km`` (dimensionless), ``tm_s`` [s], ``u_on``, ``u_off``
(dimensionless, filter-output units), ``min_on_s`` [s].

Assumptions: one-sided (unidirectional) thruster, so the demand is in [0, 1]; ``u`` constant
over a period; the valve's own delays are the bench's business. Validation requires
``0 < U_on < K_m`` (otherwise it never fires for u ≤ 1) and ``U_on − K_m < U_off < U_on``
(``h < K_m``: otherwise a pulse started at the dead-zone edge never ends).

Sources: Krøvel 2005, "Optimal Tuning of PWPF Modulator for Attitude Control", MSc
thesis, NTNU (static characteristic: dead zone, saturation, on/off times, minimum
pulse); Song & Agrawal 2001, "Vibration suppression of flexible spacecraft during
attitude control", Acta Astronautica 49(2) 73–83 (PWPF static analysis); Wie 2008, "Space
Vehicle Dynamics and Control", 2nd ed., ch. 7 (pulse modulators); seed 003 (PWPF driving
the on-off thrusters; no modulator parameters given there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mypy_extensions import mypyc_attr

from dbc import validation as check

_SOURCE = "PwpfParams"
# Minimum on-time rule: a wanted emission x with MIN_ON_ROUNDING_FRACTION × min_on_s ≤ x <
# min_on_s is rounded up to min_on_s, below that down to 0 (nearest, ties up).
MIN_ON_ROUNDING_FRACTION = 0.5


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class PwpfParams:
    """PWPF modulator parameters.

    Attributes:
        km: filter gain K_m (dimensionless, > 0).
        tm_s: filter time constant T_m [s] (> 0).
        u_on: trigger on-threshold U_on (0 < U_on < K_m).
        u_off: trigger off-threshold U_off (U_on − K_m < U_off < U_on).
        min_on_s: minimum valve on-time [s] (≥ 0; 0 disables the rule).
    """

    km: float
    tm_s: float
    u_on: float
    u_off: float
    min_on_s: float = 0.0

    def __post_init__(self) -> None:
        s = _SOURCE
        km = check.positive(s, "km", self.km)
        check.positive(s, "tm_s", self.tm_s, unit="s")
        u_on = check.number(s, "u_on", self.u_on, 0.0, km, lo_open=True,
                            hi_open=True)
        check.number(s, "u_off", self.u_off, u_on - km, u_on, lo_open=True,
                     hi_open=True)
        check.non_negative(s, "min_on_s", self.min_on_s, unit="s")

    @property
    def hysteresis(self) -> float:
        """h = U_on − U_off (> 0)."""
        return self.u_on - self.u_off


def pwpf_on_off_times_s(params: PwpfParams, u: float) -> tuple[float, float]:
    """Limit-cycle (T_on, T_off) [s] for constant ``u``; (0, inf) in the dead zone, (inf, 0)
    in saturation."""
    km, tm = params.km, params.tm_s
    if not km * u > params.u_on:
        return 0.0, math.inf
    on_floor = km * (1.0 - u) + params.u_off  # U_off − K_m (u − 1): > 0 iff the valve turns off
    if on_floor <= 0.0:
        return math.inf, 0.0
    t_on = tm * math.log((km * (1.0 - u) + params.u_on) / on_floor)
    t_off = tm * math.log((km * u - params.u_off) / (km * u - params.u_on))
    return t_on, t_off


def pwpf_duty_cycle(params: PwpfParams, u: float) -> float:
    """Static duty cycle T_on/(T_on + T_off) for constant ``u`` (0 in the dead zone)."""
    t_on, t_off = pwpf_on_off_times_s(params, u)
    if t_on == 0.0:
        return 0.0
    if t_off == 0.0:
        return 1.0
    return t_on / (t_on + t_off)


def pwpf_pulse_frequency_hz(params: PwpfParams, u: float) -> float:
    """Static pulse frequency 1/(T_on + T_off) [Hz] for constant ``u`` (0 if not pulsing)."""
    t_on, t_off = pwpf_on_off_times_s(params, u)
    if t_on == 0.0 or t_off == 0.0:
        return 0.0
    return 1.0 / (t_on + t_off)


def pwpf_min_pulse_s(params: PwpfParams) -> float:
    """Minimum (dead-zone edge) pulse width −T_m ln(1 − h/K_m) [s], before the min-on rule."""
    return -params.tm_s * math.log(1.0 - params.hysteresis / params.km)


class PwpfModulator:
    """One thruster's PWPF modulator (implements ``Modulator``)."""

    def __init__(self, params: PwpfParams) -> None:
        self._params = params
        self._f = 0.0
        self._y = False
        self._debt_s = 0.0

    @property
    def params(self) -> PwpfParams:
        """The parameters this modulator was built with."""
        return self._params

    @property
    def filter_output(self) -> float:
        """The filter state f at the end of the last period (filter-output units)."""
        return self._f

    @property
    def trigger_on(self) -> bool:
        """The Schmitt-trigger state y at the end of the last period."""
        return self._y

    @property
    def impulse_debt_s(self) -> float:
        """On-time emitted minus on-time of the exact PWPF so far [s] (min on-time rule)."""
        return self._debt_s

    def reset(self, filter_output: float = 0.0, trigger_on: bool = False) -> None:
        """Set the filter and trigger states (default: at rest, off) and clear the debt."""
        self._f = float(filter_output)
        self._y = bool(trigger_on)
        self._debt_s = 0.0

    def on_time_s(self, t_ns: int, u: float, period_s: float) -> float:
        """Valve on-time [s] for the coming period (exact event walk; ``t_ns`` unused)."""
        if not (period_s > 0.0 and math.isfinite(period_s)):
            raise ValueError(f"period_s = {period_s!r}: expected a finite number > 0")
        p = self._params
        km, tm, u_on, u_off = p.km, p.tm_s, p.u_on, p.u_off
        uc = 0.0 if not u > 0.0 else min(float(u), 1.0)  # NaN -> 0
        f, y = self._f, self._y
        t = 0.0
        on = 0.0
        while True:
            remaining = period_s - t
            if y:
                f_ss = km * (uc - 1.0)
                if f <= u_off:
                    tau = 0.0
                elif f_ss < u_off:
                    tau = tm * math.log((f - f_ss) / (u_off - f_ss))
                else:
                    tau = math.inf
            else:
                f_ss = km * uc
                if f >= u_on:
                    tau = 0.0
                elif f_ss > u_on:
                    tau = tm * math.log((f_ss - f) / (f_ss - u_on))
                else:
                    tau = math.inf
            if tau >= remaining:
                f = f_ss + (f - f_ss) * math.exp(-remaining / tm)
                if y:
                    on += remaining
                break
            if tau > 0.0:
                f = u_off if y else u_on  # the event is the threshold crossing: exact value
                if y:
                    on += tau
                t += tau
            y = not y
        self._f, self._y = f, y
        on = min(max(on, 0.0), period_s)
        min_on = p.min_on_s
        if min_on <= 0.0 or on == 0.0:
            return on
        wanted = on - self._debt_s
        if wanted >= min_on:
            emitted = min(wanted, period_s)
        elif wanted >= MIN_ON_ROUNDING_FRACTION * min_on:
            emitted = min(min_on, period_s)
        else:
            emitted = 0.0
        self._debt_s += emitted - on
        return emitted
