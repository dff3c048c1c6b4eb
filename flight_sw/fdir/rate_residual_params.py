"""Settings of the acceleration-residual thruster FDIR (:mod:`flight_sw.fdir.rate_residual`).

What it does: :class:`RateResidualParams`, the frozen, self-validating settings of the
residual FDIR: window, detection thresholds and persistence, isolation margins, the
expected-thrust model's command and valve timing (defaults stated once, in
:mod:`flight_sw.fdir.valve_timing`) and the noise and model-error figures that normalise
the residual. Units are in the field names ([s], [rad/s], [m/s²]; the rest dimensionless).

Assumptions and sources: those of :mod:`flight_sw.fdir.rate_residual`.
"""

from __future__ import annotations

from dataclasses import dataclass

from dbc import validation as check
from flight_sw.fdir.valve_timing import (
    DEFAULT_CLOSE_DELAY_S,
    DEFAULT_COMMAND_DELAY_S,
    DEFAULT_OPEN_DELAY_S,
    DEFAULT_RISE_TAU_S,
    DEFAULT_TAIL_TAU_S,
    ValveTiming,
)

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
            (These five default to :mod:`flight_sw.fdir.valve_timing`'s values.)
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
    command_delay_s: float = DEFAULT_COMMAND_DELAY_S
    valve_open_delay_s: float = DEFAULT_OPEN_DELAY_S
    valve_close_delay_s: float = DEFAULT_CLOSE_DELAY_S
    valve_rise_tau_s: float = DEFAULT_RISE_TAU_S
    valve_tail_tau_s: float = DEFAULT_TAIL_TAU_S
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

    @property
    def valve_timing(self) -> ValveTiming:
        """The command and valve timing of the expected-thrust model."""
        return ValveTiming(
            command_delay_s=self.command_delay_s,
            open_delay_s=self.valve_open_delay_s,
            close_delay_s=self.valve_close_delay_s,
            rise_tau_s=self.valve_rise_tau_s,
            tail_tau_s=self.valve_tail_tau_s,
        )
