"""Reconfiguration after isolation: masked thrusters get 0, a stuck-open column is countered."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.allocation.effectiveness import effectiveness_matrix
from flight_sw.allocation.pseudo_inverse import PseudoInverseAllocator, PseudoInverseParams
from flight_sw.computer import FlightComputer, Timeline
from flight_sw.fdir.base import (
    FailureKind,
    ThrusterFailure,
    ThrusterFdirStrategy,
    Verdict,
)
from flight_sw.fdir.layout_check import LayoutCheck
from flight_sw.fdir.sensor_watchdog import SensorWatchdog
from flight_sw.fdir.thruster_fdir import ThrusterFdir
from flight_sw.modes import FdirFlag, Mode
from flight_sw.quaternion import identity

from .conftest import SEED000_THRUST_N

N = 16
PERIOD_NS = 20_000_000
IMU_NS = 10_000_000
ACHIEVED_TOL = 1e-9
N_DEMANDS = 50
DEMAND_FRACTION = 0.15  # demands well inside the attainable set, even with one thruster out


class Scripted(ThrusterFdirStrategy):
    """A strategy that isolates a given failure at a given time."""

    name = "scripted"

    def __init__(self, thruster: int, kind: FailureKind, t_ns: int) -> None:
        self.thruster, self.kind, self.t_ns = thruster, kind, t_ns
        self.known: list[ThrusterFailure] = []

    def evaluate(self, t_ns: int) -> Verdict:
        """Isolate at ``t_ns`` (detected one cycle before)."""
        if self.known or t_ns < self.t_ns - PERIOD_NS:
            return Verdict()
        if t_ns < self.t_ns:
            return Verdict(True, t_ns)
        f = ThrusterFailure(self.thruster, self.kind, self.t_ns - PERIOD_NS, t_ns, self.name)
        return Verdict(True, f.t_detect_ns, f)

    def set_failures(self, t_ns: int, failures: Any) -> None:
        """Remember the isolation."""
        self.known = list(failures)


class Demand:
    """A stand-in controller pair returning a fixed wrench."""

    def __init__(self, wrench: np.ndarray) -> None:
        self.wrench = wrench

    def torque_B_Nm(self, *args: Any) -> np.ndarray:
        """Torque rows."""
        return self.wrench[3:6]

    def force_B_N(self, *args: Any) -> np.ndarray:
        """Force rows."""
        return self.wrench[0:3]


class Estimator:
    """An initialised estimator at rest."""

    def propagate(self, t_ns: int, omega: np.ndarray) -> None:
        """Nothing to do."""

    def update_star_tracker(self, t_ns: int, q: np.ndarray) -> None:
        """Nothing to do."""

    def estimate(self) -> Any:
        """Identity, at rest, initialised."""
        from flight_sw.estimation.base import AttitudeEstimate

        z = np.zeros(3)
        return AttitudeEstimate(0, identity(), z, z, np.zeros(6), True)


class Proportional:
    """Modulator: on-time = fraction × period (so thrust can be read back)."""

    def on_time_s(self, t_ns: int, u: float, period_s: float) -> float:
        """Linear modulation."""
        return min(max(u, 0.0), 1.0) * period_s


def computer(b6: np.ndarray, wrench: np.ndarray, fdir: ThrusterFdir) -> FlightComputer:
    """A 6-DoF flight computer with stand-in estimator, controllers and modulators."""
    ctl = Demand(wrench)
    fc = FlightComputer(
        estimator=Estimator(),
        controller=ctl,
        allocator=PseudoInverseAllocator(b6, PseudoInverseParams(SEED000_THRUST_N)),
        modulators=[Proportional() for _ in range(N)],
        max_thrust_N=np.full(N, SEED000_THRUST_N),
        control_period_ns=PERIOD_NS,
        imu_period_ns=IMU_NS,
        timeline=Timeline(identity(), 0, np.zeros(3)),
        watchdog=SensorWatchdog({}),
        translation=ctl,
        effectiveness=b6,
        thruster_fdir=fdir,
        nav_timeout_ns=10**12,
    )
    fc.on_nav_pos(0, np.zeros(3))
    fc.on_nav_vel(0, np.zeros(3))
    return fc


def test_masked_allocator_keeps_failed_thrusters_at_zero(
    layout16: tuple[np.ndarray, np.ndarray], rng: np.random.Generator
) -> None:
    """with_mask: every allocation gives 0 N to the masked thruster and meets the demand."""
    b = effectiveness_matrix(*layout16)
    full = PseudoInverseAllocator(b, PseudoInverseParams(SEED000_THRUST_N))
    for failed in (0, 6, 13):
        mask = np.ones(N, dtype=bool)
        mask[failed] = False
        alloc = full.with_mask(mask)
        for _ in range(N_DEMANDS):
            demand = b @ rng.uniform(0.0, DEMAND_FRACTION * SEED000_THRUST_N, N)
            res = alloc.allocate(demand)
            assert res.thrust_N[failed] == 0.0
            assert res.residual_norm < ACHIEVED_TOL


@pytest.mark.parametrize("failed", [0, 2, 5, 14])
def test_stuck_open_wrench_is_fed_forward(
    layout16: tuple[np.ndarray, np.ndarray], failed: int
) -> None:
    """After isolating a stuck-open thruster, commands + its full thrust give the demand."""
    b = effectiveness_matrix(*layout16)
    wrench = np.array([0.5, -0.3, 0.2, 0.4, -0.2, 0.1])
    t_iso = 3 * PERIOD_NS
    fdir = ThrusterFdir(N, [Scripted(failed, FailureKind.STUCK_OPEN, t_iso)])
    fc = computer(b, wrench, fdir)
    for k in range(6):
        res = fc.cycle(k * PERIOD_NS)
        thrust = np.array(res.on_time_s) / (PERIOD_NS / 1e9) * SEED000_THRUST_N
        if k * PERIOD_NS >= t_iso:
            assert res.on_time_s[failed] == 0.0
            achieved = b @ thrust + b[:, failed] * SEED000_THRUST_N
            assert achieved == pytest.approx(wrench, abs=1e-9)
            assert res.fdir_flags & FdirFlag.THRUSTER_ISOLATED
            assert res.fdir is not None
            assert res.fdir.failed_thruster == failed
            assert res.fdir.failure_kind == FailureKind.STUCK_OPEN
            assert res.fdir.available_mask == (1 << N) - 1 - (1 << failed)
        else:
            assert b @ thrust == pytest.approx(wrench, abs=1e-9)
            assert res.fdir is not None and res.fdir.failed_thruster is None
        assert res.mode == Mode.NOMINAL


def test_stuck_closed_reconfiguration_and_report(layout16: tuple[np.ndarray, np.ndarray]) -> None:
    """Stuck closed: thruster masked, the others meet the demand; times reported in FSW_FDIR."""
    b = effectiveness_matrix(*layout16)
    wrench = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    t_iso = 5 * PERIOD_NS
    fdir = ThrusterFdir(N, [Scripted(7, FailureKind.STUCK_CLOSED, t_iso)])
    fc = computer(b, wrench, fdir)
    seen_pending = False
    for k in range(8):
        res = fc.cycle(k * PERIOD_NS)
        assert res.fdir is not None
        if k * PERIOD_NS == t_iso - PERIOD_NS:
            seen_pending = bool(res.fdir_flags & FdirFlag.THRUSTER_FAULT_DETECTED)
            assert not res.fdir_flags & FdirFlag.THRUSTER_ISOLATED
    assert seen_pending
    assert res.on_time_s[7] == 0.0
    thrust = np.array(res.on_time_s) / (PERIOD_NS / 1e9) * SEED000_THRUST_N
    assert b @ thrust == pytest.approx(wrench, abs=1e-9)
    rep = res.fdir
    assert (rep.failed_thruster, rep.failure_kind) == (7, FailureKind.STUCK_CLOSED)
    assert rep.detection_time_s == pytest.approx((t_iso - PERIOD_NS) / 1e9)
    assert rep.isolation_delay_s == pytest.approx(PERIOD_NS / 1e9)


def test_flight_computer_wants_one_maximum_per_thruster() -> None:
    """One number, or n − 1 maxima, for n modulators: ConfigError naming max_thrust_N."""
    with pytest.raises(ConfigError) as info:
        FlightComputer(
            estimator=None,  # type: ignore[arg-type]
            controller=None,  # type: ignore[arg-type]
            allocator=None,  # type: ignore[arg-type]
            modulators=[Proportional() for _ in range(N)],
            max_thrust_N=np.full(N - 1, SEED000_THRUST_N),
            control_period_ns=PERIOD_NS,
            imu_period_ns=IMU_NS,
            timeline=Timeline(identity(), 0),
            watchdog=SensorWatchdog({}),
        )
    assert info.value.key == "max_thrust_N"


def test_each_isolation_checks_what_the_thrusters_left_can_do(
    layout16: tuple[np.ndarray, np.ndarray]
) -> None:
    """The layout check runs on the mask of every reconfiguration, and an isolation that
    costs full control leaves a note with its time (the run's warnings); one that keeps
    it leaves none."""
    b = effectiveness_matrix(*layout16)
    t_iso = 4 * PERIOD_NS
    fdir = ThrusterFdir(N, [Scripted(3, FailureKind.STUCK_CLOSED, t_iso)])
    fc = computer(b, np.zeros(6), fdir)
    masks: list[np.ndarray] = []

    def lost(mask: np.ndarray) -> LayoutCheck:
        masks.append(mask.copy())
        return LayoutCheck(tuple(np.flatnonzero(mask).tolist()), ("torque +x",), ())

    fc.layout_check = lost
    for k in range(6):
        fc.cycle(k * PERIOD_NS)
    assert len(masks) == 1 and not masks[0][3] and masks[0].sum() == N - 1
    assert len(fc.layout_notes) == 1 and "isolation at 0.08 s" in fc.layout_notes[0]
    fc2 = computer(b, np.zeros(6), ThrusterFdir(N, [Scripted(3, FailureKind.STUCK_CLOSED,
                                                             t_iso)]))
    fc2.layout_check = lambda mask: LayoutCheck(tuple(np.flatnonzero(mask).tolist()), (), None)
    for k in range(6):
        fc2.cycle(k * PERIOD_NS)
    assert fc2.layout_notes == []
