"""Pairing the flight software's receive log with the bench's transmissions (realtime)."""

from __future__ import annotations

import math

import numpy as np

from bench.operator.analysis.reception import (
    PAIRING_TOLERANCE_S,
    ReceiveLog,
    fill_reception,
    receive_log,
)
from dbc.e2e import COUNTER_MODULUS

IMU_ID, STR_ID, CMD_ID = 0x40, 0x50, 0x20
PERIOD_S = 0.01
DELAY_S = 4e-4  # transport delay of the synthetic receptions
NAN = float("nan")


def _tx_frames(can_id: int, n: int, t0_s: float = 0.0) -> dict[str, list[float]]:
    """``n`` bench transmissions of ``can_id`` every PERIOD_S, counters 0, 1, ... mod 15."""
    return {
        "t_ready_s": [t0_s + k * PERIOD_S for k in range(n)],
        "t_rx_s": [NAN] * n,
        "id": [can_id] * n,
        "tx": [1] * n,
        "counter": [k % COUNTER_MODULUS for k in range(n)],
    }


def _concat(*tables: dict[str, list[float]]) -> dict[str, np.ndarray]:
    return {k: np.concatenate([np.asarray(t[k], dtype=float) for t in tables]) for k in tables[0]}


def _fill(frames: dict[str, np.ndarray], log: ReceiveLog) -> np.ndarray:
    return fill_reception(frames["t_ready_s"], frames["t_rx_s"], frames["id"].astype(int),
                          frames["tx"].astype(int), frames["counter"].astype(int), log)


def _log(rows: list[tuple[float, int, int]]) -> ReceiveLog:
    t, i, c = zip(*rows, strict=True) if rows else ((), (), ())
    return ReceiveLog(np.asarray(t, dtype=float), np.asarray(i, dtype=np.int64),
                      np.asarray(c, dtype=np.int64))


def test_every_reception_pairs_with_its_transmission_across_counter_wraps() -> None:
    """Forty frames (the counter wraps twice) all get reception = sending + delay."""
    f = _concat(_tx_frames(IMU_ID, 40))
    log = _log([(t + DELAY_S, IMU_ID, int(c)) for t, c in zip(f["t_ready_s"], f["counter"],
                                                               strict=True)])
    t_rx = _fill(f, log)
    np.testing.assert_allclose(t_rx - f["t_ready_s"], DELAY_S, rtol=0, atol=1e-12)


def test_lost_frames_stay_unknown_and_the_rest_still_pair() -> None:
    """Frames 3..9 never arrived: they stay nan, frame 10 onwards pairs with its own sending."""
    f = _concat(_tx_frames(IMU_ID, 20))
    lost = set(range(3, 10))
    log = _log([(f["t_ready_s"][k] + DELAY_S, IMU_ID, k % COUNTER_MODULUS)
                for k in range(20) if k not in lost])
    t_rx = _fill(f, log)
    for k in range(20):
        if k in lost:
            assert math.isnan(t_rx[k]), k
        else:
            assert math.isclose(t_rx[k] - f["t_ready_s"][k], DELAY_S, abs_tol=1e-12), k


def test_ids_are_paired_separately_and_foreign_rows_ignored() -> None:
    """Two IDs interleaved pair independently; unknown IDs and received rows are left alone."""
    imu, st = _tx_frames(IMU_ID, 5), _tx_frames(STR_ID, 5, t0_s=0.003)
    received = {"t_ready_s": [0.001], "t_rx_s": [0.0015], "id": [CMD_ID], "tx": [0],
                "counter": [0]}
    f = _concat(imu, st, received)
    rows = [(t + DELAY_S, IMU_ID, k) for k, t in enumerate(imu["t_ready_s"])]
    rows += [(t + 2 * DELAY_S, STR_ID, k) for k, t in enumerate(st["t_ready_s"])]
    rows += [(0.002, 0x7FF, 0), (0.0016, CMD_ID, 0)]  # unknown ID; a frame the bench received
    t_rx = _fill(f, _log(sorted(rows)))
    np.testing.assert_allclose(t_rx[:5] - f["t_ready_s"][:5], DELAY_S, atol=1e-12)
    np.testing.assert_allclose(t_rx[5:10] - f["t_ready_s"][5:10], 2 * DELAY_S, atol=1e-12)
    assert t_rx[10] == 0.0015  # the bench's own reception time is kept


def test_a_reception_before_the_sending_is_not_its_partner() -> None:
    """A row timed before a transmission (beyond the tolerance) does not pair with it."""
    f = _concat(_tx_frames(IMU_ID, 3))
    early = f["t_ready_s"][1] - 10 * PAIRING_TOLERANCE_S
    t_rx = _fill(f, _log([(early, IMU_ID, 1)]))
    assert np.isnan(t_rx).all()


def test_receive_log_puts_wall_times_on_the_run_time_base() -> None:
    """Wall-clock receive times minus the run's wall-clock origin."""
    origin_s = 1_764_633_600.25
    cols = {"t_rx_wall_s": np.array([origin_s + 0.5, origin_s + 1.0]),
            "id": np.array([64.0, 80.0]), "counter": np.array([3.0, -1.0])}
    log = receive_log(cols, origin_s)
    np.testing.assert_allclose(log.t_rx_s, [0.5, 1.0], atol=1e-6)
    assert log.can_id.tolist() == [64, 80] and log.counter.tolist() == [3, -1]
