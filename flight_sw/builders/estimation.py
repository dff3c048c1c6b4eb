"""Builders of the estimators: ``[flight_sw.estimator]``, ``[flight_sw.inertia_identification]``.

What it does: one builder per ``kind`` (a registry: a new estimator is a new module plus
one line here): the MEKF (gyro noise in deg/√h and deg/h/√h, star-tracker noise in
arcsec, converted to rad here) and the RLS inertia identifier (seed 001 §2; guess from the
file or the nominal inertia). Each takes the table and the :class:`Vehicle` and returns the
strategy; bad values raise ConfigError naming the key.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType

import numpy as np

from dbc.schema import Table
from flight_sw.builders.vehicle import ARCSEC_RAD, DEG_RAD, SQRT_HOUR_S, Vehicle
from flight_sw.estimation.base import AttitudeEstimator, InertiaIdentifier
from flight_sw.estimation.mekf import Mekf, MekfParams
from flight_sw.estimation.rls_inertia import RlsInertiaIdentifier, RlsInertiaParams


def _mekf(t: Table, v: Vehicle) -> AttitudeEstimator:
    return Mekf(
        MekfParams(
            gyro_arw_rad_sqrt_s=t.number("gyro_arw_deg_sqrt_h", lo=0.0) * DEG_RAD / SQRT_HOUR_S,
            gyro_bias_rw_rad_s_sqrt_s=t.number("gyro_bias_rw_deg_h_sqrt_h", lo=0.0)
            * DEG_RAD
            / 3600.0
            / SQRT_HOUR_S,
            star_tracker_sigma_rad=t.number("star_tracker_noise_arcsec", lo=0.0, lo_open=True)
            * ARCSEC_RAD,
            initial_attitude_sigma_rad=t.number(
                "initial_attitude_sigma_deg", 0.1, lo=0.0, lo_open=True
            )
            * DEG_RAD,
            initial_bias_sigma_rad_s=t.number("initial_bias_sigma_deg_h", lo=0.0, lo_open=True)
            * DEG_RAD
            / 3600.0,
        )
    )


def _rls(t: Table, v: Vehicle) -> InertiaIdentifier:
    d = RlsInertiaParams(inertia_guess_B_kgm2=v.inertia_B_kgm2)
    guess = np.array(t.matrix3("inertia_guess_B_kgm2")) if t.has("inertia_guess_B_kgm2") else None
    return RlsInertiaIdentifier(
        RlsInertiaParams(
            inertia_guess_B_kgm2=v.inertia_B_kgm2 if guess is None else guess,
            forgetting_factor=t.number(
                "forgetting_factor", d.forgetting_factor, lo=0.0, lo_open=True, hi=1.0
            ),
            initial_covariance=t.number(
                "initial_covariance", d.initial_covariance, lo=0.0, lo_open=True
            ),
            min_information=t.number("min_information", d.min_information, lo=0.0),
            min_regressor_norm=t.number("min_regressor_norm", d.min_regressor_norm, lo=0.0),
            max_gap_s=t.number("max_gap_s", d.max_gap_s, lo=0.0, lo_open=True),
            window_cycles=t.integer("window_cycles", d.window_cycles, lo=1),
        )
    )


ESTIMATORS: Mapping[str, Callable[[Table, Vehicle], AttitudeEstimator]] = MappingProxyType(
    {"mekf": _mekf}
)

INERTIA_IDENTIFIERS: Mapping[str, Callable[[Table, Vehicle], InertiaIdentifier]] = (
    MappingProxyType({"rls": _rls})
)
