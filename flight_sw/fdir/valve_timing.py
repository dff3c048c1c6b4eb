"""Valve timing as the flight software knows it: delays and first-order time constants.

What it does: :class:`ValveTiming` holds the nominal timing of a thruster valve and of the
command that drives it, and the module states each default once (:data:`DEFAULT_TIMING`
and the ``DEFAULT_*`` constants); every flight-software user of valve timing (the FDIR's
expected-thrust model :mod:`flight_sw.fdir.thrust_model`, the residual FDIR's parameters
:mod:`flight_sw.fdir.rate_residual_params`, the configuration loader's vehicle data in
:mod:`flight_sw.config`) takes its defaults from here.

Fields [s]: ``command_delay_s`` from the start of the control cycle to the command's
reception by the drive electronics (the flight software's response plus the frames before
it); ``open_delay_s`` / ``close_delay_s`` from coil on / off to the valve starting to open /
close (transport delays); ``rise_tau_s`` / ``tail_tau_s`` the first-order time constants of
the thrust rising towards its maximum and decaying to zero.

Defaults: the valve data of this project's scenarios (``[thrusters]`` of
``scenarios/*.toml``: 3 ms opening, 2 ms closing, 2 ms rise, 3 ms tail; cold-gas and
small monopropellant thrusters are of this order) and a 1.5 ms command delay (1 ms
response + ~0.5 ms of status and command frames at 1 Mbit/s).

Assumptions: one timing for every valve of the vehicle (a valve that differs shows up as
an FDIR residual, which is the point). Source: first-order valve with transport delays,
Wertz & Larson (eds.) 1999, "Space Mission Analysis and Design", 3rd ed. (pulse-mode
thrusters).
"""

from __future__ import annotations

from dataclasses import dataclass

from dbc import validation as check

DEFAULT_COMMAND_DELAY_S = 0.0015
DEFAULT_OPEN_DELAY_S = 0.003
DEFAULT_CLOSE_DELAY_S = 0.002
DEFAULT_RISE_TAU_S = 0.002
DEFAULT_TAIL_TAU_S = 0.003

_SOURCE = "ValveTiming"


@dataclass(frozen=True)
class ValveTiming:
    """Nominal command and valve timing [s] (see the module docstring); each ≥ 0."""

    command_delay_s: float = DEFAULT_COMMAND_DELAY_S
    open_delay_s: float = DEFAULT_OPEN_DELAY_S
    close_delay_s: float = DEFAULT_CLOSE_DELAY_S
    rise_tau_s: float = DEFAULT_RISE_TAU_S
    tail_tau_s: float = DEFAULT_TAIL_TAU_S

    def __post_init__(self) -> None:
        for key in ("command_delay_s", "open_delay_s", "close_delay_s", "rise_tau_s",
                    "tail_tau_s"):
            check.non_negative(_SOURCE, key, getattr(self, key), unit="s")


DEFAULT_TIMING = ValveTiming()
