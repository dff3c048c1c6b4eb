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

The arithmetic is :mod:`flight_sw.fdir.residual_kernel`'s (floats, every sum in one
order, no BLAS); what an accelerometer sample contributes to every window holding it
(predicted force, variance, thrust-rate term) is computed once, when it is first used.

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
from flight_sw.fdir import residual_kernel as kernel
from flight_sw.fdir.rate_residual_params import RateResidualParams
from flight_sw.fdir.thrust_model import ThrustModel

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
    omega: list[float]
    cum_s: list[float] | None = None
    edges: list[float] | None = None


@dataclass
class _AccelSample:
    """An accelerometer sample and the modelled thrust fraction and its rate at it."""

    t_ns: int
    f: list[float]
    frac: list[float] | None = None  # modelled thrust fraction per thruster at t_ns
    terms: list[float] | None = None  # its residual_kernel.sample_terms: predicted f, ...
    ivl: list[float] | None = None  # ... and Σ_axis lin²/σ² per thruster


@dataclass(frozen=True)
class Residual:
    """The residual of one window and what the hypothesis test needs (internal; lists,
    matrices as lists of rows, for :mod:`flight_sw.fdir.residual_kernel`)."""

    t_a_ns: int
    t_b_ns: int
    span_s: float
    z: list[float]  # (6,) normalised window residual
    tau_cmd_s: list[float]  # (n,) commanded thrust-time in the window [s]
    h_ang: list[list[float]]  # (3, n) angular change per second of full thrust, over σ
    h_lin: list[list[float]]  # (3, n) window velocity change per second of full thrust, over σ
    u_s: list[float]  # (n,) sampled thrust-time [s]
    frac: list[list[float]]  # (samples, n) expected thrust fraction at the accel samples
    w_lin: list[list[float]]  # (samples, 3) sample residual over its variance
    ivl: list[list[float]]  # (samples, n) Σ_axis lin_i²/variance of each sample residual


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
        # the same as lists for the kernel, and the noise parameters in its order
        self._ang_l: list[list[float]] = self.ang.tolist()
        self._lin_l: list[list[float]] = self.lin.tolist()
        self._j_l: list[list[float]] = j.tolist()
        self._j_inv_l: list[list[float]] = j_inv.tolist()
        self._noise = [params.gyro_noise_rad_s, params.model_rel_error, params.thrust_rel_error,
                       params.edge_uncertainty_s, params.accel_noise_m_s2, params.accel_bias_m_s2]
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
        w = np.asarray(omega_meas_B, dtype=float)
        self._gyro.append(_GyroSample(t_ns, [float(w[0]), float(w[1]), float(w[2])]))

    def add_accel(self, t_ns: int, f_meas_B: np.ndarray) -> None:
        """Keep the accelerometer sample."""
        if self._accel and t_ns <= self._accel[-1].t_ns:
            return
        f = np.asarray(f_meas_B, dtype=float)
        self._accel.append(_AccelSample(t_ns, [float(f[0]), float(f[1]), float(f[2])]))

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
                g.cum_s = [0.0] * self.n
            else:
                step = model.thrust_time_s(prev.t_ns, g.t_ns).tolist()
                g.cum_s = [c + d for c, d in zip(prev.cum_s, step, strict=True)]
            g.edges = model.boundary_segments(g.t_ns, guard).tolist()
            prev = g
        accel = self._accel
        i = len(accel)
        while i > 0 and accel[i - 1].frac is None:
            i -= 1
        new = [accel[j] for j in range(i, len(accel))]
        if new:
            frac, rate = model.fraction_at(np.array([a.t_ns for a in new], dtype=np.int64))
            frac_l, rate_l = frac.tolist(), rate.tolist()
            for i, a in enumerate(new):
                a.frac = frac_l[i]
                a.terms, a.ivl = kernel.sample_terms(a.f, frac_l[i], rate_l[i], self._lin_l,
                                                     self._noise)

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
        ga, gb = win
        assert ga.cum_s is not None and gb.cum_s is not None
        assert ga.edges is not None and gb.edges is not None
        t_a, t_b = ga.t_ns, gb.t_ns
        span_s = (t_b - t_a) * S_PER_NS
        stuck: list[bool] = self.thrust.stuck_open.tolist()
        tau_s = [b - a for a, b in zip(ga.cum_s, gb.cum_s, strict=True)]  # thrust-time [s]
        tau_cmd_s = [0.0 if st else t for st, t in zip(stuck, tau_s, strict=True)]
        edges = [a + b for a, b in zip(ga.edges, gb.edges, strict=True)]
        acc = [a for a in self._accel if t_a < a.t_ns <= t_b] if self.params.use_accel else []
        if len(acc) < 2:  # no linear channel
            acc = []
        f = [a.f for a in acc]
        terms = [a.terms for a in acc if a.terms is not None]
        frac = [a.frac for a in acc if a.frac is not None]
        ivl = [a.ivl for a in acc if a.ivl is not None]
        z, h_ang, h_lin, u_s, w_lin, mean = kernel.window_residual(
            self._ang_l, self._lin_l, self._j_l, self._j_inv_l, tau_s, edges, ga.omega,
            gb.omega, span_s, f, terms, frac, self.bias.tolist(), self.imu_period_s, self._noise)
        self.pending_bias = None if mean is None else np.array(mean)
        return Residual(t_a, t_b, span_s, z, tau_cmd_s, h_ang, h_lin, u_s, frac, w_lin, ivl)
