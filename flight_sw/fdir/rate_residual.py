"""Thruster FDIR from the acceleration residual: commanded vs observed (gyro, accelerometer).

What it does: over a sliding window ``[t_a, t_b]`` of length ``window_s`` (re-evaluated
every control cycle) it compares
- the observed change of body rate ``Δω_meas = ω(t_b) − ω(t_a)`` (two gyro samples; the
  gyro bias cancels) with the change predicted from the on-times the flight software
  commanded, ``Δω_pred = J⁻¹ Σ_i (r_i × d_i) T_max τ_i − J⁻¹ (ω̄ × J ω̄)(t_b − t_a)``
  (Euler's equation, nominal inertia J, ω̄ the mean measured rate), τ_i = ∫ F_i/T_max dt
  over the window from the expected thrust history;
- the observed velocity change ``Δv_meas = Σ_s (f_s − b̂) Δt`` (the accelerometer samples
  in (t_a, t_b], b̂ the estimated accelerometer bias) with the same sum over the expected
  thrust at each sample time, ``f_pred(t_s) = Σ_i d_i T_max F_i(t_s)/(T_max m)`` (sampled
  like the accelerometer: a short pulse between two samples is seen only through its
  rise or tail, as it really is).
The expected thrust history ``F_i(t)`` comes from :class:`flight_sw.fdir.thrust_model.
ThrustModel`: the commands with their transmission delay and the valves' opening and
closing delays and first-order rise and tail (the vehicle's valve data, parameters
``command_delay_s``, ``valve_*``). Known failures (after reconfiguration) are modelled:
a stuck-open thruster is on all the time.

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
``−β J⁻¹(r_i × d_i) T_max τ_i``, and at every accelerometer sample
``−β d_i T_max F_i(t_s)/(T_max m)``); stuck open adds full thrust where none was expected
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
T_max [N], minimum on-time [s]. Output: :class:`flight_sw.fdir.base.Verdict`; the numbers
of the last evaluation in :attr:`RateResidualFdir.last`.

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
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dbc.errors import ConfigError
from flight_sw import validation as check
from flight_sw.fdir.base import (
    NOTHING,
    FailureKind,
    ThrusterFailure,
    ThrusterFdirStrategy,
    Verdict,
)
from flight_sw.fdir.thrust_model import ThrustModel
from flight_sw.quaternion import cross as cross3

NS_PER_S = 1_000_000_000
S_PER_NS = 1e-9
# History kept beyond one window: commands whose pulses may still overlap it, late samples.
HISTORY_MARGIN = 6
# A window shorter than this fraction of ``window_s`` is not evaluated (start-up, gaps).
MIN_WINDOW_FRACTION = 0.75

_SOURCE = "RateResidualParams"


@dataclass(frozen=True)
class RateResidualParams:
    """Settings of the residual FDIR (see the module docstring for their roles).

    Attributes:
        window_s: residual window [s] (> 0).
        threshold: detection threshold on ‖z‖, the normalised residual norm (> 0).
        glr_threshold: detection threshold on the best hypothesis' likelihood gain (> 0).
        persistence_cycles: consecutive cycles above threshold to detect (≥ 1).
        isolation_cycles: consecutive detected cycles the same hypothesis must win (≥ 1).
        explained_fraction: largest share of ‖z‖² the winning hypothesis may leave (0, 1].
        isolation_margin: smallest likelihood gain of the winner over the best hypothesis
            on another thruster (≥ 0; 2 ln of a likelihood ratio).
        command_delay_s: control-cycle time to the command's reception by the valves [s].
        valve_open_delay_s, valve_close_delay_s: valve transport delays [s] (≥ 0).
        valve_rise_tau_s, valve_tail_tau_s: first-order rise and tail time constants [s].
        edge_uncertainty_s: 1σ timing error of each modelled valve edge [s] (≥ 0).
        gyro_noise_rad_s: 1σ noise of one gyro sample, quantisation included [rad/s] (> 0).
        accel_noise_m_s2: 1σ noise of one accelerometer sample [m/s²] (> 0).
        accel_bias_m_s2: 1σ uncertainty of the tracked accelerometer bias [m/s²] (≥ 0).
        model_rel_error: relative error of the net predicted change (inertia, mass) (≥ 0).
        thrust_rel_error: relative thrust error of each thruster (≥ 0).
        bias_time_constant_s: time constant of the accelerometer-bias filter [s] (> 0).
        use_accel: use the accelerometer (linear) channel.
    """

    window_s: float = 0.5
    threshold: float = 5.0
    glr_threshold: float = 20.0
    persistence_cycles: int = 3
    isolation_cycles: int = 3
    explained_fraction: float = 0.35
    isolation_margin: float = 6.0
    command_delay_s: float = 0.0015
    valve_open_delay_s: float = 0.003
    valve_close_delay_s: float = 0.002
    valve_rise_tau_s: float = 0.002
    valve_tail_tau_s: float = 0.003
    edge_uncertainty_s: float = 0.0005
    gyro_noise_rad_s: float = 5e-5
    accel_noise_m_s2: float = 5e-3
    accel_bias_m_s2: float = 1e-3
    model_rel_error: float = 0.1
    thrust_rel_error: float = 0.05
    bias_time_constant_s: float = 10.0
    use_accel: bool = True

    def __post_init__(self) -> None:
        s = _SOURCE
        for key in ("window_s", "threshold", "glr_threshold", "gyro_noise_rad_s",
                    "accel_noise_m_s2", "bias_time_constant_s"):
            check.positive(s, key, getattr(self, key))
        for key in ("isolation_margin", "command_delay_s", "valve_open_delay_s",
                    "valve_close_delay_s", "valve_rise_tau_s", "valve_tail_tau_s",
                    "edge_uncertainty_s", "accel_bias_m_s2", "model_rel_error",
                    "thrust_rel_error"):
            check.non_negative(s, key, getattr(self, key))
        for key in ("persistence_cycles", "isolation_cycles"):
            check.integer(s, key, getattr(self, key), 1)
        check.number(s, "explained_fraction", self.explained_fraction, 0.0, 1.0, lo_open=True)
        check.flag(s, "use_accel", self.use_accel)


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


@dataclass
class _GyroSample:
    """A gyro sample, the cumulative modelled thrust-time up to it and edges near it."""

    t_ns: int
    omega: np.ndarray
    cum_s: np.ndarray | None = None
    edges: np.ndarray | None = None


@dataclass
class _AccelSample:
    """An accelerometer sample and the modelled thrust fraction and its rate at it."""

    t_ns: int
    f: np.ndarray
    frac: np.ndarray | None = None
    rate: np.ndarray | None = None


@dataclass(frozen=True)
class Residual:
    """The residual of one window and what the hypothesis test needs (internal)."""

    t_a_ns: int
    t_b_ns: int
    span_s: float
    z: np.ndarray  # (6,) normalised window residual
    tau_cmd_s: np.ndarray  # (n,) commanded thrust-time in the window [s]
    h_ang: np.ndarray  # (3, n) angular change per second of full thrust, over σ
    h_lin: np.ndarray  # (3, n) window velocity change per second of full thrust, over σ
    u_s: np.ndarray  # (n,) sampled thrust-time [s]
    frac: np.ndarray  # (samples, n) expected thrust fraction at the accelerometer samples
    w_lin: np.ndarray  # (samples, 3) sample residual over its variance
    inv_var: np.ndarray  # (samples, 3) 1/variance of each sample residual


class RateResidualFdir(ThrusterFdirStrategy):
    """Residual-based thruster FDIR (see the module docstring)."""

    name = "rate_residual"

    def __init__(
        self,
        effectiveness: np.ndarray,
        inertia_B_kgm2: np.ndarray,
        mass_kg: float,
        max_thrust_N: float,
        min_on_s: float,
        control_period_ns: int,
        imu_period_ns: int,
        params: RateResidualParams,
    ) -> None:
        b = np.asarray(effectiveness, dtype=float)
        if b.ndim != 2 or b.shape[0] != 6 or b.shape[1] < 1:
            raise ConfigError(_SOURCE, "effectiveness", b.shape, "a 6×n wrench matrix")
        j = np.asarray(inertia_B_kgm2, dtype=float)
        if j.shape != (3, 3):
            raise ConfigError(_SOURCE, "inertia_B_kgm2", j.shape, "a 3×3 matrix")
        self.params = params
        self.n = b.shape[1]
        self._j = j
        j_inv = np.linalg.inv(j)
        self._j_inv = j_inv
        # Per thruster, full thrust: angular acceleration [rad/s²] and linear [m/s²].
        self._ang = j_inv @ b[3:6] * max_thrust_N
        self._lin = b[0:3] * (max_thrust_N / mass_kg)
        self._period_ns = control_period_ns
        self._imu_period_s = imu_period_ns * S_PER_NS
        self._window_ns = round(params.window_s * NS_PER_S)
        self._n_imu = math.ceil(self._window_ns / imu_period_ns) + HISTORY_MARGIN
        self.model = ThrustModel(
            self.n,
            min_on_s,
            params.command_delay_s,
            params.valve_open_delay_s,
            params.valve_close_delay_s,
            params.valve_rise_tau_s,
            params.valve_tail_tau_s,
            self._window_ns + HISTORY_MARGIN * control_period_ns,
        )
        self.last: ResidualSample | None = None
        self.reset()

    # --- observations ---------------------------------------------------------------

    def reset(self) -> None:
        """Forget every observation and known failure."""
        n = self.n
        self.model.reset()
        # samples with their model quantities, computed once (at the first evaluation after
        # they arrive: by then no command can change the modelled thrust at their time)
        self._gyro: deque[_GyroSample] = deque(maxlen=self._n_imu)
        self._accel: deque[_AccelSample] = deque(maxlen=self._n_imu)
        self._known = np.zeros(n, dtype=bool)
        self._pending_bias: np.ndarray | None = None
        self._bias = np.zeros(3)
        self._quiet_until_ns: int | None = None
        self._above = 0
        self._t_detect: int | None = None
        self._streak_id = -1
        self._streak = 0
        self.last = None

    def on_command(self, t_ns: int, on_time_s: np.ndarray) -> None:
        """Add the commands of the period starting at ``t_ns`` to the thrust model."""
        self.model.command(t_ns, on_time_s)
        if self._quiet_until_ns is None:  # evaluate only once a window of commands exists
            self._quiet_until_ns = t_ns + self._window_ns

    def on_gyro(self, t_ns: int, omega_meas_B: np.ndarray) -> None:
        """Keep the gyro sample (time order is the caller's; older samples are dropped)."""
        if self._gyro and t_ns <= self._gyro[-1].t_ns:
            return
        self._gyro.append(_GyroSample(t_ns, np.array(omega_meas_B, dtype=float)))

    def on_accel(self, t_ns: int, f_meas_B: np.ndarray) -> None:
        """Keep the accelerometer sample."""
        if self._accel and t_ns <= self._accel[-1].t_ns:
            return
        self._accel.append(_AccelSample(t_ns, np.array(f_meas_B, dtype=float)))

    def _refresh(self) -> None:
        """Model quantities of the samples that have none yet (each computed once)."""
        model = self.model
        guard = round(2.0 * self.params.edge_uncertainty_s * NS_PER_S)
        prev: _GyroSample | None = None
        for g in self._gyro:
            if g.cum_s is None:
                if prev is None or prev.cum_s is None:
                    g.cum_s = np.zeros(self.n)
                else:
                    g.cum_s = prev.cum_s + model.thrust_time_s(prev.t_ns, g.t_ns)
                g.edges = model.boundary_segments(g.t_ns, guard)
            prev = g
        new = [a for a in self._accel if a.frac is None]
        if new:
            frac, rate = model.fraction_at(np.array([a.t_ns for a in new], dtype=np.int64))
            for i, a in enumerate(new):
                a.frac, a.rate = frac[i], rate[i]

    def set_failures(self, t_ns: int, failures: Sequence[ThrusterFailure]) -> None:
        """Model the known failures from now on; restart the tests after one window."""
        for f in failures:
            if 0 <= f.thruster < self.n:
                self._known[f.thruster] = True
                if f.kind == FailureKind.STUCK_OPEN:
                    self.model.stuck_open[f.thruster] = True
        self._quiet_until_ns = t_ns + self._window_ns
        self._above = 0
        self._t_detect = None
        self._streak_id, self._streak = -1, 0

    # --- model ----------------------------------------------------------------------

    def _window(self, t_ns: int) -> tuple[_GyroSample, _GyroSample] | None:
        """The gyro samples opening and closing the window (the newest one closes it)."""
        if len(self._gyro) < 2:
            return None
        b = self._gyro[-1]
        a = self._gyro[0]
        for g in self._gyro:
            if g.t_ns >= b.t_ns - self._window_ns:
                a = g
                break
        if b.t_ns - a.t_ns < MIN_WINDOW_FRACTION * self._window_ns:
            return None
        return a, b

    def residual(self, t_ns: int) -> Residual | None:
        """The residual of the window ending at the newest gyro sample (None: too short)."""
        win = self._window(t_ns)
        if win is None:
            return None
        self._refresh()
        p = self.params
        n = self.n
        ga, gb = win
        assert ga.cum_s is not None and gb.cum_s is not None
        assert ga.edges is not None and gb.edges is not None
        t_a, w_a, t_b, w_b = ga.t_ns, ga.omega, gb.t_ns, gb.omega
        span_s = (t_b - t_a) * S_PER_NS
        model = self.model
        tau_s = gb.cum_s - ga.cum_s  # (n,) thrust-time in the window [s]
        tau_cmd_s = np.where(model.stuck_open, 0.0, tau_s)
        edges = ga.edges + gb.edges
        # angular channel
        w_bar = 0.5 * (w_a + w_b)
        gyroscopic = self._j_inv @ cross3(w_bar, self._j @ w_bar) * span_s
        dw_pred = self._ang @ tau_s - gyroscopic
        r_ang = (w_b - w_a) - dw_pred
        contrib_ang = self._ang * tau_s  # (3, n)
        var_ang = (
            2.0 * p.gyro_noise_rad_s**2
            + (p.model_rel_error * dw_pred) ** 2
            + (p.thrust_rel_error**2) * (contrib_ang**2).sum(axis=1)
            + (p.edge_uncertainty_s**2) * (self._ang**2 @ edges)
        )
        sig_ang = np.sqrt(var_ang)
        z = np.zeros(6)
        z[0:3] = r_ang / sig_ang
        h_ang = self._ang / sig_ang[:, None]
        # linear channel (sampled like the accelerometer)
        acc = [a for a in self._accel if t_a < a.t_ns <= t_b] if p.use_accel else []
        self._pending_bias = None
        s_count = len(acc) if len(acc) >= 2 else 0
        frac = np.zeros((s_count, n))
        w_lin = np.zeros((s_count, 3))
        inv_var = np.zeros((s_count, 3))
        h_lin = np.zeros((3, n))
        u_s = np.zeros(n)
        if s_count:
            fs = np.array([a.f for a in acc])
            frac = np.array([a.frac for a in acc])
            rate = np.array([a.rate for a in acc])
            dt = self._imu_period_s
            f_pred = frac @ self._lin.T  # (samples, 3)
            r_s = (fs - self._bias) - f_pred
            var_s = (
                p.accel_noise_m_s2**2
                + p.accel_bias_m_s2**2
                + (p.model_rel_error * f_pred) ** 2
                + (p.thrust_rel_error**2) * ((frac**2) @ (self._lin.T**2))
                + (p.edge_uncertainty_s**2) * ((rate**2) @ (self._lin.T**2))
            )
            inv_var = 1.0 / var_s
            w_lin = r_s * inv_var
            u_s = frac.sum(axis=0) * dt  # sampled thrust-time per thruster [s]
            r_lin = r_s.sum(axis=0) * dt
            sig_lin = np.sqrt(
                s_count * (p.accel_noise_m_s2 * dt) ** 2
                + (p.accel_bias_m_s2 * span_s) ** 2
                + (p.model_rel_error * (self._lin @ u_s)) ** 2
                + (p.thrust_rel_error**2) * ((self._lin * u_s) ** 2).sum(axis=1)
                + (p.edge_uncertainty_s * dt) ** 2 * ((rate @ self._lin.T) ** 2).sum(axis=0)
            )
            z[3:6] = r_lin / sig_lin
            h_lin = self._lin / sig_lin[:, None]
            self._pending_bias = (fs.mean(axis=0)) - f_pred.mean(axis=0)
        return Residual(t_a, t_b, span_s, z, tau_cmd_s, h_ang, h_lin, u_s, frac, w_lin, inv_var)

    # --- decision -------------------------------------------------------------------

    def _hypotheses(self, res: Residual) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per hypothesis (closed 0..n−1, open n..2n−1): likelihood gain, β, window signature.

        The gain is ``2β·hz − β²·hh`` (the drop of the cost ``‖z − β g‖²`` summed over the
        angular window residual and the accelerometer samples) at the least-squares β
        clipped to ``[0, β_max]``; the window signature (6×2n) is ``g`` summed per window,
        for the "explains the residual" test.
        """
        p = self.params
        n = self.n
        frac_cmd = res.frac.copy()
        frac_cmd[:, self.model.stuck_open] = 0.0
        lin = self._lin
        wl = res.w_lin @ lin  # (samples, n): Σ_axis r/σ² · lin_i
        ivl = res.inv_var @ (lin**2)  # (samples, n): Σ_axis lin_i²/σ²
        g_ang_c = -res.h_ang * res.tau_cmd_s  # (3, n)
        g_ang_o = res.h_ang * np.maximum(res.span_s - res.tau_cmd_s, 0.0)
        z_ang = res.z[0:3]
        hz = np.concatenate(
            (
                z_ang @ g_ang_c - (wl * frac_cmd).sum(axis=0),
                z_ang @ g_ang_o + (wl * (1.0 - frac_cmd)).sum(axis=0),
            )
        )
        hh = np.concatenate(
            (
                (g_ang_c**2).sum(axis=0) + (ivl * frac_cmd**2).sum(axis=0),
                (g_ang_o**2).sum(axis=0) + (ivl * (1.0 - frac_cmd) ** 2).sum(axis=0),
            )
        )
        beta_max = 1.0 + p.thrust_rel_error + p.model_rel_error
        with np.errstate(divide="ignore", invalid="ignore"):
            beta = np.clip(np.where(hh > 0.0, hz / hh, 0.0), 0.0, beta_max)
        gain = 2.0 * beta * hz - beta**2 * hh
        known = np.concatenate((self._known, self._known))
        gain[known] = -np.inf
        dt = self._imu_period_s
        u_open = res.frac.shape[0] * dt - res.u_s
        sig = np.zeros((6, 2 * n))
        sig[0:3, :n], sig[0:3, n:] = g_ang_c, g_ang_o
        sig[3:6, :n] = -res.h_lin * np.where(self.model.stuck_open, 0.0, res.u_s)
        sig[3:6, n:] = res.h_lin * np.maximum(u_open, 0.0)
        return gain, beta, sig

    def evaluate(self, t_ns: int) -> Verdict:
        """Threshold and persistence test, then isolation (see the module docstring)."""
        p = self.params
        if self._quiet_until_ns is None or t_ns < self._quiet_until_ns:
            self.last = None
            return NOTHING
        res = self.residual(t_ns)
        if res is None:
            return NOTHING
        z = res.z
        zz = float(z @ z)
        norm = math.sqrt(zz)
        n = self.n
        gain, beta, sig = self._hypotheses(res)
        best = int(np.argmax(gain))
        if norm > p.threshold or gain[best] > p.glr_threshold:
            self._above += 1
        else:
            self._above = 0
            self._t_detect = None
            self._streak_id, self._streak = -1, 0
            if self._pending_bias is not None:
                alpha = min(1.0, self._period_ns * S_PER_NS / p.bias_time_constant_s)
                self._bias += alpha * (self._pending_bias - self._bias)
        detected = self._above >= p.persistence_cycles
        failure = None
        thruster = best % n
        kind = FailureKind.STUCK_OPEN if best >= n else FailureKind.STUCK_CLOSED
        others = gain.copy()
        others[[thruster, thruster + n]] = -np.inf
        margin = float(gain[best] - others.max())
        window_fit = z - beta[best] * sig[:, best]
        unexplained = float(window_fit @ window_fit)
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
            z,
            norm,
            thruster,
            kind,
            float(beta[best]),
            float(gain[best]),
            margin,
            unexplained / zz if zz > 0.0 else 0.0,
        )
        return Verdict(detected, self._t_detect if detected else None, failure)
