"""Shared fixtures of the flight-software algorithm tests: the seed-003 vehicle and thrusters."""

from __future__ import annotations

import numpy as np
import pytest

# Seed 003, Table 1.
SEED003_INERTIA_KGM2 = (15.95, 72.19, 72.19)
SEED003_THRUST_N = 15.0
SEED003_ARM_R_M = 0.45
SEED003_LENGTH_L_M = 0.22


def seed003_layout() -> tuple[np.ndarray, np.ndarray]:
    """Positions (n×3, m) and unit directions (n×3) of the 8 tangential thrusters, body axes."""
    r, l_ = SEED003_ARM_R_M, SEED003_LENGTH_L_M
    positions = np.array(
        [
            (r, 0.0, l_),
            (r, 0.0, -l_),
            (r, l_, 0.0),
            (r, -l_, 0.0),
            (-r, 0.0, l_),
            (-r, 0.0, -l_),
            (-r, l_, 0.0),
            (-r, -l_, 0.0),
        ]
    )
    directions = np.array(
        [
            (0.0, 1.0, 0.0),
            (0.0, -1.0, 0.0),
            (0.0, 0.0, 1.0),
            (0.0, 0.0, -1.0),
            (0.0, -1.0, 0.0),
            (0.0, 1.0, 0.0),
            (0.0, 0.0, -1.0),
            (0.0, 0.0, 1.0),
        ]
    )
    return positions, directions


@pytest.fixture
def layout() -> tuple[np.ndarray, np.ndarray]:
    """The seed-003 thruster layout (positions, directions)."""
    return seed003_layout()


@pytest.fixture
def inertia_kgm2() -> tuple[float, float, float]:
    """The seed-003 principal moments of inertia (Table 1) [kg m²]."""
    return SEED003_INERTIA_KGM2


@pytest.fixture
def max_thrust_n() -> float:
    """The seed-003 thrust level (Table 1) [N]."""
    return SEED003_THRUST_N


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator, so every test run draws the same numbers."""
    return np.random.default_rng(20240531)
