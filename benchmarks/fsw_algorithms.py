"""Per-call cost of the flight-software algorithms; prints JSON (median µs per call).

Measures, on the seed-003 vehicle (8 thrusters, Table 1 inertia and thrust):
- ``mekf_propagate_us``: one gyro sample (``Mekf.propagate``);
- ``mekf_update_us``: one star-tracker update (``Mekf.update_star_tracker``);
- ``mekf_estimate_us``: building the estimate (``Mekf.estimate``);
- ``quaternion_pd_us``: one torque demand (``QuaternionPd.torque_B_Nm``);
- ``allocate_8thr_us``: one torque allocation on the common path (attainable demands);
- ``allocate_8thr_saturated_us``: one allocation of an unattainable demand (scaling path);
- ``pwpf_x8_us``: eight PWPF modulators for one 20 ms period;
- ``chain_50hz_cycle_us``: one 50 Hz cycle = 2 gyro samples (100 Hz), a star-tracker update
  every 10th cycle (5 Hz) amortised, estimate, PD, allocation and 8 modulators.
Each figure is the median over ``REPEATS`` batches of ``CALLS`` calls.

Usage: ``python benchmarks/fsw_algorithms.py``
"""

from __future__ import annotations

import json
import platform
import statistics
import time
from collections.abc import Callable

import numpy as np

from flight_sw import quaternion as qt
from flight_sw.allocation.effectiveness import TORQUE_ROWS, effectiveness_matrix
from flight_sw.allocation.pseudo_inverse import PseudoInverseAllocator, PseudoInverseParams
from flight_sw.control.quaternion_pd import QuaternionPd, QuaternionPdParams
from flight_sw.estimation.mekf import Mekf, MekfParams
from flight_sw.modulation.pwpf import PwpfModulator, PwpfParams

REPEATS = 15
CALLS = 400
NS_PER_US = 1_000
GYRO_PERIOD_NS = 10_000_000
CONTROL_PERIOD_NS = 20_000_000
CONTROL_PERIOD_S = CONTROL_PERIOD_NS / 1e9
STAR_TRACKER_EVERY_CYCLES = 10
INERTIA_KGM2 = (15.95, 72.19, 72.19)
MAX_THRUST_N = 15.0
ARM_R_M, LENGTH_L_M = 0.45, 0.22
SEED = 3


def seed003_layout() -> tuple[np.ndarray, np.ndarray]:
    """Seed-003 thruster positions and directions (body axes)."""
    r, l_ = ARM_R_M, LENGTH_L_M
    pos = np.array(
        [
            (r, 0, l_),
            (r, 0, -l_),
            (r, l_, 0),
            (r, -l_, 0),
            (-r, 0, l_),
            (-r, 0, -l_),
            (-r, l_, 0),
            (-r, -l_, 0),
        ],
        dtype=float,
    )
    direction = np.array(
        [
            (0, 1, 0),
            (0, -1, 0),
            (0, 0, 1),
            (0, 0, -1),
            (0, -1, 0),
            (0, 1, 0),
            (0, 0, -1),
            (0, 0, 1),
        ],
        dtype=float,
    )
    return pos, direction


def median_us(fn: Callable[[int], object]) -> float:
    """Median over REPEATS batches of the per-call time of ``fn(i)`` [µs]."""
    per_call = []
    for _ in range(REPEATS):
        start = time.perf_counter_ns()
        for i in range(CALLS):
            fn(i)
        per_call.append((time.perf_counter_ns() - start) / CALLS / NS_PER_US)
    return round(statistics.median(per_call), 2)


