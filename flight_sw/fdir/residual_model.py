"""The window residual of the acceleration-residual FDIR: observed minus commanded motion.

What it does: :class:`ResidualModel` keeps the gyro and accelerometer samples of the last
window and the expected-thrust model of the commands sent
(:class:`flight_sw.fdir.thrust_model.ThrustModel`), and computes, for the window
``[t_a, t_b]`` ending at the newest gyro sample, the normalised residual
``z = [Δω_meas − Δω_pred ; Δv_meas − Δv_pred] / σ`` and what the hypothesis test of
:mod:`flight_sw.fdir.rate_residual` needs (:class:`Residual`):

- angular: ``Δω_pred = Σ_i α_i τ_i − J⁻¹ (ω̄ × J ω̄)(t_b − t_a)`` with, per thruster,
  ``α_i = J⁻¹ (r_i × d_i) T_max,i`` [rad/s²] its angular acceleration at its own full
  thrust and ``τ_i = ∫ F_i/T_max,i dt`` over the window [s] (Euler's equation, nominal
  inertia J, ω̄ the mean measured rate);
- linear, sampled like the accelerometer: ``f_pred(t_s) = Σ_i a_i F_i(t_s)/T_max,i`` with
  ``a_i = d_i T_max,i / m`` [m/s²] (nominal mass m), compared with the samples less the
  tracked bias;
- the expected standard deviation σ per axis: gyro and accelerometer noise, the relative
  error of the net prediction (``model_rel_error``), the per-thruster thrust error
  (``thrust_rel_error``), the timing error of the modelled valve edges
  (``edge_uncertainty_s``) and the accelerometer-bias uncertainty.

Each thruster enters with its own maximum thrust ``T_max,i`` (a vector, shape (n,)): a
thruster of a non-uniform layout predicts the rate change of its own thrust.

Inputs: the 6×n effectiveness matrix (rows force [N/N] then torque [N m/N], body axes),
nominal inertia [kg m²] and mass [kg], per-thruster maximum thrust [N], minimum on-time
[s], control and IMU periods [ns], :class:`~flight_sw.fdir.rate_residual_params.RateResidualParams`;
per cycle the commands, gyro samples [rad/s] and accelerometer samples [m/s²].

Assumptions: rigid body, IMU at the centre of mass with axes along B, no external force or
torque that matters over a window. Sources: those of :mod:`flight_sw.fdir.rate_residual`
(Gertler 1998; Chen & Patton 1999; Wie 2008, ch. 7 for Euler's equation and ``r × F``).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from dbc.errors import ConfigError
from flight_sw.fdir.rate_residual_params import RateResidualParams
from flight_sw.fdir.thrust_model import ThrustModel
from flight_sw.quaternion import cross as cross3

NS_PER_S = 1_000_000_000
S_PER_NS = 1e-9
WRENCH_ROWS = 6
# History kept beyond one window: commands whose pulses may still overlap it, late samples.
HISTORY_MARGIN = 6
# A window shorter than this fraction of ``window_s`` is not evaluated (start-up, gaps).
MIN_WINDOW_FRACTION = 0.75

_SOURCE = "ResidualModel"


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
    row: np.ndarray | None = None  # f, thrust fraction and its rate, one row (one stacking)


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


class ResidualModel:
    """Samples, expected thrust and the normalised window residual (module docstring)."""

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
        b = np.asarray(effectiveness, dtype=float)
        if b.ndim != 2 or b.shape[0] != WRENCH_ROWS or b.shape[1] < 1:
            raise ConfigError(_SOURCE, "effectiveness", b.shape, "a 6×n wrench matrix")
        j = np.asarray(inertia_B_kgm2, dtype=float)
        if j.shape != (3, 3):
            raise ConfigError(_SOURCE, "inertia_B_kgm2", j.shape, "a 3×3 matrix")
        n = b.shape[1]
        t_max = np.asarray(max_thrust_N, dtype=float)
        if t_max.shape != (n,) or not bool(np.all(t_max > 0.0)) or not np.all(np.isfinite(t_max)):
            raise ConfigError(_SOURCE, "max_thrust_N", max_thrust_N,
                              f"{n} finite numbers > 0 [N] (one per thruster)")
        self.params = params
        self.n = n
        self._j = j
        j_inv = np.linalg.inv(j)
        self._j_inv = j_inv
        # Per thruster, at its own full thrust: angular acceleration [rad/s²] and linear [m/s²].
        self.ang = j_inv @ b[3:6] * t_max
        self.lin = b[0:3] * (t_max / mass_kg)
        self.imu_period_s = imu_period_ns * S_PER_NS
        self.window_ns = round(params.window_s * NS_PER_S)
        self._n_imu = math.ceil(self.window_ns / imu_period_ns) + HISTORY_MARGIN
        self.thrust = ThrustModel(
            n,
            min_on_s,
            params.valve_timing,
            self.window_ns + HISTORY_MARGIN * control_period_ns,
        )
        self.reset()

    def reset(self) -> None:
        """Forget every sample, command and the accelerometer bias."""
        self.thrust.reset()
        # samples with their model quantities, computed once (at the first evaluation after
        # they arrive: by then no command can change the modelled thrust at their time)
        self._gyro: deque[_GyroSample] = deque(maxlen=self._n_imu)
        self._accel: deque[_AccelSample] = deque(maxlen=self._n_imu)
        self.pending_bias: np.ndarray | None = None
        self.bias = np.zeros(3)

    def add_gyro(self, t_ns: int, omega_meas_B: np.ndarray) -> None:
        """Keep the gyro sample (time order is the caller's; older samples are dropped)."""
        if self._gyro and t_ns <= self._gyro[-1].t_ns:
            return
        self._gyro.append(_GyroSample(t_ns, np.array(omega_meas_B, dtype=float)))

    def add_accel(self, t_ns: int, f_meas_B: np.ndarray) -> None:
        """Keep the accelerometer sample."""
        if self._accel and t_ns <= self._accel[-1].t_ns:
            return
        self._accel.append(_AccelSample(t_ns, np.array(f_meas_B, dtype=float)))

    def track_bias(self, fraction: float) -> None:
        """Move the accelerometer-bias estimate by ``fraction`` of the way towards the last
        window's mean linear residual (first-order filter; nothing if it had none)."""
        if self.pending_bias is not None:
            self.bias += fraction * (self.pending_bias - self.bias)

    def _refresh(self) -> None:
        """Model quantities of the samples that have none yet (each computed once)."""
        model = self.thrust
        guard = round(2.0 * self.params.edge_uncertainty_s * NS_PER_S)
        gyro = self._gyro
        i = len(gyro)  # the samples without them are the newest ones
        while i > 0 and gyro[i - 1].cum_s is None:
            i -= 1
        prev = gyro[i - 1] if i > 0 else None
        for j in range(i, len(gyro)):
            g = gyro[j]
            if prev is None or prev.cum_s is None:
                g.cum_s = np.zeros(self.n)
            else:
                g.cum_s = prev.cum_s + model.thrust_time_s(prev.t_ns, g.t_ns)
            g.edges = model.boundary_segments(g.t_ns, guard)
            prev = g
        accel = self._accel
        i = len(accel)
        while i > 0 and accel[i - 1].row is None:
            i -= 1
        new = [accel[j] for j in range(i, len(accel))]
        if new:
            frac, rate = model.fraction_at(np.array([a.t_ns for a in new], dtype=np.int64))
            for i, a in enumerate(new):
                a.row = np.concatenate((a.f, frac[i], rate[i]))

    def _window(self, t_ns: int) -> tuple[_GyroSample, _GyroSample] | None:
        """The gyro samples opening and closing the window (the newest one closes it)."""
        if len(self._gyro) < 2:
            return None
        b = self._gyro[-1]
        a = self._gyro[0]
        for g in self._gyro:
            if g.t_ns >= b.t_ns - self.window_ns:
                a = g
                break
        if b.t_ns - a.t_ns < MIN_WINDOW_FRACTION * self.window_ns:
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
        model = self.thrust
        tau_s = gb.cum_s - ga.cum_s  # (n,) thrust-time in the window [s]
        tau_cmd_s = np.where(model.stuck_open, 0.0, tau_s)
        edges = ga.edges + gb.edges
        # angular channel
        w_bar = 0.5 * (w_a + w_b)
        gyroscopic = self._j_inv @ cross3(w_bar, self._j @ w_bar) * span_s
        dw_pred = self.ang @ tau_s - gyroscopic
        r_ang = (w_b - w_a) - dw_pred
        contrib_ang = self.ang * tau_s  # (3, n)
        var_ang = (
            2.0 * p.gyro_noise_rad_s**2
            + (p.model_rel_error * dw_pred) ** 2
            + (p.thrust_rel_error**2) * (contrib_ang**2).sum(axis=1)
            + (p.edge_uncertainty_s**2) * (self.ang**2 @ edges)
        )
        sig_ang = np.sqrt(var_ang)
        z = np.zeros(6)
        z[0:3] = r_ang / sig_ang
        h_ang = self.ang / sig_ang[:, None]
        # linear channel (sampled like the accelerometer)
        acc = [a for a in self._accel if t_a < a.t_ns <= t_b] if p.use_accel else []
        self.pending_bias = None
        s_count = len(acc) if len(acc) >= 2 else 0
        frac = np.zeros((s_count, n))
        w_lin = np.zeros((s_count, 3))
        inv_var = np.zeros((s_count, 3))
        h_lin = np.zeros((3, n))
        u_s = np.zeros(n)
        if s_count:
            rows = np.array([a.row for a in acc])  # (samples, 3 + 2n), then each part
            fs = np.ascontiguousarray(rows[:, :3])  # contiguous: the products below as
            frac = np.ascontiguousarray(rows[:, 3 : 3 + n])  # on separately stacked arrays
            rate = np.ascontiguousarray(rows[:, 3 + n :])
            dt = self.imu_period_s
            f_pred = frac @ self.lin.T  # (samples, 3)
            r_s = (fs - self.bias) - f_pred
            var_s = (
                p.accel_noise_m_s2**2
                + p.accel_bias_m_s2**2
                + (p.model_rel_error * f_pred) ** 2
                + (p.thrust_rel_error**2) * ((frac**2) @ (self.lin.T**2))
                + (p.edge_uncertainty_s**2) * ((rate**2) @ (self.lin.T**2))
            )
            inv_var = 1.0 / var_s
            w_lin = r_s * inv_var
            u_s = frac.sum(axis=0) * dt  # sampled thrust-time per thruster [s]
            r_lin = r_s.sum(axis=0) * dt
            sig_lin = np.sqrt(
                s_count * (p.accel_noise_m_s2 * dt) ** 2
                + (p.accel_bias_m_s2 * span_s) ** 2
                + (p.model_rel_error * (self.lin @ u_s)) ** 2
                + (p.thrust_rel_error**2) * ((self.lin * u_s) ** 2).sum(axis=1)
                + (p.edge_uncertainty_s * dt) ** 2 * ((rate @ self.lin.T) ** 2).sum(axis=0)
            )
            z[3:6] = r_lin / sig_lin
            h_lin = self.lin / sig_lin[:, None]
            # the means as numpy's mean takes them (add.reduce, then / count), less its
            # overhead
            self.pending_bias = fs.sum(axis=0) / s_count - f_pred.sum(axis=0) / s_count
        return Residual(t_a, t_b, span_s, z, tau_cmd_s, h_ang, h_lin, u_s, frac, w_lin, inv_var)
