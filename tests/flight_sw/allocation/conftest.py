"""Effectiveness matrices of the allocation tests: seed 000 (16 thr), seed 003 (8), seed 001 (8)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flight_sw.allocation.effectiveness import TORQUE_ROWS, effectiveness_matrix

# Seed 000 reconstructed four-quad layout (bench/station/valves/layouts.py, R = 0.5 m, L = 0.1 m).
SEED000_THRUST_N = 5.0
SEED000_R_M = 0.5
SEED000_L_M = 0.1
# Seed 003 Table 1 layout (R = 0.45 m, L = 0.22 m), 15 N thrusters.
SEED003_THRUST_N = 15.0
SEED003_R_M = 0.45
SEED003_L_M = 0.22
# Seed 001 sec. 5: signed thrust bounds [N] and Table 1 (positions [m], direction angles).
SEED001_LOWER_N = -2.3
SEED001_UPPER_N = 2.35
_S = 0.375 * math.sqrt(2.0)
SEED001_POSITIONS_M = (
    (0.0, -0.75, 0.75),
    (-0.75, -0.75, 0.0),
    (0.0, -0.75, -0.75),
    (0.75, -0.75, 0.0),
    (_S, -0.75, _S),
    (-_S, -0.75, _S),
    (-_S, -0.75, -_S),
    (_S, -0.75, -_S),
)
# Table 1 "orientation": the angles [rad] between the thrust and the body x, y, z axes,
# in units of π/2 (so the direction is their cosines).
SEED001_DIRECTION_ANGLES_HALF_PI = (
    (1, 1, 2),
    (0, 1, 1),
    (1, 1, 0),
    (2, 1, 1),
    (2, 1, 1),
    (0, 1, 1),
    (0, 1, 1),
    (2, 1, 1),
)


def seed000_matrix() -> np.ndarray:
    """6×16 wrench matrix of the seed-000 four-quad layout."""
    r, l_ = SEED000_R_M, SEED000_L_M
    quads = (((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)), ((0.0, 0.0, 1.0), (0.0, -1.0, 0.0)))
    quads += (((0.0, -1.0, 0.0), (0.0, 0.0, -1.0)), ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0)))
    pos, dirs = [], []
    for e, t in quads:
        p = (l_, r * e[1], r * e[2])
        for d in ((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), t, tuple(-x for x in t)):
            pos.append(p)
            dirs.append(d)
    return effectiveness_matrix(np.array(pos), np.array(dirs) + 0.0)


def seed003_torque_matrix() -> np.ndarray:
    """3×8 torque matrix of the seed-003 layout."""
    r, l_ = SEED003_R_M, SEED003_L_M
    pos = [(r, 0, l_), (r, 0, -l_), (r, l_, 0), (r, -l_, 0)]
    pos += [(-r, 0, l_), (-r, 0, -l_), (-r, l_, 0), (-r, -l_, 0)]
    dirs = [(0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1), (0, -1, 0), (0, 1, 0), (0, 0, -1)]
    dirs += [(0, 0, 1)]
    return effectiveness_matrix(np.array(pos, float), np.array(dirs, float))[TORQUE_ROWS]


def seed001_torque_matrix() -> np.ndarray:
    """3×8 torque matrix of seed 001 Table 1."""
    dirs = np.cos(np.array(SEED001_DIRECTION_ANGLES_HALF_PI, float) * math.pi / 2.0)
    dirs = np.round(dirs, 15) + 0.0
    return effectiveness_matrix(np.array(SEED001_POSITIONS_M), dirs)[TORQUE_ROWS]


@pytest.fixture
def b16() -> np.ndarray:
    """Seed-000 6×16 wrench matrix."""
    return seed000_matrix()


@pytest.fixture
def b8() -> np.ndarray:
    """Seed-003 3×8 torque matrix."""
    return seed003_torque_matrix()


@pytest.fixture
def b001() -> np.ndarray:
    """Seed-001 3×8 torque matrix (Table 1)."""
    return seed001_torque_matrix()


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator."""
    return np.random.default_rng(20240607)