def main() -> None:
    """Run every benchmark and print one JSON object."""
    rng = np.random.default_rng(SEED)
    mekf_params = MekfParams(
        gyro_arw_rad_sqrt_s=1e-5,
        gyro_bias_rw_rad_s_sqrt_s=1e-7,
        star_tracker_sigma_rad=5e-5,
        initial_attitude_sigma_rad=5e-5,
        initial_bias_sigma_rad_s=1e-3,
    )
    rate = np.array([0.01, -0.02, 0.015])
    q0 = qt.normalise(np.array([0.8, 0.2, -0.4, 0.4]))
    mekf = Mekf(mekf_params)
    mekf.update_star_tracker(0, q0)
    gyro = [rate + rng.normal(0.0, 1e-4, 3) for _ in range(CALLS)]
    t_gyro = [0]

    def propagate(i: int) -> None:
        t_gyro[0] += GYRO_PERIOD_NS
        mekf.propagate(t_gyro[0], gyro[i])

    st = [qt.multiply(q0, qt.from_rotation_vector(rng.normal(0.0, 5e-5, 3))) for _ in range(CALLS)]

    def update(i: int) -> None:
        mekf.update_star_tracker(t_gyro[0], st[i])

    pd = QuaternionPd(QuaternionPdParams.from_bandwidth(INERTIA_KGM2, 0.5, 0.7))
    q_ref = qt.from_rotation_vector(np.array([0.3, -0.2, 0.1]))
    zero = np.zeros(3)

    b = effectiveness_matrix(*seed003_layout())[TORQUE_ROWS]
    alloc = PseudoInverseAllocator(b, PseudoInverseParams(MAX_THRUST_N))
    feasible = [b @ rng.uniform(0.0, MAX_THRUST_N / 2, 8) for _ in range(CALLS)]
    unattainable = [100.0 * rng.normal(size=3) for _ in range(CALLS)]

    pwpf_params = PwpfParams(km=4.5, tm_s=0.15, u_on=0.45, u_off=0.15, min_on_s=0.005)
    mods = [PwpfModulator(pwpf_params) for _ in range(8)]
    fractions = [rng.uniform(0.0, 1.0, 8).tolist() for _ in range(CALLS)]

    def pwpf8(i: int) -> None:
        for mod, u in zip(mods, fractions[i], strict=True):
            mod.on_time_s(0, u, CONTROL_PERIOD_S)

    chain_mekf = Mekf(mekf_params)
    chain_mekf.update_star_tracker(0, q0)
    t_chain = [0]

    def chain(i: int) -> None:
        t_chain[0] += CONTROL_PERIOD_NS
        t = t_chain[0]
        chain_mekf.propagate(t - GYRO_PERIOD_NS, gyro[i])
        chain_mekf.propagate(t, gyro[i])
        if i % STAR_TRACKER_EVERY_CYCLES == 0:
            chain_mekf.update_star_tracker(t, st[i])
        est = chain_mekf.estimate()
        torque = pd.torque_B_Nm(t, est.q_BN, est.omega_BN_B, q_ref, zero)
        res = alloc.allocate(torque)
        for mod, thrust in zip(mods, res.thrust_N.tolist(), strict=True):
            mod.on_time_s(t, thrust / MAX_THRUST_N, CONTROL_PERIOD_S)

    figures = {
        "mekf_propagate_us": median_us(propagate),
        "mekf_update_us": median_us(update),
        "mekf_estimate_us": median_us(lambda i: mekf.estimate()),
        "quaternion_pd_us": median_us(lambda i: pd.torque_B_Nm(0, st[i], rate, q_ref, zero)),
        "allocate_8thr_us": median_us(lambda i: alloc.allocate(feasible[i])),
        "allocate_8thr_saturated_us": median_us(lambda i: alloc.allocate(unattainable[i])),
        "pwpf_x8_us": median_us(pwpf8),
        "chain_50hz_cycle_us": median_us(chain),
    }
    print(
        json.dumps(
            {
                "benchmark": "fsw_algorithms",
                "python": platform.python_version(),
                "numpy": np.__version__,
                "repeats": REPEATS,
                "calls_per_repeat": CALLS,
                **figures,
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
