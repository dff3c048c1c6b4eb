"""Thruster FDIR from the acceleration residual: commanded vs observed (gyro, accelerometer).

What it does: over a sliding window ``[t_a, t_b]`` of length ``window_s`` (re-evaluated
every control cycle) it compares
- the observed change of body rate ``Δω_meas = ω(t_b) − ω(t_a)`` (two gyro samples; the
  gyro bias cancels) with the change predicted from the on-times the flight software
  commanded, ``Δω_pred = J⁻¹ Σ_i (r_i × d_i) T_max,i τ_i − J⁻¹ (ω̄ × J ω̄)(t_b − t_a)``
  (Euler's equation, nominal inertia J, ω̄ the mean measured rate, ``T_max,i`` thruster i's
  own maximum thrust), τ_i = ∫ F_i/T_max,i dt over the window from the expected thrust
  history;
- the observed velocity change ``Δv_meas = Σ_s (f_s − b̂) Δt`` (the accelerometer samples
  in (t_a, t_b], b̂ the estimated accelerometer bias) with the same sum over the expected
  thrust at each sample time, ``f_pred(t_s) = Σ_i d_i F_i(t_s)/m`` (sampled
  like the accelerometer: a short pulse between two samples is seen only through its
  rise or tail, as it really is).
The expected thrust history ``F_i(t)`` comes from :class:`flight_sw.fdir.thrust_model.
ThrustModel`: the commands with their transmission delay and the valves' opening and
closing delays and first-order rise and tail (the vehicle's valve data, parameters
``command_delay_s``, ``valve_*``, defaults in :mod:`flight_sw.fdir.valve_timing`). Known
failures (after reconfiguration) are modelled: a stuck-open thruster is on all the time.
The residual itself is :class:`flight_sw.fdir.residual_model.ResidualModel`'s; this module
decides (detection, isolation).

Detection: the residual ``r = [Δω_meas − Δω_pred ; Δv_meas − Δv_pred]`` is normalised per
axis by its expected standard deviation σ (gyro and accelerometer noise; relative model
error ``model_rel_error`` on the net predicted change, for the inertia/mass mismatch;
``thrust_rel_error`` per firing thruster, root-sum-square; a timing error
``edge_uncertainty_s`` of the modelled valve edges, which matters for the pulses crossing
a window boundary (the impulse of a pulse wholly inside the window does not depend on its
timing) and, for the sampled linear channel, through the thrust's rate of change at each
sample; accelerometer bias uncertainty), ``z = r/σ``.
An anomaly is detected when ``‖z‖ > threshold`` or the best failure hypothesis' likelihood
gain (below) exceeds ``glr_threshold``, for ``persistence_cycles`` consecutive cycles
(threshold and persistence test; the second test is the generalised likelihood ratio
detector, more sensitive to a failure's own signature than the plain norm).

Isolation (generalised likelihood ratio, one amplitude per hypothesis): each hypothesis
"thruster i stuck closed" or "stuck open" predicts a residual signature: stuck closed
removes a share β of the thrust the model expects from thruster i (angular window change
``−β J⁻¹(r_i × d_i) T_max,i τ_i``, and at every accelerometer sample
``−β d_i F_i(t_s)/m``); stuck open adds full thrust where none was expected
(``+β`` times the same with ``τ_i → W − τ_i``, ``F_i → 1 − F_i``). The least-squares β,
clipped to ``[0, 1 + ε]`` (ε the relative errors), gives each hypothesis its likelihood
gain (the drop of the normalised squared residual, angular window plus every accelerometer
sample: a matched filter, so a 5 ms pulse seen by one sample is not drowned by the noise
of the fifty others). The best hypothesis must explain the window residual (at most
``explained_fraction`` of ‖z‖² left), beat the best hypothesis on any other thruster by
``isolation_margin`` (this separates thrusters with the same torque and opposite forces,
e.g. the two axial thrusters of a pure couple, by the accelerometer), and win
``isolation_cycles`` consecutive detected cycles. The kind follows from the hypothesis:
a thruster that was not commanded cannot explain a missing thrust, one commanded all the
time cannot explain an extra one.
The accelerometer bias b̂ is tracked by a first-order filter (time constant
``bias_time_constant_s``) of the mean linear residual while nothing is detected.

Inputs: ``on_command``, ``on_gyro``, ``on_accel`` (see :mod:`flight_sw.fdir.base`);
construction: the 6×n effectiveness matrix (rows force [N/N] then torque [N m/N], body
axes, :mod:`flight_sw.allocation.effectiveness`), nominal inertia [kg m²] and mass [kg],
the maximum thrust of each thruster [N] (shape (n,)), minimum on-time [s]. Output:
:class:`flight_sw.fdir.base.Verdict`; the numbers of the last evaluation in
:attr:`RateResidualFdir.last`.

Assumptions: rigid body, IMU at the centre of mass with axes along B, no external force
or torque beyond the thrusters that matters over a window (disturbances of the order of
seed 000's, 0.06 N and 1e-3 N m, are far below one 5 N thruster); one failure at a time.

Sources: analytical-redundancy residual generation with a threshold and persistence test
and isolation by the best-matching fault signature (column of the fault-input matrix):
Gertler 1998, "Fault Detection and Diagnosis in Engineering Systems", ch. 1 and 6
(structured/directional residuals); Chen & Patton 1999, "Robust Model-Based Fault
Diagnosis for Dynamic Systems", ch. 2; generalised-likelihood-ratio isolation by
least squares per hypothesis: Willsky & Jones 1976, IEEE TAC 21(1) 108–112. Euler's
equation and ``r × F``: Wie 2008, "Space Vehicle Dynamics and Control", 2nd ed., ch. 7.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flight_sw.fdir import residual_kernel
from flight_sw.fdir.base import (
    NOTHING,
    FailureKind,
    ThrusterFailure,
    ThrusterFdirStrategy,
    Verdict,
)
from flight_sw.fdir.rate_residual_params import RateResidualParams
from flight_sw.fdir.residual_model import Residual, ResidualModel
from flight_sw.fdir.thrust_model import ThrustModel

S_PER_NS = 1e-9

__all__ = ["RateResidualFdir", "RateResidualParams", "ResidualSample"]


@dataclass(frozen=True)
class ResidualSample:
    """One evaluation's numbers (for tests, tuning and telemetry).

    Attributes:
        t_a_ns, t_b_ns: the window [ns].
        z: normalised window residual (angular x, y, z, then linear x, y, z).
        norm: ‖z‖, the detection statistic.
        best_thruster, best_kind: the best-fitting failure hypothesis.
        beta: its amplitude (share of the thruster's commanded thrust missing, or of its
            uncommanded time on).
        gain: its likelihood gain over "no failure" (2 ln of the likelihood ratio).
        margin: its likelihood gain over the best hypothesis on another thruster.
        unexplained: the share of ‖z‖² it leaves unexplained.
    """

    t_a_ns: int
    t_b_ns: int
    z: np.ndarray
    norm: float
    best_thruster: int
    best_kind: FailureKind
    beta: float
    gain: float
    margin: float
    unexplained: float


def _argmax(x: list[float]) -> int:
    """``np.argmax``: the first NaN if there is one, else the first of equal maxima."""
    best = 0
    for i, v in enumerate(x):
        if v != v:
            return i
        if v > x[best]:
            best = i
    return best


def _max_or_nan(x: list[float]) -> float:
    """``np.max`` (NaN if any is NaN; −inf for none, as the hypotheses' masked gains)."""
    out = -math.inf
    for v in x:
        if v != v:
            return v
        out = max(out, v)
    return out


class RateResidualFdir(ThrusterFdirStrategy):
    """Residual-based thruster FDIR (see the module docstring)."""

    name = "rate_residual"

    def __init__(
        self,
        effectiveness: np.ndarray,
        inertia_B_kgm2: np.ndarray,
        mass_kg: float,
        max_thrust_N: np.ndarray,
        min_on_s: float,
        control_period_ns: int,
        imu_period_ns: int,
        params: RateResidualParams,
    ) -> None:
        self._res = ResidualModel(effectiveness, inertia_B_kgm2, mass_kg, max_thrust_N, min_on_s,
                                  control_period_ns, imu_period_ns, params)
        self._lin_l: list[list[float]] = self._res.lin.tolist()  # (3, n), for the kernel
        self.params = params
        self.n = self._res.n
        self._period_ns = control_period_ns
        self.last: ResidualSample | None = None
        self.reset()

    @property
    def model(self) -> ThrustModel:
        """The expected-thrust model of the commands sent."""
        return self._res.thrust

    # --- observations ---------------------------------------------------------------

    def reset(self) -> None:
        """Forget every observation and known failure."""
        self._res.reset()
        self._known = np.zeros(self.n, dtype=bool)
        self._quiet_until_ns: int | None = None
        self._above = 0
        self._t_detect: int | None = None
        self._streak_id = -1
        self._streak = 0
        self.last = None

    def on_command(self, t_ns: int, on_time_s: np.ndarray) -> None:
        """Add the commands of the period starting at ``t_ns`` to the thrust model."""
        self._res.thrust.command(t_ns, on_time_s)
        if self._quiet_until_ns is None:  # evaluate only once a window of commands exists
            self._quiet_until_ns = t_ns + self._res.window_ns

    def on_gyro(self, t_ns: int, omega_meas_B: np.ndarray) -> None:
        """Keep the gyro sample (time order is the caller's; older samples are dropped)."""
        self._res.add_gyro(t_ns, omega_meas_B)

    def on_accel(self, t_ns: int, f_meas_B: np.ndarray) -> None:
        """Keep the accelerometer sample."""
        self._res.add_accel(t_ns, f_meas_B)

    def set_failures(self, t_ns: int, failures: Sequence[ThrusterFailure]) -> None:
        """Model the known failures from now on; restart the tests after one window."""
        for f in failures:
            if 0 <= f.thruster < self.n:
                self._known[f.thruster] = True
                if f.kind == FailureKind.STUCK_OPEN:
                    self._res.thrust.stuck_open[f.thruster] = True
        self._quiet_until_ns = t_ns + self._res.window_ns
        self._above = 0
        self._t_detect = None
        self._streak_id, self._streak = -1, 0

    def residual(self, t_ns: int) -> Residual | None:
        """The residual of the window ending at the newest gyro sample (None: too short)."""
        return self._res.residual(t_ns)

    # --- decision -------------------------------------------------------------------

    def _hypotheses(self, res: Residual) -> tuple[list[float], list[float]]:
        """Per hypothesis (closed 0..n−1, open n..2n−1): likelihood gain and β.

        The gain is ``2β·hz − β²·hh`` (the drop of the cost ``‖z − β g‖²`` summed over the
        angular window residual and the accelerometer samples) at the least-squares β
        clipped to ``[0, β_max]`` (:func:`flight_sw.fdir.residual_kernel.hypotheses`).
        """
        p = self.params
        beta_max = 1.0 + p.thrust_rel_error + p.model_rel_error
        stuck: list[bool] = self._res.thrust.stuck_open.tolist()
        return residual_kernel.hypotheses(
            res.z, res.h_ang, res.tau_cmd_s, res.span_s, res.frac, stuck, res.w_lin,
            res.ivl, self._lin_l, self._known.tolist(), beta_max)

    def _signature(self, res: Residual, h: int) -> list[float]:
        """Hypothesis ``h``'s window signature (6), for the "explains the residual" test."""
        stuck: list[bool] = self._res.thrust.stuck_open.tolist()
        return residual_kernel.signature(h, res.h_ang, res.h_lin, res.tau_cmd_s, res.span_s,
                                         res.u_s, stuck, len(res.frac), self._res.imu_period_s)

    def evaluate(self, t_ns: int) -> Verdict:
        """Threshold and persistence test, then isolation (see the module docstring)."""
        p = self.params
        if self._quiet_until_ns is None or t_ns < self._quiet_until_ns:
            self.last = None
            return NOTHING
        res = self._res.residual(t_ns)
        if res is None:
            return NOTHING
        z = res.z
        zz = 0.0
        for v in z:
            zz += v * v
        norm = math.sqrt(zz)
        n = self.n
        gain, beta = self._hypotheses(res)
        best = _argmax(gain)
        if norm > p.threshold or gain[best] > p.glr_threshold:
            self._above += 1
        else:
            self._above = 0
            self._t_detect = None
            self._streak_id, self._streak = -1, 0
            self._res.track_bias(min(1.0, self._period_ns * S_PER_NS / p.bias_time_constant_s))
        detected = self._above >= p.persistence_cycles
        failure = None
        thruster = best % n
        kind = FailureKind.STUCK_OPEN if best >= n else FailureKind.STUCK_CLOSED
        others = _max_or_nan([g for h, g in enumerate(gain) if h % n != thruster])
        margin = gain[best] - others
        sig = self._signature(res, best)
        unexplained = 0.0
        for z_i, s_i in zip(z, sig, strict=True):
            fit = z_i - beta[best] * s_i
            unexplained += fit * fit
        if detected:
            if self._t_detect is None:
                self._t_detect = t_ns
            confident = unexplained <= p.explained_fraction * zz and margin >= p.isolation_margin
            if confident and best == self._streak_id:
                self._streak += 1
            elif confident:
                self._streak_id, self._streak = best, 1
            else:
                self._streak_id, self._streak = -1, 0
            if self._streak >= p.isolation_cycles:
                failure = ThrusterFailure(thruster, kind, self._t_detect, t_ns, self.name)
        self.last = ResidualSample(
            res.t_a_ns,
            res.t_b_ns,
            np.array(z),
            norm,
            thruster,
            kind,
            beta[best],
            gain[best],
            margin,
            unexplained / zz if zz > 0.0 else 0.0,
        )
        return Verdict(detected, self._t_detect if detected else None, failure)
