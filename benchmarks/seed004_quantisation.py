"""Seed 004's supervisor against the resolution of the bus: what the ICD must carry, as JSON.

What it does: runs the seed-004 supervisor (flight_sw.control.underactuated.supervisor)
from rest on cases 1-3 on the independent test plant
(tests/flight_sw/control/underactuated/ffrb_reference.py: direction-cosine RK4, the
thrusts held over each 20 ms period, continuous ideal thrusters), once per *variant*: the
thrusts and the measurements it sees are quantised as a link would quantise them.

- thrust: ``ideal`` (continuous); ``on_time`` (today's THR_CMD: the bench's throttled valve
  gives ``F = τ/P · F_max`` and τ goes over the bus in steps of the DBC's on-time LSB, the
  flight software rounding each period's on-time as ``flight_sw.frames`` does: P/LSB
  levels of ``F_max``); ``level16`` (a hypothetical 16-bit thrust level, the rounding error
  carried into the next period so the mean thrust is exact);
- sensors: ``ideal``; ``icd`` (the body rates, position and velocity rounded to today's
  LSBs of IMU_RATE, NAV_POS and NAV_VEL, read from the DBC; attitude exact: STR_QUAT's
  2e-5 is far below what matters here); ``fine_nav`` (position and velocity 10x finer);
  ``icd_rate`` and ``icd_nav`` (only the rates, only the navigation at today's LSBs);
  ``fine_nav_only`` (exact rates, navigation 10x finer).

``F_max`` is :data:`MAX_THRUST_N` (the largest thrust any case demands is 6.25 N). Each run
stops at rest on the target (the supervisor's ``done``) or after ``--limit-s``. Printed per
case and variant: whether it ended done, the time, the attitude, rate, position and
velocity errors at the end, and whether they meet issue 20's ideal-thruster tolerances.
Deterministic (no noise): any invocation gives the same numbers. No process, no bus.

    python benchmarks/seed004_quantisation.py                      # 3 cases x 6 variants
    python benchmarks/seed004_quantisation.py --cases 1 --variants on_time/icd --limit-s 300
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # the test plant lives in tests/ (the independent reference)

from dbc.database import load_database  # noqa: E402
from flight_sw.control.underactuated.supervisor import (  # noqa: E402
    Mode,
    Supervisor,
    SupervisorParams,
)
from tests.flight_sw.control.underactuated import ffrb_reference as ref  # noqa: E402
from tests.flight_sw.control.underactuated.test_supervisor import (  # noqa: E402
    ATTITUDE_TOL_DEG,
    CASES,
    POSITION_TOL_M,
    RATE_TOL_DEG_S,
    RUN_LIMIT_S,
    VELOCITY_TOL_M_S,
)

MAX_THRUST_N = 8.0
LEVEL16_STEPS = 65535
FINE_NAV_FACTOR = 10.0
THRUSTS = ("ideal", "on_time", "level16")
# sensors: (rate LSB, navigation LSBs) as fractions of the DBC's (None: exact)
SENSORS: dict[str, tuple[float | None, float | None]] = {
    "ideal": (None, None), "icd": (1.0, 1.0), "fine_nav": (1.0, 1.0 / FINE_NAV_FACTOR),
    "icd_rate": (1.0, None), "icd_nav": (None, 1.0), "fine_nav_only": (None, 1.0 / FINE_NAV_FACTOR),
}
DEFAULT_VARIANTS = ("ideal/ideal", "on_time/ideal", "ideal/icd", "level16/ideal",
                    "ideal/fine_nav", "level16/fine_nav")
MM_PER_M = 1000.0


def _lsbs(sensors: str) -> tuple[float, float, float]:
    """(rate [rad/s], position [m], velocity [m/s]) LSBs of a sensor variant, from the DBC
    (0: exact)."""
    rate_f, nav_f = SENSORS[sensors]
    db = load_database()

    def lsb(message: str, signal: str, fraction: float | None) -> float:
        if fraction is None:
            return 0.0
        return float(db.get_message_by_name(message).get_signal_by_name(signal).scale) * fraction

    return (lsb("IMU_RATE", "RateX", rate_f), lsb("NAV_POS", "PosX", nav_f),
            lsb("NAV_VEL", "VelX", nav_f))


def _steps(thrust: str) -> int | None:
    """Thrust levels of ``F_max`` a thrust variant can command (None: continuous)."""
    if thrust == "ideal":
        return None
    if thrust == "level16":
        return LEVEL16_STEPS
    db = load_database()
    lsb = db.get_message_by_name("THR_CMD_0").get_signal_by_name("OnTime_T00").scale
    return round(ref.PERIOD_S / float(lsb))


def _round(x: np.ndarray, lsb: float) -> np.ndarray:
    """``x`` in steps of ``lsb`` (0: as it is)."""
    return np.round(x / lsb) * lsb if lsb > 0.0 else x


def _parse_variant(variant: str) -> tuple[str, str]:
    """``(thrust, sensors)`` of a "thrust/sensors" variant; exits naming a bad one."""
    thrust, _, sensors = variant.partition("/")
    if thrust not in THRUSTS or sensors not in SENSORS:
        raise SystemExit(f"--variants: {variant!r} is not thrust/sensors with thrust in "
                         f"{THRUSTS} and sensors in {tuple(SENSORS)}")
    return thrust, sensors


def run_case(case: str, variant: str, limit_s: float) -> dict[str, Any]:
    """One case under one variant ("thrust/sensors"): its end state and verdict."""
    thrust, sensors = _parse_variant(variant)
    steps, lsbs = _steps(thrust), _lsbs(sensors)
    euler_zyx_deg, r0_m = CASES[case]
    sup = Supervisor(ref.vehicle(), SupervisorParams(), ref.PERIOD_S)
    c0 = Rotation.from_euler("ZYX", euler_zyx_deg, degrees=True).as_matrix()
    plant = ref.Plant(c0, np.zeros(3), np.array(r0_m), np.zeros(3), substeps=1)
    m_inv = np.linalg.inv(np.cross(ref.R_THR_B_M, ref.D_THR_B).T)
    carried = np.zeros(3)
    impulse = 0.0
    while plant.t < limit_s - 1e-9 and sup.mode is not Mode.DONE:
        w, r, v = plant.w, plant.r, plant.v
        w, r, v = _round(w, lsbs[0]), _round(r, lsbs[1]), _round(v, lsbs[2])
        f = m_inv @ sup.torque_B_Nm(plant.t, plant.q_BR(), w, r, v)
        if steps is not None:
            want = f + carried if thrust == "level16" else f
            f = np.clip(np.round(want / MAX_THRUST_N * steps), 0, steps) * MAX_THRUST_N / steps
            carried = want - f if thrust == "level16" else carried
        impulse += float(f.sum()) * ref.PERIOD_S
        plant.step(f)
    attitude_deg = math.degrees(Rotation.from_matrix(plant.c).magnitude())
    rate_deg_s = math.degrees(float(np.linalg.norm(plant.w)))
    position_mm = float(np.linalg.norm(plant.r)) * MM_PER_M
    velocity_mm_s = float(np.linalg.norm(plant.v)) * MM_PER_M
    done = sup.mode is Mode.DONE
    meets = (done and attitude_deg <= ATTITUDE_TOL_DEG and rate_deg_s <= RATE_TOL_DEG_S
             and position_mm <= POSITION_TOL_M * MM_PER_M
             and velocity_mm_s <= VELOCITY_TOL_M_S * MM_PER_M)
    out: dict[str, Any] = {
        "case": case, "variant": variant, "done": done, "end_s": round(plant.t, 1),
        "last_mode": sup.mode.value,
        "switches": [[round(t, 1), m] for t, m in sup.switches],
        "attitude_error_deg": attitude_deg, "rate_deg_s": rate_deg_s,
        "position_error_mm": position_mm, "velocity_mm_s": velocity_mm_s,
        "impulse_N_s": round(impulse, 2), "meets_issue20": meets,
    }
    return out


def main(argv: list[str]) -> None:
    """Parse the arguments, run every case and variant, print JSON."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--cases", nargs="+", choices=sorted(c.split()[-1] for c in CASES),
                   default=["1", "2", "3"], help="seed-004 cases (test_supervisor.py)")
    p.add_argument("--variants", nargs="+", default=list(DEFAULT_VARIANTS),
                   help=f"thrust/sensors pairs, thrust in {THRUSTS}, sensors in {tuple(SENSORS)}")
    p.add_argument("--limit-s", type=float, default=RUN_LIMIT_S,
                   help="simulated seconds before a run is stopped (default %(default)s)")
    p.add_argument("--jobs", type=int, default=1, help="runs at a time (processes)")
    a = p.parse_args(argv)
    if not (a.limit_s > 0.0 and math.isfinite(a.limit_s)):
        raise SystemExit(f"--limit-s: {a.limit_s} is not a positive number of seconds")
    if a.jobs < 1:
        raise SystemExit(f"--jobs: {a.jobs} is not a positive count")
    jobs = [(f"case {c}", v, a.limit_s) for c in a.cases for v in a.variants]
    for v in a.variants:  # refuse a bad variant before any run starts
        _parse_variant(v)
    with ProcessPoolExecutor(a.jobs) as pool:
        runs = list(pool.map(run_case, *zip(*jobs, strict=True)))
    print(json.dumps({"benchmark": "seed004_quantisation", "max_thrust_N": MAX_THRUST_N,
                      "limit_s": a.limit_s, "runs": runs}, indent=1))


if __name__ == "__main__":
    main(sys.argv[1:])
